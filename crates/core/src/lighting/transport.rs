//! What light transport (shadows, path tracing) asks of the lighting model: how much
//! of each light reaches a sample (a transmittance factor per light, and an occlusion
//! factor on the ambient term), and the model's response to light from one direction
//! seen from another, for a surface-like sample and for a scattering medium.
//!
//! A volume sample is a hybrid (Kroes, Post and Botha, "Exposure Render: an
//! interactive photo-realistic volume rendering framework", PLoS ONE 7(7), 2012): a
//! surface, lit by the model's diffuse and specular terms, where the gradient is
//! strong; a medium that scatters by the Henyey-Greenstein phase function where it is
//! weak. The weight of the surface is the gate's ramp ([`Shader::shade`]'s blend
//! between the shaded and the flat colour: 0 below the gate, 1 from twice it), where
//! Exposure Render draws the surface with probability `1 - exp(-s·|∇I|)`: the same
//! idea, gated as glint's local model already is.
//!
//! Units: a directional light of intensity `I` is an irradiance `E = π·I` (on a
//! plane facing it) at every sample it reaches, surface or medium alike, so a scene
//! with both parts means what a physical renderer's light of irradiance `π·I` means.
//! It sends a surface sample the radiance `E·f_r·N·L = I·(c·diffuse·N·L +
//! specular·lobe)` (Lambert's BRDF `c·diffuse/π`, the lobe over π: the `local`
//! model's shading, unchanged) and a medium sample the radiance `E·albedo·p(L, V) =
//! I·c·diffuse·π·p(L, V)` per unit of scattering, `p` the normalised phase function:
//! [`MEDIUM_IRRADIANCE`] times `c·diffuse·4π·p`. An isotropic medium (`g = 0`) under
//! one light of intensity 1 thus shows a quarter of the `local` model's flat colour
//! `c·diffuse` (the `local` model itself keeps its flat colour). As a BSDF in a path
//! tracer this is `f·cos θ_i = response / π` for the surface and `f = response / π`
//! for the medium, both per unit of `E`; the environment is a radiance seen alike by
//! both: energy-conserving for `c·diffuse <= 1`, so a white furnace stays at the
//! environment's radiance.

use crate::error::RenderError;
use crate::math::Vec3;

use super::{facing, Material, RayLighting, Shader};

/// `4π` times the Henyey-Greenstein phase function ("Diffuse radiation in the
/// galaxy", Astrophysical Journal 93, 1941) for light arriving from unit direction
/// `wi` (towards the light) and leaving towards `wo`, written with `l_dot_v = wi·wo`:
/// the scattering angle's cosine is `-wi·wo`, so
/// `(1 - g²) / (1 + g² + 2g·wi·wo)^(3/2)`. Its mean over the sphere is 1; `g > 0`
/// scatters forwards (bright when looking towards the light through the medium).
#[inline(always)]
pub fn phase_hg(g: f32, l_dot_v: f32) -> f32 {
    let g2 = g * g;
    let denom = 1.0 + g2 + 2.0 * g * l_dot_v;
    (1.0 - g2) / (denom * denom.sqrt())
}

/// The factor of a medium's response to a light over `c·diffuse·4π·p` ([`phase_hg`]):
/// `π/4π`, a light of intensity `I` being the irradiance `π·I` for the medium as for
/// the surface (see the module docs).
pub const MEDIUM_IRRADIANCE: f32 = 0.25;

/// Largest `|g|` of the phase function a shader takes (at `|g| = 1` it is a delta).
pub const MAX_ANISOTROPY: f32 = 0.95;

/// Where a volume sample is a surface: its unit normal (down the gradient) and the
/// surface's weight in the hybrid, in `(0, 1]` ([`Shader::surface_at`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePart {
    /// Unit normal, down the gradient (either side may face the viewer).
    pub normal: Vec3,
    /// The surface's weight; the medium's is `1 - weight`.
    pub weight: f32,
}

impl Shader {
    /// This shader with the medium's phase function anisotropy `g` (Henyey-Greenstein;
    /// 0, isotropic, by default).
    pub fn with_anisotropy(mut self, g: f32) -> Result<Shader, RenderError> {
        if !g.is_finite() || g.abs() > MAX_ANISOTROPY {
            return Err(RenderError::Parameter(format!(
                "anisotropy {g}: expected -{MAX_ANISOTROPY}..={MAX_ANISOTROPY}"
            )));
        }
        self.anisotropy = g;
        Ok(self)
    }

    /// The phase function's anisotropy `g`.
    pub fn anisotropy(&self) -> f32 {
        self.anisotropy
    }

