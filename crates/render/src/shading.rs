//! Lights and the per-sample lighting model: ambient + diffuse + specular, the
//! specular term a [`glint_lobe::Lobe`] evaluated at the cosine of a
//! [`glint_lobe::Geometry`].

use glint_lobe::{Geometry, Lobe, LobeKind};
use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::error::RenderError;
use crate::math::Vec3;
use crate::tf::Material;

/// A directional light given relative to the camera: `azimuth` degrees towards the
/// image's right and `elevation` degrees towards its top, from the viewing direction.
/// `(0, 0)` is a headlight.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Degrees towards the image's right.
    pub azimuth: f64,
    /// Degrees towards the image's top.
    pub elevation: f64,
    /// Intensity (white light).
    #[serde(default = "unit_intensity")]
    pub intensity: f32,
}

fn unit_intensity() -> f32 {
    1.0
}

impl Light {
    /// The headlight: along the view direction, intensity 1.
    pub const HEADLIGHT: Light = Light {
        azimuth: 0.0,
        elevation: 0.0,
        intensity: 1.0,
    };

    /// Unit world vector from a surface towards the light, for `camera`.
    pub fn direction(&self, camera: &Camera) -> Vec3 {
        let (sa, ca) = (
            self.azimuth.to_radians().sin() as f32,
            self.azimuth.to_radians().cos() as f32,
        );
        let (se, ce) = (
            self.elevation.to_radians().sin() as f32,
            self.elevation.to_radians().cos() as f32,
        );
        ((-camera.forward * ca + camera.right * sa) * ce + camera.up * se).normalize_or_zero()
    }

    /// Checks the angles and intensity are finite and sensible.
    pub fn validate(&self) -> Result<(), RenderError> {
        if !self.azimuth.is_finite()
            || !self.elevation.is_finite()
            || self.azimuth.abs() > 360.0
            || self.elevation.abs() > 90.0
        {
            return Err(RenderError::Parameter(format!(
                "light at azimuth {}, elevation {}: expected |azimuth| <= 360 and |elevation| <= 90 degrees",
                self.azimuth, self.elevation
            )));
        }
        if !self.intensity.is_finite() || !(0.0..=100.0).contains(&self.intensity) {
            return Err(RenderError::Parameter(format!(
                "light intensity {}: expected 0..=100",
                self.intensity
            )));
        }
        Ok(())
    }
}

/// Everything the lighting of one sample needs that does not change along a ray.
#[derive(Clone, Debug)]
pub struct Shader {
    pub(crate) lobe: Lobe<f32>,
    pub(crate) geometry: Geometry,
    pub(crate) material: Material,
    /// The lights, relative to the camera.
    relative: Vec<Light>,
    /// World directions towards each light, and their intensities, for the camera the
    /// shader was last [placed](Shader::placed) for (empty before).
    pub(crate) lights: Vec<(Vec3, f32)>,
    /// Gradient magnitude (value per mm) below which a sample is unshaded; full
    /// shading from twice this value (a linear ramp between).
    pub(crate) gate: f32,
}

/// Per-ray constants of the lighting: the view vector and, per light, `L·V`
/// (Phong) or the half vector (Blinn).
pub(crate) struct RayLighting {
    pub view: Vec3,
    /// Per light: direction, intensity, `L·V`, half vector (the first `count`).
    pub lights: [(Vec3, f32, f32, Vec3); MAX_LIGHTS],
    pub count: usize,
}

/// Most lights a [`Shader`] takes.
pub const MAX_LIGHTS: usize = 8;

impl Shader {
    /// A shader for `lobe` (kind, n, v), `geometry`, `material`, lights given relative
    /// to the camera (placed in the world by each render), and a gradient gate in value
    /// per mm.
    pub fn new(
        kind: LobeKind,
        n: f64,
        v: u32,
        geometry: Geometry,
        material: Material,
        lights: Vec<Light>,
        gate: f32,
    ) -> Result<Shader, RenderError> {
        material.validate()?;
        for light in &lights {
            light.validate()?;
        }
        let lobe = Lobe::<f32>::new(kind, n, v)?;
        if lights.len() > MAX_LIGHTS {
            return Err(RenderError::Parameter(format!(
                "{} lights: at most {MAX_LIGHTS}",
                lights.len()
            )));
        }
        if !gate.is_finite() || gate < 0.0 {
            return Err(RenderError::Parameter(format!(
                "gradient gate {gate}: expected a finite number >= 0"
            )));
        }
        Ok(Shader {
            lobe,
            geometry,
            material,
            relative: lights,
            lights: Vec::new(),
            gate,
        })
    }

    /// This shader with its lights placed in the world for `camera`.
    pub(crate) fn placed(&self, camera: &Camera) -> Shader {
        Shader {
            lights: self
                .relative
                .iter()
                .map(|l| (l.direction(camera), l.intensity))
                .collect(),
            ..self.clone()
        }
    }

    /// The lobe.
    pub fn lobe(&self) -> &Lobe<f32> {
        &self.lobe
    }

    pub(crate) fn for_ray(&self, view: Vec3) -> RayLighting {
        let mut lights = [(Vec3::ZERO, 0.0, 0.0, Vec3::ZERO); MAX_LIGHTS];
        for (slot, &(l, i)) in lights.iter_mut().zip(&self.lights) {
            *slot = (l, i, l.dot(view), (l + view).normalize_or_zero());
        }
        RayLighting {
            view,
            lights,
            count: self.lights.len(),
        }
    }

