//! Sampling every lobe: the pdfs integrate to 1, χ² goodness of fit of 10^6 samples
//! against the pdf (binned in cos γ and azimuth, as pbrt-v4's bsdfs_test.cpp does),
//! sample/pdf consistency, no samples where the lobe is 0, the tabulated sampler's
//! error bound, the world-space helpers (Phong and Blinn, with the Blinn Jacobian
//! checked against a numerical one), the table sampled as K_v, and K_v's energy
//! property. Expected counts and integrals come from numerical quadrature of the pdf
//! or the lobe (tests/common), never from the samplers.
//!
//! Seeds are fixed, so every run draws the same samples; the χ² threshold is a
//! significance level of 0.01 for the whole file, Šidák-corrected over its
//! [`CHI2_TESTS`] tests, so a correct sampler would fail it with probability 1% for
//! a random choice of seeds. `cargo test -p glint-lobe --test sampling -- --nocapture`
//! prints every statistic.

mod common;

use std::f64::consts::TAU;

use common::*;
use glint_lobe::{
    blinn_cos, phong_cos, AxisLobe, CosTable, Geometry, Lobe, LobeError, LobeKind, LobeSampler,
    Real, Scatter, Specular, MAX_N, TABULATED_PDF_MAX_REL_ERROR,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const SAMPLES: usize = 1_000_000;
const X_BINS: usize = 40;
const PHI_BINS: usize = 8;
const ALPHA: f64 = 0.01;

/// The axis-frame χ² cases in f64: (kind, n, v). Each power fit has a case with
/// `a < 1/2`, where the support is cut at `c = -1`.
const AXIS_CASES: [(LobeKind, f64, u32); 19] = [
    (LobeKind::Exact, 1.0, 4),
    (LobeKind::Exact, 30.0, 4),
    (LobeKind::Exact, 1000.0, 4),
    (LobeKind::EnergyFit, 3.0, 4),
    (LobeKind::EnergyFit, 10.0, 4),
    (LobeKind::EnergyFit, 100.0, 4),
    (LobeKind::EnergyFit, 1000.0, 8),
    (LobeKind::SlopeFit, 5.0, 4),
    (LobeKind::SlopeFit, 100.0, 4),
    (LobeKind::SlopeFit, 2000.0, 10),
    (LobeKind::Minimax, 10.0, 2),
    (LobeKind::Minimax, 100.0, 4),
    (LobeKind::Schlick, 1.0, 4),
    (LobeKind::Schlick, 10.0, 4),
    (LobeKind::Schlick, 100.0, 4),
    (LobeKind::Schlick, 10_000.0, 4),
    (LobeKind::Gauss, 0.5, 4),
    (LobeKind::Gauss, 20.0, 4),
    (LobeKind::Gauss, 1000.0, 4),
];

/// f32 samplers tested by χ² too: (kind, n, v).
const F32_CASES: [(LobeKind, f64, u32); 4] = [
    (LobeKind::Exact, 100.0, 4),
    (LobeKind::EnergyFit, 100.0, 4),
    (LobeKind::Schlick, 100.0, 4),
    (LobeKind::Gauss, 100.0, 4),
];

/// World-space cases, Phong (1) and Blinn (3), and the tables sampled as K_v (2).
const WORLD_CASES: usize = 6;

/// Every χ² test in this file, for the Šidák correction.
const CHI2_TESTS: usize = AXIS_CASES.len() + F32_CASES.len() + WORLD_CASES;

fn threshold() -> f64 {
    sidak(ALPHA, CHI2_TESTS)
}

fn check(name: &str, r: Chi2) {
    println!(
        "chi2 {name:<34} stat {:>8.1}  dof {:>3}  p {:.3}  (cells {})",
        r.stat, r.dof, r.p, r.cells
    );
    assert!(
        r.dof > 10 && r.p >= threshold(),
        "{name}: χ² {:.1} with {} dof, p = {:.2e} < {:.2e}",
        r.stat,
        r.dof,
        r.p,
        threshold()
    );
}

fn f64_of<T: Real>(t: T) -> f64 {
    t.to_f64().unwrap()
}

/// χ² of 10^6 axis-frame directions against `lobe`'s pdf: 40 bins in `x = 1 - cos γ`
/// (quantiles of the pdf's own mass, by quadrature) times 8 in azimuth.
fn chi2_axis<T: Real>(lobe: &impl AxisLobe<T>, kinks: &[f64], seed: u64) -> Chi2 {
    let g = grid(4000, 44.0, kinks);
    let masses = piece_integrals(&g, |x| TAU * f64_of(lobe.pdf_cos(T::from_f64(1.0 - x))));
    let edges = quantile_edges(&masses, X_BINS);
    let xb = edges.len() - 1;
    let mut expected = vec![0.0; xb * PHI_BINS];
    for j in 0..xb {
        let m: f64 = masses[edges[j]..edges[j + 1]].iter().sum();
        for k in 0..PHI_BINS {
            expected[j * PHI_BINS + k] = SAMPLES as f64 * m / PHI_BINS as f64;
        }
    }
    let x_edges: Vec<f64> = edges.iter().map(|&i| g[i]).collect();
    let mut observed = vec![0.0; xb * PHI_BINS];
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    for _ in 0..SAMPLES {
        let (u1, u2): (f64, f64) = (rng.random(), rng.random());
        let d = lobe.sample(T::from_f64(u1), T::from_f64(u2)).map(f64_of);
        let x = 1.0 - d[2];
        let phi = d[1].atan2(d[0]).rem_euclid(TAU);
        let j = x_edges.partition_point(|&e| e <= x).clamp(1, xb) - 1;
        let k = ((phi / TAU * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
        observed[j * PHI_BINS + k] += 1.0;
    }
    chi2(&observed, &expected)
}

fn run_axis_cases(kinds: &[LobeKind]) {
    for (i, &(kind, n, v)) in AXIS_CASES.iter().enumerate() {
        if kinds.contains(&kind) {
            let s = f64_sampler(kind, n, v);
            let r = chi2_axis(&s, &kinks_of(&s), 1000 + i as u64);
            check(&format!("{kind} n={n} v={v}"), r);
        }
    }
}

#[test]
fn chi2_exact() {
    run_axis_cases(&[LobeKind::Exact]);
}

#[test]
fn chi2_energy_fit() {
    run_axis_cases(&[LobeKind::EnergyFit]);
}

#[test]
fn chi2_slope_fit_and_minimax() {
    run_axis_cases(&[LobeKind::SlopeFit, LobeKind::Minimax]);
}

#[test]
fn chi2_schlick() {
    run_axis_cases(&[LobeKind::Schlick]);
}

#[test]
fn chi2_gauss() {
    run_axis_cases(&[LobeKind::Gauss]);
}

#[test]
fn chi2_f32_samplers() {
    for (i, &(kind, n, v)) in F32_CASES.iter().enumerate() {
        let s = LobeSampler::new(&Lobe::<f32>::new(kind, n, v).unwrap());
        let kinks = kinks_of(&f64_sampler(kind, n, v));
        check(
            &format!("{kind} n={n} v={v} (f32)"),
            chi2_axis(&s, &kinks, 2000 + i as u64),
        );
    }
}

/// The χ² test has power: K_4(100)'s samples against the pdf of K_4(103) are
/// rejected (one more test for the Šidák correction would not change that).
#[test]
fn chi2_rejects_a_wrong_pdf() {
    struct Wrong(LobeSampler<f64>, LobeSampler<f64>);
    impl AxisLobe<f64> for Wrong {
        fn eval_cos(&self, c: f64) -> f64 {
            self.1.eval_cos(c)
        }
        fn pdf_cos(&self, c: f64) -> f64 {
            self.1.pdf_cos(c)
        }
        fn sample_one_minus_cos(&self, u: f64) -> f64 {
            self.0.sample_one_minus_cos(u)
        }
    }
    let w = Wrong(
        f64_sampler(LobeKind::EnergyFit, 100.0, 4),
        f64_sampler(LobeKind::EnergyFit, 103.0, 4),
    );
    let r = chi2_axis(&w, &[17.0 / 101.0, 17.0 / 104.0], 8000);
    println!(
        "chi2 wrong pdf (k 100 vs 103): stat {:.1} dof {} p {:.1e}",
        r.stat, r.dof, r.p
    );
    assert!(r.p < threshold(), "{r:?}");
}

#[test]
fn every_pdf_integrates_to_one() {
    let mut worst: f64 = 0.0;
    for &kind in LobeKind::ALL {
        for n in [0.0, 1e-3, 0.5, 1.0, 3.0, 10.0, 100.0, 1000.0, MAX_N] {
            for v in [0, 1, 4, 10] {
                let s = f64_sampler(kind, n, v);
                let mass = sphere_mass(&s, &grid(4000, 44.0, &kinks_of(&s)));
                worst = worst.max((mass - 1.0).abs());
                assert!(
                    (mass - 1.0).abs() <= 1e-4,
                    "{kind} n={n} v={v}: ∫ pdf dω = {mass}"
                );
                let s32 = LobeSampler::new(&Lobe::<f32>::new(kind, n, v).unwrap());
                let mass32 = sphere_mass(&s32, &grid(4000, 44.0, &kinks_of(&s)));
                assert!(
                    (mass32 - 1.0).abs() <= 1e-4,
                    "{kind} n={n} v={v} (f32): ∫ pdf dω = {mass32}"
                );
            }
        }
    }
    println!("largest |∫ pdf dω - 1| (f64): {worst:.2e}");
}

/// The lobes, parameters and precisions of the consistency sweeps.
fn sweep() -> Vec<(LobeKind, f64, u32)> {
    let mut out = Vec::new();
    for &kind in LobeKind::ALL {
        for n in [0.0, 1e-3, 0.5, 1.0, 3.0, 7.0, 16.0, 100.0, 1000.0, MAX_N] {
            for v in [0, 1, 4, 10] {
                out.push((kind, n, v));
            }
        }
    }
    out
}

/// The sampler is the inverse CDF of its pdf: the density it implies, `1 / (dx/du)`
/// by central differences, equals `2π pdf_cos(1 - x)`.
#[test]
fn sampler_implies_its_pdf() {
    let mut worst_closed: f64 = 0.0;
    let mut worst_table: f64 = 0.0;
    for (kind, n, v) in sweep() {
        let s = f64_sampler(kind, n, v);
        let tol = if s.is_tabulated() { 1e-4 } else { 1e-5 };
        for i in 1..2000 {
            let u = f64::from(i) / 2000.0;
            let du = 1e-3 * u.min(1.0 - u);
            let x = s.sample_one_minus_cos(u);
            let slope =
                (s.sample_one_minus_cos(u + du) - s.sample_one_minus_cos(u - du)) / (2.0 * du);
            let implied = 1.0 / slope;
            let pdf = TAU * s.pdf_cos(1.0 - x);
            let rel = (implied / pdf - 1.0).abs();
            if s.is_tabulated() {
                worst_table = worst_table.max(rel);
            } else {
                worst_closed = worst_closed.max(rel);
            }
            assert!(
                rel <= tol,
                "{kind} n={n} v={v} u={u}: implied {implied}, pdf {pdf}"
            );
        }
    }
    println!("implied density vs pdf: closed forms {worst_closed:.1e}, table {worst_table:.1e}");
}

/// No sample where the lobe or its pdf is 0, NaN or infinite, in f32 or f64, from
/// the extremes of `[0, 1)` (and beyond: inputs are clamped) and a grid between.
#[test]
fn no_sample_where_the_lobe_is_zero() {
    fn check_all<T: Real>(s: &LobeSampler<T>, label: &str) {
        let mut us: Vec<f64> = (0..=1000).map(|i| f64::from(i) / 1000.0).collect();
        us.extend([
            1e-30,
            1e-12,
            1.0 - 1e-7,
            1.0 - 1e-12,
            1.0 - f64::EPSILON / 2.0,
            2.0,
            -1.0,
            f64::NAN,
        ]);
        for &u in &us {
            for u2 in [0.0, 0.3, 0.999_999] {
                let d = s.sample(T::from_f64(u), T::from_f64(u2));
                let (e, p) = (s.eval(d), s.pdf(d));
                let len = f64_of(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                assert!(
                    e > T::zero() && p > T::zero() && p.is_finite() && (len - 1.0).abs() < 1e-6,
                    "{label} u={u}: dir {d:?}, eval {e:?}, pdf {p:?}"
                );
            }
        }
    }
    for (kind, n, v) in sweep() {
        check_all(&f64_sampler(kind, n, v), &format!("{kind} n={n} v={v}"));
        let s32 = LobeSampler::new(&Lobe::<f32>::new(kind, n, v).unwrap());
        check_all(&s32, &format!("{kind} n={n} v={v} f32"));
    }
}

/// f32 samples follow f64's: the same `u` gives the same `x` up to f32 rounding.
#[test]
fn f32_sampling_follows_f64() {
    let mut worst: f64 = 0.0;
    for (kind, n, v) in sweep() {
        let s64 = f64_sampler(kind, n, v);
        let s32 = LobeSampler::new(&Lobe::<f32>::new(kind, n, v).unwrap());
        for i in 0..1000 {
            let u32_ = i as f32 / 1000.0;
            let x64 = s64.sample_one_minus_cos(f64::from(u32_));
            let x32 = f64::from(s32.sample_one_minus_cos(u32_));
            // f32's cos γ resolves 2^-24 near 1; the power forms divide that by a.
            let a = s64.lobe().coefficient().unwrap_or(1.0).min(1.0);
            let tol = 1e-5 * x64 + 2e-7 / a.max(1e-3);
            worst = worst.max((x32 - x64).abs() / tol);
            assert!(
                (x32 - x64).abs() <= tol,
                "{kind} n={n} v={v} u={u32_}: {x32} vs {x64}"
            );
        }
    }
    println!("largest |x_f32 - x_f64| over its tolerance: {worst:.2}");
}

/// Schlick's tabulated density against the lobe's own normalised one, `eval / ∫ eval`
/// (closed-form integral, checked by quadrature in `sphere_integrals_match_quadrature`):
/// 64 points per bin. Also the sampler's CDF error (the Kolmogorov–Smirnov distance
/// between the sampled distribution and the lobe): `F(x(u)) - u` over 20001 `u`, `F`
/// by quadrature of the lobe.
#[test]
fn tabulated_density_is_within_its_bound() {
    for n in [1e-3, 0.3, 1.0, 2.0, 10.0, 100.0, 1000.0, MAX_N] {
        let s = f64_sampler(LobeKind::Schlick, n, 4);
        let (bins, checked) = s.table_stats().unwrap();
        let (nodes, _) = s.table_nodes().unwrap();
        let integral = s.integral();
        let mut worst: f64 = 0.0;
        for w in nodes.windows(2) {
            for k in 0..64 {
                let x = w[0] + (w[1] - w[0]) * (f64::from(k) + 0.5) / 64.0;
                let lobe_pdf = s.eval_cos(1.0 - x) / integral;
                if lobe_pdf > 0.0 {
                    worst = worst.max((s.pdf_cos(1.0 - x) / lobe_pdf - 1.0).abs());
                }
            }
        }
        // The lobe's CDF in x on a fine grid, then F at each sample.
        let g = grid(20_000, 44.0, &[1.0]);
        let f = |x: f64| if x < 1.0 { s.eval_cos(1.0 - x) } else { 0.0 };
        let pieces = piece_integrals(&g, f);
        let total: f64 = pieces.iter().sum();
        let mut cum = vec![0.0];
        for p in &pieces {
            cum.push(cum.last().unwrap() + p);
        }
        let mut ks: f64 = 0.0;
        for i in 0..=20_000 {
            let u = f64::from(i) / 20_000.0;
            let x = s.sample_one_minus_cos(u);
            let k = g.partition_point(|&e| e <= x).clamp(1, g.len() - 1) - 1;
            let part = piece_integrals(&[g[k], x], f)[0];
            ks = ks.max(((cum[k] + part) / total - u).abs());
        }
        println!(
            "schlick n={n}: {bins} bins, chord error at checked points {checked:.2e}, \
             pdf vs lobe (64 points/bin) {worst:.2e}, CDF error (KS) {ks:.2e}"
        );
        assert!(checked <= 1e-4, "n={n}: {checked}");
        assert!(worst <= TABULATED_PDF_MAX_REL_ERROR, "n={n}: {worst}");
        assert!(ks <= 1e-5, "n={n}: KS {ks}");
        assert!(bins <= 4096, "n={n}: {bins} bins");
    }
}

/// `Lobe::sphere_integral` (the pdfs' normalisation) against quadrature of `eval`.
#[test]
fn sphere_integrals_match_quadrature() {
    for (kind, n, v) in sweep() {
        let s = f64_sampler(kind, n, v);
        let g = grid(4000, 44.0, &kinks_of(&s));
        let q: f64 = piece_integrals(&g, |x| TAU * s.eval_cos(1.0 - x))
            .iter()
            .sum();
        let closed = s.lobe().sphere_integral();
        assert!(
            (q - closed).abs() <= 1e-9 * closed,
            "{kind} n={n} v={v}: quadrature {q} vs {closed}"
        );
    }
}

/// `2π ∫_{lo}^{hi} K(c) dc` by double-exponential quadrature, split at the clamp
/// point `c = 1 - 1/a` (independent of the Gauss–Legendre grid above).
fn k_integral(l: &Lobe<f64>, lo: f64, hi: f64) -> f64 {
    let a = l.coefficient().unwrap();
    let kink = 1.0 - 1.0 / a;
    let mut cuts = vec![lo];
    if kink > lo && kink < hi {
        cuts.push(kink);
    }
    cuts.push(hi);
    cuts.windows(2)
        .map(|w| {
            quadrature::double_exponential::integrate(|c| l.eval(c), w[0], w[1], 1e-15).integral
        })
        .sum::<f64>()
        * TAU
}

/// The energy property: K_v's integral over the sphere is `2π/(a(m+1)) = 2π/(n+1)`,
/// that of `cos^n` on the hemisphere, for every `n >= (2^v - 1)/2` (where `a >= 1/2`:
/// the support `x <= 1/a` fits the sphere). Below, the support is cut at `c = -1` and
/// the integral is `2π (1 - (1-2a)^(m+1)) / (a(m+1))`, less. Restricted to the
/// hemisphere (docs/paper.md) the identity needs `n >= 2^v` (`a >= 1`).
#[test]
fn energy_property_of_k() {
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for v in 0..=10u32 {
        let m = f64::from(1u32 << v);
        let threshold = (m - 1.0) / 2.0;
        let mut ns = vec![0.0, 0.25, 1.0, 3.0, 10.0, 100.0, 1000.0, MAX_N];
        ns.extend([
            threshold,
            threshold + 0.5,
            m - 1.0,
            m,
            2.0 * m,
            threshold * 0.5,
        ]);
        for n in ns {
            if !(0.0..=MAX_N).contains(&n) {
                continue;
            }
            let l = Lobe::<f64>::new(LobeKind::EnergyFit, n, v).unwrap();
            let sphere = k_integral(&l, -1.0, 1.0);
            let hemisphere = k_integral(&l, 0.0, 1.0);
            let cos_n = TAU / (n + 1.0);
            let a = (n + 1.0) / (m + 1.0);
            if n >= threshold {
                let rel = (sphere - cos_n).abs() / cos_n;
                worst = worst.max(rel);
                checked += 1;
                assert!(rel <= 1e-9, "v={v} n={n}: {sphere} vs 2π/(n+1) = {cos_n}");
                if n < m {
                    // The lobe reaches past 90°: the hemisphere holds less, by the
                    // factor of docs/paper.md, 1 - (1-a)^(m+1).
                    let deficit = (1.0 - a).powf(m + 1.0);
                    let want = cos_n * (1.0 - deficit);
                    assert!((hemisphere - want).abs() <= 1e-9 * want, "v={v} n={n}");
                    if deficit > 1e-6 {
                        assert!(hemisphere < cos_n * (1.0 - 1e-7), "v={v} n={n}");
                    }
                }
            } else {
                let cut = TAU * (1.0 - (1.0 - 2.0 * a).powf(m + 1.0)) / (a * (m + 1.0));
                assert!(
                    (sphere - cut).abs() <= 1e-9 * cut,
                    "v={v} n={n}: {sphere} vs {cut}"
                );
                if (1.0 - 2.0 * a).powf(m + 1.0) > 1e-6 {
                    assert!(sphere < cos_n * (1.0 - 1e-7), "v={v} n={n}");
                }
            }
            assert!((l.sphere_integral() - sphere).abs() <= 1e-9 * sphere);
        }
    }
    println!("K_v energy property: {checked} (n, v) pairs, largest relative error {worst:.1e}");
}

/// Reflection of `wo` about the unit `h`, written here.
fn reflect(wo: [f64; 3], h: [f64; 3]) -> [f64; 3] {
    let k = 2.0 * dot(wo, h);
    [0, 1, 2].map(|i| k * h[i] - wo[i])
}

/// `dω_i/dω_h` of `h -> reflect(wo, h)`, numerically: the ratio of the areas of the
/// images of a small cross of half-width 1e-5 around `h` (central differences).
fn numerical_jacobian(wo: [f64; 3], h: [f64; 3]) -> f64 {
    let (t1, t2) = tangents(h);
    let e = 1e-5;
    let p = |t: [f64; 3], s: f64| unit([0, 1, 2].map(|i| h[i] + s * e * t[i]));
    let (a1, b1, a2, b2) = (p(t1, 1.0), p(t1, -1.0), p(t2, 1.0), p(t2, -1.0));
    let sub = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|i| a[i] - b[i]);
    let area = |a: [f64; 3], b: [f64; 3]| {
        let c = cross(a, b);
        dot(c, c).sqrt()
    };
    let img = area(
        sub(reflect(wo, a1), reflect(wo, b1)),
        sub(reflect(wo, a2), reflect(wo, b2)),
    );
    img / area(sub(a1, b1), sub(a2, b2))
}

/// Blinn in world space: samples binned by their own half vector
/// `normalize(ω_o + ω_i)` around N (20 × 8 cells) plus a cell for the draws returned
/// as `None`; expected counts `∫_cell pdf(ω_i(h)) · dω_i/dω_h dω_h`, with the
/// Jacobian computed numerically, so the crate's `1/(4 ω_o·h)` is checked too.
fn chi2_blinn(s: &LobeSampler<f64>, theta_o_deg: f64, seed: u64) -> (Chi2, f64) {
    let n = [0.0, 0.0, 1.0];
    let th = theta_o_deg.to_radians();
    let wo = [th.sin(), 0.0, th.cos()];
    let sc = Scatter::new(Geometry::Blinn, n, wo).unwrap();
    let g = grid(300, 30.0, &kinks_of(s));
    let cells = piece_cells(n, &g, PHI_BINS, |h| {
        let d = dot(wo, h);
        if d <= 0.0 {
            0.0
        } else {
            sc.pdf(s, reflect(wo, h)) * numerical_jacobian(wo, h)
        }
    });
    let masses: Vec<f64> = cells.iter().map(|r| r.iter().sum()).collect();
    let valid: f64 = masses.iter().sum();
    let edges = quantile_edges(&masses, 20);
    let xb = edges.len() - 1;
    let mut expected = vec![0.0; xb * PHI_BINS + 1];
    for j in 0..xb {
        for row in &cells[edges[j]..edges[j + 1]] {
            for (k, m) in row.iter().enumerate() {
                expected[j * PHI_BINS + k] += SAMPLES as f64 * m;
            }
        }
    }
    expected[xb * PHI_BINS] = SAMPLES as f64 * (1.0 - valid).max(0.0);
    let x_edges: Vec<f64> = edges.iter().map(|&i| g[i]).collect();
    let t = tangents(n);
    let mut observed = vec![0.0; expected.len()];
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    for _ in 0..SAMPLES {
        match sc.sample(s, rng.random(), rng.random()) {
            Some(smp) => {
                let h = unit([0, 1, 2].map(|i| wo[i] + smp.wi[i]));
                let (x, phi) = polar(n, t, h);
                let j = x_edges.partition_point(|&e| e <= x).clamp(1, xb) - 1;
                let k = ((phi / TAU * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
                observed[j * PHI_BINS + k] += 1.0;
            }
            None => observed[xb * PHI_BINS] += 1.0,
        }
    }
    (chi2(&observed, &expected), valid)
}

/// The share of the half-vector lobe on `ω_o·h > 0`, by rings around N: on the ring at
/// `cos γ`, `ω_o·h > 0` on an arc of `arccos(-cot θ_o cot γ) / π` of the ring.
fn blinn_valid_mass(s: &LobeSampler<f64>, theta_o_deg: f64) -> f64 {
    let th = theta_o_deg.to_radians();
    let g = grid(4000, 44.0, &kinks_of(s));
    piece_integrals(&g, |x| {
        let c = 1.0 - x;
        let sin = (x * (2.0 - x)).sqrt();
        // ω_o·h = cos θo c + sin θo sin γ cos φ > 0.
        let arg = if sin * th.sin() > 0.0 {
            (-th.cos() * c / (th.sin() * sin)).clamp(-1.0, 1.0)
        } else if th.cos() * c > 0.0 {
            -1.0
        } else {
            1.0
        };
        TAU * s.pdf_cos(c) * arg.acos() / std::f64::consts::PI
    })
    .iter()
    .sum()
}

#[test]
fn chi2_blinn_world_space() {
    let cases = [
        (LobeKind::Exact, 200.0, 4, 30.0),
        // Support up to γ = 33.7°: at θ_o = 60° some half vectors face away from ω_o.
        (LobeKind::EnergyFit, 100.0, 4, 60.0),
        (LobeKind::Gauss, 20.0, 4, 45.0),
    ];
    for (i, (kind, n, v, theta)) in cases.into_iter().enumerate() {
        let s = f64_sampler(kind, n, v);
        let (r, valid) = chi2_blinn(&s, theta, 3000 + i as u64);
        // The world pdf integrates to the share of half vectors facing ω_o.
        let rings = blinn_valid_mass(&s, theta);
        println!("blinn {kind} n={n} θo={theta}°: ∫ pdf dω_i = {valid:.6}, by rings {rings:.6}");
        assert!((valid - rings).abs() <= 1e-4, "{kind}: {valid} vs {rings}");
        check(&format!("blinn {kind} n={n} v={v} θo={theta}"), r);
    }
}

/// Phong in world space: directions binned around R (computed here) against the
/// 2D quadrature of `Scatter::pdf`.
#[test]
fn chi2_phong_world_space() {
    let s = f64_sampler(LobeKind::EnergyFit, 30.0, 4);
    let nrm = unit([0.2, -0.1, 1.0]);
    let wo = unit([0.7, 0.3, 0.5]);
    let sc = Scatter::new(Geometry::Phong, nrm, wo).unwrap();
    let r_axis = unit(reflect(wo, nrm));
    let g = grid(300, 30.0, &kinks_of(&s));
    let cells = piece_cells(r_axis, &g, PHI_BINS, |d| sc.pdf(&s, d));
    let masses: Vec<f64> = cells.iter().map(|r| r.iter().sum()).collect();
    let total: f64 = masses.iter().sum();
    assert!((total - 1.0).abs() <= 1e-4, "∫ pdf dω = {total}");
    let edges = quantile_edges(&masses, 20);
    let xb = edges.len() - 1;
    let mut expected = vec![0.0; xb * PHI_BINS];
    for j in 0..xb {
        for row in &cells[edges[j]..edges[j + 1]] {
            for (k, m) in row.iter().enumerate() {
                expected[j * PHI_BINS + k] += SAMPLES as f64 * m;
            }
        }
    }
    let x_edges: Vec<f64> = edges.iter().map(|&i| g[i]).collect();
    let t = tangents(r_axis);
    let mut observed = vec![0.0; expected.len()];
    let mut rng = Pcg64Mcg::seed_from_u64(4000);
    for _ in 0..SAMPLES {
        let smp = sc.sample(&s, rng.random(), rng.random()).unwrap();
        let (x, phi) = polar(r_axis, t, smp.wi);
        let j = x_edges.partition_point(|&e| e <= x).clamp(1, xb) - 1;
        let k = ((phi / TAU * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
        observed[j * PHI_BINS + k] += 1.0;
    }
    check("phong k n=30 v=4 (world)", chi2(&observed, &expected));
}

/// The world-space helpers agree with glint's shading cosines and with themselves:
/// a sample's value and pdf are `eval` and `pdf` at its direction.
#[test]
fn scatter_agrees_with_the_shading_cosines() {
    let mut rng = Pcg64Mcg::seed_from_u64(5000);
    for &kind in LobeKind::ALL {
        let s = f64_sampler(kind, 40.0, 4);
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            for _ in 0..2000 {
                let rand_dir =
                    |rng: &mut Pcg64Mcg| unit([0, 1, 2].map(|_| rng.random::<f64>() * 2.0 - 1.0));
                let nrm = rand_dir(&mut rng);
                let mut wo = rand_dir(&mut rng);
                if dot(wo, nrm) < 0.0 {
                    wo = wo.map(|w| -w);
                }
                let sc = Scatter::new(geometry, nrm, wo).unwrap();
                let Some(smp) = sc.sample(&s, rng.random(), rng.random()) else {
                    assert_eq!(geometry, Geometry::Blinn);
                    continue;
                };
                let c = match geometry {
                    Geometry::Phong => phong_cos(nrm, smp.wi, wo),
                    Geometry::Blinn => blinn_cos(nrm, smp.wi, wo),
                };
                let e = sc.eval(&s, smp.wi);
                assert!((e - s.lobe().eval(c)).abs() <= 1e-9, "{kind} {geometry}");
                assert!((smp.value - e).abs() <= 1e-9, "{kind} {geometry}");
                let p = sc.pdf(&s, smp.wi);
                assert!(
                    (smp.pdf - p).abs() <= 1e-9 * p,
                    "{kind} {geometry}: {} vs {p}",
                    smp.pdf
                );
                assert!(smp.value > 0.0 && smp.pdf > 0.0, "{kind} {geometry}");
            }
        }
    }
}

/// A Q1.14 table of K_4(60) with values rounded to 12 bits, as a fixed-point unit's.
fn hw_like_table(n: f64) -> CosTable {
    let k = Lobe::<f64>::new(LobeKind::EnergyFit, n, 4).unwrap();
    CosTable::from_fn(14, |code| {
        ((k.eval(f64::from(code) / 16384.0) * 4096.0).round() / 4096.0) as f32
    })
    .unwrap()
}

/// `∫ table dω` exactly: every code's value times `2π` times the length of the
/// cosines that round to it.
fn table_integral(t: &CosTable) -> f64 {
    let one = 1i32 << t.frac_bits();
    let w = 1.0 / f64::from(one);
    (-one..=one)
        .map(|code| {
            let len = if code.abs() == one { 0.5 * w } else { w };
            TAU * f64::from(t.value(code)) * len
        })
        .sum()
}

/// The table sampled as K_v: χ² of the proxy's samples, and `E[table / pdf]` over
/// 10^6 samples equals the table's exact integral (the estimator is unbiased),
/// also for a table lit beyond K_v's support (the proxy widens).
#[test]
fn table_sampled_as_k_is_unbiased() {
    let table = hw_like_table(60.0);
    assert_eq!(
        Specular::from(table.clone()).sampler(),
        Err(LobeError::TableWithoutShininess)
    );
    let spec = Specular::from(table.clone().with_shininess(60.0, 4));
    let s = spec.sampler().unwrap();
    // Sampled as K_4(60) itself: the table stays within DOMINANCE of it.
    assert!(!s.is_defensive());
    assert_eq!(s.sampler().lobe().coefficient(), Some(61.0 / 17.0));
    let kinks = [17.0 / 61.0];
    check("table K_4(60), sampled as K_4", chi2_axis(&s, &kinks, 6000));

    // A table also lit, faintly, down to c = -0.5, where K_4(60) is 0.
    let wide = CosTable::from_fn(14, |code| {
        let c = f64::from(code) / 16384.0;
        let v = table.value(code);
        if v == 0.0 && c >= -0.5 {
            1.0 / 4096.0
        } else {
            v
        }
    })
    .unwrap()
    .with_shininess(60.0, 4);
    let wide_s = Specular::from(wide.clone()).sampler().unwrap();
    // A defensive share now covers every lit cosine.
    assert!(wide_s.is_defensive());
    let lowest = (f64::from(wide.first_nonzero_code().unwrap()) - 0.5) / 16384.0;
    assert!(wide_s.pdf_cos(lowest as f32) > 0.0);
    check(
        "wide table, defensive mixture",
        chi2_axis(&wide_s, &[17.0 / 61.0, 1.0 - lowest], 6001),
    );

    for (name, t, sampler, seed) in [
        ("table", &table, &s, 7000u64),
        ("wide table", &wide, &wide_s, 7001),
    ] {
        let exact = table_integral(t);
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..SAMPLES {
            let d = sampler.sample(rng.random::<f32>(), rng.random::<f32>());
            let p = f64::from(sampler.pdf(d));
            assert!(p > 0.0);
            let w = f64::from(sampler.eval(d)) / p;
            sum += w;
            sum2 += w * w;
        }
        let mean = sum / SAMPLES as f64;
        let sigma = ((sum2 / SAMPLES as f64 - mean * mean) / SAMPLES as f64).sqrt();
        println!("{name}: E[table/pdf] = {mean:.6} ± {sigma:.1e}, exact {exact:.6}");
        assert!(
            (mean - exact).abs() <= 4.0 * sigma + 1e-6 * exact,
            "{name}: {mean} vs {exact}"
        );
    }
}