    /// This shader with the surface part of the hybrid scaled by `w` (0..=1; 1, the
    /// gate's weight as it is, by default). At 0 every sample is a pure medium (what a
    /// physical renderer's heterogeneous medium is: extinction, albedo and phase
    /// function only), so `shadows` and `path` images can be matched to one.
    pub fn with_surface_weight(mut self, w: f32) -> Result<Shader, RenderError> {
        if !(0.0..=1.0).contains(&w) {
            return Err(RenderError::Parameter(format!(
                "surface weight {w}: expected 0..=1"
            )));
        }
        self.surface_weight = w;
        Ok(self)
    }

    /// The scale of the surface part's weight ([`Shader::with_surface_weight`]).
    pub fn surface_weight(&self) -> f32 {
        self.surface_weight
    }

    /// Lit linear colour of a volume sample as [`Shader::shade`] lights it, with the
    /// light of light `i` scaled by `transmittance[i]` (what reaches the sample through
    /// the volume; one per placed light) and the ambient term by `occlusion`, and the
    /// flat part of the hybrid a scattering medium (see the module docs):
    /// [`Scattering::shadowed`](super::Scattering::shadowed). With one light of
    /// intensity 1, every factor 1 and `g = 0` it is [`Shader::shade`] up to rounding.
    /// [`Shader::shade_gradients_shadowed`] is its batch form, bit for bit.
    #[inline(always)]
    pub fn shade_shadowed(
        &self,
        base: [f32; 3],
        grad: Vec3,
        ray: &RayLighting,
        transmittance: &[f32],
        occlusion: f32,
    ) -> [f32; 3] {
        self.scattering(base, grad)
            .shadowed(ray, transmittance, occlusion)
    }

    /// The surface part of a volume sample with world gradient `grad`: its unit normal
    /// and weight, `None` where the gradient is below the gate (or not finite), the
    /// material is unshaded or the surface weight is 0 (then the sample is all
    /// medium).
    #[inline(always)]
    pub fn surface_at(&self, grad: Vec3) -> Option<SurfacePart> {
        if !self.material.shade || self.surface_weight == 0.0 {
            return None;
        }
        let gm2 = grad.dot(grad);
        let g0 = self.gate;
        if !(gm2 > g0 * g0 && gm2 < f32::INFINITY) {
            return None;
        }
        let gm = gm2.sqrt();
        Some(SurfacePart {
            normal: grad * (-1.0 / gm),
            weight: self.gate_weight(gm),
        })
    }

    /// What a surface of colour `base` and unit `normal` (either side; it is turned to
    /// face `wo`) sends towards unit `wo` per unit of light from unit `wi`:
    /// `c·diffuse·N·L + specular·lobe(cos γ)` where `N·L > 0`, else 0 (the light
    /// reaches the side the viewer sees only). Divided by π it is the BRDF times
    /// `N·wi`.
    #[inline]
    pub fn surface_response(&self, base: [f32; 3], normal: Vec3, wo: Vec3, wi: Vec3) -> [f32; 3] {
        let m = &self.material;
        let (n, n_dot_v) = facing(normal, wo);
        let h = (wi + wo).normalize_or_zero();
        match self.surface_terms(n, n_dot_v, wi, wi.dot(wo), h) {
            Some((n_dot_l, lobe)) => {
                let spec = m.specular * lobe;
                base.map(|b| b * m.diffuse * n_dot_l + spec)
            }
            None => [0.0; 3],
        }
    }

    /// What a scattering medium of colour `base` sends towards unit `wo` per unit of
    /// light from unit `wi`: `c·diffuse·π·p(wi, wo)` ([`MEDIUM_IRRADIANCE`] times
    /// [`phase_hg`]'s `4π·p`). Divided by π it is the albedo `c·diffuse` times the
    /// normalised phase function.
    #[inline]
    pub fn medium_response(&self, base: [f32; 3], wo: Vec3, wi: Vec3) -> [f32; 3] {
        let p = MEDIUM_IRRADIANCE * phase_hg(self.anisotropy, wi.dot(wo));
        base.map(|b| b * self.material.diffuse * p)
    }

    /// The medium's single-scattering albedo for a sample of colour `base`:
    /// `c·diffuse` ([`Shader::medium_response`] integrates to it over the sphere, over
    /// 4π).
    #[inline]
    pub fn medium_albedo(&self, base: [f32; 3]) -> [f32; 3] {
        base.map(|b| b * self.material.diffuse)
    }
}

