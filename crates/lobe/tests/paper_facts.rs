//! The facts listed in docs/paper.md ("Facts to test"), each checked against an
//! independent computation: the formulas are re-derived here by hand, and integrals are
//! computed by numerical quadrature in γ rather than by the closed forms in the crate.

use glint_lobe::{power_lobe_integral, Lobe, LobeError, LobeKind, MAX_N, MAX_V};
use std::f64::consts::FRAC_PI_2;

const POWER_FITS: [LobeKind; 3] = [LobeKind::EnergyFit, LobeKind::SlopeFit, LobeKind::Minimax];

fn lobe(kind: LobeKind, n: f64, v: u32) -> Lobe<f64> {
    Lobe::new(kind, n, v).unwrap()
}

/// A spread of shininess values from 0 to the maximum, powers of two among them.
fn some_n() -> Vec<f64> {
    vec![
        0.0, 0.5, 1.0, 2.0, 3.0, 7.5, 10.0, 16.0, 33.0, 100.0, 256.0, 350.0, 1000.0, 4096.0, MAX_N,
    ]
}

#[test]
fn every_lobe_is_one_at_the_mirror_direction() {
    for &kind in LobeKind::ALL {
        for n in some_n() {
            for v in [0, 1, 4, 8, MAX_V] {
                let l64 = lobe(kind, n, v);
                let l32 = Lobe::<f32>::new(kind, n, v).unwrap();
                assert_eq!(l64.eval(1.0), 1.0, "{kind} n={n} v={v}");
                assert_eq!(l32.eval(1.0), 1.0, "{kind} n={n} v={v} (f32)");
            }
        }
    }
}

#[test]
fn every_lobe_is_non_increasing_and_bounded_on_zero_to_one() {
    for &kind in LobeKind::ALL {
        for n in some_n() {
            for v in [0, 2, 4, 7, MAX_V] {
                let l = lobe(kind, n, v);
                let mut prev = l.eval(0.0);
                for i in 1..=20_000 {
                    // Denser near c = 1, where the lobes live.
                    let t = 1.0 - (i as f64 / 20_000.0);
                    let c = 1.0 - t * t;
                    let y = l.eval(c);
                    assert!((0.0..=1.0).contains(&y), "{kind} n={n} v={v} c={c}: {y}");
                    assert!(y >= prev, "{kind} n={n} v={v}: rises from c to c' = {c}");
                    prev = y;
                }
            }
        }
    }
}

#[test]
fn the_clamp_removes_the_second_lobe() {
    // m = 2^v is even, so the unclamped base (1 - a(1-c)) below zero would give a second,
    // false lobe; the lobes must be exactly zero there.
    for kind in POWER_FITS {
        for n in [40.0, 100.0, 1000.0] {
            for v in 1..=8 {
                let l = lobe(kind, n, v);
                let a = l.coefficient().unwrap();
                if a <= 1.0 {
                    continue; // the base stays positive on [0, 1]
                }
                let c_zero = 1.0 - 1.0 / a;
                for i in 0..=200 {
                    let c = -1.0 + (c_zero + 1.0) * i as f64 / 200.0 * 0.999_999;
                    assert_eq!(l.eval(c), 0.0, "{kind} n={n} v={v} c={c}");
                }
                // Where the base is -1 the unclamped formula gives a full false lobe of
                // height 1; the clamped lobe is 0 there.
                let c_false = 1.0 - 2.0 / a;
                if c_false >= -1.0 {
                    let unclamped = (1.0 - a * (1.0 - c_false)).powi(1 << v);
                    assert!((unclamped - 1.0).abs() < 1e-9, "{kind} n={n} v={v}");
                    assert_eq!(l.eval(c_false), 0.0);
                }
                // Just above the zero the lobe is positive again.
                let c_above = c_zero + 0.5 * (1.0 - c_zero); // base 1/2
                assert!(l.eval(c_above) > 0.0, "{kind} n={n} v={v}");
            }
        }
    }
}

#[test]
fn fits_equal_cos_n_when_n_is_the_power() {
    for v in 0..=MAX_V {
        let n = f64::from(1u32 << v);
        for kind in [LobeKind::EnergyFit, LobeKind::SlopeFit] {
            let l = lobe(kind, n, v);
            assert_eq!(l.coefficient(), Some(1.0), "{kind} v={v}");
            for i in 0..=1000 {
                let c = i as f64 / 1000.0;
                let want = c.powf(n);
                let got = l.eval(c);
                // The base 1 - (1 - c) carries one rounding of at most eps; m squarings
                // carry it into an absolute error of at most m·eps·b^(m-1) <= 1024·eps.
                assert!(
                    (got - want).abs() <= 2e-13,
                    "{kind} v={v} c={c}: {got} vs {want}"
                );
            }
        }
    }
}

