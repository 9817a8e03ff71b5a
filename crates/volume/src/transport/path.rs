//! Progressive Monte Carlo volume path tracing of a classified field, with the
//! lighting model's one scattering model (glint-core's `Scattering` and `Bsdf`): free
//! paths by delta tracking, the lights by next-event estimation with ratio-tracked
//! transmittance (`Bsdf::f`), a uniform environment reached by the paths that leave
//! the volume, scattering directions importance-sampled (`Bsdf::sample`: the surface's
//! diffuse cosine and its specular lobe through glint-lobe's samplers, the medium's
//! Henyey-Greenstein phase function exactly), Russian roulette, and at most `bounces`
//! scattering events. The surface is chosen at a collision with the probability of
//! its weight (`Scattering::choose`), as Exposure Render chooses its BRDF (Kroes et
//! al. 2012). An environment map, when the scene has one, replaces the uniform
//! environment and is sampled by MIS with the scattering model (`envlight.rs`).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use glint_core::camera::Camera;
use glint_core::{Bsdf, EnvMap, Image, RenderError, RenderStats, Shader, Vec3};

use super::occluders::Occluders;
use super::rng::{dims, Rng};
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

/// Samples every pixel takes before its variance decides whether it takes more, under
/// a time budget (the variance of fewer is too unsure to steer by).
pub const ADAPTIVE_MIN_SAMPLES: u32 = 4;

/// The relative standard error of a pixel's mean luminance (standard error over the
/// mean) below which adaptive passes leave it: about 1/4 of a just visible step of a
/// mid-grey (Cycles' adaptive threshold is 0.01 by default on a similar measure).
pub const ADAPTIVE_THRESHOLD: f64 = 0.02;

/// The running sums of a progressive path-traced image: per pixel the sums of the
/// samples' radiance and coverage and of their luminance squared, in sample order,
/// and how many samples each holds. The image is the same bit for bit for the same
/// samples per pixel however they were added (one batch or many), since each pixel
/// adds its samples one by one in sample order, sample `s` of pixel `p` the same
/// path whenever it is taken.
#[derive(Clone, Debug)]
pub struct PathImage {
    width: u32,
    height: u32,
    /// Per pixel: radiance (premultiplied by coverage) and coverage, summed.
    sums: Vec<[f64; 4]>,
    /// Per pixel: the sum of the samples' luminance squared (their variance).
    squares: Vec<f64>,
    /// Per pixel: samples taken.
    counts: Vec<u32>,
    /// The fewest samples a pixel holds.
    samples: u32,
    stats: RenderStats,
}

impl PathImage {
    /// An image of no samples.
    pub fn new(width: u32, height: u32) -> PathImage {
        let n = width as usize * height as usize;
        PathImage {
            width,
            height,
            sums: vec![[0.0; 4]; n],
            squares: vec![0.0; n],
            counts: vec![0; n],
            samples: 0,
            stats: RenderStats::default(),
        }
    }

    /// Width and height.
    pub fn size(&self) -> [u32; 2] {
        [self.width, self.height]
    }

    /// Samples per pixel so far: the fewest any pixel holds (every pixel holds as
    /// many unless a time budget spent samples where the noise is).
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Samples each pixel holds, row by row.
    pub fn sample_counts(&self) -> &[u32] {
        &self.counts
    }

    /// The relative standard error of pixel `i`'s mean luminance: the standard error
    /// `sqrt(var / n)` over the mean (0 for a pixel of no light or fewer than two
    /// samples).
    pub fn relative_error(&self, i: usize) -> f64 {
        let n = f64::from(self.counts[i]);
        if n < 2.0 {
            return 0.0;
        }
        let [r, g, b, _] = self.sums[i];
        let mean = (0.2126 * r + 0.7152 * g + 0.0722 * b) / n;
        if mean <= 0.0 {
            return 0.0;
        }
        let var = ((self.squares[i] / n - mean * mean) * n / (n - 1.0)).max(0.0);
        (var / n).sqrt() / mean
    }

