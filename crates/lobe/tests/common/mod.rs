//! Quadrature on the sphere and the χ² test shared by the sampling tests.
//!
//! Everything here is computed from a pdf or a lobe by plain numerical integration,
//! independently of the samplers under test.

#![allow(dead_code)]

use glint_lobe::{AxisLobe, Lobe, LobeKind, LobeSampler, Real};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Gauss–Legendre nodes and weights on [-1, 1], 8 points (Abramowitz & Stegun 25.4.30).
const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// Points of `[0, 2]` in `x = 1 - cos γ`, geometric towards 0 (consecutive points
/// within a factor 2^(span/pieces) of each other, from 2·2^-span) so the sharpest lobe
/// is resolved, plus `kinks` (where a pdf has a kink or a jump).
pub fn grid(pieces: usize, span: f64, kinks: &[f64]) -> Vec<f64> {
    let r = (span * std::f64::consts::LN_2 / pieces as f64).exp();
    let top = r.powi(pieces as i32) - 1.0;
    let mut g: Vec<f64> = (0..=pieces)
        .map(|k| 2.0 * (r.powi(k as i32) - 1.0) / top)
        .collect();
    // Around each kink (and x = 2), points closing in geometrically from both sides,
    // for pdfs steep there (c^n for tiny n near c = 0).
    for &k in kinks.iter().chain(&[2.0]) {
        for j in 1..=40 {
            let d = 2f64.powi(-j);
            g.extend([k - d, k + d, k]);
        }
    }
    g.retain(|&x| (0.0..=2.0).contains(&x));
    g.sort_by(f64::total_cmp);
    g.dedup();
    g
}

/// `∫ f(x) dx` over each piece of `grid` (8-point Gauss–Legendre per piece).
pub fn piece_integrals(grid: &[f64], f: impl Fn(f64) -> f64) -> Vec<f64> {
    grid.windows(2)
        .map(|w| {
            let (mid, half) = (0.5 * (w[0] + w[1]), 0.5 * (w[1] - w[0]));
            GL8.iter()
                .map(|&(t, wt)| wt * f(mid + half * t))
                .sum::<f64>()
                * half
        })
        .collect()
}

/// The points where an axis-frame pdf of `kind` may have a kink or a jump.
pub fn kinks_of(sampler: &LobeSampler<f64>) -> Vec<f64> {
    let lobe = sampler.lobe();
    let mut k = vec![1.0];
    if let Some(a) = lobe.coefficient() {
        if a > 0.0 {
            k.push(1.0 / a);
        }
    }
    if let Some((nodes, _)) = sampler.table_nodes() {
        k.extend_from_slice(nodes);
    }
    k
}

/// `∫ pdf dω` over the sphere for an axis-frame pdf: `2π ∫_0^2 pdf_cos(1 - x) dx`.
pub fn sphere_mass<T: Real>(lobe: &impl AxisLobe<T>, grid: &[f64]) -> f64 {
    let tau = std::f64::consts::TAU;
    piece_integrals(grid, |x| {
        tau * lobe.pdf_cos(T::from_f64(1.0 - x)).to_f64().unwrap()
    })
    .iter()
    .sum()
}

/// A χ² statistic, its degrees of freedom and p-value.
#[derive(Clone, Copy, Debug)]
pub struct Chi2 {
    pub stat: f64,
    pub dof: usize,
    pub p: f64,
    pub cells: usize,
}

/// Cells with an expected count below this are pooled (pbrt-v4's bsdfs_test.cpp,
/// after Mitsuba's χ² test: the statistic's χ² law needs expected counts >= ~5).
pub const MIN_EXPECTED: f64 = 5.0;

