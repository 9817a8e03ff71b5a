//! Under `path` lighting: each image's distance to a converged render of the exact
//! lobe (issue 29, item 5), and how fast a progressive render approaches it.
//!
//! A path-traced image carries Monte Carlo noise, so a lobe's difference from exact at
//! the same seed and samples per pixel says only part of the story: the converged
//! reference says whether that difference is visible next to the noise, which shrinks
//! as `1/sqrt(spp)`. The reference is traced with another seed
//! ([`REFERENCE_SEED_OFFSET`]), so it shares no random numbers with the images.

use std::time::{Duration, Instant};

use glint_analysis::image::{compare, ImageMetrics};
use glint_render::{Denoise, LightingModel, Renderer, Scene};

use crate::{shoot, CompareError, Comparison, Experiment, Reference, Shot};

/// Added (wrapping) to the scene's seed for the converged reference: the 64-bit golden
/// ratio constant (Knuth's multiplicative hashing), any value but 0 would do.
pub const REFERENCE_SEED_OFFSET: u64 = 0x9E37_79B9_7F4A_7C15;

/// Image size of a `path` comparison whose caller gives none (no size, no scene
/// file): small, so the converged reference takes tens of seconds.
pub const PATH_SIZE: [u32; 2] = [128, 128];

/// Samples per pixel of a `path` comparison's images when the scene sets none.
pub const PATH_SPP: u32 = 16;

/// The converged reference's samples per pixel when none is asked for: this many times
/// the images'.
pub const REFERENCE_SPP_FACTOR: u32 = 16;

/// Applies a comparison's `path` defaults to `scene`: [`PATH_SPP`] samples per pixel
/// unless it sets them, and [`PATH_SIZE`] unless `size_given`. Scenes of other lighting
/// models are left as they are. `glint compare`, `glint.compare` and the viewer's split
/// view share it, so their numbers agree.
pub fn path_defaults(scene: &mut Scene, size_given: bool) {
    if scene.lighting.model != LightingModel::Path {
        return;
    }
    if !size_given {
        scene.size = PATH_SIZE;
    }
    scene.lighting.spp.get_or_insert(PATH_SPP);
}

/// The converged reference's samples per pixel for `scene`: `requested` (0: none),
/// else [`REFERENCE_SPP_FACTOR`] times the images'; `None` for scenes not lit by
/// `path`. An error when the request does not exceed the images' samples.
pub fn reference_spp(scene: &Scene, requested: Option<u32>) -> Result<Option<u32>, CompareError> {
    let l = &scene.lighting;
    if l.model != LightingModel::Path {
        if requested.is_some_and(|s| s > 0) {
            return Err(CompareError::Invalid(
                "a converged reference needs path lighting".into(),
            ));
        }
        return Ok(None);
    }
    let own = l.spp.unwrap_or(PATH_SPP);
    match requested {
        Some(0) => Ok(None),
        Some(s) if s <= own => Err(CompareError::Invalid(format!(
            "the reference's {s} samples per pixel must exceed the images' {own}"
        ))),
        Some(s) => Ok(Some(s)),
        None => Ok(Some(own.saturating_mul(REFERENCE_SPP_FACTOR))),
    }
}

/// One image's distance to the converged reference.
#[derive(Clone, Debug)]
pub struct ConvergedRow {
    /// The lobe's name (`exact` for the exact lobe at the images' samples).
    pub label: String,
    /// Metrics over the whole image.
    pub image: ImageMetrics,
    /// Metrics over the exact image's highlight (`None` when it is empty).
    pub highlight: Option<ImageMetrics>,
}

/// The exact lobe traced with many samples per pixel, and each image's distance to it.
#[derive(Clone, Debug)]
pub struct Converged {
    /// The reference's samples per pixel.
    pub spp: u32,
    /// The reference's seed.
    pub seed: u64,
    /// The reference.
    pub shot: Shot,
    /// The exact image at the scene's samples, then one row per lobe, in order.
    pub rows: Vec<ConvergedRow>,
}

