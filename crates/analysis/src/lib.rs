//! Accuracy of glint's specular lobes against `cos^n γ`: error metrics, sampled
//! curves, summary tables, figures (PNG and SVG) and the accuracy report.
//!
//! ```
//! use glint_analysis::{lobe_metrics, cheapest_v};
//! use glint_lobe::LobeKind;
//!
//! // The paper's K_4 for n = 100: the energy of cos^n is kept exactly (n >= 2^v).
//! let k = lobe_metrics(LobeKind::EnergyFit, 100.0, 4).unwrap();
//! assert!((k.energy_ratio - 1.0).abs() < 1e-9);
//! assert!(k.max_abs.value < 0.05);
//!
//! // The cheapest power 2^v keeping each fit within 1/255 for n = 350.
//! for fit in cheapest_v(350.0, 1.0 / 255.0).unwrap() {
//!     println!("{}: v = {:?}", fit.kind, fit.v);
//! }
//!
//! // Bad parameters give a typed error.
//! assert!(lobe_metrics(LobeKind::EnergyFit, -1.0, 4).is_err());
//! ```
//!
//! [`write_analysis`] writes curves.csv, summary.csv, summary.md and the figures into
//! a directory, all or nothing; [`write_report`] regenerates docs/accuracy.md.

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod curves;
mod error;
pub mod image;
mod map;
mod metrics;
mod output;
mod plot;
mod report;
mod summary;
mod tolerance;

use std::path::{Path, PathBuf};

/// The largest accepted image width or height (a sanity bound: 16384² pixels is 800 MB
/// of RGB).
pub const MAX_IMAGE_SIDE: u32 = 16384;

pub use curves::{curve_angles, curves_header, fmt_num, write_curves_csv, Curves, COMPARED};
pub use error::AnalysisError;
pub use map::{log_spaced, ErrorMap, MAP_FITS};
pub use metrics::{
    check_n, check_v, exact, level_angle, lobe_metrics, max_abs_error, metrics_of, zero_angle,
    LobeMetrics, Peak, BLOOM_FLOOR, CUTOFF_LEVEL, EPICENTRE_LEVEL, RELATIVE_FLOOR,
};
pub use output::Staging;
pub use plot::lobe_label;
pub use report::write_report;
pub use summary::{summary_markdown, summary_rows, write_summary_csv, SUMMARY_COLUMNS};
pub use tolerance::{cheapest_v, Cheapest, TOLERANCE_FITS};

/// At most this many values of n or v per run (a list is for comparing, not a sweep).
pub const MAX_LIST: usize = 64;

/// The paper's parameters: Fig. 2 is n = 100, Fig. 3 n = 10, 100 and 1000, both v = 4.
pub const PAPER_V: u32 = 4;
/// n of the paper's Fig. 2.
pub const PAPER_N: f64 = 100.0;
/// n of the paper's Fig. 3 panels.
pub const PAPER_FIG3_NS: [f64; 3] = [10.0, 100.0, 1000.0];

/// Checks the lists of n and v: non-empty, not too long, every value valid.
pub fn check_lists(ns: &[f64], vs: &[u32]) -> Result<(), AnalysisError> {
    for (what, len) in [("n values", ns.len()), ("v values", vs.len())] {
        if len == 0 {
            return Err(AnalysisError::EmptyList(what));
        }
        if len > MAX_LIST {
            return Err(AnalysisError::TooMany {
                what,
                count: len,
                max: MAX_LIST,
            });
        }
    }
    for &n in ns {
        check_n(n)?;
    }
    for &v in vs {
        check_v(v)?;
    }
    Ok(())
}

fn csv_bytes(f: impl FnOnce(&mut Vec<u8>) -> csv::Result<()>) -> Vec<u8> {
    let mut buf = Vec::new();
    // Writing CSV into memory cannot fail.
    f(&mut buf).expect("CSV into a Vec never fails");
    buf
}

/// The Markdown document summary.md: parameters, column meanings and the table.
pub fn summary_document(ns: &[f64], vs: &[u32], rows: &[LobeMetrics]) -> String {
    let list = |xs: Vec<String>| xs.join(", ");
    format!(
        "# Lobe accuracy against cos^n γ\n\n\
         n = {}; v = {}. Errors are `lobe − cos^n γ` over γ ∈ [0°, 90°].\n\n\
         - max abs err: max |lobe − cos^n| and the angle where it occurs;\n\
         - RMS err: root mean square of the error over γ uniform in [0°, 90°];\n\
         - max rel err: max |lobe − cos^n| / cos^n where cos^n ≥ 1e-3;\n\
         - epicentre / bloom err: max |lobe − cos^n| where cos^n ≥ 0.5 / where 1e-2 ≤ cos^n < 0.5;\n\
         - energy ratio: (n+1)·∫ lobe·sin γ dγ (1 = the energy of cos^n);\n\
         - lobe = 0 at: where the lobe reaches 0 (never: stays positive up to 90°), beside \
           where cos^n falls to 1e-3.\n\n{}",
        list(ns.iter().map(|&n| fmt_num(n)).collect()),
        list(vs.iter().map(|v| v.to_string()).collect()),
        summary_markdown(rows)
    )
}

/// Writes the full analysis of every `n` in `ns` and `v` in `vs` into `out`:
/// curves.csv, summary.csv, summary.md and the figures (PNG and SVG): the paper's
/// Fig. 2 and Fig. 3, the lobe shapes of each (n, v) and the error map. Either every
/// file is written or none (the directory is staged and renamed). Returns the paths.
pub fn write_analysis(ns: &[f64], vs: &[u32], out: &Path) -> Result<Vec<PathBuf>, AnalysisError> {
    check_lists(ns, vs)?;
    let staging = Staging::new(out)?;
    let rows = summary_rows(ns, vs)?;
    let mut curves = Vec::new();
    for &n in ns {
        for &v in vs {
            curves.push(Curves::sample(n, v)?);
        }
    }
    staging.write("curves.csv", &csv_bytes(|b| write_curves_csv(b, &curves)))?;
    staging.write("summary.csv", &csv_bytes(|b| write_summary_csv(b, &rows)))?;
    staging.write("summary.md", summary_document(ns, vs, &rows).as_bytes())?;
    write_figures(staging.path(), &curves)?;
    staging.commit()
}

/// Draws every figure into `dir`: Fig. 2, Fig. 3, the error map, and the shapes of
/// each of `shapes`. Returns the file names.
pub fn write_figures(dir: &Path, shapes: &[Curves]) -> Result<Vec<String>, AnalysisError> {
    let mut files = plot::fig2(dir, &Curves::sample(PAPER_N, PAPER_V)?)?;
    let fig3: Vec<Curves> = PAPER_FIG3_NS
        .iter()
        .map(|&n| Curves::sample(n, PAPER_V))
        .collect::<Result<_, _>>()?;
    files.extend(plot::fig3(dir, &fig3)?);
    for c in shapes {
        files.extend(plot::shapes(dir, c)?);
    }
    files.extend(plot::error_map(dir, &ErrorMap::paper_range()?)?);
    Ok(files)
}
