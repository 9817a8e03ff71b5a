//! The one scattering model of every lighting model, in the manner of pbrt-v4's
//! `BSDF` and Mitsuba 3's `BSDF`/`PhaseFunction` (an object built at each shaded
//! point with `f`, `sample` and `pdf`, which every integrator calls).
//!
//! A shaded sample's [`Scattering`] ([`Shader::scattering`]) is the hybrid of the
//! module docs of `lighting/transport.rs`: a surface part (unit normal and
//! weight, from the gradient gate) and a scattering medium. The three lighting models
//! read it the same way:
//!
//! - `local`: [`Scattering::local`], `ambient + Σ I·f` over the lights, with the
//!   gate's blend towards the flat colour;
//! - `shadows`: [`Scattering::shadowed`], the same with each light's transmittance
//!   `T` and the ambient occlusion, the medium lit through the phase function;
//! - `path`: one component drawn per event ([`Scattering::choose`], the surface with
//!   the probability of its weight, as Exposure Render chooses its BRDF), whose
//!   [`Bsdf::f`] lights next-event estimation and whose [`Bsdf::sample`] continues
//!   the path.
//!
//! Units: `f(wo, wi)` is what a directional light of intensity 1 from `wi` sends
//! towards `wo`, so a light of intensity `I` adds `I·f`; the light is the irradiance
//! `π·I` for both parts: for a surface `c·diffuse·N·L + specular·lobe(cos γ)` (π
//! times the BRDF times `N·wi`), for the medium `c·diffuse·π·p(wi, wo)` (π times the
//! albedo times the phase function). [`Bsdf::pdf`] is a density per steradian and a
//! sample's weight is the path throughput factor `f/(π·pdf)`: `BRDF·cos/pdf`
//! (surface) or `albedo·p/pdf = albedo` (medium: its directions are drawn exactly by
//! the phase function).
//!
//! The sums over the lights of the scalar models are written once
//! ([`Shader::light_sums`], generic over each light's effective intensity) and the
//! batch forms ([`ShadeBatch`](super::ShadeBatch), on AVX2 where the CPU has it) are
//! tested against the scalar models bit for bit.

use std::f32::consts::PI;
use std::sync::{Arc, OnceLock};

use glint_lobe::{Frame, Scatter, SpecularSampler};

use super::transport::{hybrid_terms, medium_factor, phase_hg};
use super::{facing, flat, gated, ungated, RayLighting, Shader, SurfacePart};
use crate::color::luminance_f32;
use crate::error::RenderError;
use crate::math::Vec3;

/// The specular lobe's sampler and its share of a surface's albedo, built once per
/// shader (on first use; shared by its clones) for the path tracer.
#[derive(Debug)]
pub(super) struct SurfaceSampler {
    lobe: SpecularSampler,
    /// `specular · ∫lobe dω / π`: the specular term's share of a surface's albedo,
    /// for choosing between the lobe and the diffuse cosine.
    lobe_albedo: f32,
}

/// The lazily built [`SurfaceSampler`] of a shader (an error message for a specular
/// table without the shininess to sample it by).
pub(super) type SamplerCell = Arc<OnceLock<Result<SurfaceSampler, String>>>;

/// A shaded sample's scattering: its colour, its surface part (none where the gradient
/// is below the gate or the material is unshaded: all medium) and the shader's
/// material, lobe and medium. Built by [`Shader::scattering`] (a volume sample) or
/// [`Shader::scattering_normal`] (a surface point).
#[derive(Clone, Copy, Debug)]
pub struct Scattering<'s> {
    shader: &'s Shader,
    base: [f32; 3],
    surface: Option<SurfacePart>,
    /// Whether the local model blends the surface towards the flat colour by its
    /// weight (a volume sample) or lights it fully (a surface point).
    gated: bool,
}

/// One component of a [`Scattering`] at a path's scattering event: the surface or
/// the medium, with `f`, `sample` and `pdf` (see the module docs for the units).
#[derive(Clone, Copy, Debug)]
pub struct Bsdf<'s> {
    shader: &'s Shader,
    base: [f32; 3],
    /// The surface's unit normal (either side); `None` for the medium.
    normal: Option<Vec3>,
}