/// `scene` (a resolved `path` scene) with the exact lobe, `spp` samples per pixel and
/// the reference's seed; an error when the scene is not `path` or already has `spp`
/// samples or more.
fn reference_scene(scene: &Scene, spp: u32) -> Result<(Scene, u64), CompareError> {
    let mut s = scene.with_exact_lobe();
    s.derived = None;
    let l = &mut s.lighting;
    if l.model != LightingModel::Path {
        return Err(CompareError::Invalid(format!(
            "a converged reference needs --lighting path (the scene's lighting is {})",
            l.model.name()
        )));
    }
    let own = l.spp.unwrap_or(glint_render::DEFAULT_SPP);
    if spp <= own {
        return Err(CompareError::Invalid(format!(
            "the reference's {spp} samples per pixel must exceed the images' {own}"
        )));
    }
    let seed = l.seed.unwrap_or(0).wrapping_add(REFERENCE_SEED_OFFSET);
    // The reference is the mean of its samples: never denoised.
    l.denoise = None;
    l.spp = Some(spp);
    l.seed = Some(seed);
    Ok((s, seed))
}

impl Experiment {
    /// Traces the exact lobe of `reference`'s scene with `spp` samples per pixel and
    /// another seed, and measures the exact image and each of `rows` against it.
    pub fn converged(
        &mut self,
        reference: &Reference,
        rows: &[Comparison],
        spp: u32,
    ) -> Result<Converged, CompareError> {
        let (scene, seed) = reference_scene(&reference.shot.rendered.scene, spp)?;
        let shot = shoot(&mut self.renderer, &scene)?;
        let images = std::iter::once(("exact".to_string(), &reference.shot))
            .chain(rows.iter().map(|c| (c.lobe.name().to_string(), &c.shot)));
        let rows = images
            .map(|(label, test)| {
                let (image, highlight) = compare(&shot.srgb, &test.srgb, Some(&reference.mask))?;
                Ok(ConvergedRow {
                    label,
                    image,
                    highlight,
                })
            })
            .collect::<Result<_, CompareError>>()?;
        Ok(Converged {
            spp,
            seed,
            shot,
            rows,
        })
    }
}

/// One step of a progressive render: the samples per pixel it holds, the wall time
/// since the first step began, and its distance to the converged reference.
#[derive(Clone, Copy, Debug)]
pub struct ConvergenceStep {
    /// Samples per pixel accumulated.
    pub spp: u32,
    /// The step's denoiser (the scene's `lighting.denoise`).
    pub denoise: Option<Denoise>,
    /// Wall time of all the steps' renders so far (not of the metrics).
    pub elapsed: Duration,
    /// Metrics against the reference over the whole image.
    pub image: ImageMetrics,
}

/// A progressive render's approach to its converged reference.
#[derive(Clone, Debug)]
pub struct Convergence {
    /// The reference's samples per pixel and seed.
    pub reference_spp: u32,
    /// The reference's seed.
    pub reference_seed: u64,
    /// The reference's render time.
    pub reference_time: Duration,
    /// The steps, in order.
    pub steps: Vec<ConvergenceStep>,
}

impl Convergence {
    /// The first step whose mean ꟻLIP is below `flip`, if any.
    pub fn first_below(&self, flip: f64) -> Option<&ConvergenceStep> {
        self.steps
            .iter()
            .find(|s| s.image.flip.is_some_and(|f| f < flip))
    }
}

/// Samples per pixel at which a progressive render is measured: `round(2^(k/2))` for
/// k = 0, 1, ... (1, 2, 3, 4, 6, 8, 11, 16, ...) up to `max`, which ends the list.
pub fn convergence_schedule(max: u32) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::new();
    for k in 0.. {
        let s = 2f64.powf(f64::from(k) / 2.0).round() as u32;
        if s >= max {
            break;
        }
        if out.last() != Some(&s) {
            out.push(s);
        }
    }
    out.push(max);
    out
}