    /// Per pixel, the variance of its mean luminance (the samples' unbiased variance
    /// over their number), row by row; NaN where a pixel holds fewer than two samples.
    /// What the denoiser's colour weight measures differences against.
    pub fn variance_of_mean(&self) -> Vec<f32> {
        (self.sums.iter().zip(&self.squares).zip(&self.counts))
            .map(|((&[r, g, b, _], &square), &count)| {
                let n = f64::from(count);
                if n < 2.0 {
                    return f32::NAN;
                }
                let mean = (0.2126 * r + 0.7152 * g + 0.0722 * b) / n;
                (((square / n - mean * mean) * n / (n - 1.0)).max(0.0) / n) as f32
            })
            .collect()
    }

    /// The mean of the samples over `background` (linear RGB): the rendered image.
    /// `stats.samples` counts paths, `stats.shaded` scattering events.
    pub fn image(&self, background: [f32; 3]) -> Image {
        let (rgb, alpha) = self
            .sums
            .iter()
            .zip(&self.counts)
            .map(|(s, &n)| {
                let n = f64::from(n.max(1));
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

    /// Adds samples to each pixel until it holds `targets[pixel]` (no fewer than it
    /// holds), rows in parallel; rows not begun when `pass.cancel` is set are left.
    fn add_pass(&mut self, tracer: &PathTracer<'_>, targets: &[u32], pass: &Pass<'_>) {
        let w = self.width as usize;
        let stats = self
            .sums
            .par_chunks_mut(w)
            .zip(self.squares.par_chunks_mut(w))
            .zip(self.counts.par_chunks_mut(w))
            .enumerate()
            .map(|(y, ((sums, squares), counts))| {
                let mut stats = RenderStats::default();
                if pass.cancel.load(Ordering::Relaxed) {
                    return stats;
                }
                let row = (sums.iter_mut().zip(squares).zip(counts.iter_mut())).enumerate();
                for (x, ((sum, square), count)) in row {
                    let i = y * w + x;
                    let limit = pass.far.map_or(f32::INFINITY, |f| f[i]);
                    for s in *count..targets[i] {
                        let r = tracer.trace(x as u32, y as u32, s, limit);
                        for (acc, &x) in sum.iter_mut().zip(&r.radiance) {
                            *acc += f64::from(x);
                        }
                        sum[3] += f64::from(r.coverage);
                        let [cr, cg, cb] = r.radiance.map(f64::from);
                        let lum = 0.2126 * cr + 0.7152 * cg + 0.0722 * cb;
                        *square += lum * lum;
                        stats.samples += 1;
                        stats.shaded += u64::from(r.events);
                    }
                    *count = (*count).max(targets[i]);
                }
                (pass.progress)(w as u64);
                stats
            })
            .reduce(RenderStats::default, |a, b| RenderStats {
                samples: a.samples + b.samples,
                shaded: a.shaded + b.shaded,
                skips: a.skips + b.skips,
            });
        self.samples = self.counts.iter().copied().min().unwrap_or(0);
        self.stats.samples += stats.samples;
        self.stats.shaded += stats.shaded;
        self.stats.skips += stats.skips;
    }

    /// Adds samples with `tracer` (its size this image's): every pixel to `spp`
    /// without a time budget (`tracer`'s settings); with one, passes until the
    /// budget is spent ([`PathImage::adaptive`]). Errors with
    /// [`RenderError::Cancelled`] when `pass.cancel` was set (the image then holds
    /// part of a pass and must be dropped).
    pub(crate) fn trace(
        &mut self,
        tracer: &PathTracer<'_>,
        spp: u32,
        pass: &Pass<'_>,
    ) -> Result<(), RenderError> {
        match tracer.settings.time_budget {
            None => {
                let targets: Vec<u32> = self.counts.iter().map(|&n| n.max(spp)).collect();
                self.add_pass(tracer, &targets, pass);
            }
            Some(budget) => self.adaptive(tracer, spp, budget, pass),
        }
        if pass.cancel.load(Ordering::Relaxed) {
            return Err(RenderError::Cancelled);
        }
        Ok(())
    }

    /// Passes of samples until `budget` is spent, each a deterministic function of
    /// the image before it: one sample to every pixel until each holds
    /// [`ADAPTIVE_MIN_SAMPLES`] (or `spp`), then one more to each pixel below `spp`
    /// whose [`PathImage::relative_error`] is above [`ADAPTIVE_THRESHOLD`]. A pass
    /// starts only when the last one's time per sample says it ends within the budget
    /// (the first always runs); none starts once no pixel needs one.
    fn adaptive(&mut self, tracer: &PathTracer<'_>, spp: u32, budget: Duration, pass: &Pass<'_>) {
        let start = Instant::now();
        let mut per_sample: Option<f64> = None;
        loop {
            let uniform = ADAPTIVE_MIN_SAMPLES.min(spp);
            let targets: Vec<u32> = if self.samples < uniform {
                self.counts
                    .iter()
                    .map(|&n| n.max(self.samples + 1))
                    .collect()
            } else {
                let over = |i: usize| self.relative_error(i) > ADAPTIVE_THRESHOLD;
                (self.counts.iter().enumerate())
                    .map(|(i, &n)| if n < spp && over(i) { n + 1 } else { n })
                    .collect()
            };
            let added: u64 = (targets.iter().zip(&self.counts))
                .map(|(&t, &n)| u64::from(t - n))
                .sum();
            if added == 0 {
                return;
            }
            if let Some(cost) = per_sample {
                let left = budget.as_secs_f64() - start.elapsed().as_secs_f64();
                if cost * added as f64 > left {
                    return;
                }
            }
            let t = Instant::now();
            self.add_pass(tracer, &targets, pass);
            if pass.cancel.load(Ordering::Relaxed) {
                return;
            }
            per_sample = Some(t.elapsed().as_secs_f64() / added as f64);
        }
    }
}

/// What a frame's passes read besides the tracer: the rays' limits, the cancel flag,
/// the progress callback (rows).
pub(crate) struct Pass<'a> {
    pub(crate) far: Option<&'a [f32]>,
    pub(crate) cancel: &'a AtomicBool,
    pub(crate) progress: &'a (dyn Fn(u64) + Sync),
}

/// Which strategies light a path by the environment map (`envlight.rs`): both,
/// weighted by multiple importance sampling (what renders use), or one alone (to
/// measure MIS against).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum EnvStrategy {
    /// The map's sampling and the scattering model's, by the power heuristic.
    #[default]
    Mis,
    /// Next-event estimation of the map only (paths that leave see nothing).
    #[allow(dead_code)]
    Light,
    /// The scattering model's directions only (no next-event estimation of the map).
    #[allow(dead_code)]
    Scatter,
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
    /// The environment map that replaces the uniform environment, when the scene has
    /// one.
    pub(crate) env_map: Option<&'a EnvMap>,
    /// How the map lights the paths (MIS but in tests).
    pub(crate) env_strategy: EnvStrategy,
    /// How the shader's area lights light the paths (MIS but in tests).
    pub(crate) area_strategy: EnvStrategy,
    /// Russian roulette on the map's shadow rays: a ray whose unshadowed contribution
    /// is below this times the map's mean radiance is traced with probability
    /// contribution / (this times the mean), its result divided by it; 0 traces every
    /// one (`envlight.rs`, `env_survival`).
    pub(crate) env_roulette: f32,
}

/// [`PathTracer::env_roulette`]'s default (measured in docs/lighting.md, "Environment
/// maps", Cost).
pub(crate) const ENV_ROULETTE: f32 = 1.0;

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
            .directional_lights()
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
            env_map: None,
            env_strategy: EnvStrategy::Mis,
            area_strategy: EnvStrategy::Mis,
            env_roulette: ENV_ROULETTE,
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

