//! Area lights: a sphere or a one-sided rectangle of constant emitted radiance, in the
//! volume's world frame (mm), sampled by solid angle for the path tracer's next-event
//! estimation and intersected by the paths the scattering model sends out, the two
//! combined by multiple importance sampling (`path`); reduced to a directional light of
//! the same irradiance at a point for the deterministic models (`shadows`).
//!
//! - Sphere: the cone of directions it subtends from a point outside it, sampled
//!   uniformly (the exact solid angle, `pdf = 1/(2π(1 - cos θmax))`), as pbrt-v4's
//!   `Sphere::Sample(ShapeSampleContext)` (src/pbrt/shapes.h; Pharr, Jakob and
//!   Humphreys, "Physically Based Rendering", 4th ed., 6.2.4), with its small-angle form
//!   of `sin² θ` below 1.5°. A point inside the sphere does not see it (pdf 0, no hit).
//! - Rectangle: emits on the side of `edge_u × edge_v`; sampled uniformly over the
//!   solid angle it subtends (`pdf = 1/Ω`) by the spherical-rectangle parametrization
//!   of Ureña, Fajardo and King ("An area-preserving parametrization for spherical
//!   rectangles", Computer Graphics Forum 32(4), EGSR 2013), in f64, as pbrt-v4's
//!   `SampleSphericalRectangle` (src/pbrt/util/sampling.cpp) follows it; below
//!   `Ω = 1e-3` sr (pbrt-v4's threshold, where the angles' sum loses its digits) by
//!   area, converted to solid angle (`pdf = d²/(A·cos θ_light)`), nearly uniform in
//!   solid angle there.

use std::f32::consts::PI;

use crate::color::luminance_f32;
use crate::error::RenderError;
use crate::math::Vec3;

/// Largest radiance an area light emits (per channel).
pub const MAX_AREA_RADIANCE: f32 = 1.0e6;

/// Below this `sin² θmax` (θmax about 1.5°) a sphere's cone is sampled by the
/// small-angle form (pbrt-v4's threshold).
const SMALL_CONE: f32 = 0.000_685_23;

/// The shape of an [`AreaLight`], in world mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaShape {
    /// A sphere, emitting everywhere on its surface.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (more than 0).
        radius: f32,
    },
    /// A rectangle `center + s·edge_u + t·edge_v`, `s, t` in `[-1/2, 1/2]`, emitting on
    /// the side its normal `edge_u × edge_v` points to.
    Rect {
        /// Centre.
        center: Vec3,
        /// One edge (its full length).
        edge_u: Vec3,
        /// The other edge (its full length; at right angles to `edge_u`).
        edge_v: Vec3,
    },
}

/// A light of constant radiance over a sphere or a rectangle ([`AreaShape`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    shape: AreaShape,
    /// Linear RGB radiance leaving its surface.
    radiance: [f32; 3],
}

/// A direction towards an [`AreaLight`] drawn by [`AreaLight::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaSample {
    /// Unit world direction from the point towards the light.
    pub wi: Vec3,
    /// Distance (mm) from the point to the light's surface along `wi`.
    pub dist: f32,
    /// The radiance arriving along `wi`.
    pub radiance: [f32; 3],
    /// The density of `wi` per steradian.
    pub pdf: f32,
}

fn check_radiance(radiance: [f32; 3]) -> Result<(), RenderError> {
    if radiance
        .iter()
        .any(|c| !c.is_finite() || !(0.0..=MAX_AREA_RADIANCE).contains(c))
    {
        return Err(RenderError::Parameter(format!(
            "area light radiance {radiance:?}: expected 0..={MAX_AREA_RADIANCE} per channel"
        )));
    }
    Ok(())
}

fn finite(v: Vec3) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

impl AreaLight {
    /// A sphere light of `radius` mm (more than 0) about `center`, emitting `radiance`.
    pub fn sphere(center: Vec3, radius: f32, radiance: [f32; 3]) -> Result<AreaLight, RenderError> {
        if !finite(center) || !radius.is_finite() || radius <= 0.0 {
            return Err(RenderError::Parameter(format!(
                "sphere light of radius {radius} at {:?}: expected a finite centre and a radius > 0 mm",
                center.to_array()
            )));
        }
        check_radiance(radiance)?;
        Ok(AreaLight {
            shape: AreaShape::Sphere { center, radius },
            radiance,
        })
    }

