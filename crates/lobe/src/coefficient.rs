//! Coefficients of the power fits `f_a(c) = max(0, 1 - a(1-c))^m`, `m = 2^v`, their
//! closed-form integral, and the error search behind the minimax fit.

/// The energy-fit coefficient `a = (n+1)/(2^v+1)` of K_v (paper, eq. for K_v): it gives
/// the lobe the same integral `∫ f sin γ dγ = 1/(n+1)` as `cos^n` wherever `a >= 1`.
pub fn energy_fit_coefficient(n: f64, v: u32) -> f64 {
    (n + 1.0) / (f64::from(1u32 << v) + 1.0)
}

/// The slope-fit coefficient `a = n/2^v` of G_v (Lyon 1993): it matches the slope of
/// `cos^n` in `c` at `c = 1`.
pub fn slope_fit_coefficient(n: f64, v: u32) -> f64 {
    n / f64::from(1u32 << v)
}

/// `∫_0^{π/2} f_a(cos γ) sin γ dγ = ∫_0^1 max(0, 1 - a t)^m dt` in closed form.
///
/// Equals `1/(a(m+1))` when `a >= 1` (the base reaches 0 inside the range) and
/// `(1 - (1-a)^(m+1)) / (a(m+1))` when `0 < a < 1`; 1 when `a = 0`.
pub fn power_lobe_integral(a: f64, m: u32) -> f64 {
    let m1 = f64::from(m) + 1.0;
    if a <= 0.0 {
        1.0
    } else if a >= 1.0 {
        1.0 / (a * m1)
    } else {
        // 1 - (1-a)^(m+1) loses digits for tiny a; -expm1((m+1) ln(1-a)) does not.
        -((m1) * (-a).ln_1p()).exp_m1() / (a * m1)
    }
}

/// `∫ max(0, 1 - a(1-c))^m dω` over the whole sphere (`c ∈ [-1, 1]`), times nothing:
/// `2π ∫_0^{min(1/a, 2)} (1 - a x)^m dx` with `x = 1 - c`.
///
/// `2π/(a(m+1))` when `a >= 1/2` (the base reaches 0 at `x = 1/a <= 2`), else
/// `2π (1 - (1-2a)^(m+1))/(a(m+1))` (the support is cut at `c = -1`); `4π` at `a = 0`.
pub(crate) fn power_sphere_integral(a: f64, m: u32) -> f64 {
    use std::f64::consts::TAU;
    let m1 = f64::from(m) + 1.0;
    if a <= 0.0 {
        2.0 * TAU
    } else {
        TAU * power_support_mass(a, m) / (a * m1)
    }
}

/// `1 - (1 - a·min(1/a, 2))^(m+1)`: the share of the uncut power lobe's mass that lies
/// on the sphere (1 when `a >= 1/2`), computed without cancellation for small `a`.
pub(crate) fn power_support_mass(a: f64, m: u32) -> f64 {
    if a >= 0.5 {
        1.0
    } else {
        -((f64::from(m) + 1.0) * (-2.0 * a).ln_1p()).exp_m1()
    }
}

/// `∫_0^1 c/(n(1-c) + c) dc`, Schlick's lobe over the hemisphere (it is 0 for
/// `c <= 0`): with `x = 1 - c` and `k = n - 1`, `∫_0^1 (1-x)/(1+kx) dx =
/// n ln(n)/k^2 - 1/k`. Near `n = 1` that cancels, so there the series
/// `1 - n Σ_{i>=0} (-k)^i/(i+2)` (from `ln(1+y) - y = Σ_{j>=2} (-1)^(j+1) y^j/j`) is
/// summed instead. 1 at `n = 0` (the lobe is 1 for every `c > 0`).
pub(crate) fn schlick_hemisphere_integral(n: f64) -> f64 {
    let k = n - 1.0;
    if n == 0.0 {
        1.0
    } else if k.abs() < 0.5 {
        // |k| < 1/2: 60 terms leave < 2^-60 of the sum.
        let mut sum = 0.0;
        let mut pow = 1.0;
        for i in 0..60 {
            sum += pow / f64::from(i + 2);
            pow *= -k;
        }
        1.0 - n * sum
    } else {
        n * n.ln() / (k * k) - 1.0 / k
    }
}

