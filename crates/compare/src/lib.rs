//! glint-compare: the image-accuracy experiment of glint. One scene is rendered with
//! the exact `cos^n` lobe and with cheaper lobes, and each image is compared with the
//! exact one as a viewer sees it (the 8-bit sRGB a PNG holds): PSNR, SSIM, CIEDE2000
//! ΔE and ꟻLIP, over the whole image and over the highlight (the pixels where the exact
//! image's specular term exceeds [`HIGHLIGHT_FRACTION`] of its maximum). [`sweep`]
//! repeats it over n and v. The command line (`glint compare`), the viewer and the
//! Python module (`glint.compare`) all run this code, so they report the same numbers.
//!
//! ```
//! use glint_render::{Input, LobeSpec, Phantom, ReadOptions, Renderer, Scene, SceneLobe};
//! use glint_lobe::LobeKind;
//!
//! let scene = Scene {
//!     input: Input::Phantom { name: Phantom::SheppLogan, size: 24 },
//!     size: [32, 32],
//!     lobe: LobeSpec { n: Some(60.0), ..LobeSpec::default() },
//!     ..Scene::default()
//! };
//! let renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
//! let report = glint_compare::run(renderer, &scene, &[LobeKind::EnergyFit.into()], None).unwrap();
//! let row = &report.rows[0];
//! assert_eq!(row.lobe, SceneLobe::Float(LobeKind::EnergyFit));
//! // K_4 is close to cos^60: a high PSNR, an SSIM near 1.
//! assert!(row.image.psnr.unwrap() > 30.0);
//! assert!(row.image.ssim.unwrap() > 0.9);
//! assert_eq!(report.to_json().unwrap()["comparisons"][0]["lobe"], "k");
//! ```

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod converged;
mod report;
mod sweep;

use std::time::Duration;

use glint_analysis::image::{compare, delta_e_map, highlight_mask, ImageMetrics, Srgb8Image};
use glint_analysis::AnalysisError;
use glint_render::{luminance_f32, Depth, RenderError, Rendered, Renderer, Scene, SceneLobe};

pub use converged::{
    convergence, convergence_schedule, convergence_with, path_defaults, reference_spp, Converged,
    ConvergedRow, Convergence, ConvergenceStep, Steps, PATH_SIZE, PATH_SPP, REFERENCE_SEED_OFFSET,
    REFERENCE_SPP_FACTOR,
};
pub use glint_analysis::image::{DELTA_E_SCALE_MAX, HIGHLIGHT_FRACTION};
pub use sweep::{sweep, Sweep, SweepRow, SweepSpec, SWEEP_LOBES, SWEEP_N, SWEEP_V};

/// Why the experiment could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CompareError {
    /// A render failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A metric, the figure or an output failed.
    #[error(transparent)]
    Analysis(#[from] AnalysisError),
    /// The experiment was asked something it cannot do.
    #[error("{0}")]
    Invalid(String),
    /// Writing an output failed (the error names the file).
    #[error(transparent)]
    Write(#[from] glint_io::IoError),
}

/// A render and its 8-bit sRGB image (the PNG's samples).
#[derive(Clone, Debug)]
pub struct Shot {
    /// The render: image, resolved scene, stage times.
    pub rendered: Rendered,
    /// Its 8-bit sRGB samples, on which the metrics are taken.
    pub srgb: Srgb8Image,
}

/// The exact render of a scene and what the lobes are compared with.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The exact render.
    pub shot: Shot,
    /// Pixels where the exact specular term exceeds [`HIGHLIGHT_FRACTION`] of its
    /// maximum.
    pub mask: Vec<bool>,
}

impl Reference {
    /// How many pixels the highlight has.
    pub fn highlight_pixels(&self) -> usize {
        self.mask.iter().filter(|&&m| m).count()
    }
}

/// One lobe compared with exact.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// The lobe.
    pub lobe: SceneLobe,
    /// The unit of a `hw` lobe.
    pub hw: Option<glint_hw::Config>,
    /// Its shininess and v, as rendered.
    pub n: f64,
    /// The lobe's v (the power fits' 2^v, the unit's).
    pub v: u32,
    /// Its frame time.
    pub frame: Duration,
    /// The render.
    pub shot: Shot,
    /// Per pixel, CIEDE2000 ΔE against exact.
    pub delta_e: Vec<f64>,
    /// Metrics over the whole image.
    pub image: ImageMetrics,
    /// Metrics over the highlight (`None` when it is empty).
    pub highlight: Option<ImageMetrics>,
}