    /// A rectangle light about `center` of full edges `edge_u` and `edge_v` (each
    /// longer than 0, at right angles within 1e-3 of their lengths' product), emitting
    /// `radiance` on the side of `edge_u × edge_v`.
    pub fn rect(
        center: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        radiance: [f32; 3],
    ) -> Result<AreaLight, RenderError> {
        let (lu, lv) = (edge_u.length(), edge_v.length());
        let ok = finite(center)
            && lu.is_finite()
            && lv.is_finite()
            && lu > 0.0
            && lv > 0.0
            && edge_u.dot(edge_v).abs() <= 1e-3 * lu * lv;
        if !ok {
            return Err(RenderError::Parameter(format!(
                "rectangle light of edges {:?} and {:?}: expected two perpendicular edges longer than 0 mm",
                edge_u.to_array(),
                edge_v.to_array()
            )));
        }
        check_radiance(radiance)?;
        Ok(AreaLight {
            shape: AreaShape::Rect {
                center,
                edge_u,
                edge_v,
            },
            radiance,
        })
    }

    /// The shape.
    pub fn shape(&self) -> AreaShape {
        self.shape
    }

    /// The emitted radiance.
    pub fn radiance(&self) -> [f32; 3] {
        self.radiance
    }

    /// The centre.
    pub fn center(&self) -> Vec3 {
        match self.shape {
            AreaShape::Sphere { center, .. } | AreaShape::Rect { center, .. } => center,
        }
    }

    /// Draws a direction from `p` towards the light from two uniform numbers in
    /// `[0, 1)`, uniformly over the solid angle it subtends (sphere) or by area
    /// (rectangle). `None` where `p` does not see the light (inside the sphere, behind
    /// or in the plane of the rectangle).
    pub fn sample(&self, p: Vec3, u: [f32; 2]) -> Option<AreaSample> {
        match self.shape {
            AreaShape::Sphere { center, radius } => {
                let (axis, dc, sin2_max, one_minus_cos_max) = cone(p, center, radius)?;
                let cos_max = 1.0 - one_minus_cos_max;
                // cos θ uniform in [cos θmax, 1]; sin² θ by the small-angle form for
                // a tiny cone (where 1 - cos² loses its digits).
                let (cos, sin2) = if sin2_max < SMALL_CONE {
                    let sin2 = sin2_max * u[0];
                    ((1.0 - sin2).sqrt(), sin2)
                } else {
                    let cos = (1.0 - u[0]) + u[0] * cos_max;
                    (cos, (1.0 - cos * cos).max(0.0))
                };
                let sin = sin2.sqrt();
                let (sp, cp) = (2.0 * PI * u[1]).sin_cos();
                let (t1, t2) = basis(axis);
                let wi = (t1 * (sin * cp) + t2 * (sin * sp) + axis * cos).normalize_or_zero();
                // The near intersection along wi: dc·cos θ - sqrt(r² - dc²·sin² θ).
                let disc = (radius * radius - dc * dc * sin2).max(0.0);
                let dist = (dc * cos - disc.sqrt()).max(0.0);
                Some(AreaSample {
                    wi,
                    dist,
                    radiance: self.radiance,
                    pdf: 1.0 / (2.0 * PI * one_minus_cos_max),
                })
            }
            AreaShape::Rect {
                center,
                edge_u,
                edge_v,
            } => {
                let sph = SphericalRect::new(p, center, edge_u, edge_v)?;
                let q = if sph.omega >= SMALL_RECT {
                    sph.sample(u)
                } else {
                    center + edge_u * (u[0] - 0.5) + edge_v * (u[1] - 0.5)
                };
                let to = q - p;
                let dist = to.length();
                if dist.is_nan() || dist <= 0.0 {
                    return None;
                }
                let wi = to * (1.0 / dist);
                let pdf = if sph.omega >= SMALL_RECT {
                    (1.0 / sph.omega) as f32
                } else {
                    rect_pdf(edge_u, edge_v, wi, dist)?
                };
                Some(AreaSample {
                    wi,
                    dist,
                    radiance: self.radiance,
                    pdf,
                })
            }
        }
    }

    /// The density per steradian with which [`AreaLight::sample`] draws the unit
    /// direction `wi` from `p` (0 where the ray from `p` along `wi` does not meet the
    /// light's emitting side).
    pub fn pdf(&self, p: Vec3, wi: Vec3) -> f32 {
        match self.shape {
            AreaShape::Sphere { center, radius } => match cone(p, center, radius) {
                Some((_, _, _, one_minus_cos_max)) if self.intersect(p, wi).is_some() => {
                    1.0 / (2.0 * PI * one_minus_cos_max)
                }
                _ => 0.0,
            },
            AreaShape::Rect {
                center,
                edge_u,
                edge_v,
            } => match (
                self.intersect(p, wi),
                SphericalRect::new(p, center, edge_u, edge_v),
            ) {
                (Some(_), Some(sph)) if sph.omega >= SMALL_RECT => (1.0 / sph.omega) as f32,
                (Some(dist), _) => rect_pdf(edge_u, edge_v, wi, dist).unwrap_or(0.0),
                _ => 0.0,
            },
        }
    }

