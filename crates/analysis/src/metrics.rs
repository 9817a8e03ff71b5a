//! Error metrics of one lobe against `cos^n γ` over γ ∈ [0°, 90°].
//!
//! Maxima come from a dense grid in γ (uniform over the whole range plus two finer
//! grids over the highlight, whose width scales as `1/√n`, plus every kink of the
//! lobe), refined by golden-section search around the best few local maxima of the
//! grid. Integrals (RMS error, energy) come from double-exponential quadrature
//! (`quadrature` crate) on pieces split at the kinks and at multiples of the highlight
//! width, so every piece is smooth.

use std::f64::consts::FRAC_PI_2;

use glint_lobe::{Lobe, LobeKind};

use crate::error::AnalysisError;

/// `cos^n` level above which the relative error is measured (below it the relative
/// error of any lobe that reaches 0 is 1 and says nothing).
pub const RELATIVE_FLOOR: f64 = 1e-3;
/// `cos^n` level that bounds the epicentre of the highlight: `cos^n >= 0.5`.
pub const EPICENTRE_LEVEL: f64 = 0.5;
/// `cos^n` level that bounds the bloom zone from below: `1e-2 <= cos^n < 0.5`.
pub const BLOOM_FLOOR: f64 = 1e-2;
/// `cos^n` level whose angle is reported beside the angle where a lobe reaches 0.
pub const CUTOFF_LEVEL: f64 = 1e-3;

/// Checks a shininess exponent: finite, in `0..=MAX_N`.
pub fn check_n(n: f64) -> Result<f64, AnalysisError> {
    if n.is_finite() && (0.0..=glint_lobe::MAX_N).contains(&n) {
        Ok(n)
    } else {
        Err(AnalysisError::InvalidN(n))
    }
}

/// Checks `v`: at most `MAX_V`.
pub fn check_v(v: u32) -> Result<u32, AnalysisError> {
    if v <= glint_lobe::MAX_V {
        Ok(v)
    } else {
        Err(AnalysisError::InvalidV(v))
    }
}

/// The angle γ (radians) where `cos^n γ` falls to `level` (0 < level < 1); `None` for
/// `n = 0`, where `cos^0 = 1` never falls.
pub fn level_angle(n: f64, level: f64) -> Option<f64> {
    (n > 0.0).then(|| level.powf(1.0 / n).acos())
}

/// A maximum of an error and the angle where it occurs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    /// The (non-negative) maximum.
    pub value: f64,
    /// Where it occurs, in degrees.
    pub angle_deg: f64,
}

/// Every metric of one lobe for one `(n, v)`.
#[derive(Clone, Debug, PartialEq)]
pub struct LobeMetrics {
    /// The lobe.
    pub kind: LobeKind,
    /// Shininess exponent of the reference `cos^n`.
    pub n: f64,
    /// `v` for the power fits (`k`, `g`, `minimax`), `None` for the others.
    pub v: Option<u32>,
    /// The coefficient `a` of a power fit.
    pub coefficient: Option<f64>,
    /// Maximum absolute error `|lobe - cos^n|` over γ ∈ [0°, 90°].
    pub max_abs: Peak,
    /// The signed error `lobe - cos^n` at [`LobeMetrics::max_abs`].
    pub max_abs_signed: f64,
    /// Root mean square of `lobe - cos^n` over γ uniform in [0°, 90°].
    pub rms: f64,
    /// Maximum of `|lobe - cos^n| / cos^n` where `cos^n >= 1e-3`.
    pub max_rel: Peak,
    /// Maximum absolute error in the epicentre, `cos^n >= 0.5`.
    pub epicentre: Peak,
    /// Maximum absolute error in the bloom zone, `1e-2 <= cos^n < 0.5`; `None` for
    /// `n = 0` (no such zone).
    pub bloom: Option<Peak>,
    /// `(n+1)·∫_0^{π/2} lobe(cos γ)·sin γ dγ`: 1 when the lobe has the energy of `cos^n`.
    pub energy_ratio: f64,
    /// Angle (degrees) where the lobe first reaches 0 on [0°, 90°], `None` if it stays
    /// positive.
    pub zero_angle_deg: Option<f64>,
    /// Angle (degrees) where `cos^n` falls to 1e-3, `None` for `n = 0`.
    pub cutoff_angle_deg: Option<f64>,
}

