//! A tabulated inverse CDF for a lobe with no closed-form one (Schlick's): the lobe
//! as a function of `x = 1 - cos γ` is replaced by a piecewise-linear density on
//! adaptively refined nodes, which is sampled exactly.
//!
//! The table *is* the distribution: [`PiecewiseLinear::sample`] draws exactly from
//! the piecewise-linear density and [`PiecewiseLinear::pdf`] returns exactly that
//! density, so a Monte Carlo weight `f / pdf` is unbiased whatever the table's
//! error. The error (how far the density is from the lobe's shape) only moves the
//! weights away from a constant: it is a variance, not a bias. Building:
//!
//! 1. Nodes: starting from `[0, x_max]`, a bin is halved until the chord between its
//!    end values is within `tol·(f + 1e-12·f_peak)` of the lobe `f` at 1/4, 1/2 and
//!    3/4 of the bin (relative, but for a floor far below anything a renderer sees,
//!    so that a zero of high order, `(1-x)^n` at `x = 1`, needs no endless halving). The lobes tabulated here are convex or concave in `x` on each bin, so the
//!    chord's error is one-signed and peaks near the middle; the test
//!    `tabulated_density_is_within_its_bound` checks 64 points per bin.
//! 2. Masses: each bin's trapezoid, normalised to 1; a cumulative table and a guide
//!    table (one entry per bin: the bin holding `u = j / bins`) find a bin in O(1).
//! 3. Within a bin, the linear density is inverted in closed form (pbrt-v4's
//!    `SampleLinear`, src/pbrt/util/sampling.h, Pharr, Jakob and Humphreys,
//!    *Physically Based Rendering*, 4th ed., sec. A.4.2).
//!
//! Written here rather than taken from a crate: no maintained Rust crate samples a
//! piecewise-linear 1D density (rand_distr has no tabulated distribution;
//! pbrt's PiecewiseConstant1D is piecewise constant), and it is ~100 lines.
//!
//! Everything is f64: the table is built once per lobe, and f64 keeps the density and
//! the sampler consistent to ~1e-15 whatever the renderer's precision.

/// The relative tolerance of the chord against the lobe at the checked points.
pub(crate) const TABLE_TOLERANCE: f64 = 1e-4;

/// The absolute floor of the chord's tolerance, relative to the lobe's peak.
const ABS_FLOOR: f64 = 1e-12;

/// Deepest bisection: bins of `x_max · 2^-48` (~4e-15 for x_max = 1) are accepted
/// whatever their error; no lobe of this crate needs them.
const MAX_DEPTH: u32 = 48;

/// A piecewise-linear density on `[0, x_max]` with its exact sampler.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PiecewiseLinear {
    /// Nodes `x_0 = 0 < x_1 < ... < x_B = x_max`.
    x: Box<[f64]>,
    /// The density at each node (per unit x), normalised so that its integral is 1.
    q: Box<[f64]>,
    /// `cdf[i]`: the mass of bins `0 .. i`; `cdf[0] = 0`, `cdf[B] = 1`.
    cdf: Box<[f64]>,
    /// `guide[j]`: the last bin `i` with `cdf[i] <= j / B`.
    guide: Box<[u32]>,
    /// The largest chord error found at the checked points while building, relative
    /// to `f + 1e-12 f_peak`.
    checked_error: f64,
}

impl PiecewiseLinear {
    /// Tabulates `f` (non-negative, positive inside `(0, x_max)`) on `[0, x_max]`.
    pub(crate) fn build(f: impl Fn(f64) -> f64, x_max: f64, tol: f64) -> PiecewiseLinear {
        let floor = ABS_FLOOR * f(0.0).max(f(x_max));
        let mut nodes = vec![(0.0, f(0.0))];
        let mut checked_error: f64 = 0.0;
        // Bins still to judge, leftmost on top, so accepted bins arrive in order.
        let mut stack = vec![(0.0, f(0.0), x_max, f(x_max), 0u32)];
        while let Some((a, fa, b, fb, depth)) = stack.pop() {
            let worst = [0.25, 0.5, 0.75]
                .into_iter()
                .map(|t| {
                    let y = f(a + t * (b - a));
                    let chord = fa + t * (fb - fa);
                    (chord - y).abs() / (y + floor)
                })
                .fold(0.0, f64::max);
            if worst <= tol || depth >= MAX_DEPTH {
                checked_error = checked_error.max(worst);
                nodes.push((b, fb));
            } else {
                let m = 0.5 * (a + b);
                let fm = f(m);
                stack.push((m, fm, b, fb, depth + 1));
                stack.push((a, fa, m, fm, depth + 1));
            }
        }
        let bins = nodes.len() - 1;
        let mut cdf = Vec::with_capacity(bins + 1);
        cdf.push(0.0);
        let mut total = 0.0;
        for w in nodes.windows(2) {
            total += 0.5 * (w[1].0 - w[0].0) * (w[0].1 + w[1].1);
            cdf.push(total);
        }
        for c in &mut cdf {
            *c /= total;
        }
        cdf[bins] = 1.0;
        let mut guide = Vec::with_capacity(bins);
        let mut i = 0;
        for j in 0..bins {
            let u = j as f64 / bins as f64;
            while i + 1 < bins && cdf[i + 1] <= u {
                i += 1;
            }
            guide.push(i as u32);
        }
        PiecewiseLinear {
            x: nodes.iter().map(|n| n.0).collect(),
            q: nodes.iter().map(|n| n.1 / total).collect(),
            cdf: cdf.into(),
            guide: guide.into(),
            checked_error,
        }
    }