/// The flat part of a sample that is all medium: `ambient·occlusion +
/// diffuse·phase/4` (`phase` the lights' sum of `I·T·4π·p`, [`MEDIUM_IRRADIANCE`]).
#[inline(always)]
pub(super) fn medium_factor(m: &Material, occlusion: f32, phase: f32) -> f32 {
    m.ambient * occlusion + m.diffuse * (MEDIUM_IRRADIANCE * phase)
}

/// The factors of a volume sample's colour `c·lit + spec` from its shadowed sums
/// `[diffuse, specular, phase]`, the ambient occlusion and the surface weight `w`:
/// `lit = ambient·occ + diffuse·(w·D + (1-w)·P/4)`, `spec = w·specular·S`
/// ([`MEDIUM_IRRADIANCE`]).
#[inline(always)]
pub(super) fn hybrid_terms(
    m: &Material,
    [diffuse, specular, phase]: [f32; 3],
    occlusion: f32,
    w: f32,
) -> (f32, f32) {
    let lit =
        m.ambient * occlusion + m.diffuse * (w * diffuse + (1.0 - w) * (MEDIUM_IRRADIANCE * phase));
    let spec = w * (m.specular * specular);
    (lit, spec)
}

#[cfg(test)]
mod tests {
    use glint_lobe::{Geometry, LobeKind};

    use super::*;
    use crate::camera::{Camera, CameraSpec};
    use crate::lighting::Light;