/// ∫_0^{upper} K(cos γ) sin γ dγ by double-exponential quadrature, split at the point
/// γ0 where the clamped base reaches zero (the integrand has a kink there).
fn integral_by_quadrature(l: &Lobe<f64>) -> f64 {
    let a = l.coefficient().unwrap();
    let upper = if a > 1.0 {
        (1.0 - 1.0 / a).acos()
    } else {
        FRAC_PI_2
    };
    let f = |g: f64| l.eval(g.cos()) * g.sin();
    // Split the range where the lobe has fallen to ~1e-3 so each piece is well resolved.
    let mid = (1.0 - 7.0 / (a * f64::from(1u32 << l.v())))
        .clamp(-1.0, 1.0)
        .acos()
        .min(upper);
    let pieces = [(0.0, 0.5 * mid), (0.5 * mid, mid), (mid, upper)];
    pieces
        .iter()
        .filter(|(lo, hi)| hi > lo)
        .map(|&(lo, hi)| quadrature::double_exponential::integrate(f, lo, hi, 1e-16).integral)
        .sum()
}

#[test]
fn energy_fit_integral_matches_cos_n_or_the_closed_form() {
    let mut worst: f64 = 0.0;
    for v in 1..=8u32 {
        let m = f64::from(1u32 << v);
        for n in 1..=1000u32 {
            let n = f64::from(n);
            let l = lobe(LobeKind::EnergyFit, n, v);
            let a = (n + 1.0) / (m + 1.0); // derived here, not read from the crate
            let want = if a >= 1.0 {
                1.0 / (n + 1.0) // the paper's identity: same integral as cos^n
            } else {
                (1.0 - (1.0 - a).powf(m + 1.0)) / (a * (m + 1.0))
            };
            let got = integral_by_quadrature(&l);
            let rel = (got - want).abs() / want;
            worst = worst.max(rel);
            assert!(
                rel <= 1e-9,
                "n={n} v={v}: quadrature {got} vs {want} (rel {rel:e})"
            );
            // The crate's closed form agrees too.
            let closed = power_lobe_integral(l.coefficient().unwrap(), 1 << v);
            assert!(
                (closed - want).abs() <= 1e-12 * want,
                "n={n} v={v}: {closed}"
            );
            if a < 1.0 && (1.0 - a).powf(m + 1.0) > 1e-12 {
                // Where the base never reaches zero the integral falls short of 1/(n+1).
                assert!(want < 1.0 / (n + 1.0), "n={n} v={v}");
            }
        }
    }
    eprintln!("worst relative error of the integral identity: {worst:e}");
}

/// Max |f - cos^n| over γ in [0, 90°] by brute-force dense sampling, denser on the lobe.
fn sampled_max_error(l: &Lobe<f64>, n: f64) -> f64 {
    let width = (8.0 / n.max(1.0)).sqrt().min(FRAC_PI_2);
    let dense = (0..=40_000).map(|i| width * i as f64 / 40_000.0);
    let wide = (0..=20_000).map(|i| FRAC_PI_2 * i as f64 / 20_000.0);
    dense
        .chain(wide)
        .map(|g| {
            let c = g.cos();
            (l.eval(c) - c.powf(n)).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn minimax_beats_both_fits_in_max_abs_error() {
    let ns = [
        1.0, 2.0, 3.0, 5.0, 8.0, 10.0, 13.0, 20.0, 32.0, 50.0, 64.0, 77.0, 100.0, 150.0, 200.0,
        256.0, 350.0, 500.0, 700.0, 1000.0,
    ];
    for v in 1..=8 {
        for n in ns {
            let e_k = sampled_max_error(&lobe(LobeKind::EnergyFit, n, v), n);
            let e_g = sampled_max_error(&lobe(LobeKind::SlopeFit, n, v), n);
            let e_m = sampled_max_error(&lobe(LobeKind::Minimax, n, v), n);
            assert!(
                e_m <= e_k.min(e_g) + 1e-7,
                "n={n} v={v}: minimax {e_m:e} vs k {e_k:e}, g {e_g:e}"
            );
        }
    }
}

#[test]
fn invalid_parameters_are_typed_errors_naming_the_value() {
    for n in [f64::NAN, f64::INFINITY, -1.0, -1e-300, MAX_N * 1.0001] {
        let err = Lobe::<f32>::new(LobeKind::EnergyFit, n, 4).unwrap_err();
        assert!(matches!(err, LobeError::InvalidN(x) if x.to_bits() == n.to_bits()));
        assert!(err.to_string().contains(&format!("{n}")), "{err}");
    }
    let err = Lobe::<f64>::new(LobeKind::Exact, 10.0, MAX_V + 1).unwrap_err();
    assert_eq!(err, LobeError::InvalidV(MAX_V + 1));
    assert!(err.to_string().contains("11"));
    let err = "phongish".parse::<LobeKind>().unwrap_err();
    assert!(err.to_string().contains("phongish"));
    for &kind in LobeKind::ALL {
        assert_eq!(kind.name().parse::<LobeKind>().unwrap(), kind);
    }
}
