//! Progressive Monte Carlo volume path tracing of a classified field, with the
//! lighting model's hybrid response (glint-core's `Shader::surface_response` and
//! `Shader::medium_response`): free paths by delta tracking, the lights by next-event
//! estimation with ratio-tracked transmittance, a uniform environment reached by the
//! paths that leave the volume, scattering directions importance-sampled (the
//! surface's diffuse cosine and its specular lobe through glint-lobe's samplers, the
//! medium's Henyey-Greenstein phase function exactly), Russian roulette, and at most
//! `bounces` scattering events. The surface is chosen at a collision with the
//! probability of its weight, as Exposure Render chooses its BRDF (Kroes et al. 2012).

use std::f32::consts::PI;

use glint_core::camera::Camera;
use glint_core::{luminance_f32, Image, RenderStats, Shader, SurfacePart, Vec3};
use glint_lobe::{Frame, Scatter, SpecularSampler};

use super::occluders::Occluders;
use super::rng::Rng;
use super::tracking::{IndexRay, Tracker};
use super::PathSettings;
use crate::classification::Medium;
use crate::field::Field;

/// Russian roulette starts after this many scattering events.
const ROULETTE_AFTER: u32 = 2;

/// Largest survival probability of the roulette (paths of full throughput still end
/// sometimes, so a white furnace's paths end before `bounces`).
const MAX_SURVIVAL: f32 = 0.95;

/// The running sums of a progressive path-traced image: per pixel the sums of the
/// samples' radiance and coverage, in sample order, and how many samples each holds.
/// The image of `n` samples is the same bit for bit however they were added (one
/// batch or many), since each pixel adds its samples one by one in sample order.
#[derive(Clone, Debug)]
pub struct PathImage {
    width: u32,
    height: u32,
    /// Per pixel: radiance (premultiplied by coverage) and coverage, summed.
    sums: Vec<[f64; 4]>,
    samples: u32,
    stats: RenderStats,
}

impl PathImage {
    /// An image of no samples.
    pub fn new(width: u32, height: u32) -> PathImage {
        PathImage {
            width,
            height,
            sums: vec![[0.0; 4]; width as usize * height as usize],
            samples: 0,
            stats: RenderStats::default(),
        }
    }

    /// Width and height.
    pub fn size(&self) -> [u32; 2] {
        [self.width, self.height]
    }

    /// Samples per pixel so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The mean of the samples over `background` (linear RGB): the rendered image.
    /// `stats.samples` counts paths, `stats.shaded` scattering events.
    pub fn image(&self, background: [f32; 3]) -> Image {
        let n = f64::from(self.samples.max(1));
        let (rgb, alpha) = self
            .sums
            .iter()
            .map(|s| {
                let a = (s[3] / n) as f32;
                let c = |i: usize| (s[i] / n) as f32 + (1.0 - a) * background[i];
                ([c(0), c(1), c(2)], a)
            })
            .unzip();
        Image {
            width: self.width,
            height: self.height,
            rgb,
            alpha,
            stats: self.stats,
        }
    }

    /// The per-pixel sums, for a batch to continue (crate-internal).
    pub(crate) fn sums_mut(&mut self) -> &mut [[f64; 4]] {
        &mut self.sums
    }

    /// Records a finished batch that brought every pixel to `samples`.
    pub(crate) fn finish_batch(&mut self, samples: u32, stats: RenderStats) {
        self.samples = samples;
        self.stats.samples += stats.samples;
        self.stats.shaded += stats.shaded;
        self.stats.skips += stats.skips;
    }
}