/// Pearson's χ² of `observed` against `expected` counts: cells sorted by expected
/// count, those below [`MIN_EXPECTED`] pooled until the pool reaches it, as pbrt-v4's
/// `Chi2Test` does. A cell expected empty that holds more than 1e-5 of the samples
/// fails outright (p = 0).
pub fn chi2(observed: &[f64], expected: &[f64]) -> Chi2 {
    let total: f64 = observed.iter().sum();
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pool_o, mut pool_e, mut stat, mut dof) = (0.0, 0.0, 0.0, 0usize);
    for &i in &order {
        let (o, e) = (observed[i], expected[i]);
        if e == 0.0 {
            if o > 1e-5 * total {
                return Chi2 {
                    stat: f64::INFINITY,
                    dof: 0,
                    p: 0.0,
                    cells: expected.len(),
                };
            }
        } else if e < MIN_EXPECTED || (pool_e > 0.0 && pool_e < MIN_EXPECTED) {
            pool_o += o;
            pool_e += e;
        } else {
            stat += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 || pool_o > 0.0 {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e.max(1e-300);
        dof += 1;
    }
    // All parameters are known: one degree of freedom lost to the fixed total.
    let dof = dof.saturating_sub(1);
    let p = if dof == 0 {
        0.0
    } else {
        ChiSquared::new(dof as f64).unwrap().sf(stat)
    };
    Chi2 {
        stat,
        dof,
        p,
        cells: expected.len(),
    }
}

/// The Šidák-corrected significance level for `tests` independent tests at an
/// overall level `alpha`: `1 - (1 - alpha)^(1/tests)`.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}

/// The lobes and parameters the sampling tests sweep.
pub fn f64_sampler(kind: LobeKind, n: f64, v: u32) -> LobeSampler<f64> {
    LobeSampler::new(&Lobe::<f64>::new(kind, n, v).unwrap())
}

/// `[x_edges as grid indices]`: grid points closest above each `j / bins` quantile of
/// the cumulative masses `pieces` (so each cell's expected mass is a sum of pieces).
pub fn quantile_edges(pieces: &[f64], bins: usize) -> Vec<usize> {
    let total: f64 = pieces.iter().sum();
    let mut edges = vec![0];
    let mut acc = 0.0;
    let mut next = 1;
    for (i, p) in pieces.iter().enumerate() {
        acc += p;
        while next < bins && acc >= total * next as f64 / bins as f64 {
            if *edges.last().unwrap() != i + 1 {
                edges.push(i + 1);
            }
            next += 1;
        }
    }
    if *edges.last().unwrap() != pieces.len() {
        edges.push(pieces.len());
    }
    edges
}

/// Dot product.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a` scaled to unit length.
pub fn unit(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// Two unit tangents `(t1, t2)` with `t1 × t2 = z`, built here by cross products
/// (independently of the crate's `Frame`).
pub fn tangents(z: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let helper = if z[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let t1 = unit(cross(helper, z));
    let t2 = cross(z, t1);
    (t1, t2)
}

/// The unit vector at `x = 1 - cos γ` and azimuth `phi` around `z` (tangents `t`).
pub fn at(z: [f64; 3], t: ([f64; 3], [f64; 3]), x: f64, phi: f64) -> [f64; 3] {
    let s = (x * (2.0 - x)).max(0.0).sqrt();
    let (sp, cp) = phi.sin_cos();
    let c = 1.0 - x;
    [0, 1, 2].map(|i| s * cp * t.0[i] + s * sp * t.1[i] + c * z[i])
}

/// `(x, φ)` of a unit vector around `z` (tangents `t`), φ in `[0, 2π)`.
pub fn polar(z: [f64; 3], t: ([f64; 3], [f64; 3]), d: [f64; 3]) -> (f64, f64) {
    let x = 1.0 - dot(z, d);
    let phi = dot(t.1, d).atan2(dot(t.0, d));
    (
        x,
        if phi < 0.0 {
            phi + std::f64::consts::TAU
        } else {
            phi
        },
    )
}

/// `∫ g dω` over cells of `(x, φ)` around `z`: for each piece of `grid` in `x` and
/// each of `phi_bins` azimuth bins, by 8-point Gauss–Legendre in `x` and 8 pieces of
/// 8-point Gauss–Legendre per azimuth bin. Returns `[piece][phi_bin]`.
pub fn piece_cells(
    z: [f64; 3],
    grid: &[f64],
    phi_bins: usize,
    g: impl Fn([f64; 3]) -> f64,
) -> Vec<Vec<f64>> {
    let t = tangents(z);
    let tau = std::f64::consts::TAU;
    let sub = 8;
    let dphi = tau / (phi_bins * sub) as f64;
    grid.windows(2)
        .map(|w| {
            let (mid, half) = (0.5 * (w[0] + w[1]), 0.5 * (w[1] - w[0]));
            (0..phi_bins)
                .map(|b| {
                    let mut sum = 0.0;
                    for s in 0..sub {
                        let p0 = (b * sub + s) as f64 * dphi + 0.5 * dphi;
                        for &(tx, wx) in &GL8 {
                            for &(tp, wp) in &GL8 {
                                let d = at(z, t, mid + half * tx, p0 + 0.5 * dphi * tp);
                                sum += wx * wp * g(d);
                            }
                        }
                    }
                    sum * half * 0.5 * dphi
                })
                .collect()
        })
        .collect()
}