impl Comparison {
    /// Whether the lobe has a v to show (the power fits and the unit).
    pub fn uses_v(&self) -> bool {
        self.lobe.float().is_none_or(|k| k.uses_v())
    }
}

/// The experiment on one renderer: the scene's volume read and classified once, the
/// image without specular light rendered once.
pub struct Experiment {
    renderer: Renderer,
    /// The scene without specular light (it depends on neither the lobe nor n).
    dark: Rendered,
}

/// `scene` without specular light.
fn dark_scene(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.material.specular = Some(0.0);
    s
}

/// Renders `scene` with the shared renderer.
fn shoot(renderer: &mut Renderer, scene: &Scene) -> Result<Shot, CompareError> {
    let rendered = renderer.render(scene, &|_| {})?;
    let img = &rendered.image;
    let srgb = Srgb8Image::from_bytes(img.width, img.height, &img.encode_srgb(Depth::Eight))?;
    Ok(Shot { rendered, srgb })
}

/// The specular term's contribution per pixel: the luminance of `full` minus that of
/// the same scene rendered without specular (`dark`), in linear light, at least 0.
fn specular_term(full: &Rendered, dark: &Rendered) -> Vec<f32> {
    full.image
        .rgb
        .iter()
        .zip(&dark.image.rgb)
        .map(|(a, b)| (luminance_f32(*a) - luminance_f32(*b)).max(0.0))
        .collect()
}

impl Experiment {
    /// Starts the experiment on `renderer` (which holds `scene`'s volume and meshes):
    /// renders the scene without specular light.
    pub fn new(mut renderer: Renderer, scene: &Scene) -> Result<Experiment, CompareError> {
        let dark = renderer.render(&dark_scene(&scene.with_exact_lobe()), &|_| {})?;
        Ok(Experiment { renderer, dark })
    }

    /// The render without specular light (its stage times include the classification).
    pub fn dark(&self) -> &Rendered {
        &self.dark
    }

    /// The exact render of `scene` (its lobe made exact) and its highlight mask.
    pub fn reference(&mut self, scene: &Scene) -> Result<Reference, CompareError> {
        let shot = shoot(&mut self.renderer, &scene.with_exact_lobe())?;
        let mask = highlight_mask(&specular_term(&shot.rendered, &self.dark));
        Ok(Reference { shot, mask })
    }

    /// The reference's scene rendered with `lobe` and compared with it. `v` sets the
    /// lobe's v; without it a `hw` lobe takes its unit's and the others the
    /// reference's ([`glint_render::LobeSpec::set_kind`]).
    pub fn compare(
        &mut self,
        reference: &Reference,
        lobe: SceneLobe,
        v: Option<u32>,
    ) -> Result<Comparison, CompareError> {
        let mut scene = reference.shot.rendered.scene.clone();
        scene.derived = None;
        scene.lobe.set_kind(lobe, v);
        let shot = shoot(&mut self.renderer, &scene)?;
        let exact = &reference.shot.srgb;
        let (image, highlight) = compare(exact, &shot.srgb, Some(&reference.mask))?;
        let resolved = &shot.rendered.scene.lobe;
        Ok(Comparison {
            lobe,
            hw: resolved.hw.clone().filter(|_| lobe == SceneLobe::Hw),
            n: resolved.n.unwrap_or_default(),
            v: resolved.v,
            frame: shot.rendered.timings.get("frame"),
            delta_e: delta_e_map(exact, &shot.srgb)?,
            shot,
            image,
            highlight,
        })
    }
}

/// The result of [`run`]: the reference and one comparison per lobe.
pub struct Report {
    /// The render without specular light (its `classify` time is the run's).
    pub dark: Rendered,
    /// The exact render.
    pub reference: Reference,
    /// One row per lobe, in the order asked.
    pub rows: Vec<Comparison>,
    /// Under `path` lighting, when asked: each image's distance to the exact lobe
    /// traced with many samples ([`run_against`]).
    pub converged: Option<Converged>,
}

/// Renders `scene` with the exact lobe and with each of `lobes` (v: see
/// [`Experiment::compare`]) and compares them.
pub fn run(
    renderer: Renderer,
    scene: &Scene,
    lobes: &[SceneLobe],
    v: Option<u32>,
) -> Result<Report, CompareError> {
    run_against(renderer, scene, lobes, v, None)
}