    /// The cosine the lobe is evaluated at, from unit `n`, unit `l`, unit `v`:
    /// Phong `R·V = 2(N·L)(N·V) - L·V`, Blinn `N·H`. Equal to
    /// [`Geometry::cos`] for unit vectors (tested), with the per-ray parts hoisted.
    #[inline(always)]
    fn cos(&self, n_dot_l: f32, n_dot_v: f32, l_dot_v: f32, n: Vec3, h: Vec3) -> f32 {
        match self.geometry {
            Geometry::Phong => 2.0 * n_dot_l * n_dot_v - l_dot_v,
            Geometry::Blinn => n.dot(h),
        }
    }

    /// Shaded linear colour of a sample with transfer-function colour `base` and world
    /// gradient `grad`.
    #[inline(always)]
    pub(crate) fn shade(&self, base: [f32; 3], grad: Vec3, ray: &RayLighting) -> [f32; 3] {
        let m = &self.material;
        let flat = m.ambient + m.diffuse;
        if !m.shade {
            return base;
        }
        let gm2 = grad.dot(grad);
        let g0 = self.gate;
        if gm2 <= g0 * g0 || !gm2.is_finite() {
            return base.map(|c| c * flat);
        }
        let gm = gm2.sqrt();
        // Normal points from high to low values: out of dense structures.
        let mut n = grad * (-1.0 / gm);
        let mut n_dot_v = n.dot(ray.view);
        if n_dot_v < 0.0 {
            // Two-sided lighting: face the viewer.
            n = -n;
            n_dot_v = -n_dot_v;
        }
        let mut diffuse = 0.0f32;
        let mut specular = 0.0f32;
        for &(l, intensity, l_dot_v, h) in &ray.lights[..ray.count] {
            let n_dot_l = n.dot(l);
            if n_dot_l > 0.0 {
                diffuse += intensity * n_dot_l;
                let c = self.cos(n_dot_l, n_dot_v, l_dot_v, n, h);
                specular += intensity * self.lobe.eval(c);
            }
        }
        let lit = m.ambient + m.diffuse * diffuse;
        let spec = m.specular * specular;
        // Gradient-magnitude gating: blend from flat (no normal) to lit between g0
        // and 2 g0, so near-zero gradients give no random highlights.
        let w = if g0 > 0.0 {
            ((gm - g0) / g0).min(1.0)
        } else {
            1.0
        };
        let mut out = [0.0f32; 3];
        for c in 0..3 {
            let shaded = base[c] * lit + spec;
            let unshaded = base[c] * flat;
            out[c] = unshaded + w * (shaded - unshaded);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hoisted_cosines_match_glint_lobe_geometry() {
        let dirs = [
            Vec3::new(0.3, -0.2, 0.9),
            Vec3::new(-0.7, 0.1, 0.4),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.5, 0.5, -0.2),
        ];
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            let shader = Shader::new(
                LobeKind::Exact,
                10.0,
                4,
                geometry,
                Material::default(),
                vec![],
                0.0,
            )
            .unwrap();
            for n in dirs {
                for l in dirs {
                    for v in dirs {
                        let (n, l, v) = (
                            n.normalize_or_zero(),
                            l.normalize_or_zero(),
                            v.normalize_or_zero(),
                        );
                        let h = (l + v).normalize_or_zero();
                        let ours = shader.cos(n.dot(l), n.dot(v), l.dot(v), n, h);
                        let theirs = geometry.cos(n.to_array(), l.to_array(), v.to_array());
                        if h != Vec3::ZERO {
                            assert!((ours - theirs).abs() < 1e-5, "{geometry}: {ours} {theirs}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn headlight_points_back_along_the_view() {
        let cam =
            Camera::frame(&crate::camera::CameraSpec::default(), Vec3::ZERO, 1.0, 4, 4).unwrap();
        let l = Light::HEADLIGHT.direction(&cam);
        assert!((l + cam.forward).length() < 1e-6);
        let side = Light {
            azimuth: 90.0,
            elevation: 0.0,
            intensity: 1.0,
        };
        assert!((side.direction(&cam) - cam.right).length() < 1e-6);
    }

    #[test]
    fn flat_regions_get_no_highlight() {
        let shader = Shader::new(
            LobeKind::EnergyFit,
            40.0,
            4,
            Geometry::Phong,
            Material::default(),
            vec![Light::HEADLIGHT],
            0.5,
        )
        .unwrap();
        // A camera looking down -z: the headlight shines along +z.
        let cam = Camera::frame(
            &crate::camera::CameraSpec {
                view: crate::camera::View::Superior,
                ..Default::default()
            },
            Vec3::ZERO,
            1.0,
            4,
            4,
        )
        .unwrap();
        let shader = shader.placed(&cam);
        assert!((shader.lights[0].0 - Vec3::new(0.0, 0.0, 1.0)).length() < 1e-6);
        let ray = shader.for_ray(Vec3::new(0.0, 0.0, 1.0));
        let m = Material::default();
        // Below the gate: ambient + diffuse, no specular.
        let c = shader.shade([1.0, 1.0, 1.0], Vec3::new(0.0, 0.0, -0.1), &ray);
        assert!((c[0] - (m.ambient + m.diffuse)).abs() < 1e-6);
        // Well above: full mirror highlight (normal towards the light and viewer).
        let c = shader.shade([1.0, 1.0, 1.0], Vec3::new(0.0, 0.0, -10.0), &ray);
        assert!((c[0] - (m.ambient + m.diffuse + m.specular)).abs() < 1e-6);
    }
}