/// The angle (radians) where a lobe first reaches 0 on [0, π/2], from its closed form.
pub fn zero_angle(lobe: &Lobe<f64>) -> Option<f64> {
    let n = lobe.n();
    match lobe.kind() {
        // max(0, 1 - a(1-c))^m is 0 from c = 1 - 1/a on, inside the range iff a >= 1.
        LobeKind::EnergyFit | LobeKind::SlopeFit | LobeKind::Minimax => {
            let a = lobe.coefficient()?;
            (a >= 1.0).then(|| (1.0 - 1.0 / a).acos())
        }
        // cos^n and c/(n - nc + c) vanish at c = 0 only (for n > 0).
        LobeKind::Exact | LobeKind::Schlick => (n > 0.0).then_some(FRAC_PI_2),
        // exp(n(c-1)) > 0 everywhere.
        LobeKind::Gauss => None,
    }
}

/// `cos^n γ` for γ in [0, π/2] (n = 0 gives 1).
#[inline]
pub fn exact(n: f64, gamma: f64) -> f64 {
    gamma.cos().max(0.0).powf(n)
}

/// Points of γ (radians) where the error of this lobe is not smooth: its zero angle.
fn kinks(lobe: &Lobe<f64>) -> Vec<f64> {
    zero_angle(lobe)
        .into_iter()
        .filter(|&g| g > 0.0 && g < FRAC_PI_2)
        .collect()
}

/// The search grid in γ (radians) for a lobe approximating `cos^n`.
fn search_grid(n: f64, extra: &[f64]) -> Vec<f64> {
    let width = 1.0 / (n + 1.0).sqrt();
    let mut grid = Vec::with_capacity(6000);
    for (span, count) in [(FRAC_PI_2, 2000), (30.0 * width, 1500), (6.0 * width, 2000)] {
        let span = f64::min(span, FRAC_PI_2);
        grid.extend((0..=count).map(|i| span * i as f64 / count as f64));
    }
    grid.extend(extra.iter().copied());
    grid.retain(|g| (0.0..=FRAC_PI_2).contains(g));
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    grid
}

/// Maximises `g` over `[lo, hi]`: the grid points inside plus both ends, then a
/// golden-section refinement between the neighbours of the best local maxima.
pub(crate) fn maximise(g: &dyn Fn(f64) -> f64, grid: &[f64], lo: f64, hi: f64) -> (f64, f64) {
    let mut xs: Vec<f64> = Vec::with_capacity(grid.len() + 2);
    xs.push(lo);
    xs.extend(grid.iter().copied().filter(|&x| x > lo && x < hi));
    if hi > lo {
        xs.push(hi);
    }
    let ys: Vec<f64> = xs.iter().map(|&x| g(x)).collect();
    let last = xs.len() - 1;
    let mut candidates: Vec<usize> = (0..xs.len())
        .filter(|&i| (i == 0 || ys[i] >= ys[i - 1]) && (i == last || ys[i] >= ys[i + 1]))
        .collect();
    candidates.sort_by(|&a, &b| ys[b].total_cmp(&ys[a]));
    candidates.truncate(4);
    let mut best = (xs[0], ys[0]);
    for i in candidates {
        let l = xs[i.saturating_sub(1)];
        let h = xs[(i + 1).min(last)];
        let found = glint_lobe::golden_max(g, l, h, xs[i], ys[i]);
        if found.1 > best.1 {
            best = found;
        }
    }
    best
}

/// `∫_lo^hi f(γ) dγ` by double-exponential quadrature on pieces split at `breaks`.
pub(crate) fn integrate(f: &dyn Fn(f64) -> f64, lo: f64, hi: f64, breaks: &[f64]) -> f64 {
    let mut points: Vec<f64> = vec![lo, hi];
    points.extend(breaks.iter().copied().filter(|&b| b > lo && b < hi));
    points.sort_by(f64::total_cmp);
    points.dedup();
    points
        .windows(2)
        .map(|w| quadrature::double_exponential::integrate(f, w[0], w[1], 1e-15).integral)
        .sum()
}

/// Break points for the integrals: the kinks and multiples of the highlight width.
fn breaks(n: f64, kinks: &[f64]) -> Vec<f64> {
    let width = 1.0 / (n + 1.0).sqrt();
    let mut b: Vec<f64> = [0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0]
        .iter()
        .map(|k| k * width)
        .collect();
    b.extend_from_slice(kinks);
    b
}

/// Peak of `|err|` over `[lo, hi]` (radians).
fn abs_peak(err: &dyn Fn(f64) -> f64, grid: &[f64], lo: f64, hi: f64) -> Peak {
    let (x, y) = maximise(&|g| err(g).abs(), grid, lo, hi);
    Peak {
        value: y,
        angle_deg: x.to_degrees(),
    }
}

