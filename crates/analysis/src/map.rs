//! The error map: maximum absolute error over a log grid of n and every v, per fit.

use glint_lobe::{Lobe, LobeKind};
use rayon::prelude::*;

use crate::error::AnalysisError;
use crate::metrics::max_abs_error;

/// The fits shown in the map.
pub const MAP_FITS: [LobeKind; 3] = [LobeKind::EnergyFit, LobeKind::SlopeFit, LobeKind::Minimax];

/// Maximum absolute error of each fit over a grid of n (log-spaced) and v.
#[derive(Clone, Debug)]
pub struct ErrorMap {
    /// The n values (increasing).
    pub ns: Vec<f64>,
    /// The v values (increasing).
    pub vs: Vec<u32>,
    /// Per fit of [`MAP_FITS`]: `errors[fit][iv][in]`.
    pub errors: Vec<Vec<Vec<f64>>>,
}

/// `count` values of n spaced evenly in log from `lo` to `hi` (both > 0).
pub fn log_spaced(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    let (a, b) = (lo.ln(), hi.ln());
    (0..count)
        .map(|i| (a + (b - a) * i as f64 / (count.max(2) - 1) as f64).exp())
        .collect()
}

impl ErrorMap {
    /// Computes the map (in parallel; the minimax fit searches its coefficient per cell).
    pub fn compute(ns: Vec<f64>, vs: Vec<u32>) -> Result<Self, AnalysisError> {
        let (nn, nv) = (ns.len(), vs.len());
        let cells: Vec<(usize, usize, usize)> = (0..MAP_FITS.len())
            .flat_map(|f| (0..nv).flat_map(move |iv| (0..nn).map(move |i| (f, iv, i))))
            .collect();
        let values: Vec<f64> = cells
            .par_iter()
            .map(|&(f, iv, i)| {
                Lobe::<f64>::new(MAP_FITS[f], ns[i], vs[iv]).map(|l| max_abs_error(&l).value)
            })
            .collect::<Result<_, _>>()?;
        let mut errors = vec![vec![vec![0.0; ns.len()]; vs.len()]; MAP_FITS.len()];
        for (&(f, iv, i), e) in cells.iter().zip(values) {
            errors[f][iv][i] = e;
        }
        Ok(ErrorMap { ns, vs, errors })
    }

    /// The paper's range: n from 1 to 1000 (61 log-spaced values), v from 1 to 8.
    pub fn paper_range() -> Result<Self, AnalysisError> {
        Self::compute(log_spaced(1.0, 1000.0, 61), (1..=8).collect())
    }
}
