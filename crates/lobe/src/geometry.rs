//! The two highlight conventions: the cosine a lobe is evaluated at.
//!
//! Vectors are `[T; 3]`, pointing away from the surface (`light` towards the light,
//! `view` towards the eye). Inputs need not be normalised; zero, NaN or infinite
//! vectors give a cosine of 0 (no highlight) instead of NaN.

use crate::lobe::{LobeError, Real};

/// Which angle γ the specular lobe is a function of (`phong` or `blinn`).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    Default,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[strum(
    serialize_all = "lowercase",
    ascii_case_insensitive,
    parse_err_ty = LobeError,
    parse_err_fn = unknown_geometry
)]
pub enum Geometry {
    /// Phong: γ between the view vector V and R, the reflection of L about N.
    #[default]
    Phong,
    /// Blinn: γ between the normal N and the half vector H = normalize(L + V).
    Blinn,
}

impl Geometry {
    /// Both geometries, Phong first.
    pub const ALL: &'static [Geometry] = <Geometry as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`Geometry::ALL`].
    pub const NAMES: &'static [&'static str] = <Geometry as strum::VariantNames>::VARIANTS;

    /// `cos γ` for this convention; see [`phong_cos`] and [`blinn_cos`].
    #[inline]
    pub fn cos<T: Real>(self, normal: [T; 3], light: [T; 3], view: [T; 3]) -> T {
        match self {
            Geometry::Phong => phong_cos(normal, light, view),
            Geometry::Blinn => blinn_cos(normal, light, view),
        }
    }

    /// The name users type: `phong` or `blinn`.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl crate::names::Named for Geometry {
    const WHAT: &'static str = "geometry";
}

/// The error for a name that is not a geometry's.
fn unknown_geometry(name: &str) -> LobeError {
    LobeError::UnknownName(crate::names::unknown::<Geometry>(name))
}

fn dot<T: Real>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a` scaled to unit length, or `None` when its length is zero, NaN or infinite.
fn normalize<T: Real>(a: [T; 3]) -> Option<[T; 3]> {
    let len = dot(a, a).sqrt();
    if len.is_finite() && len > T::zero() {
        Some([a[0] / len, a[1] / len, a[2] / len])
    } else {
        None
    }
}

/// The reflection of `light` about `normal`: `R = 2 (N·L) N - L`, both normalised
/// first. `None` for a degenerate input.
pub fn reflect<T: Real>(normal: [T; 3], light: [T; 3]) -> Option<[T; 3]> {
    let n = normalize(normal)?;
    let l = normalize(light)?;
    let k = T::from_f64(2.0) * dot(n, l);
    Some([k * n[0] - l[0], k * n[1] - l[1], k * n[2] - l[2]])
}

/// Phong's cosine `R·V`, clamped to `[-1, 1]`; 0 for degenerate vectors.
pub fn phong_cos<T: Real>(normal: [T; 3], light: [T; 3], view: [T; 3]) -> T {
    match (reflect(normal, light), normalize(view)) {
        (Some(r), Some(v)) => clamp_unit(dot(r, v)),
        _ => T::zero(),
    }
}

/// Blinn's cosine `N·H`, `H = normalize(L + V)`, clamped to `[-1, 1]`; 0 for
/// degenerate vectors, including `L = -V` where the half vector is undefined.
pub fn blinn_cos<T: Real>(normal: [T; 3], light: [T; 3], view: [T; 3]) -> T {
    let (Some(n), Some(l), Some(v)) = (normalize(normal), normalize(light), normalize(view)) else {
        return T::zero();
    };
    match normalize([l[0] + v[0], l[1] + v[1], l[2] + v[2]]) {
        Some(h) => clamp_unit(dot(n, h)),
        None => T::zero(),
    }
}

fn clamp_unit<T: Real>(x: T) -> T {
    x.max(-T::one()).min(T::one())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror_direction_gives_one() {
        let n = [0.0, 0.0, 1.0];
        let l = [1.0, 0.0, 1.0];
        let v = [-1.0, 0.0, 1.0];
        assert!((phong_cos(n, l, v) - 1.0f64).abs() < 1e-15);
        assert!((blinn_cos(n, l, v) - 1.0f64).abs() < 1e-15);
    }

    #[test]
    fn blinn_angle_is_half_of_phong_in_the_plane() {
        // In the plane of incidence, the Phong angle is twice the Blinn angle.
        let n = [0.0f64, 0.0, 1.0];
        let l = [30f64.to_radians().sin(), 0.0, 30f64.to_radians().cos()];
        let view_angle = -10f64.to_radians();
        let v = [view_angle.sin(), 0.0, view_angle.cos()];
        let phong = phong_cos(n, l, v).acos().to_degrees();
        let blinn = blinn_cos(n, l, v).acos().to_degrees();
        assert!((phong - 20.0).abs() < 1e-9, "{phong}");
        assert!((blinn - 10.0).abs() < 1e-9, "{blinn}");
    }

    #[test]
    fn degenerate_vectors_give_zero() {
        let z = [0.0f32; 3];
        let n = [0.0f32, 0.0, 1.0];
        assert_eq!(phong_cos(z, n, n), 0.0);
        assert_eq!(phong_cos(n, n, [f32::NAN, 0.0, 1.0]), 0.0);
        assert_eq!(blinn_cos(n, [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]), 0.0);
        assert_eq!(blinn_cos(n, [f32::INFINITY, 0.0, 0.0], n), 0.0);
        assert_eq!(Geometry::Blinn.cos(n, n, n), 1.0);
    }
}
