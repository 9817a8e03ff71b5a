//! The written files: CSVs parse with the declared columns and agree with the metrics;
//! bad arguments and unwritable directories give an error and leave nothing behind.

use std::fs;
use std::path::Path;

use glint_analysis::{
    check_lists, curves_header, lobe_metrics, write_analysis, AnalysisError, COMPARED,
    SUMMARY_COLUMNS,
};

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn analysis_files_parse_and_agree() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("analysis");
    let written = write_analysis(&[100.0], &[4], &out).unwrap();
    let names = entries(&out);
    for want in [
        "curves.csv",
        "summary.csv",
        "summary.md",
        "fig2-error-n100-v4.png",
        "fig2-error-n100-v4.svg",
        "fig3-error-whole-range-v4.png",
        "fig3-error-whole-range-v4.svg",
        "shapes-n100-v4.png",
        "shapes-n100-v4.svg",
        "error-map.png",
        "error-map.svg",
    ] {
        assert!(
            names.contains(&want.to_string()),
            "{want} missing: {names:?}"
        );
    }
    assert_eq!(written.len(), names.len());
    // Nothing but the files: no staging directory left behind.
    assert_eq!(entries(tmp.path()), vec!["analysis".to_string()]);
    // PNG signature.
    let png = fs::read(out.join("fig2-error-n100-v4.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");

    // curves.csv: the declared header, >= 4000 rows, numbers everywhere, errors
    // consistent with the lobe columns.
    let mut r = csv::Reader::from_path(out.join("curves.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header, curves_header());
    assert!(header.contains(&"abs_err_k".to_string()) && header.contains(&"exact".to_string()));
    let mut rows = 0;
    let mut last_gamma = -1.0;
    for rec in r.records() {
        let rec = rec.unwrap();
        assert_eq!(rec.len(), header.len());
        let x: Vec<f64> = rec.iter().map(|f| f.parse::<f64>().unwrap()).collect();
        let gamma = x[2];
        assert!(gamma > last_gamma && (0.0..=90.0).contains(&gamma));
        last_gamma = gamma;
        // gamma_deg is rounded to 1e-10 degrees; cos is written in full.
        assert!((x[3] - gamma.to_radians().cos()).abs() < 1e-11);
        let exact = x[3].max(0.0).powf(100.0);
        assert!((x[4] - exact).abs() < 1e-14);
        for (i, _) in COMPARED.iter().enumerate() {
            let (lobe, err, abs) = (x[5 + i], x[10 + i], x[15 + i]);
            assert!((err - (lobe - x[4])).abs() < 1e-15);
            assert!((abs - err.abs()).abs() < 1e-15);
        }
        rows += 1;
    }
    assert!(rows >= 4000, "{rows} rows");
    assert_eq!(last_gamma, 90.0);

    // summary.csv: declared columns, one row per lobe, numbers equal to the metrics.
    let mut r = csv::Reader::from_path(out.join("summary.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header, SUMMARY_COLUMNS);
    let recs: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert_eq!(recs.len(), COMPARED.len());
    for rec in &recs {
        let kind: glint_lobe::LobeKind = rec[0].parse().unwrap();
        assert_eq!(&rec[1], "100");
        let m = lobe_metrics(kind, 100.0, 4).unwrap();
        let max_abs: f64 = rec[4].parse().unwrap();
        assert!((max_abs - m.max_abs.value).abs() <= 1e-9 * m.max_abs.value);
        let energy: f64 = rec[14].parse().unwrap();
        assert!((energy - m.energy_ratio).abs() < 1e-11);
        if kind.uses_v() {
            assert_eq!(&rec[2], "4");
        } else {
            assert_eq!(&rec[2], "");
        }
    }
    let md = fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("| k | 100 | 4 |"));

    // Writing again into the existing directory replaces the files.
    write_analysis(&[100.0], &[4], &out).unwrap();
    assert_eq!(entries(&out), names);
}

#[test]
fn bad_lists_are_refused_before_any_output() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let cases: Vec<(Vec<f64>, Vec<u32>, &str)> = vec![
        (vec![-1.0], vec![4], "invalid n = -1"),
        (vec![f64::NAN], vec![4], "invalid n"),
        (vec![100.0], vec![11], "invalid v = 11"),
        (vec![], vec![4], "list of n values is empty"),
        (vec![100.0], vec![], "list of v values is empty"),
    ];
    for (ns, vs, msg) in cases {
        let err = write_analysis(&ns, &vs, &out).unwrap_err();
        assert!(err.to_string().contains(msg), "{err} vs {msg}");
        assert!(check_lists(&ns, &vs).is_err());
        assert!(
            entries(tmp.path()).is_empty(),
            "output left behind for {msg}"
        );
    }
}

#[test]
fn unwritable_directories_leave_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("a-file");
    fs::write(&file, b"x").unwrap();
    // The target is a file.
    let err = write_analysis(&[100.0], &[4], &file).unwrap_err();
    assert!(matches!(err, AnalysisError::Output { .. }), "{err}");
    // The target's parent is a file.
    let err = write_analysis(&[100.0], &[4], &file.join("out")).unwrap_err();
    assert!(err.to_string().contains("cannot write to"), "{err}");
    // The target's parent does not exist.
    let err = write_analysis(&[100.0], &[4], &tmp.path().join("no/such/out")).unwrap_err();
    assert!(err.to_string().contains("does not exist"), "{err}");
    assert_eq!(entries(tmp.path()), vec!["a-file".to_string()]);
    assert_eq!(fs::read(&file).unwrap(), b"x");
}
