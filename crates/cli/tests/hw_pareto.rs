//! `glint hw check --config` reports, for a design of every family, the same error
//! figures that `glint hw pareto` writes into pareto.csv for it; bad designs fail with
//! one line.

mod common;

use common::glint;
use std::process::Command;

use glint_hw::hdl::{PowParams, SchlickParams};
use glint_hw::pareto::{csv_text, Candidate, Fronts, Measured, Row, CSV_HEADER};
use glint_hw::{CoefSource, Config, Design, Squarer};

/// The numbers of check's `pareto figures` line, in CSV column order.
fn check_figures(design: &Design) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("design.json");
    std::fs::write(&path, design.to_json()).unwrap();
    let out = glint(&["hw", "check", "--config", path.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("pareto figures"))
        .unwrap_or_else(|| panic!("no figures line in {text}"));
    // "... lobe X | cos^n n 1-15 A | n 16-63 B | n 64-255 C | n 256-1023 D | all n E"
    line.split('|')
        .map(|part| part.split_whitespace().last().unwrap().to_string())
        .collect()
}

/// The error columns of the design's pareto.csv row.
fn csv_figures(design: &Design) -> Vec<String> {
    let errors = design.errors().unwrap();
    let row = Row {
        candidate: Candidate {
            id: "d".into(),
            target: "t".into(),
            design: design.clone(),
        },
        measured: Measured {
            errors,
            // The error columns do not depend on the costs: a row without them.
            costs: None,
            rom_bits: 0,
            latency: 1,
            verified: None,
            seconds: 0.0,
            measured_at: String::new(),
            tools: String::new(),
        },
        fronts: Fronts::default(),
    };
    let text = csv_text(&[row]).unwrap();
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let rec = r.records().next().unwrap().unwrap();
    let first = CSV_HEADER.iter().position(|&h| h == "err_lobe").unwrap();
    (first..first + 6).map(|i| rec[i].to_string()).collect()
}

#[test]
fn check_reports_the_csv_figures_for_every_family() {
    let designs = [
        // A K_v unit of the space (constant multiplier, truncated squarers) at a
        // narrow cosine so that the exhaustive check is short in a debug build.
        Design::Kv(Config {
            cos_bits: 12,
            coef_source: CoefSource::Const,
            squarer: Squarer::Truncated,
            square_guard: 3,
            ..Config::default()
        }),
        Design::Pow {
            out_bits: 10,
            params: PowParams {
                log_index: 6,
                log_frac: 18,
                log_interp: true,
                exp_index: 4,
                exp_frac: 12,
                exp_interp: true,
            },
        },
        Design::Schlick {
            out_bits: 8,
            params: SchlickParams {
                quot_frac: 8,
                x_frac: 14,
            },
        },
    ];
    for d in &designs {
        let from_check = check_figures(d);
        assert_eq!(from_check.len(), 6, "{from_check:?}");
        assert_eq!(from_check, csv_figures(d), "{}", d.to_json());
        // Figures are numbers, and the sized units are not trivially exact.
        let lobe: f64 = from_check[0].parse().unwrap();
        assert!(lobe > 0.0 && lobe < 10.0, "{lobe}");
    }
}

#[test]
fn bad_designs_fail_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text, want) in [
        (
            "a.json",
            r#"{"family": "pow", "out_bits": 8, "params": {"log_index": 13, "log_frac": 20, "log_interp": true, "exp_index": 8, "exp_frac": 16, "exp_interp": true}}"#,
            "log_index = 13",
        ),
        (
            "b.json",
            r#"{"family": "schlick", "out_bits": 8}"#,
            "params",
        ),
        (
            "c.json",
            r#"{"family": "kv", "coefficients": "minimax", "coef_source": "const"}"#,
            "coef_source",
        ),
        (
            "d.json",
            r#"{"squarer": "truncated", "square_guard": 0}"#,
            "square_guard",
        ),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        let out = glint(&["hw", "check", "--config", p.to_str().unwrap()]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(want), "{name}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{name}: {err}");
    }
}

/// `glint hw check | head -1`: the reader closes the pipe after the first line; glint
/// stops quietly (exit 0, nothing on stderr) instead of panicking on the next write.
#[test]
fn check_into_a_closed_pipe_exits_quietly() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let design = schlick_json_file();
    let mut child = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["hw", "check", "--config"])
        .arg(design.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run glint");
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    // The reader is dropped here: the pipe is closed with more lines to come.
    assert!(first.starts_with("# glint hw check"), "{first}");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    assert!(stderr.is_empty(), "{stderr}");
}

/// A small design file (the 8-bit Schlick unit, checked in about a second).
fn schlick_json_file() -> tempfile::NamedTempFile {
    let file = tempfile::NamedTempFile::new().unwrap();
    let design = Design::Schlick {
        out_bits: 8,
        params: SchlickParams::default(),
    };
    std::fs::write(file.path(), design.to_json()).unwrap();
    file
}
