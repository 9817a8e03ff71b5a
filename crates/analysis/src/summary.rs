//! The summary table: one row of [`LobeMetrics`] per (lobe, n, v), as CSV and Markdown.

use rayon::prelude::*;

use crate::curves::{fmt_num, COMPARED};
use crate::error::AnalysisError;
use crate::metrics::{lobe_metrics, LobeMetrics};

/// The rows for every n and v: the power fits once per (n, v), Schlick and the
/// Gaussian (which do not depend on v) once per n.
pub fn summary_rows(ns: &[f64], vs: &[u32]) -> Result<Vec<LobeMetrics>, AnalysisError> {
    let mut jobs = Vec::new();
    for &n in ns {
        for &v in vs {
            jobs.extend(COMPARED.iter().filter(|k| k.uses_v()).map(|&k| (k, n, v)));
        }
        jobs.extend(
            COMPARED
                .iter()
                .filter(|k| !k.uses_v())
                .map(|&k| (k, n, vs[0])),
        );
    }
    jobs.par_iter()
        .map(|&(k, n, v)| lobe_metrics(k, n, v))
        .collect()
}

/// The columns of summary.csv.
pub const SUMMARY_COLUMNS: [&str; 17] = [
    "lobe",
    "n",
    "v",
    "a",
    "max_abs_err",
    "max_abs_err_signed",
    "max_abs_angle_deg",
    "rms_err",
    "max_rel_err",
    "max_rel_angle_deg",
    "epicentre_max_abs_err",
    "epicentre_angle_deg",
    "bloom_max_abs_err",
    "bloom_angle_deg",
    "energy_ratio",
    "zero_angle_deg",
    "cutoff_1e-3_angle_deg",
];

fn opt(x: Option<f64>, f: impl Fn(f64) -> String) -> String {
    x.map(f).unwrap_or_default()
}

fn e(x: f64) -> String {
    format!("{x:.9e}")
}

fn deg(x: f64) -> String {
    format!("{x:.6}")
}

/// Writes summary.csv (empty fields where a value does not exist: `v` and `a` for
/// lobes without them, the bloom zone for n = 0, a zero angle the lobe never reaches).
pub fn write_summary_csv<W: std::io::Write>(out: W, rows: &[LobeMetrics]) -> csv::Result<()> {
    let mut w = csv::Writer::from_writer(out);
    w.write_record(SUMMARY_COLUMNS)?;
    for r in rows {
        w.write_record([
            r.kind.name().to_string(),
            fmt_num(r.n),
            r.v.map(|v| v.to_string()).unwrap_or_default(),
            opt(r.coefficient, |a| format!("{a:.12}")),
            e(r.max_abs.value),
            e(r.max_abs_signed),
            deg(r.max_abs.angle_deg),
            e(r.rms),
            e(r.max_rel.value),
            deg(r.max_rel.angle_deg),
            e(r.epicentre.value),
            deg(r.epicentre.angle_deg),
            opt(r.bloom.map(|p| p.value), e),
            opt(r.bloom.map(|p| p.angle_deg), deg),
            format!("{:.12}", r.energy_ratio),
            opt(r.zero_angle_deg, deg),
            opt(r.cutoff_angle_deg, deg),
        ])?;
    }
    w.flush()?;
    Ok(())
}

/// The summary as a Markdown table (4 significant digits, angles in degrees).
pub fn summary_markdown(rows: &[LobeMetrics]) -> String {
    let mut s = String::new();
    s.push_str(
        "| lobe | n | v | max abs err (at γ°) | RMS err | max rel err, cos^n ≥ 1e-3 (at γ°) \
         | epicentre err, cos^n ≥ 0.5 | bloom err, 1e-2 ≤ cos^n < 0.5 | energy ratio \
         | lobe = 0 at γ° | cos^n = 1e-3 at γ° |\n",
    );
    s.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for r in rows {
        let g = |x: f64| format!("{x:.4}");
        s.push_str(&format!(
            "| {} | {} | {} | {:.4} ({:.2}) | {:.3e} | {:.4} ({:.2}) | {:.4} | {} | {:.4} | {} | {} |\n",
            r.kind.name(),
            fmt_num(r.n),
            r.v.map(|v| v.to_string()).unwrap_or_else(|| "–".into()),
            r.max_abs.value,
            r.max_abs.angle_deg,
            r.rms,
            r.max_rel.value,
            r.max_rel.angle_deg,
            r.epicentre.value,
            r.bloom.map(|p| g(p.value)).unwrap_or_else(|| "–".into()),
            r.energy_ratio,
            r.zero_angle_deg
                .map(|x| format!("{x:.2}"))
                .unwrap_or_else(|| "never".into()),
            r.cutoff_angle_deg
                .map(|x| format!("{x:.2}"))
                .unwrap_or_else(|| "never".into()),
        ));
    }
    s
}