/// Computes every metric of `kind` against `cos^n` (with power `2^v` for the fits).
pub fn lobe_metrics(kind: LobeKind, n: f64, v: u32) -> Result<LobeMetrics, AnalysisError> {
    let lobe = Lobe::<f64>::new(kind, check_n(n)?, check_v(v)?)?;
    Ok(metrics_of(&lobe))
}

/// Computes every metric of a built lobe against `cos^n`, `n` being the lobe's own.
pub fn metrics_of(lobe: &Lobe<f64>) -> LobeMetrics {
    let n = lobe.n();
    let err = |g: f64| lobe.eval(g.cos()) - exact(n, g);
    let kinks = kinks(lobe);
    let half = level_angle(n, EPICENTRE_LEVEL);
    let bloom_end = level_angle(n, BLOOM_FLOOR);
    let rel_end = level_angle(n, RELATIVE_FLOOR);
    let mut extra = kinks.clone();
    extra.extend([half, bloom_end, rel_end].into_iter().flatten());
    let grid = search_grid(n, &extra);

    let max_abs = abs_peak(&err, &grid, 0.0, FRAC_PI_2);
    let max_abs_signed = err(max_abs.angle_deg.to_radians());
    let rel_hi = rel_end.unwrap_or(FRAC_PI_2);
    let (rx, ry) = maximise(&|g| err(g).abs() / exact(n, g), &grid, 0.0, rel_hi);
    let max_rel = Peak {
        value: ry,
        angle_deg: rx.to_degrees(),
    };
    let epicentre = abs_peak(&err, &grid, 0.0, half.unwrap_or(FRAC_PI_2));
    let bloom = half
        .zip(bloom_end)
        .map(|(lo, hi)| abs_peak(&err, &grid, lo, hi));

    let br = breaks(n, &kinks);
    let mean_sq = integrate(&|g| err(g).powi(2), 0.0, FRAC_PI_2, &br) / FRAC_PI_2;
    let energy = (n + 1.0) * integrate(&|g| lobe.eval(g.cos()) * g.sin(), 0.0, FRAC_PI_2, &br);

    LobeMetrics {
        kind: lobe.kind(),
        n,
        v: lobe.kind().uses_v().then_some(lobe.v()),
        coefficient: lobe.coefficient(),
        max_abs,
        max_abs_signed,
        rms: mean_sq.sqrt(),
        max_rel,
        epicentre,
        bloom,
        energy_ratio: energy,
        zero_angle_deg: zero_angle(lobe).map(f64::to_degrees),
        cutoff_angle_deg: level_angle(n, CUTOFF_LEVEL).map(f64::to_degrees),
    }
}

/// Only the maximum absolute error of a lobe over [0°, 90°] (cheaper than
/// [`metrics_of`]; used by the error map and the tolerance search).
pub fn max_abs_error(lobe: &Lobe<f64>) -> Peak {
    let n = lobe.n();
    let err = |g: f64| lobe.eval(g.cos()) - exact(n, g);
    let grid = search_grid(n, &kinks(lobe));
    abs_peak(&err, &grid, 0.0, FRAC_PI_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maximise_finds_an_interior_and_an_end_peak() {
        let grid: Vec<f64> = (0..=10).map(|i| i as f64 / 10.0).collect();
        let (x, y) = maximise(&|x| -(x - 0.337_f64).powi(2), &grid, 0.0, 1.0);
        assert!((x - 0.337).abs() < 1e-6 && y.abs() < 1e-12, "{x} {y}");
        let (x, _) = maximise(&|x| x, &grid, 0.0, 0.55);
        assert_eq!(x, 0.55);
    }

    #[test]
    fn quadrature_pieces_add_up() {
        // ∫_0^{π/2} |sin(4γ)| dγ = 1 (four humps of area 1/4 each).
        let i = integrate(
            &|g: f64| (4.0 * g).sin().abs(),
            0.0,
            FRAC_PI_2,
            &[0.25 * std::f64::consts::PI],
        );
        assert!((i - 1.0).abs() < 1e-12, "{i}");
    }

    #[test]
    fn level_angles() {
        // cos^1 = 0.5 at 60 degrees; cos^2 = 0.5 at 45 degrees.
        assert!((level_angle(1.0, 0.5).unwrap().to_degrees() - 60.0).abs() < 1e-12);
        assert!((level_angle(2.0, 0.5).unwrap().to_degrees() - 45.0).abs() < 1e-12);
        assert!(level_angle(0.0, 0.5).is_none());
    }
}
