//! Error bounds of the default configuration, checked exhaustively: every cos code in
//! [-1, 1] (Q1.14: 32769 codes) × every n in 0..=1023, k_s·I at full scale, for 8-bit
//! and 10-bit outputs. The references come from glint-lobe (an independent f64
//! implementation of K_v and cos^n), not from this crate.

use glint_hw::{Config, Unit};
use glint_lobe::{max_abs_error, Lobe, LobeKind};
use rayon::prelude::*;

/// The design bounds of the default configuration against the exact K_4, in output
/// LSBs (docs/hardware.md): faithful (<= 1 LSB) at 10 bits. The 8-bit output comes
/// from the same lobe code, so its bound follows: at 10 bits
/// |lobe·1023 - K·1023| <= 1 + 0.5 (undoing the final rounding), hence at 8 bits
/// |lobe·255 - K·255| <= 1.5·255/1023 < 0.374 and the error <= 0.5 + 0.374 < 0.875.
const BOUND_10: f64 = 1.0;
const BOUND_8: f64 = 0.875;

/// Max over every (cos code in [-1, 1], n) of |output - F·K_4|, and the max over
/// cos in [0, 1] of |output - F·cos^n| minus F·(max |K_4 - cos^n|) (which the
/// triangle inequality bounds by the first).
fn worst(out_bits: u32) -> (f64, f64) {
    let unit = Unit::new(Config {
        out_bits,
        ..Config::default()
    })
    .unwrap();
    assert_eq!(unit.config().v, 4);
    let full = unit.full_scale();
    let f = full as f64;
    let one = unit.cos_one();
    (0..1024u32)
        .into_par_iter()
        .map(|n| {
            let k = Lobe::<f64>::new(LobeKind::EnergyFit, n as f64, 4).unwrap();
            let exact = Lobe::<f64>::new(LobeKind::Exact, n as f64, 4).unwrap();
            let a = k.coefficient().unwrap();
            let approx = max_abs_error(|c| k.eval(c), n as f64, &[1.0 / a])
                .error
                .abs();
            let (mut e_lobe, mut e_pow) = (0.0f64, 0.0f64);
            for cos in -one..=one {
                let c = unit.cos_value(cos);
                let out = unit.output_code(unit.lobe_code(cos, n), full) as f64;
                e_lobe = e_lobe.max((out - f * k.eval(c)).abs());
                if cos >= 0 {
                    e_pow = e_pow.max((out - f * exact.eval(c)).abs() - f * approx);
                }
            }
            (e_lobe, e_pow)
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1.max(b.1)))
}

#[test]
fn default_configuration_10_bit_is_faithful_to_k4() {
    let (lobe, excess) = worst(10);
    assert!(lobe <= BOUND_10 + 1e-9, "10-bit: {lobe} LSB vs K_4");
    // max_abs_error finds the approximation peak to ~1e-12; allow that.
    assert!(excess <= BOUND_10 + 1e-6, "10-bit: cos^n excess {excess}");
}

#[test]
fn default_configuration_8_bit_bound() {
    let (lobe, excess) = worst(8);
    assert!(lobe <= BOUND_8 + 1e-9, "8-bit: {lobe} LSB vs K_4");
    assert!(excess <= BOUND_8 + 1e-6, "8-bit: cos^n excess {excess}");
}