    /// The tracer with `map` (when given) as its environment instead of the uniform
    /// one.
    pub(crate) fn lit_by(mut self, map: Option<&'a EnvMap>) -> PathTracer<'a> {
        self.env_map = map;
        self
    }

    /// Where `ray` meets the meshes past `t0` (its first cell excluded).
    #[inline]
    pub(super) fn mesh_hit_from(&self, ray: &IndexRay, t0: f32) -> Option<f32> {
        self.mesh_hit(ray, t0, f32::INFINITY)
    }

    /// Where `ray` meets the meshes over `[t0, t1]` (its first cell excluded).
    #[inline]
    pub(super) fn mesh_hit_between(&self, ray: &IndexRay, t0: f32, t1: f32) -> Option<f32> {
        self.mesh_hit(ray, t0, t1)
    }

    /// The index-space direction of world direction `v`.
    #[inline]
    pub(super) fn index_dir(&self, v: Vec3) -> Vec3 {
        self.to_index(v)
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
        let mut rng = Rng::for_path(self.settings.sampler, self.settings.seed, pixel, sample);
        // A point of the pixel's square, uniformly (anti-aliasing).
        let jx = rng.dim(dims::JITTER) - 0.5;
        let jy = rng.dim(dims::JITTER + 1) - 0.5;
        // A point of the lens (thin-lens depth of field; a pinhole draws none).
        let lens = self
            .camera
            .has_lens()
            .then(|| [rng.dim(dims::LENS), rng.dim(dims::LENS + 1)]);
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
        // The density of the last scattered direction (MIS with an environment map).
        let mut scatter_pdf = 0.0f32;
        loop {
            // Camera rays stop at the meshes' depth (`far`); scattered rays at their
            // cells, where the path ends (meshes absorb), or at an area light.
            let (mesh, area) = self.stops(&ray, wdir, (t0, t1), events);
            let end = area.map_or(mesh.unwrap_or(t1), |(_, t)| t);
            // This event's block of dimensions (the sampler's layout, `rng::dims`).
            let block = dims::event(events);
            rng.window(block + dims::FREE_PATH, 2);
            let hit = self.track.free_path(&ray, t0, end, &mut rng);
            rng.close();
            let Some(t) = hit else {
                // A scattered path that meets an area light ends there; one that
                // leaves sees the environment; a camera ray sees it, and the area
                // lights, (opaque) where the scene shows it and no mesh is behind.
                let seen = if events == 0 {
                    self.settings.show_environment && t1 == f32::INFINITY
                } else {
                    mesh.is_none()
                };
                let l = match area {
                    Some((i, _)) => Some(self.area_escape(i, ray.o, wdir, (scatter_pdf, events))),
                    None => seen.then(|| self.escaped(wdir, events, scatter_pdf)),
                };
                if let Some(l) = l {
                    for c in 0..3 {
                        radiance[c] += beta[c] * l[c];
                    }
                    coverage = 1.0;
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
            let bsdf = self
                .shader
                .scattering(color, grad)
                .choose(|| rng.dim(block + dims::CHOOSE));
            self.direct(p, &bsdf, wo, (&mut rng, block), beta, &mut radiance);
            if let Some(map) = self.env_map {
                let at = (p, &bsdf, wo);
                self.env_direct(map, at, (&mut rng, events - 1), beta, &mut radiance);
            }
            self.area_direct((p, &bsdf, wo), (&mut rng, events - 1), beta, &mut radiance);
            let u = [
                rng.dim(block + dims::LOBE),
                rng.dim(block + dims::DIRECTION),
                rng.dim(block + dims::DIRECTION + 1),
            ];
            let Some(sample) = bsdf.sample(wo, u) else {
                break;
            };
            let (wi, weight) = (sample.wi, sample.weight);
            scatter_pdf = sample.pdf;
            for c in 0..3 {
                beta[c] *= weight[c];
            }
            if events >= ROULETTE_AFTER {
                let q = beta[0].max(beta[1]).max(beta[2]).min(MAX_SURVIVAL);
                if rng.dim(block + dims::ROULETTE) >= q || q.is_nan() {
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
    /// tracking (the first light's first tentative collision from the event `block`'s
    /// dimensions).
    #[inline]
    fn direct(
        &self,
        p: Vec3,
        bsdf: &Bsdf<'_>,
        wo: Vec3,
        (rng, block): (&mut Rng, u32),
        beta: [f32; 3],
        radiance: &mut [f32; 3],
    ) {
        let t0 = if bsdf.is_surface() {
            self.surface_bias
        } else {
            0.0
        };
        for (i, &(l, l_index, intensity)) in self.lights.iter().enumerate() {
            let response = bsdf.f(wo, l);
            if response == [0.0; 3] || intensity == 0.0 {
                continue;
            }
            let shadow = IndexRay { o: p, d: l_index };
            if self.mesh_hit(&shadow, t0, f32::INFINITY).is_some() {
                continue;
            }
            if i == 0 {
                rng.window(block + dims::TRANSMIT, 2);
            }
            let tr = self.track.transmittance(&shadow, t0, f32::INFINITY, rng);
            rng.close();
            if tr > 0.0 {
                for c in 0..3 {
                    radiance[c] += beta[c] * response[c] * (intensity * tr);
                }
            }
        }
    }
}
