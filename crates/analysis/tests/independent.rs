//! The summary numbers against an independent computation: a uniform dense f64 scan
//! with trapezoid sums (instead of grid + golden section and double-exponential
//! quadrature), closed forms, and bisection on the lobe itself.

use std::f64::consts::FRAC_PI_2;

use glint_analysis::{lobe_metrics, COMPARED};
use glint_lobe::{Lobe, LobeKind};

const POINTS: usize = 1_000_000;

struct Scan {
    max_abs: f64,
    max_abs_at: f64,
    epicentre: f64,
    bloom: f64,
    max_rel: f64,
    rms: f64,
    energy: f64,
}

/// Brute force over a uniform grid of γ, with cos^n written out here.
fn scan(kind: LobeKind, n: f64, v: u32) -> Scan {
    let lobe = Lobe::<f64>::new(kind, n, v).unwrap();
    let h = FRAC_PI_2 / POINTS as f64;
    let mut s = Scan {
        max_abs: 0.0,
        max_abs_at: 0.0,
        epicentre: 0.0,
        bloom: 0.0,
        max_rel: 0.0,
        rms: 0.0,
        energy: 0.0,
    };
    let (mut sq, mut en) = (0.0, 0.0);
    for i in 0..=POINTS {
        let g = i as f64 * h;
        let c = g.cos();
        let reference = c.max(0.0).powf(n);
        let f = lobe.eval(c);
        let e = (f - reference).abs();
        if e > s.max_abs {
            s.max_abs = e;
            s.max_abs_at = g.to_degrees();
        }
        if reference >= 0.5 {
            s.epicentre = s.epicentre.max(e);
        } else if reference >= 1e-2 {
            s.bloom = s.bloom.max(e);
        }
        if reference >= 1e-3 {
            s.max_rel = s.max_rel.max(e / reference);
        }
        let wgt = if i == 0 || i == POINTS { 0.5 } else { 1.0 };
        sq += wgt * e * e;
        en += wgt * f * g.sin();
    }
    s.rms = (sq * h / FRAC_PI_2).sqrt();
    s.energy = (n + 1.0) * en * h;
    s
}

#[test]
fn metrics_agree_with_a_dense_scan() {
    for (n, v) in [(10.0, 4), (100.0, 4), (1000.0, 4), (100.0, 2), (350.0, 6)] {
        for kind in COMPARED {
            let m = lobe_metrics(kind, n, v).unwrap();
            let s = scan(kind, n, v);
            let ctx = format!("{kind} n={n} v={v}");
            // The scan can only miss the peak: it is never above the refined maximum,
            // and below it by at most the slope times half a step (< 1e-4 here).
            for (name, mine, brute) in [
                ("max abs", m.max_abs.value, s.max_abs),
                ("epicentre", m.epicentre.value, s.epicentre),
                ("bloom", m.bloom.unwrap().value, s.bloom),
            ] {
                assert!(brute <= mine + 1e-12, "{ctx} {name}: scan {brute} > {mine}");
                assert!(mine - brute < 1e-4, "{ctx} {name}: {mine} vs scan {brute}");
            }
            assert!(
                (m.max_abs.angle_deg - s.max_abs_at).abs() < 0.05
                    || (m.max_abs.value - s.max_abs).abs() < 1e-9,
                "{ctx}: peak at {} vs scan {}",
                m.max_abs.angle_deg,
                s.max_abs_at
            );
            assert!(
                s.max_rel <= m.max_rel.value * (1.0 + 1e-9) + 1e-12,
                "{ctx} rel"
            );
            assert!(
                (m.max_rel.value - s.max_rel) / m.max_rel.value < 1e-3,
                "{ctx} rel: {} vs {}",
                m.max_rel.value,
                s.max_rel
            );
            assert!(
                (m.rms - s.rms).abs() <= 1e-6 * m.rms.max(1e-3),
                "{ctx} rms: {} vs {}",
                m.rms,
                s.rms
            );
            assert!(
                (m.energy_ratio - s.energy).abs() < 1e-7,
                "{ctx} energy: {} vs {}",
                m.energy_ratio,
                s.energy
            );
        }
    }
}

/// `(n+1)·∫_0^1 max(0, 1 - a t)^m dt`, written out.
fn power_energy(n: f64, a: f64, m: f64) -> f64 {
    let integral = if a >= 1.0 {
        1.0 / (a * (m + 1.0))
    } else {
        (1.0 - (1.0 - a).powf(m + 1.0)) / (a * (m + 1.0))
    };
    (n + 1.0) * integral
}

