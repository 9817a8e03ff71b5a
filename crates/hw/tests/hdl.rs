//! The Verilog units against their Rust models (Icarus Verilog), Verilator lint, and
//! the models against independent formulas.
//!
//! Tests that need iverilog or verilator FAIL when the tool is missing in strict mode
//! (`GLINT_STRICT` or `CI` set: glint_testkit); otherwise they print a note and return.

use glint_hw::hdl::{
    cosim, lint, stimulus, HdlUnit, KvUnit, Ports, PowerUnit, SchlickUnit, ToolError,
};
use glint_hw::{Config, Input, Unit};

/// Vectors per unit in the ordinary test run (`glint hw cosim` runs 1e6); override
/// with GLINT_COSIM_VECTORS.
const TEST_VECTORS: usize = 200_000;

fn vectors() -> usize {
    std::env::var("GLINT_COSIM_VECTORS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(TEST_VECTORS)
}

fn ports() -> Ports {
    let c = Config::default();
    Ports {
        cos_bits: c.cos_bits,
        n_bits: c.n_bits,
        out_bits: c.out_bits,
    }
}

/// `None` if the tool is missing outside strict mode (skip, said and recorded), the
/// result otherwise; in strict mode (glint_testkit) a missing tool fails, naming it.
fn tool<T>(r: Result<T, ToolError>) -> Option<T> {
    match r {
        Err(e @ ToolError::Missing { .. }) => {
            glint_testkit::missing(&e.to_string());
            None
        }
        Err(e) => panic!("{e}"),
        Ok(x) => Some(x),
    }
}

fn check_cosim(unit: &dyn HdlUnit) {
    let dir = tempfile::tempdir().unwrap();
    let n = vectors();
    if let Some(r) = tool(cosim(unit, n, 14, 4, dir.path())) {
        eprintln!("{r:?}");
        glint_testkit::ran("iverilog co-simulation");
        assert_eq!(r.mismatches, 0, "{:#?}", r.first_mismatches);
        assert!(r.vectors as usize >= n);
        assert_eq!(r.passed, r.vectors);
        assert!(r.clocks > r.vectors, "bubbles and the flush are clocks too");
    }
}

#[test]
fn kv_verilog_matches_the_pipeline_model() {
    check_cosim(&KvUnit::new(Unit::new(Config::default()).unwrap()));
}

#[test]
fn kv_verilog_matches_at_other_widths() {
    // v = 2, truncation everywhere, a minimax ROM and 10-bit colours.
    let cfg = Config {
        v: 2,
        square_frac: vec![13, 11],
        coefficients: glint_hw::Coefficients::Minimax,
        mul_round: glint_hw::Rounding::Truncate,
        square_round: glint_hw::Rounding::Truncate,
        out_bits: 10,
        n_bits: 8,
        ..Config::default()
    };
    let unit = KvUnit::new(Unit::new(cfg).unwrap());
    let dir = tempfile::tempdir().unwrap();
    if let Some(r) = tool(cosim(&unit, 20_000, 3, 2, dir.path())) {
        assert!(r.ok(), "{r:#?}");
    }
}

#[test]
fn power_verilog_matches_its_model() {
    check_cosim(&PowerUnit::new(ports()).unwrap());
}

#[test]
fn schlick_verilog_matches_its_model() {
    check_cosim(&SchlickUnit::new(ports()).unwrap());
}

#[test]
fn verilator_lint_is_clean() {
    let units: [Box<dyn HdlUnit>; 3] = [
        Box::new(KvUnit::new(Unit::new(Config::default()).unwrap())),
        Box::new(PowerUnit::new(ports()).unwrap()),
        Box::new(SchlickUnit::new(ports()).unwrap()),
    ];
    for u in &units {
        let dir = tempfile::tempdir().unwrap();
        if tool(lint(u.as_ref(), dir.path())).is_none() {
            return;
        }
    }
    glint_testkit::ran("verilator lint");
}

#[test]
fn power_unit_is_within_one_lsb_of_cos_n_everywhere() {
    // Exhaustive: every cos code in [0, 1] x every n, against f64 powi.
    let e = PowerUnit::new(ports()).unwrap().max_error_vs_power();
    assert!(e <= 1.0, "max error {e} LSB");
    // And it is not trivially exact: some rounding shows.
    assert!(e > 0.4, "max error {e} LSB");
}

#[test]
fn schlick_model_is_schlicks_formula() {
    let u = SchlickUnit::new(ports()).unwrap();
    for n in [1u32, 2, 7, 100, 1023] {
        for cos in (0..=16384i64).step_by(97).chain([16384]) {
            let c = cos as f64 / 16384.0;
            let s = c / (n as f64 - n as f64 * c + c);
            let code = u.lobe_code(cos, n) as f64 / 4096.0;
            assert!(
                (code - s).abs() <= 0.5 / 4096.0 + 1e-12,
                "n {n} cos {c}: {code} vs {s}"
            );
        }
    }
    // n = 0 is 1 everywhere in [0, 1], 0^0 included; negative cos is clamped to 0.
    assert_eq!(u.lobe_code(0, 0), 4096);
    assert_eq!(u.lobe_code(5000, 0), 4096);
    assert_eq!(u.lobe_code(-5000, 3), 0);
}

#[test]
fn stimulus_holds_the_corners_and_bubbles() {
    let s = stimulus(ports(), 4, 50_000, 1);
    let inputs: Vec<Input> = s.stream.iter().flatten().copied().collect();
    assert_eq!(inputs.len(), 50_000);
    let has = |cos: i64, n: u32| inputs.iter().any(|i| i.cos == cos && i.n == n);
    for n in [0, 1, 16, 1023] {
        for cos in [-16384, 0, 16384] {
            assert!(has(cos, n), "cos {cos} n {n}");
        }
    }
    // The K_4 base 1 - (n+1)/17 (1 - c) crosses zero at c = 1 - 17/(n+1): n = 100
    // gives c = 84/101, code 13626.6; codes on both sides are present.
    assert!(has(13626, 100) && has(13627, 100));
    let bubbles = s.stream.len() - inputs.len();
    assert!(bubbles > 50_000 / 32 && bubbles < 50_000 / 8, "{bubbles}");
}
