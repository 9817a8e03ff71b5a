//! The design space of `glint hw pareto`: every new circuit's Verilog against its
//! model (Icarus Verilog) and Verilator-clean, the models against independent
//! formulas, the fronts and the CSV.
//!
//! Tests that need iverilog or verilator FAIL when the tool is missing and the
//! environment variable CI is set; otherwise they print a note and pass.

use glint_hw::hdl::{
    cosim, lint, Costs, Ecp5Cells, HdlUnit, KvUnit, Ports, PowParams, PowerUnit, SchlickParams,
    SchlickUnit, ToolError,
};
use glint_hw::pareto::{
    csv_text, mark_fronts, read_csv, Candidate, Fronts, Measured, Row, Verified,
};
use glint_hw::{
    within, CoefCircuit, CoefSource, Config, Design, DesignErrors, Reference, Squarer, Unit,
};

/// `Ok(None)` if the tool is missing outside CI (skip), the result otherwise.
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

fn cosim_and_lint(unit: &dyn HdlUnit, vectors: usize, v: u32) {
    let dir = tempfile::tempdir().unwrap();
    if let Some(r) = tool(cosim(unit, vectors, 7, v, dir.path())) {
        assert!(r.ok(), "{}: {r:#?}", unit.describe());
        assert!(r.vectors as usize >= vectors);
    }
    tool(lint(unit, dir.path()));
}

fn ports(out_bits: u32) -> Ports {
    Ports {
        cos_bits: 16,
        n_bits: 10,
        out_bits,
    }
}

#[test]
fn kv_sources_and_squarers_match_their_models_in_verilog() {
    for (source, squarer, guard) in [
        (CoefSource::Const, Squarer::Symmetric, 2),
        (CoefSource::Table, Squarer::Generic, 2),
        (CoefSource::Const, Squarer::Truncated, 1),
        (CoefSource::Rom, Squarer::Truncated, 4),
    ] {
        for v in [3u32, 5] {
            let cfg = Config {
                v,
                square_frac: vec![13; v as usize],
                coef_source: source,
                squarer,
                square_guard: guard,
                out_bits: 10,
                ..Config::default()
            };
            cosim_and_lint(&KvUnit::new(Unit::new(cfg).unwrap()), 30_000, v);
        }
    }
}

#[test]
fn constant_and_table_sources_are_rom1_and_cheaper_in_bits() {
    let rom = Unit::new(Config::default()).unwrap();
    for source in [CoefSource::Const, CoefSource::Table] {
        let u = Unit::new(Config {
            coef_source: source,
            ..Config::default()
        })
        .unwrap();
        // Same words, so the same function for every input.
        assert_eq!(u.rom().words(), rom.rom().words());
        let kv = KvUnit::new(u.clone());
        assert!(kv.rom_bits() < KvUnit::new(rom.clone()).rom_bits() / 8);
        match u.coef_circuit() {
            // 1/17 = 0.00001111 00001111...: two signed digits per byte of K.
            CoefCircuit::Const { k, csd, .. } => {
                let bytes = (128 - k.leading_zeros()).div_ceil(8) as usize;
                assert!(csd.len() <= 2 * bytes + 1, "{csd:?}");
            }
            CoefCircuit::Table { hi, lo, .. } => assert_eq!(hi.len() + lo.len(), 64),
            CoefCircuit::Rom => panic!("not a ROM"),
        }
    }
    // Minimax coefficients are not a constant multiple of n + 1.
    let e = Unit::new(Config {
        coefficients: glint_hw::Coefficients::Minimax,
        coef_source: CoefSource::Const,
        n_bits: 6,
        ..Config::default()
    });
    assert!(e.is_err());
}

#[test]
fn truncated_squarers_stay_close_to_full_ones() {
    // Same widths; dropping columns below 2^-guard of each stage's LSB moves the 8-bit
    // output by at most about 2^-guard per stage, amplified by the later squarings:
    // at guard 6 the unit still meets the 1 LSB its full-squarer twin meets.
    let full = Unit::new(Config::default()).unwrap();
    assert!(within(&full, Reference::Lobe, 0.65, None));
    let t = Unit::new(Config {
        squarer: Squarer::Truncated,
        square_guard: 6,
        ..Config::default()
    })
    .unwrap();
    assert!(t.truncated_square(0).is_some());
    assert!(within(&t, Reference::Lobe, 1.0, None));
    // Truncation changes results somewhere (it is not a no-op).
    let differs = (0..=16384i64).step_by(3).any(|c| {
        (0..1024)
            .step_by(7)
            .any(|n| t.lobe_code(c, n) != full.lobe_code(c, n))
    });
    assert!(differs);
}

#[test]
fn sized_power_and_schlick_units_match_their_models_in_verilog() {
    let pow = [
        PowParams {
            log_index: 7,
            log_frac: 16,
            log_interp: true,
            exp_index: 6,
            exp_frac: 12,
            exp_interp: true,
        },
        PowParams {
            log_index: 11,
            log_frac: 18,
            log_interp: false,
            exp_index: 10,
            exp_frac: 13,
            exp_interp: false,
        },
    ];
    for p in pow {
        cosim_and_lint(&PowerUnit::with_params(ports(8), p).unwrap(), 30_000, 4);
    }
    let s = SchlickParams {
        quot_frac: 9,
        x_frac: 10,
    };
    cosim_and_lint(&SchlickUnit::with_params(ports(10), s).unwrap(), 30_000, 4);
}