/// Where a lobe's error against `cos^n` peaks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorPeak {
    /// The signed error `lobe(c) - c^n` at the peak; its magnitude is the max abs error.
    pub error: f64,
    /// `c = cos γ` at the peak.
    pub cos: f64,
}

impl ErrorPeak {
    /// The angle γ of the peak in degrees.
    pub fn angle_deg(&self) -> f64 {
        self.cos.clamp(-1.0, 1.0).acos().to_degrees()
    }
}

/// The largest positive and the largest negative error of `f(c) - c^n` over
/// `c ∈ [0, 1]`, as `(positive, negative)` (the negative peak carries a negative or
/// zero error).
///
/// Method: a sorted grid in `t = 1 - c` that is dense on the scale of the lobe (`1/n`)
/// and covers the whole range, the clamp point `t = 1/a` given in `kinks`, then a
/// golden-section refinement between the neighbours of each grid maximum. The error
/// functions of these lobes have a few smooth or kinked humps, so the refinement
/// converges to the true peak to ~1e-12 in `t`.
fn signed_peaks(f: &dyn Fn(f64) -> f64, n: f64, kinks: &[f64]) -> (ErrorPeak, ErrorPeak) {
    let scale = 1.0 / n.max(1.0);
    let mut grid: Vec<f64> = Vec::with_capacity(1600);
    for (span, count) in [(1.0, 400), (30.0 * scale, 400), (4.0 * scale, 400)] {
        let span = f64::min(span, 1.0);
        grid.extend((0..=count).map(|i| span * i as f64 / count as f64));
    }
    grid.extend(kinks.iter().copied().filter(|t| (0.0..=1.0).contains(t)));
    grid.sort_by(f64::total_cmp);
    grid.dedup();

    let d = |t: f64| {
        let c = 1.0 - t;
        f(c) - c.powf(n)
    };
    let values: Vec<f64> = grid.iter().map(|&t| d(t)).collect();
    let refine = |sign: f64| {
        let (i, _) = values
            .iter()
            .enumerate()
            .max_by(|a, b| (sign * a.1).total_cmp(&(sign * b.1)))
            .expect("grid is never empty");
        let lo = grid[i.saturating_sub(1)];
        let hi = grid[(i + 1).min(grid.len() - 1)];
        let (t, e) = golden_max(|t| sign * d(t), lo, hi, grid[i], sign * values[i]);
        ErrorPeak {
            error: sign * e,
            cos: 1.0 - t,
        }
    };
    (refine(1.0), refine(-1.0))
}

/// Maximises `g` on `[lo, hi]` by golden-section search, never returning worse than
/// the starting point `(t0, g0)`; returns `(t, g(t))`.
///
/// For a unimodal `g` (smooth or kinked) the bracket shrinks to ~1e-15. Shared by the
/// minimax search here and the error metrics of `glint-analysis`.
pub fn golden_max(
    g: impl Fn(f64) -> f64,
    mut lo: f64,
    mut hi: f64,
    t0: f64,
    g0: f64,
) -> (f64, f64) {
    const INV_PHI: f64 = 0.618_033_988_749_894_8;
    let (mut best_t, mut best) = (t0, g0);
    let mut x1 = hi - INV_PHI * (hi - lo);
    let mut x2 = lo + INV_PHI * (hi - lo);
    let (mut g1, mut g2) = (g(x1), g(x2));
    for _ in 0..80 {
        if hi - lo <= 1e-15 {
            break;
        }
        if g1 < g2 {
            lo = x1;
            x1 = x2;
            g1 = g2;
            x2 = lo + INV_PHI * (hi - lo);
            g2 = g(x2);
        } else {
            hi = x2;
            x2 = x1;
            g2 = g1;
            x1 = hi - INV_PHI * (hi - lo);
            g1 = g(x1);
        }
    }
    for (t, v) in [(x1, g1), (x2, g2)] {
        if v > best {
            best = v;
            best_t = t;
        }
    }
    (best_t, best)
}

