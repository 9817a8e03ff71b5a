//! The one lighting model of glint's renderers: a sample of colour `c` with unit
//! normal `N` (facing the viewer: two-sided) takes, over camera-relative lights `L` of
//! intensity `I`,
//!
//! `c · (ambient + diffuse · Σ I·max(N·L, 0)) + specular · Σ_{N·L > 0} I·lobe(cos γ)`
//!
//! where `cos γ` is Phong's `R·V` or Blinn's `N·H` ([`glint_lobe::Geometry`]) and the
//! lobe any [`glint_lobe::Specular`] (a closed-form lobe or a table over the quantised
//! cosine, e.g. the hardware unit's). Volume samples take their normal from the
//! gradient and blend towards the flat colour `c · (ambient + diffuse)` where the
//! gradient is weak (the gate); surface samples have a normal and no gate.
//!
//! Every lighting model reads one scattering model, built per shaded sample
//! ([`Scattering`]: the surface part and the medium, with `f`, `sample` and `pdf` on
//! each component, [`Bsdf`]): `local` is `ambient + Σ I·f`, `shadows` the same with
//! each light's transmittance and the ambient occlusion, `path` samples it.
//!
//! The model has a scalar form ([`Shader::shade`] for a gradient, [`Shader::shade_normal`]
//! for a unit normal, [`Shader::shade_shadowed`]; each a [`Scattering`]) and a batch
//! form over columns of samples ([`ShadeBatch`], on AVX2 where the CPU has it), which
//! gives the scalar form's results bit for bit (the same operations in the same order,
//! no FMA contraction; tested). The ray caster, the rasterizer and the path tracer use
//! these and nothing else to light a sample.

use glint_lobe::{Geometry, Lobe, LobeKind, Specular};
use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::error::RenderError;
use crate::math::Vec3;

mod area;
mod area_spec;
#[cfg(target_arch = "x86_64")]
mod avx2;
mod batch;
mod dispatch;
mod envmap;
#[cfg(test)]
mod fixtures;
mod material;
mod median_cut;
mod scatter;
mod scratch;
mod shadowed;
mod transport;

pub use area::{AreaLight, AreaSample, AreaShape, MAX_AREA_RADIANCE};
pub use area_spec::{AreaLightSpec, AreaShapeSpec, LightFrame, MAX_AREA_EXTENT, MAX_AREA_LIGHTS};
pub use batch::ShadeBatch;
pub use envmap::{
    check_env_size, power_heuristic, EnvMap, EnvSample, MAX_ENV_HEIGHT, MAX_ENV_INTENSITY,
    MAX_ENV_WIDTH,
};
pub use material::{Material, MaterialOverrides};
pub use median_cut::MAX_MEDIAN_CUT_SPLITS;
pub use scatter::{cosine_hemisphere, sample_phase, Bsdf, BsdfSample, Scattering};
pub use transport::{phase_hg, SurfacePart, MAX_ANISOTROPY, MEDIUM_IRRADIANCE};

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
    specular: Specular,
    geometry: Geometry,
    material: Material,
    /// The lights, relative to the camera.
    relative: Vec<Light>,
    /// World directions towards each light, and their intensities, for the camera the
    /// shader was last [placed](Shader::placed) for (empty before): the directional
    /// lights, then each area light as the directional light of its irradiance at the
    /// volume's centre (what `local` and `shadows` take of it).
    lights: Vec<(Vec3, f32)>,
    /// The scene's area lights and the volume's centre (world mm) they are placed
    /// about.
    area: Vec<AreaLightSpec>,
    anchor: Vec3,
    /// The area lights in the world for the camera the shader was last placed for.
    placed_area: Vec<AreaLight>,
    /// An environment map's directional lights ([`EnvMap::median_cut`]: world
    /// directions and energies), fixed to the world (`shadows`).
    environment: Vec<(Vec3, f32)>,
    /// Gradient magnitude (value per mm) below which a sample is unshaded; full
    /// shading from twice this value (a linear ramp between).
    gate: f32,
    /// Henyey-Greenstein anisotropy of the medium's phase function (light transport
    /// only: [`Shader::shade_shadowed`]).
    anisotropy: f32,
    /// Scale of the surface part's weight in the hybrid, 0..=1 (light transport only:
    /// 1 keeps the gate's weight, 0 makes every sample a pure medium).
    surface_weight: f32,
    /// The specular lobe's sampler for path tracing ([`Bsdf::sample`]), built on first
    /// use and shared by the shader's clones.
    sampler: scatter::SamplerCell,
}