#[test]
fn plain_power_tables_hold_segment_middles() {
    // With one exp segment per 2^-3 and no interpolation, 2^-y at y = 0 reads the
    // middle of [0, 1/8): 2^(-1/16) in UQ1.12, rounded.
    let p = PowParams {
        log_index: 12,
        log_frac: 20,
        log_interp: false,
        exp_index: 3,
        exp_frac: 12,
        exp_interp: false,
    };
    let u = PowerUnit::with_params(ports(8), p).unwrap();
    let want = (2f64.powf(-1.0 / 16.0) * 4096.0).round() as u64;
    // cos = 1: L = 0 up to the log table's middle value, y = n L small.
    assert_eq!(u.lobe_code(16384, 1), want);
    assert_eq!(u.lobe_code(16384, 0), 4096);
    assert_eq!(u.lobe_code(0, 5), 0);
    // Out-of-range widths are refused with a message.
    let bad = PowParams { log_index: 13, ..p };
    assert!(PowerUnit::with_params(ports(8), bad).is_err());
    assert!(SchlickUnit::with_params(
        ports(8),
        SchlickParams {
            quot_frac: 1,
            x_frac: 14
        }
    )
    .is_err());
}

fn row(id: &str, family: Design, cost: u64, err: f64, lobe: f64) -> Row {
    Row {
        candidate: Candidate {
            id: id.into(),
            target: "t".into(),
            design: family,
        },
        measured: Measured {
            errors: DesignErrors {
                lobe,
                power: [err; 4],
                power_all: err,
            },
            costs: Some(Costs {
                gate_cells: cost,
                transistors: 4 * cost,
                ice40_luts: cost,
                ice40_carries: 0,
                ice40_ffs: 0,
                ice40_brams: 0,
                ice40_fmax: 50.0,
                ecp5_luts: cost,
                ecp5_ccu2: 0,
                ecp5_ffs: 0,
                ecp5_mult18: 0,
                ecp5_brams: 0,
                ecp5_lutram: 0,
                ice40_fmax_seeds: vec![50.0, 47.5, 52.25],
                ecp5_nodsp: Some(Ecp5Cells {
                    luts: 3 * cost,
                    ccu2: 1,
                    ffs: 2,
                    mult18: 0,
                    brams: 0,
                    lutram: 0,
                }),
            }),
            rom_bits: 0,
            latency: 8,
            verified: Some(Verified {
                lint_clean: true,
                vectors: 10,
                mismatches: 0,
            }),
            seconds: 1.0,
            measured_at: "2026-11-28T07:00:00Z".into(),
            tools: "test".into(),
        },
        fronts: Fronts::default(),
    }
}

#[test]
fn fronts_are_the_undominated_designs_of_each_family() {
    let kv = || Design::Kv(Config::default());
    let pow = Design::Pow {
        out_bits: 8,
        params: PowParams::default(),
    };
    let mut rows = vec![
        row("a", kv(), 100, 4.0, 1.0),
        row("b", kv(), 200, 3.0, 0.5),
        row("c", kv(), 300, 3.5, 0.4), // dominated on cos^n by b, on the lobe front
        row("d", kv(), 100, 5.0, 2.0), // dominated by a (same cost, worse)
        row("e", pow.clone(), 1000, 0.5, 0.5), // another family: its own front
    ];
    mark_fronts(&mut rows);
    let on: Vec<bool> = rows.iter().map(|r| r.fronts.power[0]).collect();
    assert_eq!(on, [true, true, false, false, true]);
    let on_lobe: Vec<bool> = rows.iter().map(|r| r.fronts.lobe[1]).collect();
    assert_eq!(on_lobe, [true, true, true, false, true]);

    // The CSV keeps the fronts and the designs.
    let text = csv_text(&rows).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pareto.csv");
    std::fs::write(&path, &text).unwrap();
    let back = read_csv(&path).unwrap();
    assert_eq!(back.len(), 5);
    assert_eq!(back[4].design, pow);
    let flags: Vec<bool> = back.iter().map(|r| r.on_front).collect();
    assert_eq!(flags, [true, true, true, false, true]);
    assert_eq!(back[1].fields[10], "0.5000");
    // Another CSV is refused with a message, not read wrongly.
    std::fs::write(&path, "id,x\n1,2\n").unwrap();
    assert!(read_csv(&path).is_err());
}

/// The front co-simulation (the CI step) runs the slow squarer designs first but reports
/// in the order it was given, every design with at least the vectors asked, matched and linted.
#[test]
fn front_cosim_reports_every_design_in_the_given_order() {
    let kv = |squarer| {
        Design::Kv(Config {
            v: 3,
            square_frac: vec![14, 14, 12],
            coef_source: CoefSource::Const,
            squarer,
            ..Config::default()
        })
    };
    let rows = vec![
        ("generic".to_string(), kv(Squarer::Generic)),
        (
            "schlick".to_string(),
            Design::Schlick {
                out_bits: 8,
                params: SchlickParams::default(),
            },
        ),
        ("symmetric".to_string(), kv(Squarer::Symmetric)),
    ];
    let dir = tempfile::tempdir().unwrap();
    let r = glint_hw::pareto::cosim_fronts(&rows, 300, 2, dir.path(), &|_| {});
    let results = match r {
        Err(glint_hw::pareto::ParetoError::Tool { source, .. }) => {
            // Panics unless the tool is missing outside CI (then skip).
            tool::<()>(Err(source));
            return;
        }
        other => other.unwrap(),
    };
    let ids: Vec<&str> = results.iter().map(|f| f.id.as_str()).collect();
    assert_eq!(ids, ["generic", "schlick", "symmetric"]);
    for f in &results {
        // The corner vectors come first, so there can be more than asked.
        assert!(f.verified.vectors >= 300, "{}", f.id);
        assert_eq!(f.verified.mismatches, 0, "{}", f.id);
        assert!(f.verified.lint_clean, "{}", f.id);
    }
}
