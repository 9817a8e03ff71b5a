//! The experiment over n and v: a table (CSV and Markdown) and plots of ΔE against n.

use std::path::Path;
use std::time::Duration;

use glint_analysis::image::{sweep_plot, ImageMetrics, SweepSeries};
use glint_analysis::{check_lists, fmt_num, lobe_label};
use glint_lobe::LobeKind;
use glint_render::{Input, Renderer, Scene};

use crate::report::{input_name, ms, num};
use crate::{CompareError, Experiment};

/// The n of the default sweep (issue 13, item 3).
pub const SWEEP_N: [f64; 7] = [10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0];
/// The v of the default sweep (issue 13, item 3).
pub const SWEEP_V: [u32; 5] = [2, 3, 4, 5, 6];
/// Lobes swept by default: the paper's K_v and the slope fit G_v.
pub const SWEEP_LOBES: [LobeKind; 2] = [LobeKind::EnergyFit, LobeKind::SlopeFit];

/// What a sweep varies.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSpec {
    /// Shininess values (each > 0: the plots put n on a log axis).
    pub ns: Vec<f64>,
    /// The v of the lobes that have one.
    pub vs: Vec<u32>,
    /// The lobes compared with exact (closed forms only: a unit fixes its v).
    pub lobes: Vec<LobeKind>,
}

impl Default for SweepSpec {
    fn default() -> Self {
        SweepSpec {
            ns: SWEEP_N.to_vec(),
            vs: SWEEP_V.to_vec(),
            lobes: SWEEP_LOBES.to_vec(),
        }
    }
}

/// One point of the sweep.
#[derive(Clone, Debug)]
pub struct SweepRow {
    /// The lobe.
    pub kind: LobeKind,
    /// Its shininess.
    pub n: f64,
    /// Its v, for the lobes that have one.
    pub v: Option<u32>,
    /// Its frame time.
    pub frame: Duration,
    /// Metrics over the whole image.
    pub image: ImageMetrics,
    /// Metrics over the highlight.
    pub highlight: Option<ImageMetrics>,
}

/// A finished sweep.
pub struct Sweep {
    /// The scene without specular light, resolved (names the input and preset).
    pub scene: Scene,
    /// The lobes swept.
    pub lobes: Vec<LobeKind>,
    /// One row per (n, lobe, v), in that order.
    pub rows: Vec<SweepRow>,
}

/// Compares each lobe of `spec` with exact at each n and, for the lobes with a v, each
/// v; `progress` is called after each point.
pub fn sweep(
    renderer: Renderer,
    scene: &Scene,
    spec: &SweepSpec,
    progress: &dyn Fn(&SweepRow),
) -> Result<Sweep, CompareError> {
    check_lists(&spec.ns, &spec.vs)?;
    if let Some(n) = spec.ns.iter().find(|&&n| n <= 0.0) {
        return Err(CompareError::Invalid(format!(
            "--sweep-n {n}: the plots put n on a log axis, give n > 0"
        )));
    }
    if spec.lobes.is_empty() {
        return Err(CompareError::Invalid("no lobe to sweep".into()));
    }
    let mut experiment = Experiment::new(renderer, scene)?;
    let mut rows = Vec::new();
    for &n in &spec.ns {
        let mut s = scene.clone();
        s.lobe.n = Some(n);
        let reference = experiment.reference(&s)?;
        for &kind in &spec.lobes {
            let kind_vs: Vec<Option<u32>> = if kind.uses_v() {
                spec.vs.iter().map(|&v| Some(v)).collect()
            } else {
                vec![None]
            };
            for v in kind_vs {
                let c = experiment.compare(&reference, kind.into(), v)?;
                let row = SweepRow {
                    kind,
                    n,
                    v,
                    frame: c.frame,
                    image: c.image,
                    highlight: c.highlight,
                };
                progress(&row);
                rows.push(row);
            }
        }
    }
    Ok(Sweep {
        scene: experiment.dark.scene,
        lobes: spec.lobes.clone(),
        rows,
    })
}

const SWEEP_COLUMNS: [&str; 13] = [
    "lobe",
    "n",
    "v",
    "render_ms",
    "pixels",
    "psnr_db",
    "ssim",
    "de_mean",
    "de_p99",
    "de_max",
    "pct_above_1",
    "pct_above_2_3",
    "flip_mean",
];

