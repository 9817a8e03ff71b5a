//! Bad configurations and inputs are rejected with a clear, typed error.

use glint_hw::{Config, HwError, Input, Pipeline, Unit, MAX_COS_BITS};

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

#[test]
fn huge_widths_are_rejected_without_wrapping() {
    let d = Config::default;
    // cos_bits + 1 used to be formed in u32: u32::MAX + 1 wrapped to 0 in release and
    // passed (overflow panic in debug).
    let e = err(Config {
        cos_bits: u32::MAX,
        ..d()
    });
    assert_eq!(
        e,
        HwError::TooWide {
            register: "Sm1 = cos_bits + 1 (so cos_bits <= 63)",
            bits: 1 << 32,
        }
    );
    assert!(e.to_string().contains("cos_bits <= 63"), "{e}");
    for (cfg, want_bits) in [
        (
            Config {
                mul_frac: u32::MAX,
                ..d()
            },
            1u64 << 32,
        ),
        (
            Config {
                square_frac: vec![14, u32::MAX, 14, 12],
                ..d()
            },
            1 << 32,
        ),
        (
            Config {
                coef_bits: u32::MAX,
                ..d()
            },
            u64::from(u32::MAX),
        ),
        (
            Config {
                out_bits: u32::MAX,
                ..d()
            },
            u64::from(u32::MAX),
        ),
    ] {
        match err(cfg.clone()) {
            HwError::TooWide { bits, .. } => assert_eq!(bits, want_bits, "{cfg:?}"),
            e => panic!("{cfg:?}: {e}"),
        }
    }
    assert_eq!(
        err(Config {
            n_bits: u32::MAX,
            ..d()
        }),
        HwError::InvalidNBits(u32::MAX)
    );
    assert_eq!(
        err(Config { v: u32::MAX, ..d() }),
        HwError::InvalidV(u32::MAX)
    );
    // The largest accepted cos_bits works end to end: Q1.61, 1.0 = 2^61.
    let unit = Unit::new(Config {
        cos_bits: MAX_COS_BITS,
        ..d()
    })
    .unwrap();
    assert_eq!(unit.cos_one(), 1 << 61);
    assert_eq!(unit.cos_code_range(), (-(1 << 62), (1 << 62) - 1));
    let input = Input {
        cos: unit.cos_code(0.98).unwrap(),
        n: 100,
        ks: [255, 255, 255],
    };
    // K_4(100, 0.98) = (1 - 101/17 · 0.02)^16 ≈ 0.128 (the lib example), · 255 ≈ 32.6.
    let exact = (1.0f64 - 101.0 / 17.0 * (1.0 - unit.cos_value(input.cos))).powi(16) * 255.0;
    let out = unit.eval(&input).unwrap();
    assert!(
        (out.rgb[0] as f64 - exact).abs() <= 1.0,
        "{out:?} vs {exact}"
    );
    assert_eq!(unit.trace(&input).unwrap().output, out);
}

#[test]
fn exhaustive_points_are_exact_and_never_wrap() {
    let with = |cos_bits, n_bits| Config {
        cos_bits,
        n_bits,
        ..Config::default()
    };
    // Every code in [-1, 1] of Q1.(c-2) is 2·2^(c-2) + 1 codes, times 2^n_bits n.
    assert_eq!(
        with(16, 10).exhaustive_points(),
        Some((2 * (1 << 14) + 1) * 1024)
    );
    // The reviewer's case, which wrapped to 8192 in u64.
    assert_eq!(
        with(60, 13).exhaustive_points(),
        Some(((1u128 << 59) + 1) * 8192)
    );
    let unit = Unit::new(with(63, 13)).unwrap();
    assert_eq!(unit.exhaustive_points(), ((1u128 << 62) + 1) * 8192);
    // Unvalidated absurd widths give None, not a wrapped count or a panic.
    assert_eq!(with(u32::MAX, 13).exhaustive_points(), None);
    assert_eq!(with(16, u32::MAX).exhaustive_points(), None);
    assert_eq!(with(1, 10).exhaustive_points(), None);
    assert_eq!(with(128, 1).exhaustive_points(), None); // (2^127 + 1) · 2 > u128::MAX
}

