//! The lobe in world space at one scattering event: Phong geometry samples the
//! direction around the mirror direction R; Blinn geometry samples the half vector
//! around the normal and reflects the outgoing direction about it, with the
//! Jacobian `dω_h/dω_i = 1/(4 |ω_o·h|)` (Walter et al., "Microfacet Models for
//! Refraction through Rough Surfaces", EGSR 2007, eq. 14; pbrt-v4's
//! `ConductorBxDF::Sample_f` in src/pbrt/bxdfs.h divides the same way).
//!
//! Vectors are `[T; 3]` pointing away from the surface (ω_o towards the viewer, ω_i
//! towards the light, as in glint's [`Geometry`]).

use crate::lobe::Real;
use crate::Geometry;

use super::AxisLobe;

fn dot<T: Real>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize<T: Real>(a: [T; 3]) -> Option<[T; 3]> {
    let len = dot(a, a).sqrt();
    (len.is_finite() && len > T::zero()).then(|| [a[0] / len, a[1] / len, a[2] / len])
}

/// `v` reflected about the unit `axis`: `2 (v·axis) axis - v` (the mirror direction R
/// of `v` about a normal, or ω_i from ω_o about a half vector).
#[inline]
pub fn reflect_about<T: Real>(v: [T; 3], axis: [T; 3]) -> [T; 3] {
    let k = T::from_f64(2.0) * dot(v, axis);
    [k * axis[0] - v[0], k * axis[1] - v[1], k * axis[2] - v[2]]
}

/// The Jacobian of Blinn geometry, `dω_h / dω_i = 1 / (4 |ω_o·h|)`: a half vector
/// drawn with density `p_h` gives the reflected direction the density
/// `p_h · blinn_jacobian(ω_o·h)`. Infinite at `ω_o·h = 0`.
#[inline]
pub fn blinn_jacobian<T: Real>(wo_dot_h: T) -> T {
    T::one() / (T::from_f64(4.0) * wo_dot_h.abs())
}

/// An orthonormal frame whose `z` is a given unit axis: world directions from the
/// axis-frame directions of [`AxisLobe::sample`] and back.
///
/// Built branch-free by Duff et al., "Building an Orthonormal Basis, Revisited"
/// (JCGT 6(1), 2017), the construction of pbrt-v4's `CoordinateSystem`
/// (src/pbrt/util/vecmath.h).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame<T> {
    x: [T; 3],
    y: [T; 3],
    z: [T; 3],
}

impl<T: Real> Frame<T> {
    /// The frame around the unit vector `z` (not checked: pass a unit vector).
    #[inline]
    pub fn from_z(z: [T; 3]) -> Frame<T> {
        let one = T::one();
        let sign = one.copysign(z[2]);
        let a = -one / (sign + z[2]);
        let b = z[0] * z[1] * a;
        Frame {
            x: [one + sign * z[0] * z[0] * a, sign * b, -sign * z[0]],
            y: [b, sign + z[1] * z[1] * a, -z[1]],
            z,
        }
    }

    /// The axis `z`.
    pub fn z(&self) -> [T; 3] {
        self.z
    }

    /// The world vector with coordinates `v` in this frame.
    #[inline]
    pub fn to_world(&self, v: [T; 3]) -> [T; 3] {
        let (x, y, z) = (self.x, self.y, self.z);
        [
            v[0] * x[0] + v[1] * y[0] + v[2] * z[0],
            v[0] * x[1] + v[1] * y[1] + v[2] * z[1],
            v[0] * x[2] + v[1] * y[2] + v[2] * z[2],
        ]
    }

    /// The coordinates in this frame of the world vector `v`.
    #[inline]
    pub fn to_local(&self, v: [T; 3]) -> [T; 3] {
        [dot(v, self.x), dot(v, self.y), dot(v, self.z)]
    }
}

/// A sampled incident direction, with what an estimator needs (pbrt's `BSDFSample`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LobeSample<T> {
    /// The incident direction ω_i (unit, world space).
    pub wi: [T; 3],
    /// The lobe's value there ([`Scatter::eval`] at `wi`).
    pub value: T,
    /// The density of `wi` per steradian ([`Scatter::pdf`] at `wi`).
    pub pdf: T,
    /// `cos γ`: `R·ω_i` (Phong) or `N·H` (Blinn).
    pub cos: T,
}