fn cells(r: &SweepRow, m: Option<&ImageMetrics>) -> Vec<String> {
    let de = m.and_then(|m| m.delta_e);
    vec![
        r.kind.name().to_string(),
        fmt_num(r.n),
        r.v.map_or("-".into(), |v| v.to_string()),
        format!("{:.1}", ms(r.frame)),
        m.map_or("0".into(), |m| m.pixels.to_string()),
        num(m.and_then(|m| m.psnr), 2),
        num(m.and_then(|m| m.ssim), 5),
        num(de.map(|d| d.mean), 4),
        num(de.map(|d| d.p99), 3),
        num(de.map(|d| d.max), 3),
        num(de.map(|d| 100.0 * d.above_1), 3),
        num(de.map(|d| 100.0 * d.above_jnd), 3),
        num(m.and_then(|m| m.flip), 5),
    ]
}

impl Sweep {
    /// The plots' title: the metric, the input's file name and the preset.
    pub fn title(&self) -> String {
        let s = &self.scene;
        let input = match &s.input {
            Input::Path(p) => p.file_name().map_or_else(
                || p.display().to_string(),
                |f| f.to_string_lossy().into_owned(),
            ),
            other => input_name(other),
        };
        format!(
            "CIEDE2000 ΔE against exact cosⁿ: {}, {}",
            input,
            s.preset.as_deref().unwrap_or("custom")
        )
    }

    /// The table as CSV, a row per point and scope (image, highlight).
    pub fn csv(&self) -> String {
        let mut out = format!("scope,{}\n", SWEEP_COLUMNS.join(","));
        for r in &self.rows {
            out.push_str(&format!("image,{}\n", cells(r, Some(&r.image)).join(",")));
            out.push_str(&format!(
                "highlight,{}\n",
                cells(r, r.highlight.as_ref()).join(",")
            ));
        }
        out
    }

    /// The table as Markdown, the whole image then the highlight.
    pub fn markdown(&self) -> String {
        let mut out = format!("# {}\n\n", self.title());
        for (scope, hl) in [
            ("Whole image", false),
            ("Highlight pixels (exact specular > 10% of its max)", true),
        ] {
            out.push_str(&format!(
                "## {scope}\n\n| {} |\n|{}\n",
                SWEEP_COLUMNS.join(" | "),
                "---|".repeat(13)
            ));
            for r in &self.rows {
                let m = if hl {
                    r.highlight.as_ref()
                } else {
                    Some(&r.image)
                };
                out.push_str(&format!("| {} |\n", cells(r, m).join(" | ")));
            }
            out.push('\n');
        }
        out
    }

    /// Mean and p99 ΔE against n, one series per lobe and v.
    fn series(&self, highlight: bool) -> Vec<SweepSeries> {
        let mut out: Vec<SweepSeries> = Vec::new();
        for &kind in &self.lobes {
            let mut vs: Vec<Option<u32>> = self
                .rows
                .iter()
                .filter(|r| r.kind == kind)
                .map(|r| r.v)
                .collect();
            vs.sort();
            vs.dedup();
            for v in vs {
                let points = self
                    .rows
                    .iter()
                    .filter(|r| r.kind == kind && r.v == v)
                    .filter_map(|r| {
                        let m = if highlight {
                            r.highlight.as_ref()?
                        } else {
                            &r.image
                        };
                        let d = m.delta_e?;
                        Some((r.n, d.mean, d.p99))
                    })
                    .collect();
                out.push(SweepSeries {
                    label: lobe_label(kind, 0.0, v.unwrap_or(0)),
                    points,
                });
            }
        }
        out
    }

    /// Writes the plots of ΔE against n (whole image and highlight, PNG and SVG) into
    /// `dir`.
    pub fn write_plots(&self, dir: &Path) -> Result<(), CompareError> {
        let title = self.title();
        for (stem, hl) in [("sweep-delta-e", false), ("sweep-delta-e-highlight", true)] {
            let t = if hl {
                format!("{title}, highlight pixels")
            } else {
                title.clone()
            };
            sweep_plot(dir, stem, &t, &self.series(hl))?;
        }
        Ok(())
    }
}