    fn shader(g: f32, gate: f32, lights: Vec<Light>) -> Shader {
        let cam = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 1.0, 8, 8).unwrap();
        Shader::new(
            LobeKind::EnergyFit,
            30.0,
            4,
            Geometry::Phong,
            Material::default(),
            lights,
            gate,
        )
        .unwrap()
        .with_anisotropy(g)
        .unwrap()
        .placed(&cam)
    }

    #[test]
    fn phase_function_has_mean_one_and_peaks_forwards() {
        // Mean of 4π p over the sphere: (1/2)∫_{-1}^{1} f(μ) dμ by the midpoint rule.
        for g in [-0.8f32, -0.3, 0.0, 0.5, 0.9] {
            let n = 200_000;
            let mean: f64 = (0..n)
                .map(|i| {
                    let mu = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                    f64::from(phase_hg(g, mu as f32))
                })
                .sum::<f64>()
                / n as f64;
            assert!((mean - 1.0).abs() < 1e-3, "g = {g}: mean {mean}");
        }
        // Forward scattering: light from wi seen from wo = -wi (through the medium).
        assert!(phase_hg(0.6, -1.0) > phase_hg(0.6, 1.0) * 50.0);
        assert_eq!(phase_hg(0.0, 0.3), 1.0);
    }

    #[test]
    fn unshadowed_isotropic_light_is_the_local_model_but_for_the_mediums_irradiance() {
        // The surface part is the local model's; the medium part takes the light's
        // irradiance π·I (a quarter of the local model's flat diffuse term, which is
        // 4π·I·p): local - shadowed = (1 - w)·c·diffuse·3/4.
        let s = shader(0.0, 0.3, vec![Light::HEADLIGHT]);
        let view = Vec3::new(0.2, -0.1, 1.0).normalize_or_zero();
        let ray = s.for_ray(view);
        for grad in [
            Vec3::new(0.0, 0.0, -2.0),
            Vec3::new(0.5, 0.2, -0.4),
            Vec3::new(0.1, 0.0, 0.0), // below the gate: flat
            Vec3::new(0.4, 0.0, 0.1), // inside the ramp
            Vec3::ZERO,
        ] {
            let base = [0.8, 0.5, 0.3];
            let local = s.shade(base, grad, &ray);
            let lit = s.shade_shadowed(base, grad, &ray, &[1.0], 1.0);
            let w = s.surface_at(grad).map_or(0.0, |p| p.weight);
            let d = Material::default().diffuse;
            for c in 0..3 {
                let want = local[c] - (1.0 - w) * base[c] * d * (1.0 - MEDIUM_IRRADIANCE);
                assert!((want - lit[c]).abs() < 1e-6, "{grad:?}: {local:?} {lit:?}");
            }
        }
    }

    #[test]
    fn transmittance_scales_each_light_and_occlusion_the_ambient() {
        let lights = vec![
            Light::HEADLIGHT,
            Light {
                azimuth: 30.0,
                elevation: 10.0,
                intensity: 0.5,
            },
        ];
        let s = shader(0.3, 0.0, lights);
        let ray = s.for_ray(s.world_lights()[0].0);
        let base = [1.0, 0.5, 0.25];
        let grad = s.world_lights()[0].0 * -3.0;
        let m = Material::default();
        // Everything dark but the ambient term, scaled by the occlusion.
        let dark = s.shade_shadowed(base, grad, &ray, &[0.0, 0.0], 0.5);
        for c in 0..3 {
            assert!((dark[c] - base[c] * m.ambient * 0.5).abs() < 1e-7);
        }
        // Linear in each light's transmittance.
        let a = s.shade_shadowed(base, grad, &ray, &[1.0, 0.0], 0.0);
        let b = s.shade_shadowed(base, grad, &ray, &[0.0, 1.0], 0.0);
        let ab = s.shade_shadowed(base, grad, &ray, &[1.0, 1.0], 0.0);
        let half = s.shade_shadowed(base, grad, &ray, &[0.5, 0.5], 0.0);
        for c in 0..3 {
            assert!((a[c] + b[c] - ab[c]).abs() < 1e-6);
            assert!((half[c] - 0.5 * ab[c]).abs() < 1e-6);
        }
    }

    #[test]
    fn responses_are_the_shading_of_one_light() {
        // One light along the view: the surface response plus ambient is the local
        // shading of a full-weight surface, and a medium's is c·diffuse at g = 0.
        let s = shader(0.0, 0.0, vec![Light::HEADLIGHT]);
        let l = s.world_lights()[0].0;
        let ray = s.for_ray(l);
        let n = Vec3::new(0.3, 0.1, 0.0) + l;
        let n = n.normalize_or_zero();
        let base = [0.9, 0.6, 0.2];
        let m = Material::default();
        let r = s.surface_response(base, n, l, l);
        let local = s.shade(base, n * -5.0, &ray);
        for c in 0..3 {
            assert!((r[c] + base[c] * m.ambient - local[c]).abs() < 1e-6);
        }
        // The back side of the normal gives the same (two-sided), light behind gives 0.
        assert_eq!(s.surface_response(base, -n, l, l), r);
        assert_eq!(s.surface_response(base, n, l, -l), [0.0; 3]);
        // The medium's: c·diffuse·π·p, at g = 0 c·diffuse/4 (one irradiance π·I).
        let med = s.medium_response(base, l, Vec3::new(0.0, 1.0, 0.0));
        for c in 0..3 {
            assert!((med[c] - base[c] * m.diffuse * 0.25).abs() < 1e-7);
        }
        assert!(s.surface_at(Vec3::ZERO).is_none());
        let part = s.surface_at(n * -2.0).unwrap();
        assert_eq!(part.weight, 1.0);
        assert!((part.normal - n).length() < 1e-6);
    }

    #[test]
    fn bad_anisotropy_is_refused() {
        let s = Shader::new(
            LobeKind::Exact,
            10.0,
            4,
            Geometry::Phong,
            Material::default(),
            vec![],
            0.0,
        )
        .unwrap();
        assert!(s.clone().with_anisotropy(0.99).is_err());
        assert!(s.clone().with_anisotropy(f32::NAN).is_err());
        assert_eq!(s.with_anisotropy(-0.5).unwrap().anisotropy(), -0.5);
    }

    #[test]
    fn surface_weight_scales_the_surface_part_and_zero_leaves_a_pure_medium() {
        let s = shader(0.0, 1.0, vec![Light::HEADLIGHT]);
        let grad = Vec3::new(0.0, 0.0, -1.5);
        // The gate's ramp: half way from the gate (1) to twice it.
        assert_eq!(s.surface_at(grad).unwrap().weight, 0.5);
        let scaled = s.clone().with_surface_weight(0.5).unwrap();
        assert_eq!(scaled.surface_at(grad).unwrap().weight, 0.25);
        let medium = s.clone().with_surface_weight(0.0).unwrap();
        assert!(medium.surface_at(grad).is_none());
        assert!(medium.surface_at(grad * 100.0).is_none());
        // A pure medium shades as the medium alone: the shadowed colour of a strong
        // gradient equals that of no gradient.
        let ray = medium.for_ray(medium.world_lights()[0].0);
        let base = [0.8, 0.5, 0.3];
        let strong = medium.shade_shadowed(base, grad * 100.0, &ray, &[1.0], 1.0);
        let none = medium.shade_shadowed(base, Vec3::ZERO, &ray, &[1.0], 1.0);
        assert_eq!(strong, none);
        for bad in [-0.1, 1.5, f32::NAN] {
            assert!(s.clone().with_surface_weight(bad).is_err());
        }
    }
}