/// The lobe at one scattering event: a geometry, a normal and the outgoing direction,
/// with the frame around the lobe's axis built once; then [`sample`](Self::sample),
/// [`pdf`](Self::pdf) and [`eval`](Self::eval) of any [`AxisLobe`] at incident
/// directions ω_i.
///
/// - Phong: `cos γ = R·ω_i`, `R = 2 (N·ω_o) N - ω_o`; ω_i is drawn around R, so its
///   density is the lobe's own, `pdf_cos(R·ω_i)`. Draws may point below the surface
///   (`N·ω_i < 0`); what a BRDF does there is the caller's choice.
/// - Blinn: `cos γ = N·H`, `H = normalize(ω_o + ω_i)`; H is drawn around N and
///   `ω_i = 2 (ω_o·H) H - ω_o`, so the density of ω_i is `pdf_cos(N·H) / (4 ω_o·H)`.
///   A drawn H with `ω_o·H <= 0` reflects ω_o to a direction whose own half vector
///   is `-H`; such a draw is returned as `None` (an estimator counts it as 0), so the
///   density of ω_i integrates to the lobe's probability of `ω_o·H > 0`, not to 1, and
///   every returned sample has `value > 0` wherever the lobe is positive at `cos γ`.
///
/// ```
/// use glint_lobe::{AxisLobe, Geometry, Lobe, LobeKind, LobeSampler, Scatter};
///
/// let lobe = LobeSampler::new(&Lobe::<f64>::new(LobeKind::EnergyFit, 60.0, 4).unwrap());
/// let n = [0.0, 0.0, 1.0];
/// let wo = [0.6, 0.0, 0.8];
/// let at = Scatter::new(Geometry::Blinn, n, wo).unwrap();
/// let s = at.sample(&lobe, 0.25, 0.5).unwrap();
/// assert!((s.pdf - at.pdf(&lobe, s.wi)).abs() < 1e-9 * s.pdf);
/// assert!((s.value - at.eval(&lobe, s.wi)).abs() < 1e-9);
/// // The value is the Blinn cosine's lobe, as glint's shading computes it.
/// let c = glint_lobe::blinn_cos(n, s.wi, wo);
/// assert!((s.value - lobe.lobe().eval(c)).abs() < 1e-9);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter<T> {
    geometry: Geometry,
    normal: [T; 3],
    wo: [T; 3],
    /// Around R (Phong) or N (Blinn).
    frame: Frame<T>,
}

impl<T: Real> Scatter<T> {
    /// The lobe at a point with `normal` and outgoing direction `wo` (both normalised
    /// here). `None` when either is zero, NaN or infinite.
    pub fn new(geometry: Geometry, normal: [T; 3], wo: [T; 3]) -> Option<Scatter<T>> {
        let normal = normalize(normal)?;
        let wo = normalize(wo)?;
        let axis = match geometry {
            Geometry::Phong => normalize(reflect_about(wo, normal))?,
            Geometry::Blinn => normal,
        };
        Some(Scatter {
            geometry,
            normal,
            wo,
            frame: Frame::from_z(axis),
        })
    }

    /// The geometry.
    pub fn geometry(&self) -> Geometry {
        self.geometry
    }

    /// The lobe's axis: R for Phong, N for Blinn.
    pub fn axis(&self) -> [T; 3] {
        self.frame.z
    }

    /// The frame around the axis.
    pub fn frame(&self) -> &Frame<T> {
        &self.frame
    }

    /// `cos γ` at the unit incident direction `wi`, clamped to `[-1, 1]`: `R·ω_i`
    /// (Phong, equal to glint's [`phong_cos`](crate::phong_cos)) or `N·H` (Blinn, equal
    /// to [`blinn_cos`](crate::blinn_cos)); `None` for Blinn at `ω_i = -ω_o`, where H
    /// is undefined.
    #[inline]
    pub fn cos(&self, wi: [T; 3]) -> Option<T> {
        let one = T::one();
        match self.geometry {
            Geometry::Phong => Some(dot(self.frame.z, wi).max(-one).min(one)),
            Geometry::Blinn => {
                let h = self.half_vector(wi)?;
                Some(dot(self.normal, h).max(-one).min(one))
            }
        }
    }

