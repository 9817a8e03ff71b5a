//! The experiment's report: the table `glint compare` prints, its JSON form (the same
//! numbers `glint.compare` returns in Python) and the side-by-side figure.

use std::time::Duration;

use glint_analysis::image::{comparison_png, ComparisonRow, ImageMetrics, HIGHLIGHT_FRACTION};
use glint_analysis::{fmt_num, lobe_label};
use glint_lobe::LobeKind;
use glint_render::{Input, SceneLobe};
use serde_json::{json, Value};

use crate::{CompareError, Comparison, Converged, Report};

/// Milliseconds of a duration.
pub(crate) fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Formats an optional number, "-" when absent.
pub(crate) fn num(x: Option<f64>, digits: usize) -> String {
    match x {
        Some(v) if v.is_infinite() => "inf".into(),
        Some(v) => format!("{v:.digits$}"),
        None => "-".into(),
    }
}

/// How a scene's input is named in reports.
pub(crate) fn input_name(input: &Input) -> String {
    match input {
        Input::Path(p) => p.display().to_string(),
        Input::Phantom { name, size } => format!("{name} phantom {size}^3"),
        Input::None => "meshes".into(),
    }
}

const TABLE_HEAD: &str =
    "lobe      n     v  render ms  pixels  scope      PSNR dB  SSIM     mean ΔE  p99 ΔE  max ΔE  >1 %    >2.3 %  FLIP\n";

impl Comparison {
    /// A row title: the lobe with its parameters (for the unit: its ROM and output
    /// width).
    pub fn title(&self) -> String {
        let (n, v) = (self.n, self.v);
        let kind = match (self.lobe, &self.hw) {
            (SceneLobe::Float(kind), _) => kind,
            (SceneLobe::Hw, hw) => {
                let hw = hw.clone().unwrap_or_default();
                return format!(
                    "hw unit ({} ROM, {}-bit output, v = {v}), n = {}",
                    hw.coefficients,
                    hw.out_bits,
                    fmt_num(n.round())
                );
            }
        };
        let label = lobe_label(kind, n, v);
        if kind == LobeKind::Exact {
            label
        } else {
            format!("{label}, n = {}", fmt_num(n))
        }
    }

    fn table_row(&self, scope: &str, m: &ImageMetrics) -> String {
        let de = m.delta_e;
        format!(
            "{:<9} {:<5} {:<2} {:<10.1} {:<7} {:<10} {:<8} {:<8} {:<8} {:<7} {:<7} {:<7} {:<7} {}\n",
            self.lobe.name(),
            fmt_num(self.n),
            if self.uses_v() {
                self.v.to_string()
            } else {
                "-".into()
            },
            ms(self.frame),
            m.pixels,
            scope,
            num(m.psnr, 2),
            num(m.ssim, 5),
            num(de.map(|d| d.mean), 4),
            num(de.map(|d| d.p99), 3),
            num(de.map(|d| d.max), 3),
            num(de.map(|d| 100.0 * d.above_1), 3),
            num(de.map(|d| 100.0 * d.above_jnd), 3),
            num(m.flip, 5),
        )
    }
}

/// The JSON form of one set of metrics.
fn metrics_json(m: &ImageMetrics) -> Value {
    let finite = |x: Option<f64>| x.filter(|v| v.is_finite());
    json!({
        "pixels": m.pixels,
        "psnr_db": finite(m.psnr),
        "ssim": m.ssim,
        "delta_e": m.delta_e.map(|d| json!({
            "mean": d.mean, "p99": d.p99, "max": d.max,
            "share_above_1": d.above_1, "share_above_2_3": d.above_jnd,
        })),
        "flip_mean": m.flip,
    })
}

impl Report {
    /// The table `glint compare` prints; the classification time is the first
    /// render's (the image without specular light).
    pub fn text(&self) -> String {
        let r = &self.reference.shot.rendered;
        let s = &r.scene;
        let hl = self.reference.highlight_pixels();
        let mut out = format!(
            "glint compare: {}, preset {}, {} mode, {}x{}, n = {}, {} geometry\n\
             exact: classify {:.1} ms, render {:.1} ms\n\
             highlight: {hl} pixels ({:.2}%) where the exact specular term exceeds {}% of its max\n\n",
            input_name(&s.input),
            s.preset.as_deref().unwrap_or("custom"),
            s.mode.name(),
            s.size[0],
            s.size[1],
            fmt_num(s.lobe.n.unwrap_or_default()),
            s.lobe.geometry,
            ms(self.dark.timings.get("classify")),
            ms(r.timings.get("frame")),
            100.0 * hl as f64 / self.reference.mask.len().max(1) as f64,
            fmt_num(100.0 * HIGHLIGHT_FRACTION),
        );
        out.push_str(TABLE_HEAD);
        for c in &self.rows {
            out.push_str(&c.table_row("image", &c.image));
            if let Some(h) = &c.highlight {
                out.push_str(&c.table_row("highlight", h));
            }
        }
        if let Some(c) = &self.converged {
            out.push_str(&converged_text(c, s.lighting.spp.unwrap_or_default()));
        }
        out
    }

