//! docs/accuracy.md: tables, figures and a verdict on each of the paper's claims.

use std::path::{Path, PathBuf};

use crate::error::AnalysisError;

/// Regenerates `docs/accuracy.md` and `docs/figures/` under `docs`.
pub fn write_report(docs: &Path, command: &str) -> Result<Vec<PathBuf>, AnalysisError> {
    let _ = (docs, command);
    todo!()
}
