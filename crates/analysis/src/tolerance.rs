//! The cheapest v that keeps a fit within an error tolerance.

use glint_lobe::{Lobe, LobeKind};

use crate::error::AnalysisError;
use crate::metrics::{check_n, max_abs_error};

/// The fits the tolerance search covers.
pub const TOLERANCE_FITS: [LobeKind; 3] =
    [LobeKind::EnergyFit, LobeKind::SlopeFit, LobeKind::Minimax];

/// The answer for one fit and one n.
#[derive(Clone, Debug, PartialEq)]
pub struct Cheapest {
    /// The fit.
    pub kind: LobeKind,
    /// The shininess exponent.
    pub n: f64,
    /// The smallest v in `0..=MAX_V` whose max abs error is within the tolerance and
    /// that error, or `None` if even `MAX_V` is not enough.
    pub v: Option<(u32, f64)>,
    /// The error at `MAX_V` (the best reachable), for the message when `v` is `None`.
    pub best_error: f64,
}

impl Cheapest {
    /// Cost of the fit in squarings: v (the cascade multiplier BMUL of the paper).
    pub fn squarings(&self) -> Option<u32> {
        self.v.map(|(v, _)| v)
    }
}

/// For each fit, the smallest v whose maximum absolute error against `cos^n` over
/// [0°, 90°] is at most `tolerance`.
pub fn cheapest_v(n: f64, tolerance: f64) -> Result<Vec<Cheapest>, AnalysisError> {
    check_n(n)?;
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(AnalysisError::InvalidTolerance(tolerance));
    }
    TOLERANCE_FITS
        .iter()
        .map(|&kind| {
            let mut best_error = f64::INFINITY;
            for v in 0..=glint_lobe::MAX_V {
                let err = max_abs_error(&Lobe::<f64>::new(kind, n, v)?).value;
                best_error = err;
                if err <= tolerance {
                    return Ok(Cheapest {
                        kind,
                        n,
                        v: Some((v, err)),
                        best_error,
                    });
                }
            }
            Ok(Cheapest {
                kind,
                n,
                v: None,
                best_error,
            })
        })
        .collect()
}