/// A direction drawn by [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The incident direction (unit, towards where the light comes from).
    pub wi: Vec3,
    /// The path throughput factor: `f/(π·pdf)` for a surface, the albedo for the
    /// medium.
    pub weight: [f32; 3],
    /// The density of `wi` per steradian.
    pub pdf: f32,
}

impl Shader {
    /// The scattering of a volume sample of transfer-function colour `base` and world
    /// gradient `grad` (its normal points down the gradient: out of dense structures),
    /// under the gradient gate.
    #[inline(always)]
    pub fn scattering(&self, base: [f32; 3], grad: Vec3) -> Scattering<'_> {
        Scattering {
            shader: self,
            base,
            surface: self.surface_at(grad),
            gated: true,
        }
    }

    /// The scattering of a surface point of colour `base` and unit `normal` (either
    /// side: two-sided), with no gate.
    #[inline(always)]
    pub fn scattering_normal(&self, base: [f32; 3], normal: Vec3) -> Scattering<'_> {
        Scattering {
            shader: self,
            base,
            surface: self.material.shade.then_some(SurfacePart {
                normal,
                weight: 1.0,
            }),
            gated: false,
        }
    }

    /// The diffuse and specular sums over the ray's lights, `Σ I·N·L` and
    /// `Σ I·lobe(cos γ)` over the lights with `N·L > 0`, for the unit normal `n`
    /// turned to face the viewer, with `intensities` the lights' effective intensities
    /// in light order (their own, or times a transmittance).
    #[inline(always)]
    pub(super) fn light_sums(
        &self,
        n: Vec3,
        ray: &RayLighting,
        intensities: impl Iterator<Item = f32>,
    ) -> (f32, f32) {
        let (n, n_dot_v) = facing(n, ray.view);
        let mut diffuse = 0.0f32;
        let mut specular = 0.0f32;
        for (&(l, _, l_dot_v, h), intensity) in ray.lights[..ray.count].iter().zip(intensities) {
            if let Some((n_dot_l, lobe)) = self.surface_terms(n, n_dot_v, l, l_dot_v, h) {
                diffuse += intensity * n_dot_l;
                specular += intensity * lobe;
            }
        }
        (diffuse, specular)
    }

    /// A surface's response to one direction of light: `N·L` and `lobe(cos γ)` for the
    /// unit normal `n` facing the viewer (`N·V = n_dot_v`), unit `l` towards the light,
    /// `L·V` and the half vector `h`; `None` where `N·L <= 0` (the light reaches the
    /// side the viewer sees only).
    #[inline(always)]
    pub(super) fn surface_terms(
        &self,
        n: Vec3,
        n_dot_v: f32,
        l: Vec3,
        l_dot_v: f32,
        h: Vec3,
    ) -> Option<(f32, f32)> {
        let n_dot_l = n.dot(l);
        if n_dot_l > 0.0 {
            let c = self.cos(n_dot_l, n_dot_v, l_dot_v, n, h);
            Some((n_dot_l, self.specular.eval(c)))
        } else {
            None
        }
    }

    /// `Σ_i I_i·T_i·4π·p(L_i, V)` over the ray's lights, in light order.
    #[inline(always)]
    fn phase_sum(&self, ray: &RayLighting, transmittance: &[f32]) -> f32 {
        let g = self.anisotropy;
        let mut phase = 0.0f32;
        for (&(_, intensity, l_dot_v, _), &t) in ray.lights[..ray.count].iter().zip(transmittance) {
            phase += (intensity * t) * phase_hg(g, l_dot_v);
        }
        phase
    }

    /// The lobe's sampler for path tracing, built on first use. Errors for a specular
    /// table without the shininess to sample it by.
    fn surface_sampler(&self) -> Result<&SurfaceSampler, RenderError> {
        self.sampler
            .get_or_init(|| {
                let lobe = SpecularSampler::new(&self.specular).map_err(|e| e.to_string())?;
                let lobe_albedo = self.material.specular * lobe.sampler().integral() as f32 / PI;
                Ok(SurfaceSampler { lobe, lobe_albedo })
            })
            .as_ref()
            .map_err(|e| RenderError::Parameter(e.clone()))
    }

    /// Checks the shader can be path traced (its specular term has a sampler: a table
    /// needs its shininess) and builds the sampler [`Bsdf::sample`] uses.
    pub fn check_sampling(&self) -> Result<(), RenderError> {
        self.surface_sampler().map(|_| ())
    }
}