    /// Number of bins.
    pub(crate) fn bins(&self) -> usize {
        self.x.len() - 1
    }

    /// The largest relative error of the chord found at the checked points.
    pub(crate) fn checked_error(&self) -> f64 {
        self.checked_error
    }

    /// The nodes and the normalised density at them (for tests and reports).
    pub(crate) fn nodes(&self) -> (&[f64], &[f64]) {
        (&self.x, &self.q)
    }

    /// `x` for `u ∈ [0, 1)`, drawn exactly from the piecewise-linear density.
    #[inline]
    pub(crate) fn sample(&self, u: f64) -> f64 {
        let bins = self.bins();
        let j = ((u * bins as f64) as usize).min(bins - 1);
        let mut i = self.guide[j] as usize;
        while i + 1 < bins && self.cdf[i + 1] <= u {
            i += 1;
        }
        let mass = self.cdf[i + 1] - self.cdf[i];
        let t = if mass > 0.0 {
            ((u - self.cdf[i]) / mass).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (a, b) = (self.q[i], self.q[i + 1]);
        self.x[i] + (self.x[i + 1] - self.x[i]) * sample_linear(t, a, b)
    }

    /// The density per unit `x` at `x`: 0 outside `[0, x_max]`.
    #[inline]
    pub(crate) fn pdf(&self, x: f64) -> f64 {
        let bins = self.bins();
        if !(x >= 0.0 && x <= self.x[bins]) {
            return 0.0;
        }
        let i = self.x[1..bins].partition_point(|&node| node <= x);
        let (x0, x1) = (self.x[i], self.x[i + 1]);
        let t = (x - x0) / (x1 - x0);
        self.q[i] + t * (self.q[i + 1] - self.q[i])
    }
}

/// `t ∈ [0, 1)` distributed with density proportional to `(1-t)a + t b` (both
/// non-negative, not both 0), by inverting its CDF: `t = u(a+b) / (a +
/// sqrt(lerp(u, a^2, b^2)))`, the cancellation-free root of the quadratic (pbrt-v4,
/// `SampleLinear` in src/pbrt/util/sampling.h).
#[inline]
fn sample_linear(u: f64, a: f64, b: f64) -> f64 {
    if u == 0.0 && a == 0.0 {
        return 0.0;
    }
    let t = u * (a + b) / (a + ((1.0 - u) * a * a + u * b * b).sqrt());
    t.min(1.0 - f64::EPSILON / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_sampling_inverts_its_cdf() {
        // CDF of the density ((1-t)a + t b)/((a+b)/2): (a t + (b-a) t^2/2) / ((a+b)/2).
        for (a, b) in [(1.0, 1.0), (0.0, 2.0), (2.0, 0.0), (0.3, 1.7), (5.0, 0.01)] {
            for k in 0..=100 {
                let u = f64::from(k) / 100.0 * (1.0 - 1e-12);
                let t = sample_linear(u, a, b);
                let cdf = (a * t + 0.5 * (b - a) * t * t) / (0.5 * (a + b));
                assert!((cdf - u).abs() < 1e-12, "a={a} b={b} u={u}: {cdf}");
            }
        }
    }

    #[test]
    fn a_linear_function_needs_one_bin() {
        let t = PiecewiseLinear::build(|x| 2.0 - x, 2.0, 1e-6);
        assert_eq!(t.bins(), 1);
        // Density (2 - x)/2 on [0, 2]; its inverse CDF is 2 - 2 sqrt(1 - u).
        for k in 0..100 {
            let u = f64::from(k) / 100.0;
            let x = t.sample(u);
            assert!(
                (x - (2.0 - 2.0 * (1.0 - u).sqrt())).abs() < 1e-12,
                "{u}: {x}"
            );
            assert!((t.pdf(x) - (2.0 - x) / 2.0).abs() < 1e-12);
        }
        assert_eq!(t.pdf(-1e-9), 0.0);
        assert_eq!(t.pdf(2.0 + 1e-9), 0.0);
    }

    #[test]
    fn the_table_follows_a_closed_form_inverse_cdf() {
        // cos^n tabulated: its CDF in x is 1 - (1-x)^(n+1).
        for n in [3.0, 100.0, 5000.0] {
            let t = PiecewiseLinear::build(|x: f64| (1.0 - x).powf(n), 1.0, TABLE_TOLERANCE);
            let mut ks: f64 = 0.0;
            for k in 0..=100_000 {
                let u = f64::from(k) / 100_000.0 * (1.0 - 1e-12);
                let x = t.sample(u);
                ks = ks.max((1.0 - (1.0 - x).powf(n + 1.0) - u).abs());
            }
            assert!(t.checked_error() <= TABLE_TOLERANCE);
            assert!(ks <= 1e-5, "n={n}: {ks}");
        }
    }

    #[test]
    fn the_guide_finds_every_bin() {
        // A peaked density: bins of very different masses.
        let t = PiecewiseLinear::build(|x| 1.0 / (1.0 + 1e3 * x), 1.0, 1e-4);
        for i in 0..t.bins() {
            for s in [0.0, 0.5, 0.999] {
                let u = t.cdf[i] + s * (t.cdf[i + 1] - t.cdf[i]);
                let x = t.sample(u);
                assert!(x >= t.x[i] && x <= t.x[i + 1], "bin {i}: {x}");
            }
        }
    }
}