    /// `normalize(ω_o + ω_i)`, or `None` where it is undefined.
    #[inline]
    fn half_vector(&self, wi: [T; 3]) -> Option<[T; 3]> {
        let wo = self.wo;
        normalize([wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]])
    }

    /// The lobe's value at the unit incident direction `wi` (0 where `cos γ` is
    /// undefined).
    #[inline]
    pub fn eval<L: AxisLobe<T> + ?Sized>(&self, lobe: &L, wi: [T; 3]) -> T {
        self.cos(wi).map_or(T::zero(), |c| lobe.eval_cos(c))
    }

    /// The density per steradian with which [`sample`](Self::sample) draws the unit
    /// direction `wi`.
    #[inline]
    pub fn pdf<L: AxisLobe<T> + ?Sized>(&self, lobe: &L, wi: [T; 3]) -> T {
        match self.geometry {
            Geometry::Phong => lobe.pdf_cos(dot(self.frame.z, wi)),
            Geometry::Blinn => match self.half_vector(wi) {
                // ω_o·H = (1 + ω_o·ω_i)/|ω_o + ω_i| > 0 for every ω_i != -ω_o.
                Some(h) => lobe.pdf_cos(dot(self.normal, h)) * blinn_jacobian(dot(self.wo, h)),
                None => T::zero(),
            },
        }
    }

    /// Draws an incident direction from two uniform numbers in `[0, 1)`. `None` for a
    /// Blinn draw whose half vector faces away from ω_o (see the type's docs).
    #[inline]
    pub fn sample<L: AxisLobe<T> + ?Sized>(&self, lobe: &L, u1: T, u2: T) -> Option<LobeSample<T>> {
        let local = lobe.sample(u1, u2);
        let c = local[2];
        let value = lobe.eval_cos(c);
        let pdf = lobe.pdf_cos(c);
        let dir = self.frame.to_world(local);
        match self.geometry {
            Geometry::Phong => Some(LobeSample {
                wi: dir,
                value,
                pdf,
                cos: c,
            }),
            Geometry::Blinn => {
                let d = dot(self.wo, dir);
                // Also rejects NaN.
                if d.is_nan() || d <= T::zero() {
                    return None;
                }
                Some(LobeSample {
                    wi: reflect_about(self.wo, dir),
                    value,
                    pdf: pdf * blinn_jacobian(d),
                    cos: c,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_and_right_handed() {
        for z in [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [0.6, 0.0, 0.8],
            [0.0, -0.6, -0.8],
            [1.0, 0.0, 0.0],
            [0.48, 0.6, -0.64],
        ] {
            let f = Frame::<f64>::from_z(z);
            for (a, b) in [(f.x, f.y), (f.y, f.z), (f.x, f.z)] {
                assert!(dot(a, b).abs() < 1e-15, "{z:?}");
            }
            for v in [f.x, f.y, f.z] {
                assert!((dot(v, v) - 1.0).abs() < 1e-15, "{z:?}");
            }
            // x × y = z.
            let c = [
                f.x[1] * f.y[2] - f.x[2] * f.y[1],
                f.x[2] * f.y[0] - f.x[0] * f.y[2],
                f.x[0] * f.y[1] - f.x[1] * f.y[0],
            ];
            assert!((dot(c, z) - 1.0).abs() < 1e-15, "{z:?}");
            let v = [0.3, -0.2, 0.7];
            let back = f.to_local(f.to_world(v));
            assert!((0..3).all(|i| (back[i] - v[i]).abs() < 1e-15));
            assert!((0..3).all(|i| (f.to_world([0.0, 0.0, 1.0])[i] - z[i]).abs() < 1e-15));
        }
    }

    #[test]
    fn degenerate_inputs_give_no_scatter() {
        let n = [0.0f32, 0.0, 1.0];
        assert!(Scatter::new(Geometry::Phong, [0.0; 3], n).is_none());
        assert!(Scatter::new(Geometry::Blinn, n, [f32::NAN, 0.0, 1.0]).is_none());
        let s = Scatter::new(Geometry::Blinn, n, [0.0, 0.6, 0.8]).unwrap();
        assert_eq!(s.cos([0.0, -0.6, -0.8]), None);
    }
}