/// Everything a path needs that does not change during a frame.
pub(crate) struct PathTracer<'a> {
    pub(crate) track: Tracker<'a>,
    /// The shader, its lights placed for the camera.
    pub(crate) shader: &'a Shader,
    pub(crate) lobe: SpecularSampler,
    /// `specular · ∫lobe dω / π`: the specular term's share of a surface's albedo,
    /// for choosing between the lobe and the diffuse cosine.
    pub(crate) lobe_albedo: f32,
    pub(crate) camera: Camera,
    pub(crate) size: [u32; 2],
    pub(crate) settings: PathSettings,
    /// Per light: world direction towards it, index-space direction, intensity.
    pub(crate) lights: Vec<(Vec3, Vec3, f32)>,
    /// World to index directions: the images of the world axes.
    pub(crate) axes: [Vec3; 3],
    /// Offset (mm) of rays leaving a surface event, past the matter the event lies
    /// in: one voxel of the smallest spacing.
    pub(crate) surface_bias: f32,
    /// Meshes that end shadow rays and scattered paths, when the scene has any.
    pub(crate) occluders: Option<&'a Occluders>,
}

/// One path's result: radiance, whether the camera ray met matter, scattering events.
pub(crate) struct PathSample {
    pub(crate) radiance: [f32; 3],
    pub(crate) coverage: f32,
    pub(crate) events: u32,
}