    /// The report as JSON (`glint compare --json`, `glint.compare` in Python): the
    /// resolved scene, the exact render's times, the highlight, and per lobe its
    /// metrics over the image and the highlight; under `path` lighting with a
    /// reference, `converged`: each image's distance to it.
    pub fn to_json(&self) -> Result<Value, CompareError> {
        let r = &self.reference.shot.rendered;
        let comparisons: Vec<Value> = self
            .rows
            .iter()
            .map(|c| {
                json!({
                    "lobe": c.lobe.name(),
                    "n": c.n,
                    "v": c.uses_v().then_some(c.v),
                    "render_ms": ms(c.frame),
                    "image": metrics_json(&c.image),
                    "highlight": c.highlight.as_ref().map(metrics_json),
                })
            })
            .collect();
        let scene = serde_json::to_value(&r.scene)
            .map_err(|e| CompareError::Invalid(format!("the scene as JSON: {e}")))?;
        let mut out = json!({
            "scene": scene,
            "exact": { "classify_ms": ms(self.dark.timings.get("classify")), "render_ms": ms(r.timings.get("frame")) },
            "highlight": {
                "fraction_of_max": HIGHLIGHT_FRACTION,
                "pixels": self.reference.highlight_pixels(),
            },
            "metrics_on": "8-bit sRGB; PSNR over RGB; SSIM on Rec. 709 luma; CIEDE2000 (D65); LDR-FLIP at 67 pixels per degree",
            "comparisons": comparisons,
        });
        // Only when traced: a `local` report's JSON stays as it was.
        if let Some(c) = &self.converged {
            out["converged"] = converged_json(c);
        }
        Ok(out)
    }

    /// The comparison picture as PNG bytes: per lobe, exact, the lobe and the ΔE heat
    /// map (scale top `scale_max`), titled with its mean and p99 ΔE.
    pub fn figure_png(&self, scale_max: f64) -> Result<Vec<u8>, CompareError> {
        let titles: Vec<String> = self
            .rows
            .iter()
            .map(|c| {
                let de = c.image.delta_e.map(|d| (d.mean, d.p99)).unwrap_or_default();
                format!(
                    "{}: mean ΔE {:.3}, p99 {:.3}{}",
                    c.title(),
                    de.0,
                    de.1,
                    match c.highlight.and_then(|h| h.delta_e) {
                        Some(h) => format!("; highlight mean {:.3}, p99 {:.3}", h.mean, h.p99),
                        None => String::new(),
                    }
                )
            })
            .collect();
        let fig: Vec<ComparisonRow> = self
            .rows
            .iter()
            .zip(&titles)
            .map(|(c, t)| ComparisonRow {
                title: t,
                reference: &self.reference.shot.srgb,
                test: &c.shot.srgb,
                delta_e: &c.delta_e,
            })
            .collect();
        Ok(comparison_png(&fig, scale_max)?)
    }
}

/// The section of [`Report::text`] on the distance to the converged reference, the
/// images having `spp` samples per pixel.
fn converged_text(c: &Converged, spp: u32) -> String {
    let mut out = format!(
        "\ndistance to the exact lobe at {} spp (seed {}; render {:.1} ms), images at {spp} spp:\n\
         image     scope      PSNR dB  SSIM     mean ΔE  p99 ΔE  FLIP\n",
        c.spp,
        c.seed,
        ms(c.shot.rendered.timings.get("frame")),
    );
    for r in &c.rows {
        let scopes = std::iter::once(("image", &r.image))
            .chain(r.highlight.iter().map(|h| ("highlight", h)));
        for (scope, m) in scopes {
            let de = m.delta_e;
            out.push_str(&format!(
                "{:<9} {:<10} {:<8} {:<8} {:<8} {:<7} {}\n",
                r.label,
                scope,
                num(m.psnr, 2),
                num(m.ssim, 5),
                num(de.map(|d| d.mean), 4),
                num(de.map(|d| d.p99), 3),
                num(m.flip, 5),
            ));
        }
    }
    out
}

/// The JSON form of [`Converged`].
fn converged_json(c: &Converged) -> Value {
    json!({
        "spp": c.spp,
        "seed": c.seed,
        "render_ms": ms(c.shot.rendered.timings.get("frame")),
        "rows": c.rows.iter().map(|r| json!({
            "lobe": r.label,
            "image": metrics_json(&r.image),
            "highlight": r.highlight.as_ref().map(metrics_json),
        })).collect::<Vec<_>>(),
    })
}