impl<'s> Scattering<'s> {
    /// The surface part: unit normal and weight (`None`: all medium).
    pub fn surface(&self) -> Option<SurfacePart> {
        self.surface
    }

    /// The `local` model's lit linear colour under the ray's lights: `c·ambient +
    /// Σ I·f` for the surface, blended towards the flat colour `c·(ambient + diffuse)`
    /// by the surface's weight for a volume sample; the flat colour where there is no
    /// surface; `c` itself for an unshaded material.
    #[inline(always)]
    pub fn local(&self, ray: &RayLighting) -> [f32; 3] {
        let m = &self.shader.material;
        if !m.shade {
            return self.base;
        }
        let Some(s) = self.surface else {
            return self.base.map(|c| c * flat(m));
        };
        let intensities = ray.lights[..ray.count].iter().map(|l| l.1);
        let (diffuse, specular) = self.shader.light_sums(s.normal, ray, intensities);
        if self.gated {
            gated(m, self.base, diffuse, specular, s.weight)
        } else {
            ungated(m, self.base, diffuse, specular)
        }
    }

    /// The `shadows` model's lit linear colour: [`Scattering::local`]'s terms with the
    /// light of light `i` scaled by `transmittance[i]` (what reaches the sample through
    /// the volume; one per placed light) and the ambient term by `occlusion`, and the
    /// part of the sample that is not surface a medium lit through the phase function
    /// (see [`Shader::shade_shadowed`]).
    #[inline(always)]
    pub fn shadowed(&self, ray: &RayLighting, transmittance: &[f32], occlusion: f32) -> [f32; 3] {
        let m = &self.shader.material;
        if !m.shade {
            return self.base;
        }
        let phase = self.shader.phase_sum(ray, transmittance);
        let Some(s) = self.surface else {
            return self.base.map(|c| c * medium_factor(m, occlusion, phase));
        };
        let lights = ray.lights[..ray.count].iter().zip(transmittance);
        let intensities = lights.map(|(l, &t)| l.1 * t);
        let (diffuse, specular) = self.shader.light_sums(s.normal, ray, intensities);
        let (lit, spec) = hybrid_terms(m, [diffuse, specular, phase], occlusion, s.weight);
        self.base.map(|c| c * lit + spec)
    }

    /// The component a path scatters by at this sample: the surface with the
    /// probability of its weight (`u` is called for one uniform number in `[0, 1)`
    /// only when there is a surface part), else the medium.
    #[inline]
    pub fn choose(&self, u: impl FnOnce() -> f32) -> Bsdf<'s> {
        let normal = self.surface.filter(|s| u() < s.weight).map(|s| s.normal);
        Bsdf {
            shader: self.shader,
            base: self.base,
            normal,
        }
    }
}