#[test]
fn energy_ratios_match_closed_forms() {
    for v in [1u32, 2, 4, 6, 8] {
        let m = f64::from(1u32 << v);
        for n in [0.5, 3.0, 10.0, 16.0, 100.0, 256.0, 1000.0] {
            let k = lobe_metrics(LobeKind::EnergyFit, n, v).unwrap();
            let a_k = (n + 1.0) / (m + 1.0);
            if n >= m {
                // The paper's identity: K_v has exactly the energy of cos^n.
                assert!(
                    (k.energy_ratio - 1.0).abs() < 1e-10,
                    "K n={n} v={v}: {}",
                    k.energy_ratio
                );
            }
            let want = power_energy(n, a_k, m);
            assert!((k.energy_ratio - want).abs() < 1e-9 * want, "K n={n} v={v}");
            assert!(
                (k.energy_ratio - (n + 1.0) * glint_lobe::power_lobe_integral(a_k, m as u32)).abs()
                    < 1e-9
            );
            let g = lobe_metrics(LobeKind::SlopeFit, n, v).unwrap();
            let want = power_energy(n, n / m, m);
            assert!((g.energy_ratio - want).abs() < 1e-9 * want, "G n={n} v={v}");
        }
    }
    for n in [2.0, 10.0, 100.0, 1000.0] {
        // ∫_0^1 e^{-n t} dt = (1 - e^{-n})/n.
        let gauss = lobe_metrics(LobeKind::Gauss, n, 4).unwrap();
        let want = (n + 1.0) * (1.0 - (-n).exp()) / n;
        assert!((gauss.energy_ratio - want).abs() < 1e-9, "gauss n={n}");
        // ∫_0^1 c/(n - (n-1)c) dc = (n ln n - (n-1))/(n-1)^2.
        let schlick = lobe_metrics(LobeKind::Schlick, n, 4).unwrap();
        let b = n - 1.0;
        let want = (n + 1.0) * (n * n.ln() - b) / (b * b);
        assert!(
            (schlick.energy_ratio - want).abs() < 1e-8 * want,
            "schlick n={n}"
        );
    }
}

#[test]
fn zero_angles_match_bisection_on_the_lobe() {
    for (kind, n, v) in [
        (LobeKind::EnergyFit, 100.0, 4),
        (LobeKind::SlopeFit, 100.0, 4),
        (LobeKind::Minimax, 1000.0, 3),
    ] {
        let lobe = Lobe::<f64>::new(kind, n, v).unwrap();
        let (mut lo, mut hi) = (0.0f64, FRAC_PI_2);
        assert_eq!(lobe.eval(hi.cos()), 0.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if lobe.eval(mid.cos()) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let m = lobe_metrics(kind, n, v).unwrap();
        let z = m.zero_angle_deg.unwrap();
        assert!(
            (z - hi.to_degrees()).abs() < 1e-6,
            "{kind}: {z} vs {}",
            hi.to_degrees()
        );
        // The paper's closed form for K_v: arccos((a-1)/a).
        if kind == LobeKind::EnergyFit {
            let a = (n + 1.0) / 17.0;
            assert!((z - ((a - 1.0) / a).acos().to_degrees()).abs() < 1e-9);
        }
        // cos^n = 1e-3 at arccos(1e-3^(1/n)).
        let cut = m.cutoff_angle_deg.unwrap();
        assert!((cut.to_radians().cos().powf(n) - 1e-3).abs() < 1e-12);
    }
    // Lobes that stay positive have no zero angle; K_4 for n < 16 has a < 1.
    assert!(lobe_metrics(LobeKind::Gauss, 100.0, 4)
        .unwrap()
        .zero_angle_deg
        .is_none());
    assert!(lobe_metrics(LobeKind::EnergyFit, 10.0, 4)
        .unwrap()
        .zero_angle_deg
        .is_none());
}

#[test]
fn fits_are_exact_where_n_is_the_power() {
    // n = 2^v: a = 1 for both fits, and the lobe is cos^n itself.
    for v in [1u32, 3, 4, 6] {
        let n = f64::from(1u32 << v);
        for kind in [LobeKind::EnergyFit, LobeKind::SlopeFit] {
            let m = lobe_metrics(kind, n, v).unwrap();
            assert!(m.max_abs.value < 1e-12, "{kind} v={v}: {}", m.max_abs.value);
            assert!(m.rms < 1e-12);
        }
    }
}

#[test]
fn paper_case_hand_checked() {
    // K_4 at n = 100 and γ = 0 is 1 (no error at the centre); the base of K_4 is
    // 1 - (101/17)(1 - cos γ), zero at γ = arccos(1 - 17/101) = 33.7275°.
    let m = lobe_metrics(LobeKind::EnergyFit, 100.0, 4).unwrap();
    assert!((m.zero_angle_deg.unwrap() - (1.0f64 - 17.0 / 101.0).acos().to_degrees()).abs() < 1e-9);
    assert!((m.zero_angle_deg.unwrap() - 33.7275).abs() < 1e-3);
    // cos^100 = 1e-3 at arccos(10^(-0.03)) = 21.05°.
    assert!((m.cutoff_angle_deg.unwrap() - 10f64.powf(-0.03).acos().to_degrees()).abs() < 1e-9);
}