    /// Where the ray from `o` along unit `d` first meets the light's emitting surface
    /// (its distance in mm), if it does: the near side of a sphere from outside it
    /// (none from inside), the emitting side of a rectangle.
    pub fn intersect(&self, o: Vec3, d: Vec3) -> Option<f32> {
        match self.shape {
            AreaShape::Sphere { center, radius } => {
                let oc = o - center;
                let c = oc.dot(oc) - radius * radius;
                if c <= 0.0 {
                    return None;
                }
                let b = oc.dot(d);
                // Distance of the centre from the ray's line, squared, computed without
                // the cancellation of b² - c (Hearn and Baker; pbrt-v4 6.8.3).
                let perp = oc - d * b;
                let disc = radius * radius - perp.dot(perp);
                if b >= 0.0 || disc < 0.0 {
                    return None;
                }
                let t = -b - disc.sqrt();
                (t > 0.0).then_some(t)
            }
            AreaShape::Rect {
                center,
                edge_u,
                edge_v,
            } => {
                let n = edge_u.cross(edge_v);
                let denom = d.dot(n);
                // Light leaves the front (n) side, so a ray meets it going against n.
                if denom.is_nan() || denom >= 0.0 {
                    return None;
                }
                let t = (center - o).dot(n) / denom;
                if !(t > 0.0 && t.is_finite()) {
                    return None;
                }
                let q = o + d * t - center;
                let s = q.dot(edge_u) / edge_u.dot(edge_u);
                let r = q.dot(edge_v) / edge_v.dot(edge_v);
                (s.abs() <= 0.5 && r.abs() <= 0.5).then_some(t)
            }
        }
    }

    /// The direction from `p` towards the light's centre and the irradiance the light
    /// gives at `p` on a plane facing that direction, for the deterministic models
    /// that reduce it to a directional light: `π·L·sin² θmax` for a sphere (exact:
    /// Nusselt's analog of a sphere's cap), `L·A·cos θ_light / d²` for a rectangle (a
    /// point source of its area: its error grows as the rectangle's size over its
    /// distance, see docs/lighting.md). The radiance's luminance; `None` where `p` does
    /// not see it.
    pub fn irradiance(&self, p: Vec3) -> Option<(Vec3, f32)> {
        let l = luminance_f32(self.radiance);
        match self.shape {
            AreaShape::Sphere { center, radius } => {
                let (axis, _, sin2_max, _) = cone(p, center, radius)?;
                Some((axis, PI * l * sin2_max))
            }
            AreaShape::Rect {
                center,
                edge_u,
                edge_v,
            } => {
                let to = center - p;
                let d2 = to.dot(to);
                let n = edge_u.cross(edge_v);
                let cos_area = -to.dot(n) / d2.sqrt();
                (cos_area > 0.0 && d2 > 0.0).then(|| (to.normalize_or_zero(), l * cos_area / d2))
            }
        }
    }
}

/// A sphere's cone seen from `p`: the unit axis towards the centre, the distance to
/// it, `sin² θmax` and `1 - cos θmax` (computed without cancellation); `None` from
/// inside the sphere.
fn cone(p: Vec3, center: Vec3, radius: f32) -> Option<(Vec3, f32, f32, f32)> {
    let to = center - p;
    let dc2 = to.dot(to);
    let r2 = radius * radius;
    if dc2.is_nan() || dc2 <= r2 {
        return None;
    }
    let dc = dc2.sqrt();
    let sin2_max = r2 / dc2;
    let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
    Some((to * (1.0 / dc), dc, sin2_max, sin2_max / (1.0 + cos_max)))
}

/// Solid angle (sr) below which a rectangle is sampled by area.
const SMALL_RECT: f64 = 1e-3;

/// A rectangle seen from a point in its own frame (x along `edge_u`, y along `edge_v`,
/// z its normal; the point at the origin, the rectangle in the plane `z = z0 < 0`
/// over `[x0, x1] × [y0, y1]`), with what Ureña et al.'s sampling needs: the normals'
/// z of two edges, the angles `g2 + g3` and the solid angle `Ω`. f64 throughout.
struct SphericalRect {
    p: [f64; 3],
    axes: [[f64; 3]; 3],
    x: [f64; 2],
    y: [f64; 2],
    z0: f64,
    b0: f64,
    b1: f64,
    g23: f64,
    omega: f64,
}

type D3 = [f64; 3];

fn d3(v: Vec3) -> D3 {
    [v.x, v.y, v.z].map(f64::from)
}