/// Per-ray constants of the lighting: the view vector and, per light, `L·V`
/// (Phong) or the half vector (Blinn).
pub struct RayLighting {
    /// Unit vector towards the eye.
    pub view: Vec3,
    /// Per light: direction, intensity, `L·V`, half vector (the first `count`).
    pub lights: [(Vec3, f32, f32, Vec3); MAX_LIGHTS],
    /// How many lights.
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
        let lobe = Lobe::<f32>::new(kind, n, v)?;
        Shader::with_specular(lobe.into(), geometry, material, lights, gate)
    }

    /// A shader whose specular term is `specular`: a closed-form lobe or a table over
    /// the quantised cosine (e.g. `glint_hw::Unit::cos_table`); otherwise as
    /// [`Shader::new`].
    pub fn with_specular(
        specular: Specular,
        geometry: Geometry,
        material: Material,
        lights: Vec<Light>,
        gate: f32,
    ) -> Result<Shader, RenderError> {
        material.validate()?;
        for light in &lights {
            light.validate()?;
        }
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
            specular,
            geometry,
            material,
            relative: lights,
            lights: Vec::new(),
            area: Vec::new(),
            anchor: Vec3::ZERO,
            placed_area: Vec::new(),
            environment: Vec::new(),
            gate,
            anisotropy: 0.0,
            surface_weight: 1.0,
            sampler: Default::default(),
        })
    }

    /// This shader with its lights placed in the world for `camera`: the directional
    /// lights, and the area lights (each also as the directional light of its
    /// irradiance at the volume's centre, [`AreaLight::irradiance`], for `local` and
    /// `shadows`).
    pub fn placed(&self, camera: &Camera) -> Shader {
        let placed_area: Vec<AreaLight> = (self.area.iter())
            .filter_map(|a| a.place(camera, self.anchor).ok())
            .collect();
        let lights = (self.relative.iter())
            .map(|l| (l.direction(camera), l.intensity))
            .chain(placed_area.iter().filter_map(|a| {
                let (dir, e) = a.irradiance(self.anchor)?;
                Some((dir, e / std::f32::consts::PI))
            }))
            .chain((self.environment.iter()).map(|&(d, e)| (d, e / std::f32::consts::PI)))
            .collect();
        Shader {
            lights,
            placed_area,
            ..self.clone()
        }
    }

    /// This shader with the scene's area lights, placed about `center` (the volume's
    /// centre, world mm). Errors for a light [`AreaLightSpec::validate`] refuses, a
    /// rectangle at the centre, more than [`MAX_AREA_LIGHTS`], or more than
    /// [`MAX_LIGHTS`] lights in all.
    pub fn with_area_lights(
        mut self,
        area: Vec<AreaLightSpec>,
        center: Vec3,
    ) -> Result<Shader, RenderError> {
        if area.len() > MAX_AREA_LIGHTS || area.len() + self.relative.len() > MAX_LIGHTS {
            return Err(RenderError::Parameter(format!(
                "{} area lights and {} lights: at most {MAX_AREA_LIGHTS} area lights and {MAX_LIGHTS} in all",
                area.len(),
                self.relative.len()
            )));
        }
        let probe = Camera::frame(&Default::default(), center, 1.0, 1, 1)?;
        for a in &area {
            a.place(&probe, center)?;
        }
        self.area = area;
        self.anchor = center;
        Ok(self)
    }

    /// This shader with an environment map's directional lights (world directions
    /// and energies `Φ`, [`EnvMap::median_cut`]), each placed as the directional
    /// light of intensity `Φ / π` (irradiance `Φ` facing it) after the area lights'
    /// stand-ins, whatever the camera (`shadows`). Errors for more than
    /// [`MAX_LIGHTS`] lights in all, or a light that is not a unit direction with a
    /// finite energy >= 0.
    pub fn with_environment_lights(
        mut self,
        lights: Vec<(Vec3, f32)>,
    ) -> Result<Shader, RenderError> {
        let n = self.relative.len() + self.area.len() + lights.len();
        if n > MAX_LIGHTS {
            return Err(RenderError::Parameter(format!(
                "{n} lights with the environment map's {}: at most {MAX_LIGHTS} in all",
                lights.len()
            )));
        }
        if let Some(l) = (lights.iter())
            .find(|(d, e)| !e.is_finite() || *e < 0.0 || (d.length() - 1.0).abs() > 1e-3)
        {
            return Err(RenderError::Parameter(format!(
                "environment light {l:?}: expected a unit direction and a finite energy >= 0"
            )));
        }
        self.environment = lights;
        Ok(self)
    }

    /// How many lights the shader places besides the environment map's: the
    /// directional and the area lights.
    pub fn lights_without_environment(&self) -> usize {
        self.relative.len() + self.area.len()
    }

    /// The area lights in the world, for the camera the shader was
    /// [placed](Shader::placed) for (empty before).
    pub fn area_lights(&self) -> &[AreaLight] {
        &self.placed_area
    }

    /// The directional lights alone among [`Shader::world_lights`] (not the area
    /// lights' directional stand-ins): what `path` lights by next-event estimation
    /// besides the area lights themselves.
    pub fn directional_lights(&self) -> &[(Vec3, f32)] {
        &self.lights[..self.relative.len().min(self.lights.len())]
    }

    /// The specular term.
    pub fn specular(&self) -> &Specular {
        &self.specular
    }

    /// The closed-form lobe, `None` for a table.
    pub fn lobe(&self) -> Option<&Lobe<f32>> {
        self.specular.lobe()
    }

    /// Replaces the specular term (e.g. by a hardware unit's table for the same `n`),
    /// keeping the geometry, material, lights and gate.
    pub fn set_specular(&mut self, specular: Specular) {
        self.specular = specular;
        self.sampler = Default::default();
    }

    /// The material.
    pub fn material(&self) -> &Material {
        &self.material
    }

    /// The gradient gate (value per mm): gradients weaker than it get no directional
    /// shading, and full shading from twice it.
    pub fn gate(&self) -> f32 {
        self.gate
    }

    /// The lighting geometry (Phong or Blinn).
    pub fn geometry(&self) -> Geometry {
        self.geometry
    }

    /// The world directions towards the lights and their intensities, for the camera
    /// the shader was [placed](Shader::placed) for (empty before).
    pub fn world_lights(&self) -> &[(Vec3, f32)] {
        &self.lights
    }

    /// The per-ray terms of the lighting for the unit view vector `view` (towards the
    /// eye): `L·V` and the half vector of each placed light.
    pub fn for_ray(&self, view: Vec3) -> RayLighting {
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

    /// Lit linear colour of a volume sample with transfer-function colour `base` and
    /// world gradient `grad` (the normal points down the gradient: out of dense
    /// structures), under the gradient gate: [`Scattering::local`].
    #[inline(always)]
    pub fn shade(&self, base: [f32; 3], grad: Vec3, ray: &RayLighting) -> [f32; 3] {
        self.scattering(base, grad).local(ray)
    }

    /// Lit linear colour of a surface point of colour `base`, unit `normal` and unit
    /// `view` (towards the eye), with no gate. Two-sided: a normal facing away from the
    /// viewer is flipped, so open surfaces and inner walls are lit from the side that
    /// is seen.
    #[inline(always)]
    pub fn shade_normal(&self, base: [f32; 3], normal: Vec3, view: Vec3) -> [f32; 3] {
        if !self.material.shade {
            return base;
        }
        self.scattering_normal(base, normal)
            .local(&self.for_ray(view))
    }

    /// The gate's blend weight for gradient magnitude `gm` (above the gate): from 0 at
    /// the gate to 1 at twice it, so near-zero gradients give no random highlights;
    /// times the surface weight ([`Shader::with_surface_weight`]; 1, exact, by
    /// default).
    #[inline(always)]
    fn gate_weight(&self, gm: f32) -> f32 {
        let g0 = self.gate;
        let w = if g0 > 0.0 {
            ((gm - g0) / g0).min(1.0)
        } else {
            1.0
        };
        w * self.surface_weight
    }
}