/// [`run`], and with `reference_spp` (a `path` scene only) each image's distance to
/// the exact lobe traced with that many samples per pixel
/// ([`Experiment::converged`]).
pub fn run_against(
    renderer: Renderer,
    scene: &Scene,
    lobes: &[SceneLobe],
    v: Option<u32>,
    reference_spp: Option<u32>,
) -> Result<Report, CompareError> {
    if lobes.is_empty() {
        return Err(CompareError::Invalid(
            "no lobe to compare with exact: give at least one".into(),
        ));
    }
    let mut experiment = Experiment::new(renderer, scene)?;
    let reference = experiment.reference(scene)?;
    let rows: Vec<Comparison> = lobes
        .iter()
        .map(|&lobe| experiment.compare(&reference, lobe, v))
        .collect::<Result<_, _>>()?;
    let converged = reference_spp
        .map(|spp| experiment.converged(&reference, &rows, spp))
        .transpose()?;
    Ok(Report {
        dark: experiment.dark,
        reference,
        rows,
        converged,
    })
}

#[cfg(test)]
mod tests {
    use glint_lobe::LobeKind;
    use glint_render::{LobeSpec, Phantom, ReadOptions};

    use super::*;

    fn scene() -> Scene {
        Scene {
            lobe: LobeSpec {
                n: Some(80.0),
                ..LobeSpec::default()
            },
            ..Scene::phantom(Phantom::SheppLogan, 24, [32, 28])
        }
    }

    #[test]
    fn exact_against_itself_is_identical_and_the_highlight_is_where_the_specular_is() {
        let s = scene();
        let report = run(
            Renderer::open(&s, &ReadOptions::default()).unwrap(),
            &s,
            &[LobeKind::Exact.into()],
            None,
        )
        .unwrap();
        let row = &report.rows[0];
        // The same render twice: no ΔE anywhere.
        assert!(row.delta_e.iter().all(|&d| d == 0.0));
        assert_eq!(row.image.delta_e.unwrap().max, 0.0);
        // The highlight mask is the pixels where the specular term is over 10% of its
        // maximum, recomputed here from the two renders.
        let spec = specular_term(&report.reference.shot.rendered, &report.dark);
        let max = spec.iter().cloned().fold(0.0f32, f32::max);
        assert!(max > 0.0);
        let want: Vec<bool> = spec
            .iter()
            .map(|&x| f64::from(x) > HIGHLIGHT_FRACTION * f64::from(max))
            .collect();
        assert_eq!(report.reference.mask, want);
        assert!(report.reference.highlight_pixels() > 0);
    }

    #[test]
    fn no_lobe_is_an_error_and_a_sweep_covers_every_point() {
        let s = scene();
        assert!(matches!(
            run(
                Renderer::open(&s, &ReadOptions::default()).unwrap(),
                &s,
                &[],
                None
            ),
            Err(CompareError::Invalid(_))
        ));
        let spec = SweepSpec {
            ns: vec![20.0, 80.0],
            vs: vec![3, 4],
            lobes: vec![LobeKind::EnergyFit, LobeKind::Schlick],
        };
        let done = std::cell::Cell::new(0);
        let sweep = sweep(
            Renderer::open(&s, &ReadOptions::default()).unwrap(),
            &s,
            &spec,
            &|_| done.set(done.get() + 1),
        )
        .unwrap();
        // Per n: K_v at each v, Schlick once.
        assert_eq!(sweep.rows.len(), 2 * (2 + 1));
        assert_eq!(done.get(), sweep.rows.len());
        assert_eq!(sweep.csv().lines().count(), 1 + 2 * sweep.rows.len());
        let k80: Vec<_> = sweep
            .rows
            .iter()
            .filter(|r| r.kind == LobeKind::EnergyFit && r.n == 80.0)
            .collect();
        assert_eq!(
            k80.iter().map(|r| r.v).collect::<Vec<_>>(),
            [Some(3), Some(4)]
        );
        let bad = SweepSpec {
            ns: vec![0.0],
            ..spec
        };
        assert!(sweep_is_refused(&s, &bad));
    }

    fn sweep_is_refused(s: &Scene, spec: &SweepSpec) -> bool {
        sweep(
            Renderer::open(s, &ReadOptions::default()).unwrap(),
            s,
            spec,
            &|_| {},
        )
        .is_err()
    }
}
