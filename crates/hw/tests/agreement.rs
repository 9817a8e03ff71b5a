//! The cycle model against the functional model, and both against an independent
//! floating-point restatement of the stage definitions, exhaustively for small
//! configurations.

use glint_hw::{
    CoefSource, Coefficients, Config, Input, Output, Pipeline, Rounding, Squarer, Unit,
};

fn small(v: u32, round: Rounding) -> Config {
    Config {
        v,
        n_bits: 4,
        cos_bits: 8,
        coefficients: Coefficients::EnergyFit,
        coef_bits: 7,
        coef_round: round,
        mul_frac: 6,
        mul_round: round,
        square_frac: [5, 7, 4, 6][..v as usize].to_vec(),
        square_round: round,
        out_bits: 4,
        out_round: round,
        coef_source: CoefSource::Rom,
        squarer: Squarer::Generic,
        square_guard: 2,
    }
}

/// Every input of a small configuration: every signed cos code, every n, every k_s
/// code on R (G and B get other codes, so the channels are told apart).
fn all_inputs(unit: &Unit) -> Vec<Input> {
    let (lo, hi) = unit.cos_code_range();
    let full = unit.full_scale();
    let mut v = Vec::new();
    for cos in lo..=hi {
        for n in 0..(1u32 << unit.config().n_bits) {
            for k in 0..=full {
                v.push(Input {
                    cos,
                    n,
                    ks: [k, full - k, (k * 5 + n as u64) % (full + 1)],
                });
            }
        }
    }
    v
}

fn stream_and_compare(config: Config) {
    let unit = Unit::new(config).unwrap();
    let inputs = all_inputs(&unit);
    let latency = unit.latency() as usize;
    let mut pipe = Pipeline::new(&unit);
    // Valid high except every 7th clock (a bubble), so the valid bit is exercised too.
    let mut schedule: Vec<Option<Input>> = Vec::new();
    for (i, inp) in inputs.iter().enumerate() {
        if i % 7 == 3 {
            schedule.push(None);
        }
        schedule.push(Some(*inp));
    }
    schedule.resize(schedule.len() + latency, None);
    let mut outputs: Vec<Option<Output>> = Vec::with_capacity(schedule.len());
    for inp in &schedule {
        outputs.push(pipe.clock(*inp).unwrap());
    }
    let mut compared = 0usize;
    for (clock, inp) in schedule.iter().enumerate() {
        // What leaves `latency` edges after clock `clock` belongs to the input of that
        // clock: a result exactly when the input was valid.
        let out = if clock + latency < outputs.len() {
            outputs[clock + latency]
        } else {
            None
        };
        match inp {
            Some(inp) => {
                assert_eq!(out, Some(unit.eval(inp).unwrap()), "input {inp:?}");
                compared += 1;
            }
            None => assert_eq!(out, None, "a bubble must leave as a bubble"),
        }
    }
    assert_eq!(compared, inputs.len());
    // Before the first result, the output valid bit is low.
    assert!(outputs[..latency].iter().all(Option::is_none));
}

#[test]
fn pipeline_agrees_with_functional_model_exhaustively() {
    for v in [0, 1, 2, 4] {
        for round in [Rounding::Nearest, Rounding::Truncate] {
            stream_and_compare(small(v, round));
        }
    }
}

#[test]
fn pipeline_agrees_with_functional_model_for_the_new_circuits() {
    // The constant / table a(n) and the truncated squarers go through the same
    // pipeline registers (only the truncated squarer changes the arithmetic).
    for (source, squarer, guard) in [
        (CoefSource::Const, Squarer::Truncated, 1),
        (CoefSource::Table, Squarer::Truncated, 2),
        (CoefSource::Const, Squarer::Symmetric, 2),
    ] {
        for v in [1, 2, 4] {
            stream_and_compare(Config {
                coef_source: source,
                squarer,
                square_guard: guard,
                ..small(v, Rounding::Nearest)
            });
        }
    }
}

#[test]
fn latency_is_v_plus_four() {
    for v in [0, 2, 4] {
        let unit = Unit::new(small(v, Rounding::Nearest)).unwrap();
        assert_eq!(unit.latency(), v + 4);
        let trace = unit
            .trace(&Input {
                cos: 64,
                n: 3,
                ks: [15, 7, 1],
            })
            .unwrap();
        assert_eq!(trace.latency, v + 4);
        assert_eq!(trace.squares.len(), v as usize);
    }
}