/// Traces `scene` (lobe and all, `path` lighting) with `reference_spp` samples per pixel
/// and another seed, then progressively with the scene's own seed: the renderer keeps
/// its samples while only the count grows, so each step of `schedule` (increasing
/// samples per pixel) adds only its new samples, as the viewer's refinement does. Each
/// step's wall time is added up (the metrics are not timed); the reference renders
/// first, so the volume's classification is not in the steps' times. `progress` is told
/// each step as it is measured. Stops after the first step whose mean ꟻLIP is below
/// `stop_below`, if given.
pub fn convergence(
    renderer: Renderer,
    scene: &Scene,
    reference_spp: u32,
    schedule: &[u32],
    stop_below: Option<f64>,
    progress: &dyn Fn(&ConvergenceStep),
) -> Result<Convergence, CompareError> {
    let steps = Steps {
        schedule,
        stop_below,
        cold: false,
        denoisers: &[],
    };
    convergence_with(renderer, scene, reference_spp, &steps, progress)
}

/// The steps of [`convergence_with`].
#[derive(Clone, Copy, Debug)]
pub struct Steps<'a> {
    /// Samples per pixel of each step, increasing.
    pub schedule: &'a [u32],
    /// Stop (each denoiser's run) after the first step whose mean ꟻLIP is below it.
    pub stop_below: Option<f64>,
    /// Each step from no samples, timed alone (a cold start of the frame).
    pub cold: bool,
    /// The schedule is run once per denoiser (the scene's `lighting.denoise`), against
    /// the one reference; empty: once, with the scene's own.
    pub denoisers: &'a [Option<Denoise>],
}

/// [`convergence`] with more [`Steps`]: `cold` steps trace their samples from none
/// (the renderer forgets its samples first, as a frame after a camera move does),
/// each step's time its own render's (its denoising included), not the sum so far;
/// several denoisers measured against one reference.
pub fn convergence_with(
    mut renderer: Renderer,
    scene: &Scene,
    reference_spp: u32,
    steps_asked: &Steps,
    progress: &dyn Fn(&ConvergenceStep),
) -> Result<Convergence, CompareError> {
    let Steps {
        schedule,
        stop_below,
        cold,
        denoisers,
    } = *steps_asked;
    if schedule.is_empty() || schedule.windows(2).any(|w| w[0] >= w[1]) {
        return Err(CompareError::Invalid(
            "the progressive steps' samples per pixel must increase".into(),
        ));
    }
    let mut progressive = scene.clone();
    progressive.lighting.spp = Some(schedule[0]);
    let (mut reference, seed) = reference_scene(&progressive, reference_spp)?;
    // The reference keeps the scene's lobe: only the seed and the samples differ.
    reference.lobe = scene.lobe.clone();
    let start = Instant::now();
    let shot = shoot(&mut renderer, &reference)?;
    let reference_time = start.elapsed();
    let mut steps = Vec::new();
    let own = [scene.lighting.denoise];
    for &denoise in if denoisers.is_empty() {
        &own[..]
    } else {
        denoisers
    } {
        progressive.lighting.denoise = denoise;
        renderer.forget_paths();
        let mut elapsed = Duration::ZERO;
        for &spp in schedule {
            progressive.lighting.spp = Some(spp);
            if cold {
                renderer.forget_paths();
                elapsed = Duration::ZERO;
            }
            let start = Instant::now();
            let test = shoot(&mut renderer, &progressive)?;
            elapsed += start.elapsed();
            let (image, _) = compare(&shot.srgb, &test.srgb, None)?;
            let step = ConvergenceStep {
                spp,
                denoise,
                elapsed,
                image,
            };
            progress(&step);
            steps.push(step);
            if stop_below.is_some_and(|t| image.flip.is_some_and(|f| f < t)) {
                break;
            }
        }
    }
    Ok(Convergence {
        reference_spp,
        reference_seed: seed,
        reference_time,
        steps,
    })
}

#[cfg(test)]
mod tests {
    use glint_render::{Lighting, LobeSpec, Phantom, ReadOptions};

    use super::*;
    use crate::run_against;
    use glint_lobe::LobeKind;

    fn path_scene(spp: u32) -> Scene {
        Scene {
            lobe: LobeSpec {
                n: Some(40.0),
                ..LobeSpec::default()
            },
            lighting: Lighting {
                model: LightingModel::Path,
                spp: Some(spp),
                ..Lighting::default()
            },
            ..Scene::phantom(Phantom::SheppLogan, 24, [24, 20])
        }
    }