impl<'a> PathTracer<'a> {
    /// A tracer of `field`'s `medium` lit by `shader` (placed for `camera`).
    pub(crate) fn new(
        field: &'a Field,
        medium: &'a Medium,
        shader: &'a Shader,
        camera: Camera,
        size: [u32; 2],
        settings: PathSettings,
    ) -> Result<PathTracer<'a>, glint_core::RenderError> {
        let lobe = SpecularSampler::new(shader.specular())
            .map_err(|e| glint_core::RenderError::Parameter(e.to_string()))?;
        let lobe_albedo = shader.material().specular * lobe.sampler().integral() as f32 / PI;
        let axes = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ]
        .map(|e| field.index_direction(e));
        let to_index = |v: Vec3| axes[0] * v.x + axes[1] * v.y + axes[2] * v.z;
        let lights = shader
            .world_lights()
            .iter()
            .map(|&(l, i)| (l, to_index(l), i))
            .collect();
        Ok(PathTracer {
            track: Tracker { field, medium },
            shader,
            lobe,
            lobe_albedo,
            camera,
            size,
            settings,
            lights,
            axes,
            surface_bias: field.min_spacing() as f32,
            occluders: None,
        })
    }

    /// The tracer with `occluders` (voxelised on its field) ending its shadow rays
    /// and scattered paths.
    pub(crate) fn occluded_by(
        mut self,
        occluders: Option<&'a Occluders>,
    ) -> Result<PathTracer<'a>, glint_core::RenderError> {
        let grid = self.track.field.dims().map(super::grid_len);
        if occluders.is_some_and(|o| o.dims() != grid) {
            return Err(glint_core::RenderError::Parameter(
                "the mesh occupancy was built for another volume's grid".into(),
            ));
        }
        self.occluders = occluders;
        Ok(self)
    }

    /// Where `ray` meets the meshes over `[t0, t1]` (its first cell excluded).
    #[inline]
    fn mesh_hit(&self, ray: &IndexRay, t0: f32, t1: f32) -> Option<f32> {
        self.occluders.and_then(|o| o.first_hit(ray, t0, t1))
    }

    #[inline(always)]
    fn to_index(&self, v: Vec3) -> Vec3 {
        self.axes[0] * v.x + self.axes[1] * v.y + self.axes[2] * v.z
    }

    /// Sample `sample` of pixel `(x, y)`, its camera ray stopped at `far` mm.
    pub(crate) fn trace(&self, x: u32, y: u32, sample: u32, far: f32) -> PathSample {
        let [w, h] = self.size;
        let pixel = u64::from(y) * u64::from(w) + u64::from(x);
        let mut rng = Rng::new(self.settings.seed, pixel, u64::from(sample));
        // A point of the pixel's square, uniformly (anti-aliasing).
        let (jx, jy) = (rng.uniform() - 0.5, rng.uniform() - 0.5);
        let (eye, dir) = self.camera.ray(x as f32 + jx, y as f32 + jy, w, h);
        let field = self.track.field;
        let mut ray = IndexRay::from_world(field, eye, dir);
        let (mut wdir, mut t0, mut t1) = (dir, 0.0f32, far);
        let mut beta = [1.0f32; 3];
        let mut radiance = [0.0f32; 3];
        let mut coverage = 0.0;
        let mut events = 0;
        let env = self.settings.environment;
        loop {
            // Camera rays stop at the meshes' depth (`far`); scattered rays at their
            // cells, where the path ends: meshes absorb.
            let mesh = if events > 0 {
                self.mesh_hit(&ray, t0, t1)
            } else {
                None
            };
            let Some(t) = self.track.free_path(&ray, t0, mesh.unwrap_or(t1), &mut rng) else {
                if events > 0 && mesh.is_none() {
                    for c in 0..3 {
                        radiance[c] += beta[c] * env;
                    }
                }
                break;
            };
            if events == 0 {
                coverage = 1.0;
            }
            if events >= self.settings.bounces {
                break;
            }
            events += 1;
            let p = ray.at(t);
            let value = field.value(p);
            let color = self.track.medium.color(value);
            let wo = -wdir;
            let surface = self
                .shader
                .surface_at(field.gradient(p))
                .filter(|s| rng.uniform() < s.weight);
            self.direct(
                p,
                color,
                wo,
                surface.as_ref(),
                &mut rng,
                beta,
                &mut radiance,
            );
            let Some((wi, weight)) = self.scatter(color, wo, surface.as_ref(), &mut rng) else {
                break;
            };
            for c in 0..3 {
                beta[c] *= weight[c];
            }
            if events >= ROULETTE_AFTER {
                let q = beta[0].max(beta[1]).max(beta[2]).min(MAX_SURVIVAL);
                if rng.uniform() >= q || q.is_nan() {
                    break;
                }
                for b in &mut beta {
                    *b /= q;
                }
            }
            ray = IndexRay {
                o: p,
                d: self.to_index(wi),
            };
            wdir = wi;
            t0 = if surface.is_some() {
                self.surface_bias
            } else {
                0.0
            };
            t1 = f32::INFINITY;
        }
        PathSample {
            radiance,
            coverage,
            events,
        }
    }

    /// Adds the lights' direct contribution at `p` (next-event estimation), each
    /// light's transmittance estimated by ratio tracking.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn direct(
        &self,
        p: Vec3,
        color: [f32; 3],
        wo: Vec3,
        surface: Option<&SurfacePart>,
        rng: &mut Rng,
        beta: [f32; 3],
        radiance: &mut [f32; 3],
    ) {
        for &(l, l_index, intensity) in &self.lights {
            let (response, t0) = match surface {
                Some(s) => (
                    self.shader.surface_response(color, s.normal, wo, l),
                    self.surface_bias,
                ),
                None => (self.shader.medium_response(color, wo, l), 0.0),
            };
            if response == [0.0; 3] || intensity == 0.0 {
                continue;
            }
            let shadow = IndexRay { o: p, d: l_index };
            if self.mesh_hit(&shadow, t0, f32::INFINITY).is_some() {
                continue;
            }
            let tr = self.track.transmittance(&shadow, t0, f32::INFINITY, rng);
            if tr > 0.0 {
                for c in 0..3 {
                    radiance[c] += beta[c] * response[c] * (intensity * tr);
                }
            }
        }
    }

    /// The next direction from a scattering event, and the path's weight `f cos / pdf`;
    /// `None` ends the path (a direction the surface does not reflect into).
    #[inline]
    fn scatter(
        &self,
        color: [f32; 3],
        wo: Vec3,
        surface: Option<&SurfacePart>,
        rng: &mut Rng,
    ) -> Option<(Vec3, [f32; 3])> {
        let (u0, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
        let Some(s) = surface else {
            let wi = sample_phase(self.shader.anisotropy(), wo, u1, u2);
            return Some((wi, self.shader.medium_albedo(color)));
        };
        let n = if s.normal.dot(wo) < 0.0 {
            -s.normal
        } else {
            s.normal
        };
        let diffuse = luminance_f32(color) * self.shader.material().diffuse;
        let total = diffuse + self.lobe_albedo;
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let p_lobe = self.lobe_albedo / total;
        let at = Scatter::new(self.shader.geometry(), n.to_array(), wo.to_array())?;
        let wi = if u0 < p_lobe {
            let s = at.sample(&self.lobe, u1, u2)?;
            Vec3::new(s.wi[0], s.wi[1], s.wi[2])
        } else {
            let local = cosine_hemisphere(u1, u2);
            let w = Frame::from_z(n.to_array()).to_world(local);
            Vec3::new(w[0], w[1], w[2])
        };
        let response = self.shader.surface_response(color, n, wo, wi);
        if response == [0.0; 3] {
            return None;
        }
        let pdf =
            (1.0 - p_lobe) * n.dot(wi).max(0.0) / PI + p_lobe * at.pdf(&self.lobe, wi.to_array());
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let k = 1.0 / (PI * pdf);
        Some((wi, response.map(|r| r * k)))
    }
}