impl Bsdf<'_> {
    /// Whether this is the surface (rays leaving it start past the matter it lies in).
    #[inline]
    pub fn is_surface(&self) -> bool {
        self.normal.is_some()
    }

    /// What a directional light of intensity 1 from unit `wi` sends towards unit `wo`
    /// (see the module docs for the units): [`Shader::surface_response`] or
    /// [`Shader::medium_response`].
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3) -> [f32; 3] {
        match self.normal {
            Some(n) => self.shader.surface_response(self.base, n, wo, wi),
            None => self.shader.medium_response(self.base, wo, wi),
        }
    }

    /// Draws an incident direction for the outgoing unit `wo` from three uniform
    /// numbers in `[0, 1)`: for a surface the lobe (with `u[0]` below the lobe's share
    /// of the albedo) or the diffuse cosine, for the medium the phase function
    /// (`u[0]` unused). `None` ends a path: a direction the surface does not reflect
    /// into, a surface with no albedo, or a shader without a sampler
    /// ([`Shader::check_sampling`]).
    #[inline]
    pub fn sample(&self, wo: Vec3, u: [f32; 3]) -> Option<BsdfSample> {
        let Some(normal) = self.normal else {
            let g = self.shader.anisotropy;
            let wi = sample_phase(g, wo, u[1], u[2]);
            return Some(BsdfSample {
                wi,
                weight: self.shader.medium_albedo(self.base),
                pdf: phase_hg(g, wi.dot(wo)) / (4.0 * PI),
            });
        };
        let (n, p_lobe, at, sampler) = self.surface_mixture(normal, wo)?;
        let wi = if u[0] < p_lobe {
            let s = at.sample(&sampler.lobe, u[1], u[2])?;
            Vec3::new(s.wi[0], s.wi[1], s.wi[2])
        } else {
            let local = cosine_hemisphere(u[1], u[2]);
            let w = Frame::from_z(n.to_array()).to_world(local);
            Vec3::new(w[0], w[1], w[2])
        };
        let response = self.shader.surface_response(self.base, n, wo, wi);
        if response == [0.0; 3] {
            return None;
        }
        let pdf = mixture_pdf(n, p_lobe, &at, sampler, wi);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let k = 1.0 / (PI * pdf);
        Some(BsdfSample {
            wi,
            weight: response.map(|r| r * k),
            pdf,
        })
    }

    /// The density per steradian with which [`Bsdf::sample`] draws unit `wi` for the
    /// outgoing unit `wo` (0 where it cannot).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(normal) = self.normal else {
            return phase_hg(self.shader.anisotropy, wi.dot(wo)) / (4.0 * PI);
        };
        match self.surface_mixture(normal, wo) {
            Some((n, p_lobe, at, sampler)) => mixture_pdf(n, p_lobe, &at, sampler, wi),
            None => 0.0,
        }
    }

    /// The surface's sampling mixture at `wo`: the normal turned to face `wo`, the
    /// lobe's probability (its share of the albedo: the diffuse part by the colour's
    /// luminance), the lobe at this event and the sampler. `None` for a surface with
    /// no albedo, a degenerate normal or no sampler.
    #[inline]
    fn surface_mixture(
        &self,
        normal: Vec3,
        wo: Vec3,
    ) -> Option<(Vec3, f32, Scatter<f32>, &SurfaceSampler)> {
        let sampler = self.shader.surface_sampler().ok()?;
        let n = if normal.dot(wo) < 0.0 {
            -normal
        } else {
            normal
        };
        let diffuse = luminance_f32(self.base) * self.shader.material.diffuse;
        let total = diffuse + sampler.lobe_albedo;
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let p_lobe = sampler.lobe_albedo / total;
        let at = Scatter::new(self.shader.geometry, n.to_array(), wo.to_array())?;
        Some((n, p_lobe, at, sampler))
    }
}

/// The density of the surface's mixture: the diffuse cosine's `N·wi/π` with
/// probability `1 - p_lobe`, the lobe's with `p_lobe`.
#[inline]
fn mixture_pdf(n: Vec3, p_lobe: f32, at: &Scatter<f32>, s: &SurfaceSampler, wi: Vec3) -> f32 {
    (1.0 - p_lobe) * n.dot(wi).max(0.0) / PI + p_lobe * at.pdf(&s.lobe, wi.to_array())
}

/// A unit direction about `z` with density `cos θ / π` (Malley's method).
#[inline]
pub fn cosine_hemisphere(u1: f32, u2: f32) -> [f32; 3] {
    let r = u1.sqrt();
    let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
    [r * c, r * s, (1.0 - u1).max(0.0).sqrt()]
}

/// An incident direction `wi` for the outgoing `wo` drawn with the density of the
/// Henyey-Greenstein phase function `p(wi·wo)` ([`phase_hg`] over 4π): pbrt-v4's
/// `SampleHenyeyGreenstein` (src/pbrt/util/scattering.h), whose `wo` and `wi` both
/// point away from the event as here.
#[inline]
pub fn sample_phase(g: f32, wo: Vec3, u1: f32, u2: f32) -> Vec3 {
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u1
    } else {
        let sq = (1.0 - g * g) / (1.0 + g - 2.0 * g * u1);
        -(1.0 + g * g - sq * sq) / (2.0 * g)
    }
    .clamp(-1.0, 1.0);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let (sp, cp) = (std::f32::consts::TAU * u2).sin_cos();
    let w = Frame::from_z(wo.to_array()).to_world([sin * cp, sin * sp, cos]);
    Vec3::new(w[0], w[1], w[2])
}

#[cfg(test)]
#[path = "scatter_tests.rs"]
mod tests;