    fn mean_delta_e(m: &ImageMetrics) -> f64 {
        m.delta_e.expect("pixels were compared").mean
    }

    #[test]
    fn images_approach_the_converged_reference_as_samples_grow() {
        let report = |spp: u32| {
            let s = path_scene(spp);
            run_against(
                Renderer::open(&s, &ReadOptions::default()).unwrap(),
                &s,
                &[LobeKind::EnergyFit.into()],
                None,
                Some(48),
            )
            .unwrap()
        };
        let (few, more) = (report(1), report(12));
        for r in [&few, &more] {
            let c = r.converged.as_ref().expect("path lighting has a reference");
            assert_eq!(c.spp, 48);
            assert_eq!(c.seed, REFERENCE_SEED_OFFSET);
            let labels: Vec<_> = c.rows.iter().map(|r| r.label.as_str()).collect();
            assert_eq!(labels, ["exact", "k"]);
            assert!(r.text().contains("distance to the exact lobe at 48 spp"));
            assert_eq!(r.to_json().unwrap()["converged"]["rows"][1]["lobe"], "k");
        }
        let (a, b) = (
            few.converged.as_ref().unwrap(),
            more.converged.as_ref().unwrap(),
        );
        for (x, y) in a.rows.iter().zip(&b.rows) {
            let (dx, dy) = (mean_delta_e(&x.image), mean_delta_e(&y.image));
            assert!(
                dy < 0.8 * dx,
                "{}: mean ΔE {dx} at 1 spp, {dy} at 12",
                x.label
            );
            assert!(y.image.flip.unwrap() < x.image.flip.unwrap());
        }
        // Without path lighting there is no reference to trace.
        let local = Scene {
            lighting: Lighting::default(),
            ..path_scene(1)
        };
        assert!(matches!(
            run_against(
                Renderer::open(&local, &ReadOptions::default()).unwrap(),
                &local,
                &[LobeKind::EnergyFit.into()],
                None,
                Some(48),
            ),
            Err(CompareError::Invalid(_))
        ));
    }

    #[test]
    fn a_progressive_render_approaches_its_reference() {
        assert_eq!(convergence_schedule(20), [1, 2, 3, 4, 6, 8, 11, 16, 20]);
        assert_eq!(convergence_schedule(1), [1]);
        let s = path_scene(1);
        let renderer = Renderer::open(&s, &ReadOptions::default()).unwrap();
        let seen = std::cell::Cell::new(0);
        let conv = convergence(renderer, &s, 32, &[1, 4, 16], None, &|_| {
            seen.set(seen.get() + 1)
        })
        .unwrap();
        assert_eq!(seen.get(), 3);
        let spp: Vec<_> = conv.steps.iter().map(|s| s.spp).collect();
        assert_eq!(spp, [1, 4, 16]);
        let de: Vec<_> = conv.steps.iter().map(|s| mean_delta_e(&s.image)).collect();
        assert!(de[2] < de[1] && de[1] < de[0], "mean ΔE by step: {de:?}");
        assert!(conv.steps.windows(2).all(|w| w[0].elapsed <= w[1].elapsed));
        // A threshold between the first and last steps' ꟻLIP stops the run there.
        let flips: Vec<_> = conv.steps.iter().map(|s| s.image.flip.unwrap()).collect();
        let t = (flips[0] + flips[2]) / 2.0;
        let want = conv.first_below(t).unwrap().spp;
        let stopped = convergence(
            Renderer::open(&s, &ReadOptions::default()).unwrap(),
            &s,
            32,
            &[1, 4, 16],
            Some(t),
            &|_| {},
        )
        .unwrap();
        assert_eq!(stopped.steps.last().unwrap().spp, want);
        assert!(convergence(
            Renderer::open(&s, &ReadOptions::default()).unwrap(),
            &s,
            32,
            &[4, 4],
            None,
            &|_| {}
        )
        .is_err());
    }
}
