//! Progressive Monte Carlo volume path tracing of a classified field, with the
//! lighting model's one scattering model (glint-core's `Scattering` and `Bsdf`): free
//! paths by delta tracking, the lights by next-event estimation with ratio-tracked
//! transmittance (`Bsdf::f`), a uniform environment reached by the paths that leave
//! the volume, scattering directions importance-sampled (`Bsdf::sample`: the surface's
//! diffuse cosine and its specular lobe through glint-lobe's samplers, the medium's
//! Henyey-Greenstein phase function exactly), Russian roulette, and at most `bounces`
//! scattering events. The surface is chosen at a collision with the probability of
//! its weight (`Scattering::choose`), as Exposure Render chooses its BRDF (Kroes et
//! al. 2012).

use glint_core::camera::Camera;
use glint_core::{Bsdf, Image, RenderStats, Shader, Vec3};

use super::occluders::Occluders;
use super::rng::Rng;
use super::tracking::{IndexRay, Tracker};
use super::PathSettings;
use crate::classification::Medium;
use crate::clip::IndexClip;
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
    /// The shader, its lights placed for the camera (its sampler built:
    /// [`Shader::check_sampling`]).
    pub(crate) shader: &'a Shader,
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
        shader.check_sampling()?;
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
            track: Tracker {
                field,
                medium,
                clip: None,
            },
            shader,
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

    /// The tracer with `clip` (on its field) cutting away space: no collision, no
    /// extinction there, and cut faces lit by the plane's normal where the gradient
    /// is weak, as the ray caster lights them.
    pub(crate) fn clipped_by(mut self, clip: Option<&'a IndexClip>) -> PathTracer<'a> {
        self.track.clip = clip;
        self
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
        // A point of the lens (thin-lens depth of field; a pinhole draws none).
        let lens = self
            .camera
            .has_lens()
            .then(|| [rng.uniform(), rng.uniform()]);
        let (eye, dir) = self
            .camera
            .lens_ray(x as f32 + jx, y as f32 + jy, w, h, lens);
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
            let mut grad = field.gradient(p);
            if let Some(clip) = self.track.clip {
                grad = clip.cut_gradient(p, grad);
            }
            let bsdf = self.shader.scattering(color, grad).choose(|| rng.uniform());
            self.direct(p, &bsdf, wo, &mut rng, beta, &mut radiance);
            let u = [rng.uniform(), rng.uniform(), rng.uniform()];
            let Some(sample) = bsdf.sample(wo, u) else {
                break;
            };
            let (wi, weight) = (sample.wi, sample.weight);
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
            t0 = if bsdf.is_surface() {
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

    /// Adds the lights' direct contribution at `p` through `bsdf` towards `wo`
    /// (next-event estimation), each light's transmittance estimated by ratio
    /// tracking.
    #[inline]
    fn direct(
        &self,
        p: Vec3,
        bsdf: &Bsdf<'_>,
        wo: Vec3,
        rng: &mut Rng,
        beta: [f32; 3],
        radiance: &mut [f32; 3],
    ) {
        let t0 = if bsdf.is_surface() {
            self.surface_bias
        } else {
            0.0
        };
        for &(l, l_index, intensity) in &self.lights {
            let response = bsdf.f(wo, l);
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
}