fn dot3(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross3(a: D3, b: D3) -> D3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit3(a: D3) -> D3 {
    let l = dot3(a, a).sqrt();
    a.map(|c| c / l)
}

/// The angle between unit vectors, accurate near 0 and π (pbrt-v4's `AngleBetween`).
fn angle3(a: D3, b: D3) -> f64 {
    let (s, d) = (
        [0, 1, 2].map(|i| a[i] + b[i]),
        [0, 1, 2].map(|i| a[i] - b[i]),
    );
    if dot3(a, b) < 0.0 {
        std::f64::consts::PI - 2.0 * (dot3(s, s).sqrt() / 2.0).min(1.0).asin()
    } else {
        2.0 * (dot3(d, d).sqrt() / 2.0).min(1.0).asin()
    }
}

impl SphericalRect {
    /// The rectangle `center ± edge_u/2 ± edge_v/2` seen from `p`; `None` from behind
    /// it or in its plane.
    fn new(p: Vec3, center: Vec3, edge_u: Vec3, edge_v: Vec3) -> Option<SphericalRect> {
        let (eu, ev) = (d3(edge_u), d3(edge_v));
        let (lu, lv) = (dot3(eu, eu).sqrt(), dot3(ev, ev).sqrt());
        let (ax, ay) = (eu.map(|c| c / lu), ev.map(|c| c / lv));
        let az = unit3(cross3(ax, ay));
        let pd = d3(p);
        let corner = [0, 1, 2].map(|i| d3(center)[i] - eu[i] / 2.0 - ev[i] / 2.0 - pd[i]);
        let (x0, y0, z0) = (dot3(corner, ax), dot3(corner, ay), dot3(corner, az));
        // The point must be on the emitting (normal) side: the plane below it.
        if z0.is_nan() || z0 >= 0.0 {
            return None;
        }
        let (x1, y1) = (x0 + lu, y0 + lv);
        let v = |x: f64, y: f64| [x, y, z0];
        let n0 = unit3(cross3(v(x0, y0), v(x1, y0)));
        let n1 = unit3(cross3(v(x1, y0), v(x1, y1)));
        let n2 = unit3(cross3(v(x1, y1), v(x0, y1)));
        let n3 = unit3(cross3(v(x0, y1), v(x0, y0)));
        let neg = |a: D3| a.map(|c| -c);
        let g = [
            angle3(neg(n0), n1),
            angle3(neg(n1), n2),
            angle3(neg(n2), n3),
            angle3(neg(n3), n0),
        ];
        let omega = g.iter().sum::<f64>() - 2.0 * std::f64::consts::PI;
        (omega.is_finite() && omega > 0.0).then_some(SphericalRect {
            p: pd,
            axes: [ax, ay, az],
            x: [x0, x1],
            y: [y0, y1],
            z0,
            b0: n0[2],
            b1: n2[2],
            g23: g[2] + g[3],
            omega,
        })
    }

    /// The point of the rectangle (world) of the direction at `u` of the uniform
    /// distribution over its solid angle (Ureña et al. 2013, algorithm 1).
    fn sample(&self, u: [f32; 2]) -> Vec3 {
        let (u0, u1) = (f64::from(u[0]), f64::from(u[1]));
        let au = u0 * self.omega - self.g23;
        let fu = (au.cos() * self.b0 - self.b1) / au.sin();
        let one = 1.0 - f64::EPSILON;
        let cu = (1.0f64.copysign(fu) / (fu * fu + self.b0 * self.b0).sqrt()).clamp(-one, one);
        let z0 = self.z0;
        let xu = (-(cu * z0) / (1.0 - cu * cu).max(0.0).sqrt()).clamp(self.x[0], self.x[1]);
        let dd = (xu * xu + z0 * z0).sqrt();
        let [y0, y1] = self.y;
        let h0 = y0 / (dd * dd + y0 * y0).sqrt();
        let h1 = y1 / (dd * dd + y1 * y1).sqrt();
        let hv = h0 + u1 * (h1 - h0);
        let yv = if hv * hv < 1.0 - 1e-6 {
            hv * dd / (1.0 - hv * hv).sqrt()
        } else {
            y1
        };
        let [ax, ay, az] = self.axes;
        let q = [0, 1, 2].map(|i| self.p[i] + ax[i] * xu + ay[i] * yv + az[i] * z0);
        Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32)
    }
}

/// The solid-angle density of the rectangle's area sampling at unit `wi` reaching it
/// at `dist`: `d²/(A·cos θ_light)`; `None` from behind it or edge on.
fn rect_pdf(edge_u: Vec3, edge_v: Vec3, wi: Vec3, dist: f32) -> Option<f32> {
    let n = edge_u.cross(edge_v);
    let area = n.length();
    let cos = -wi.dot(n) / area;
    let pdf = dist * dist / (area * cos);
    (cos > 0.0 && pdf.is_finite()).then_some(pdf)
}

/// Two unit vectors completing unit `n` to an orthonormal basis (Duff et al., "Building
/// an orthonormal basis, revisited", JCGT 6(1), 2017).
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
#[path = "area_tests.rs"]
mod tests;
