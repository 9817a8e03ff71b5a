//! Bad configurations and inputs are rejected with a clear, typed error.

use glint_hw::{Config, HwError, Input, Pipeline, Unit};

fn err(config: Config) -> HwError {
    Unit::new(config).expect_err("configuration must be rejected")
}

#[test]
fn zero_widths_are_rejected() {
    let d = Config::default;
    for (cfg, field) in [
        (Config { n_bits: 0, ..d() }, "n_bits"),
        (Config { cos_bits: 0, ..d() }, "cos_bits"),
        (
            Config {
                coef_bits: 0,
                ..d()
            },
            "coef_bits",
        ),
        (Config { mul_frac: 0, ..d() }, "mul_frac"),
        (Config { out_bits: 0, ..d() }, "out_bits"),
        (
            Config {
                square_frac: vec![16, 0, 16, 16],
                ..d()
            },
            "square_frac",
        ),
    ] {
        let e = err(cfg);
        assert_eq!(e, HwError::ZeroWidth { field }, "{e}");
        let msg = e.to_string();
        assert!(
            msg.contains(field) && msg.contains("at least 1 bit"),
            "{msg}"
        );
        assert!(!msg.contains('\n'));
    }
}

#[test]
fn v_above_ten_is_rejected() {
    let e = err(Config {
        v: 11,
        square_frac: vec![16; 11],
        ..Config::default()
    });
    assert_eq!(e, HwError::InvalidV(11));
    assert!(e.to_string().contains("v = 11"), "{e}");
    // v = 10 is the largest accepted.
    assert!(Unit::new(Config {
        v: 10,
        square_frac: vec![20; 10],
        ..Config::default()
    })
    .is_ok());
}

#[test]
fn widths_overflowing_64_bit_registers_are_rejected() {
    let d = Config::default;
    // A 65-bit ROM word.
    assert!(matches!(
        err(Config {
            coef_bits: 65,
            ..d()
        }),
        HwError::TooWide { bits: 65, .. }
    ));
    // MUL output: 6 integer bits of a (n <= 1023, v = 4) + 2 + 57 = 65 bits.
    let e = err(Config {
        mul_frac: 57,
        ..d()
    });
    assert!(matches!(e, HwError::TooWide { bits: 65, .. }), "{e}");
    assert!(e.to_string().contains("64-bit"), "{e}");
    // ... while 6 + 2 + 55 + 1 (signed Sm2) = 64 fits.
    assert!(Unit::new(Config {
        mul_frac: 55,
        ..d()
    })
    .is_ok());
    // A squaring stage UQ1.63 is 64 bits, UQ1.64 is 65.
    assert!(Unit::new(Config {
        square_frac: vec![63, 63, 63, 63],
        ..d()
    })
    .is_ok());
    assert!(matches!(
        err(Config {
            square_frac: vec![63, 64, 20, 20],
            ..d()
        }),
        HwError::TooWide { bits: 65, .. }
    ));
    // Sm1 forms 1 - cos in cos_bits + 1 bits.
    assert!(matches!(
        err(Config {
            cos_bits: 64,
            ..d()
        }),
        HwError::TooWide { bits: 65, .. }
    ));
    assert!(matches!(
        err(Config {
            out_bits: 65,
            ..d()
        }),
        HwError::TooWide { bits: 65, .. }
    ));
}

#[test]
fn other_inconsistent_configurations_are_rejected() {
    let d = Config::default;
    assert_eq!(
        err(Config {
            square_frac: vec![16; 3],
            ..d()
        }),
        HwError::SquareCount { v: 4, got: 3 }
    );
    assert_eq!(err(Config { n_bits: 14, ..d() }), HwError::InvalidNBits(14));
    // a(1023) = 1024/17 ≈ 60.2 needs 6 integer bits.
    assert!(matches!(
        err(Config {
            coef_bits: 5,
            ..d()
        }),
        HwError::TooNarrow {
            field: "coef_bits",
            ..
        }
    ));
    assert!(matches!(
        err(Config { cos_bits: 1, ..d() }),
        HwError::TooNarrow {
            field: "cos_bits",
            ..
        }
    ));
}

#[test]
fn configuration_files_are_parsed_strictly() {
    // Missing fields take the defaults.
    let c = Config::from_json(r#"{"v": 3, "square_frac": [18, 16, 14]}"#).unwrap();
    assert_eq!(c.v, 3);
    assert_eq!(c.n_bits, Config::default().n_bits);
    // Unknown fields, bad values and bad JSON are errors.
    for bad in [
        r#"{"v": 4, "widht": 3}"#,
        r#"{"mul_round": "sideways"}"#,
        r#"{"coefficients": "g"}"#,
        r#"{"v": -1}"#,
        "{",
    ] {
        let e = Config::from_json(bad).expect_err(bad);
        assert!(matches!(e, HwError::Parse(_)), "{bad}: {e}");
    }
    // The JSON form round-trips.
    let d = Config::default();
    assert_eq!(Config::from_json(&d.to_json()).unwrap(), d);
}

#[test]
fn inputs_out_of_range_are_rejected() {
    let unit = Unit::new(Config::default()).unwrap();
    let ok = Input {
        cos: 0,
        n: 0,
        ks: [0, 0, 0],
    };
    for bad in [
        Input { cos: 1 << 15, ..ok },
        Input {
            cos: -(1 << 15) - 1,
            ..ok
        },
        Input { n: 1024, ..ok },
        Input {
            ks: [0, 256, 0],
            ..ok
        },
    ] {
        assert!(matches!(unit.eval(&bad), Err(HwError::Input(_))), "{bad:?}");
        // The pipeline refuses it too, without taking a clock edge.
        let mut pipe = Pipeline::new(&unit);
        assert!(pipe.clock(Some(bad)).is_err());
        assert_eq!(pipe.cycle(), 0);
    }
    assert!(unit.cos_code(1.5).is_ok()); // Q1.14 holds up to 2 - 2^-14
    assert!(unit.cos_code(2.0).is_err());
    assert!(unit.cos_code(f64::NAN).is_err());
}