/// floor(x) or floor(x + 1/2) of a value scaled to `frac` bits, in f64. Every value of
/// the small configurations is a dyadic rational of < 30 bits, so f64 is exact here.
fn quantise(x: f64, frac: u32, round: Rounding) -> f64 {
    let s = x * 2f64.powi(frac as i32);
    let q = match round {
        Rounding::Truncate => s.floor(),
        Rounding::Nearest => (s + 0.5).floor(),
    };
    q / 2f64.powi(frac as i32)
}

/// The stage definitions of docs/hardware.md restated in real arithmetic:
/// a = Q(( n+1)/(2^v+1)), t = max(0, 1-c), p = Q(a·t), b = max(0, 1-p),
/// s_k = Q(s_{k-1}^2), out = Q(s_v·ks).
fn spec(cfg: &Config, input: &Input) -> [u64; 3] {
    let cos_frac = cfg.cos_bits - 2;
    let c = input.cos as f64 / 2f64.powi(cos_frac as i32);
    let m1 = f64::from((1u32 << cfg.v) + 1);
    // Largest a = 2^n_bits/(2^v+1); its integer bits (for the small configs, 0 or 1).
    let max_a = f64::from(1u32 << cfg.n_bits) / m1;
    let int_bits = if max_a < 1.0 {
        0
    } else {
        (max_a.floor() as u64).ilog2() + 1
    };
    let coef_frac = cfg.coef_bits - int_bits;
    let a = quantise((input.n as f64 + 1.0) / m1, coef_frac, cfg.coef_round)
        .min((2f64.powi(cfg.coef_bits as i32) - 1.0) / 2f64.powi(coef_frac as i32));
    let t = (1.0 - c).max(0.0);
    let p = quantise(a * t, cfg.mul_frac, cfg.mul_round);
    let mut s = (1.0 - p).max(0.0);
    for &f in &cfg.square_frac {
        s = quantise(s * s, f, cfg.square_round);
    }
    input
        .ks
        .map(|k| quantise(s * k as f64, 0, cfg.out_round) as u64)
}

#[test]
fn functional_model_matches_an_independent_real_arithmetic_spec() {
    for v in [0, 1, 2, 4] {
        for round in [Rounding::Nearest, Rounding::Truncate] {
            let cfg = small(v, round);
            let unit = Unit::new(cfg.clone()).unwrap();
            for inp in all_inputs(&unit) {
                assert_eq!(
                    unit.eval(&inp).unwrap().rgb,
                    spec(&cfg, &inp),
                    "{cfg:?} {inp:?}"
                );
            }
        }
    }
}

#[test]
fn trace_by_hand_at_cos_one() {
    // cos = 1: t = 0, p = 0, base = 1, every square 1, outputs = ks.
    let unit = Unit::new(Config::default()).unwrap();
    let f = unit.formats().clone();
    let tr = unit
        .trace(&Input {
            cos: unit.cos_one(),
            n: 700,
            ks: [255, 128, 0],
        })
        .unwrap();
    assert_eq!(tr.rom_sm1.t, 0);
    assert_eq!(tr.mul.p, 0);
    assert_eq!(tr.base.b, 1 << f.mul_frac);
    for (sq, &fr) in tr.squares.iter().zip(&f.square_frac) {
        assert_eq!(sq.s, 1 << fr);
    }
    assert_eq!(tr.output.rgb, [255, 128, 0]);
    // ROM1 word for n = 700 is round(701/17 · 2^f).
    let want = (701.0 / 17.0 * 2f64.powi(f.coef_frac as i32)).round() as u64;
    assert_eq!(tr.rom_sm1.a, want);
}

#[test]
fn negative_base_is_switched_to_zero() {
    // n = 1023: a = 1024/17 ≈ 60.2, so at cos = 0.5 the base 1 - 30.1 is negative.
    let unit = Unit::new(Config::default()).unwrap();
    let tr = unit
        .trace(&Input {
            cos: unit.cos_code(0.5).unwrap(),
            n: 1023,
            ks: [255, 255, 255],
        })
        .unwrap();
    assert!(tr.base.diff < 0);
    assert_eq!(tr.base.b, 0);
    assert_eq!(tr.output.rgb, [0, 0, 0]);
}