#[test]
fn configuration_files_must_be_json_objects() {
    // serde's derived struct code reads a JSON array as the fields in order: "[4, 10]"
    // was silently v = 4, n_bits = 10.
    for bad in ["[4, 10]", "[]", "[4]", "null", "4", "\"v\"", "true"] {
        let e = Config::from_json(bad).expect_err(bad);
        let msg = e.to_string();
        assert!(matches!(e, HwError::Parse(_)), "{bad}: {e}");
        assert!(msg.contains("JSON object"), "{bad}: {msg}");
        assert!(!msg.contains('\n'), "{msg}");
    }
    // An object still works, with positions in errors of its fields.
    assert_eq!(Config::from_json("{}").unwrap(), Config::default());
    let e = Config::from_json("{\n  \"v\": \"four\"\n}").unwrap_err();
    assert!(e.to_string().contains("line 2"), "{e}");
    // Duplicate fields and fields of the wrong shape are errors.
    for bad in [
        r#"{"v": 4, "v": 5}"#,
        r#"{"square_frac": 14}"#,
        r#"{"square_frac": {"0": 14}}"#,
        r#"{"n_bits": 4294967296}"#,
        r#"{"n_bits": 1.5}"#,
    ] {
        assert!(Config::from_json(bad).is_err(), "{bad}");
    }
    // A parseable file with absurd widths is caught by validation.
    let c = Config::from_json(r#"{"cos_bits": 4294967295}"#).unwrap();
    assert!(c.validate().is_err());
}

mod any_config {
    use super::*;
    use glint_hw::{CoefSource, Coefficients, Rounding, Squarer};
    use proptest::prelude::*;

    /// Mostly plausible widths, so that many cases get past validation, plus the
    /// edges and anything at all.
    fn width() -> impl Strategy<Value = u32> {
        prop_oneof![
            24 => 1u32..=64,
            1 => Just(0u32),
            1 => 65u32..=70,
            1 => Just(u32::MAX),
            1 => any::<u32>(),
        ]
    }

    prop_compose! {
        fn config()(
            v in prop_oneof![8 => 0u32..=10, 1 => 11u32..=12, 1 => any::<u32>()],
            n_bits in prop_oneof![8 => 1u32..=10, 1 => 0u32..=14, 1 => any::<u32>()],
            cos_bits in width(),
            coef_bits in width(),
            mul_frac in width(),
            out_bits in width(),
            extra in prop_oneof![8 => Just(0usize), 1 => Just(1usize)],
            square in proptest::collection::vec(width(), 0..=12),
            nearest in any::<bool>(),
            source in prop_oneof![6 => Just(CoefSource::Rom), 1 => Just(CoefSource::Const), 1 => Just(CoefSource::Table)],
            squarer in prop_oneof![6 => Just(Squarer::Generic), 1 => Just(Squarer::Symmetric), 1 => Just(Squarer::Truncated)],
            square_guard in prop_oneof![8 => 1u32..=16, 1 => any::<u32>()],
        ) -> Config {
            // Mostly the right number of square_frac entries, so later checks run.
            let want = (v.min(12) as usize + extra).min(square.len());
            let round = if nearest { Rounding::Nearest } else { Rounding::Truncate };
            Config {
                v, n_bits, cos_bits, coefficients: Coefficients::EnergyFit, coef_bits,
                coef_round: round, mul_frac, mul_round: round,
                square_frac: square[..want].to_vec(), square_round: round,
                out_bits, out_round: round, coef_source: source, squarer, square_guard,
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1024))]

        /// Any configuration is either rejected with an error or builds a unit whose
        /// extreme inputs evaluate without overflow: no panic in between (the tests
        /// run with overflow checks on).
        #[test]
        fn never_panics(cfg in config()) {
            match Unit::new(cfg.clone()) {
                Err(e) => prop_assert!(!e.to_string().contains('\n')),
                Ok(unit) => {
                    prop_assert!(cfg.cos_bits <= MAX_COS_BITS && cfg.out_bits <= 64);
                    prop_assert!(unit.config().exhaustive_points().is_some());
                    let (lo, hi) = unit.cos_code_range();
                    let n_max = (1u32 << cfg.n_bits) - 1;
                    for cos in [lo, -unit.cos_one(), 0, unit.cos_one(), hi] {
                        for n in [0, n_max] {
                            let input = Input { cos, n, ks: [unit.full_scale(), 0, 1] };
                            let out = unit.eval(&input).unwrap();
                            prop_assert!(out.rgb[0] <= unit.full_scale());
                            prop_assert_eq!(unit.trace(&input).unwrap().output, out);
                        }
                    }
                }
            }
        }
    }
}

/// The spellings the hand-written parsers accepted before the strum derives, written
/// out here (not taken from the derives), and the names printed in tables and files.
#[test]
fn named_enums_keep_their_spellings() {
    use glint_hw::{CoefSource, Coefficients, Rounding, Squarer};
    for (s, want) in [
        ("truncate", Rounding::Truncate),
        ("trunc", Rounding::Truncate),
        ("FLOOR", Rounding::Truncate),
        ("nearest", Rounding::Nearest),
        ("Round", Rounding::Nearest),
    ] {
        assert_eq!(s.parse::<Rounding>().unwrap(), want, "{s}");
    }
    for (s, want) in [
        ("k", Coefficients::EnergyFit),
        ("energy", Coefficients::EnergyFit),
        ("Energy-Fit", Coefficients::EnergyFit),
        ("minimax", Coefficients::Minimax),
    ] {
        assert_eq!(s.parse::<Coefficients>().unwrap(), want, "{s}");
    }
    let names = |v: &[&str]| v.join(",");
    assert_eq!(
        names(&[Rounding::Truncate.name(), Rounding::Nearest.name()]),
        "truncate,nearest"
    );
    assert_eq!(Coefficients::EnergyFit.to_string(), "k");
    assert_eq!(Coefficients::Minimax.name(), "minimax");
    assert_eq!(
        names(&[
            CoefSource::Rom.name(),
            CoefSource::Const.name(),
            CoefSource::Table.name()
        ]),
        "rom,const,table"
    );
    assert_eq!(
        names(&[
            Squarer::Generic.name(),
            Squarer::Symmetric.name(),
            Squarer::Truncated.name()
        ]),
        "generic,symmetric,truncated"
    );
    // The JSON spellings of configuration files are serde's, unchanged.
    let json = Config::default().to_json();
    assert!(json.contains(r#""coefficients": "k""#), "{json}");
    assert!(json.contains(r#""coef_round": "nearest""#), "{json}");
    assert!(json.contains(r#""coef_source": "rom""#), "{json}");
    assert!(json.contains(r#""squarer": "generic""#), "{json}");
    // A wrong name is a typed error with one line naming the accepted ones.
    let e = "half".parse::<Rounding>().unwrap_err();
    assert!(matches!(e, HwError::Parse(_)));
    assert_eq!(
        e.to_string(),
        "invalid configuration: unknown rounding 'half': expected one of truncate, nearest"
    );
    let e = "phong".parse::<Coefficients>().unwrap_err().to_string();
    assert_eq!(
        e,
        "invalid configuration: unknown coefficients 'phong': expected one of k, minimax"
    );
}
