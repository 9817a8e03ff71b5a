//! The width search on a small configuration: what it reports meets the target, and
//! every stage one bit narrower misses it.

use glint_hw::{mask_ranges, measure, sweep_row, within, Config, Reference, Target, Unit};

fn base() -> Config {
    Config {
        v: 2,
        n_bits: 5,
        cos_bits: 10,
        coef_bits: 1,
        mul_frac: 1,
        square_frac: vec![1, 1],
        out_bits: 6,
        ..Config::default()
    }
}

#[test]
fn sweep_result_meets_the_target_and_is_locally_minimal() {
    let target = Target {
        reference: Reference::Lobe,
        bound: 1.0,
    };
    let mut lines = 0;
    let row = sweep_row(&base(), target, &mut |_| lines += 1).unwrap();
    assert!(lines > 0, "progress is reported");
    let cfg = row.config.clone().expect("1 LSB is reachable");
    let unit = Unit::new(cfg.clone()).unwrap();
    // Independently of `within`: the exhaustive measurement agrees.
    let m = measure(&unit);
    let worst = m.worst_lobe(0..=31).error;
    assert!(
        worst <= 1.0 + 1e-9 && (worst - row.max_error).abs() < 1e-12,
        "{worst}"
    );
    // Every stage one bit narrower breaks the bound.
    let mut narrower = vec![Config {
        coef_bits: cfg.coef_bits - 1,
        ..cfg.clone()
    }];
    narrower.push(Config {
        mul_frac: cfg.mul_frac - 1,
        ..cfg.clone()
    });
    for k in 0..cfg.square_frac.len() {
        let mut c = cfg.clone();
        c.square_frac[k] -= 1;
        narrower.push(c);
    }
    for c in narrower {
        if let Ok(u) = Unit::new(c.clone()) {
            assert!(
                !within(&u, Reference::Lobe, 1.0, None),
                "{c:?} also meets it"
            );
        }
    }
}

#[test]
fn cos_n_rows_only_ask_where_an_ideal_unit_can_succeed() {
    // 0.5 LSB of cos^n: K_2 equals cos^4 exactly at n = 4, so n = 4 is always asked.
    let row = sweep_row(
        &base(),
        Target {
            reference: Reference::Power,
            bound: 0.5,
        },
        &mut |_| {},
    )
    .unwrap();
    assert!(
        row.feasible_n.iter().any(|&(a, b)| a <= 4 && 4 <= b),
        "{:?}",
        row.feasible_n
    );
    // ... and n = 31 (a = 32/5, error ~0.1 of full scale) is not.
    assert!(
        row.feasible_n.iter().all(|&(_, b)| b < 31),
        "{:?}",
        row.feasible_n
    );
}

#[test]
fn mask_ranges_join_runs() {
    assert_eq!(
        mask_ranges(&[true, true, false, true, false, false, true]),
        vec![(0, 1), (3, 3), (6, 6)]
    );
    assert!(mask_ranges(&[false, false]).is_empty());
}