/// `ambient + diffuse`: the factor of a sample without a usable normal.
#[inline(always)]
fn flat(m: &Material) -> f32 {
    m.ambient + m.diffuse
}

/// The unit normal `n` turned to face the viewer, and `N·V` (two-sided lighting).
#[inline(always)]
fn facing(n: Vec3, view: Vec3) -> (Vec3, f32) {
    let n_dot_v = n.dot(view);
    if n_dot_v < 0.0 {
        (-n, -n_dot_v)
    } else {
        (n, n_dot_v)
    }
}

/// A surface sample's colour from its sums: `c · lit + spec`.
#[inline(always)]
fn ungated(m: &Material, base: [f32; 3], diffuse: f32, specular: f32) -> [f32; 3] {
    let lit = m.ambient + m.diffuse * diffuse;
    let spec = m.specular * specular;
    base.map(|c| c * lit + spec)
}

/// A volume sample's colour from its sums: the lit colour blended with the flat one by
/// the gate's weight `w`.
#[inline(always)]
fn gated(m: &Material, base: [f32; 3], diffuse: f32, specular: f32, w: f32) -> [f32; 3] {
    let lit = m.ambient + m.diffuse * diffuse;
    let spec = m.specular * specular;
    let mut out = [0.0f32; 3];
    for c in 0..3 {
        let shaded = base[c] * lit + spec;
        let unshaded = base[c] * flat(m);
        out[c] = unshaded + w * (shaded - unshaded);
    }
    out
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
    fn table_specular_is_the_units_output_per_sample() {
        // Normal along the view (0, 0, 1) and a light l with l·view = l.z: Phong's
        // cosine 2(N·L)(N·V) - L·V is exactly l.z in f32, so each sample's specular
        // is material.specular times the unit's output for cos_code(l.z), which
        // `Unit::eval` gives independently of the table.
        use glint_hw::{Config, Input, Unit};
        for config in [
            Config::default(),
            Config {
                out_bits: 12,
                ..Config::default()
            },
        ] {
            let unit = Unit::new(config).unwrap();
            let n = 60;
            let m = Material::default();
            let full = unit.full_scale();
            let one = unit.cos_one() as f32;
            let table = unit.cos_table(n).unwrap();
            let mut distinct = std::collections::BTreeSet::new();
            // Every code in (0.75, 1] and the cosines halfway between codes.
            for k in (1..=(one as i32) / 2).rev() {
                let c = (2.0 * one - k as f32) / (2.0 * one);
                for c in [c, c.next_up(), c.next_down()] {
                    let light = Vec3::new((1.0 - c * c).sqrt(), 0.0, c);
                    let shader = Shader::with_specular(
                        Specular::from(table.clone()),
                        Geometry::Phong,
                        m,
                        vec![],
                        0.0,
                    )
                    .unwrap();
                    // The light in world space, as `placed` would put it.
                    let shader = Shader {
                        lights: vec![(light, 1.0)],
                        ..shader
                    };
                    let ray = shader.for_ray(Vec3::new(0.0, 0.0, 1.0));
                    // Black base colour: the shaded colour is the specular term alone.
                    let got = shader.shade([0.0; 3], Vec3::new(0.0, 0.0, -2.0), &ray);
                    let code = unit.cos_code(f64::from(c)).unwrap();
                    let out = unit
                        .eval(&Input {
                            cos: code,
                            n,
                            ks: [full; 3],
                        })
                        .unwrap();
                    let value = (out.rgb[0] as f64 / full as f64) as f32;
                    assert_eq!(got, [m.specular * value; 3], "c = {c}, code {code}");
                    distinct.insert(out.rgb[0]);
                }
            }
            // Not vacuous: the unit's output takes many values over this range.
            assert!(distinct.len() > 50, "{} output codes", distinct.len());
        }
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

    #[test]
    fn surface_shading_matches_glint_lobe_geometry_and_is_two_sided() {
        // An independent restatement of the model for one light: ambient + diffuse
        // N·L + specular cos^n of glint-lobe's own geometry.
        let l = Vec3::new(0.3, 0.2, 0.9).normalize_or_zero();
        let v = Vec3::new(-0.1, 0.1, 1.0).normalize_or_zero();
        let n = Vec3::new(0.1, 0.0, 1.0).normalize_or_zero();
        let m = Material::default();
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            let mut shader =
                Shader::new(LobeKind::Exact, 20.0, 4, geometry, m, vec![], 0.0).unwrap();
            shader.lights = vec![(l, 1.0)];
            let c = geometry.cos(n.to_array(), l.to_array(), v.to_array());
            let want = m.ambient + m.diffuse * n.dot(l) + m.specular * c.max(0.0).powf(20.0);
            let got = shader.shade_normal([1.0; 3], n, v);
            assert!(
                (got[0] - want).abs() < 1e-5,
                "{geometry}: {got:?} vs {want}"
            );
            // The back face seen from the front is lit like the front.
            assert_eq!(shader.shade_normal([1.0; 3], -n, v), got);
        }
    }
}