fn power_form(a: f64, v: u32) -> impl Fn(f64) -> f64 {
    move |c: f64| {
        let b = 1.0 - a * (1.0 - c);
        if b <= 0.0 {
            0.0
        } else {
            b.powi(1 << v)
        }
    }
}

/// The maximum absolute error of `f` against `c^n` over `c ∈ [0, 1]` (γ from 0 to 90
/// degrees) and where it occurs. `kinks` lists points `t = 1 - c` where `f` is not
/// smooth (for a power fit, `1/a`), so the search looks there too.
pub fn max_abs_error(f: impl Fn(f64) -> f64, n: f64, kinks: &[f64]) -> ErrorPeak {
    let (pos, neg) = signed_peaks(&f, n, kinks);
    if pos.error >= -neg.error {
        pos
    } else {
        neg
    }
}

/// The coefficient `a` of `max(0, 1 - a(1-c))^(2^v)` that minimises the maximum
/// absolute error against `c^n` over `c ∈ [0, 1]`.
///
/// Raising `a` lowers the lobe at every `c < 1`, so the largest positive error
/// `max(f_a - c^n)` falls with `a` and the largest negative one `max(c^n - f_a)` rises.
/// The maximum absolute error is the larger of the two, so it is minimised where they
/// are equal (the equioscillation point); this function finds that `a` by bisection,
/// starting from the bracket spanned by the energy and slope fits. Costs a few
/// milliseconds; the result is accurate to ~1e-12 relative.
pub fn minimax_coefficient(n: f64, v: u32) -> f64 {
    if n <= 0.0 {
        // cos^0 = 1 everywhere on [0, 1]; a = 0 reproduces it exactly.
        return 0.0;
    }
    let balance = |a: f64| {
        let kink = [1.0 / a];
        let (pos, neg) = signed_peaks(&power_form(a, v), n, &kink);
        pos.error + neg.error // > 0: lobe too wide, raise a
    };
    let ke = energy_fit_coefficient(n, v);
    let ks = slope_fit_coefficient(n, v);
    let mut lo = 0.5 * ke.min(ks);
    let mut hi = 2.0 * ke.max(ks);
    while balance(lo) < 0.0 && lo > 1e-300 {
        lo *= 0.5;
    }
    while balance(hi) > 0.0 && hi < 1e300 {
        hi *= 2.0;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if balance(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integral_closed_form_limits() {
        // a = 1: ∫ (1-t)^m dt = 1/(m+1), reached from both branches.
        assert!((power_lobe_integral(1.0, 16) - 1.0 / 17.0).abs() < 1e-15);
        assert!((power_lobe_integral(1.0 - 1e-12, 16) - 1.0 / 17.0).abs() < 1e-10);
        // a -> 0: the lobe tends to 1 on the whole range.
        assert!((power_lobe_integral(1e-14, 16) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn schlick_integral_branches_agree() {
        // The series (|k| < 1/2) and the closed form meet continuously at k = ±1/2.
        for n in [0.5f64, 1.5] {
            let closed = n * n.ln() / ((n - 1.0) * (n - 1.0)) - 1.0 / (n - 1.0);
            let below = schlick_hemisphere_integral(n - 1e-9);
            let above = schlick_hemisphere_integral(n + 1e-9);
            assert!((below - closed).abs() < 1e-8 && (above - closed).abs() < 1e-8);
        }
        // n = 1: the lobe is c, whose integral is 1/2.
        assert!((schlick_hemisphere_integral(1.0) - 0.5).abs() < 1e-16);
    }

    #[test]
    fn golden_section_finds_a_kinked_peak() {
        let (t, g) = golden_max(|t| -(t - 0.3).abs(), 0.0, 1.0, 0.0, -0.3);
        assert!((t - 0.3).abs() < 1e-9, "{t}");
        assert!(g.abs() < 1e-9);
    }

    #[test]
    fn minimax_is_exact_where_the_fits_are() {
        // n = 2^v: a = 1 reproduces cos^n exactly, so the minimax error is ~0.
        let a = minimax_coefficient(16.0, 4);
        assert!((a - 1.0).abs() < 1e-9, "{a}");
    }
}