/// A unit direction about `z` with density `cos θ / π` (Malley's method).
#[inline]
pub(crate) fn cosine_hemisphere(u1: f32, u2: f32) -> [f32; 3] {
    let r = u1.sqrt();
    let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
    [r * c, r * s, (1.0 - u1).max(0.0).sqrt()]
}

/// An incident direction `wi` for the outgoing `wo` drawn with the density of the
/// Henyey-Greenstein phase function `p(wi·wo)` (glint-core's `phase_hg` over 4π):
/// pbrt-v4's `SampleHenyeyGreenstein` (src/pbrt/util/scattering.h), whose `wo` and
/// `wi` both point away from the event as here.
#[inline]
pub(crate) fn sample_phase(g: f32, wo: Vec3, u1: f32, u2: f32) -> Vec3 {
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
mod tests {
    use super::*;
    use glint_core::phase_hg;

    #[test]
    fn phase_samples_follow_the_phase_function() {
        // E[wi·wo] under p(wi·wo) = (1/2)∫ μ (4π p)(μ)/(4π)·2π dμ... = -g for HG in
        // this convention; and a histogram of wi·wo against the density.
        let wo = Vec3::new(0.0, 0.6, 0.8);
        for g in [-0.7f32, 0.0, 0.4, 0.85] {
            let n = 400_000;
            let mut rng = Rng::new(3, 1, 0);
            let bins = 20;
            let mut hist = vec![0u32; bins];
            let mut mean = 0.0f64;
            for _ in 0..n {
                let wi = sample_phase(g, wo, rng.uniform(), rng.uniform());
                assert!((wi.length() - 1.0).abs() < 1e-4);
                let mu = wi.dot(wo).clamp(-1.0, 1.0);
                mean += f64::from(mu);
                hist[(((mu + 1.0) / 2.0 * bins as f32) as usize).min(bins - 1)] += 1;
            }
            mean /= n as f64;
            assert!((mean + f64::from(g)).abs() < 0.005, "g = {g}: mean {mean}");
            for (b, &count) in hist.iter().enumerate() {
                // The density of μ is (4π p)(μ)/2; its integral over the bin by the
                // midpoint rule on 50 points.
                let (lo, w) = (-1.0 + 2.0 * b as f64 / bins as f64, 2.0 / bins as f64);
                let want: f64 = (0..50)
                    .map(|i| {
                        let mu = lo + (i as f64 + 0.5) * w / 50.0;
                        f64::from(phase_hg(g, mu as f32)) / 2.0 * w / 50.0
                    })
                    .sum();
                let got = f64::from(count) / n as f64;
                assert!(
                    (got - want).abs() < 0.003 + 0.03 * want,
                    "g = {g}, bin {b}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn cosine_samples_have_mean_cosine_two_thirds() {
        let mut rng = Rng::new(5, 0, 0);
        let n = 200_000;
        let mean: f64 = (0..n)
            .map(|_| f64::from(cosine_hemisphere(rng.uniform(), rng.uniform())[2]))
            .sum::<f64>()
            / n as f64;
        assert!((mean - 2.0 / 3.0).abs() < 0.003, "{mean}");
    }
}
