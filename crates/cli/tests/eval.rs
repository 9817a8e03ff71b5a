//! `glint eval` end to end: values against the formulas written out by hand, JSON shape,
//! and one-line errors for bad arguments.

mod common;

use common::glint;

fn json(args: &[&str]) -> serde_json::Value {
    let out = glint(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

#[test]
fn k_matches_the_papers_formula_at_the_issue_angles() {
    let doc = json(&[
        "eval",
        "--lobe",
        "k",
        "--n",
        "100",
        "--v",
        "4",
        "--angle",
        "0,2.5,5,10",
        "--json",
    ]);
    let rows = doc["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4);
    for (row, deg) in rows.iter().zip([0.0f64, 2.5, 5.0, 10.0]) {
        let c = deg.to_radians().cos();
        let want = (1.0 - 101.0 / 17.0 * (1.0 - c)).max(0.0).powi(16);
        let got = row["k"].as_f64().unwrap();
        assert!((got - want).abs() < 1e-12, "{deg}: {got} vs {want}");
        assert_eq!(row["angle_deg"].as_f64().unwrap(), deg);
    }
    assert!((doc["coefficients"]["k"].as_f64().unwrap() - 101.0 / 17.0).abs() < 1e-15);
}

#[test]
fn every_lobe_gets_a_column_with_its_formula() {
    let doc = json(&[
        "eval",
        "--n",
        "50",
        "--v",
        "3",
        "--cos",
        "0.99,0.9,0.5",
        "--json",
    ]);
    let names: Vec<&str> = doc["lobes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(names, ["exact", "k", "g", "schlick", "gauss", "minimax"]);
    for row in doc["rows"].as_array().unwrap() {
        let c = row["cos"].as_f64().unwrap();
        let close = |key: &str, want: f64| {
            let got = row[key].as_f64().unwrap();
            assert!((got - want).abs() < 1e-12, "{key} at {c}: {got} vs {want}");
        };
        close("exact", c.powf(50.0));
        close("k", (1.0 - 51.0 / 9.0 * (1.0 - c)).max(0.0).powi(8));
        close("g", (1.0 - 50.0 / 8.0 * (1.0 - c)).max(0.0).powi(8));
        close("schlick", c / (50.0 - 50.0 * c + c));
        close("gauss", (50.0 * (c - 1.0)).exp());
        let m = row["minimax"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&m));
    }
}

#[test]
fn the_table_has_one_column_per_lobe() {
    let out = glint(&["eval", "--lobe", "exact,k", "--lobe", "g", "--angle", "0,5"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let header = text.lines().find(|l| l.contains("angle_deg")).unwrap();
    assert_eq!(
        header.split_whitespace().collect::<Vec<_>>(),
        ["angle_deg", "cos", "exact", "k", "g"]
    );
    assert_eq!(text.lines().filter(|l| !l.starts_with('#')).count(), 3);
}

#[test]
fn bad_arguments_give_one_error_line_and_fail() {
    for args in [
        &["eval", "--n", "-1"][..],
        &["eval", "--n", "nan"],
        &["eval", "--v", "11"],
        &["eval", "--lobe", "blinnish"],
        &["eval", "--cos", "1.5"],
        &["eval", "--angle", "abc"],
        &["eval", "--angle", "1", "--cos", "0.5"],
        &["eval", "--bogus"],
    ] {
        let out = glint(args);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(out.stdout.is_empty(), "{args:?} printed to stdout");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("glint: error: "), "{args:?}: {err}");
    }
}
