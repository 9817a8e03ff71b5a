//! Conformance: every file of pydicom's test suite data (pydicom 3.0.2) and of the
//! pydicom-data 1.0.0 wheel (both fetched by scripts/fetch-samples into samples/pydicom
//! and samples/pydicom-data) through the DICOM reader, checked against
//! tests/data/pydicom-corpus.tsv and pydicom-data-corpus.tsv, which
//! scripts/fixtures/pydicom-table.py recorded with pydicom (and its pylibjpeg, openjpeg, rle and
//! pyjpegls decoders): read with pydicom's dims, spacing and stored values (min, max,
//! sum, a position-weighted checksum; colour over the RGB channels; within a stated
//! tolerance for lossy DCT JPEG), or refused with the expected reason. Fails in CI when
//! a corpus is missing.

mod common;

use std::path::Path;

use common::table::{self, Row};

#[test]
fn pydicom_test_files_match_the_table() {
    // The README is always in the wheel's test_files; its absence means no corpus.
    if common::sample("pydicom/README.txt").is_none() {
        return;
    }
    let dir = common::samples_dir().join("pydicom");
    conform(&dir, include_str!("data/pydicom-corpus.tsv"), 150);
}

#[test]
fn pydicom_data_files_match_the_table() {
    // One of the wheel's files stands for the whole set (fetched together).
    if common::sample("pydicom-data/liver.dcm").is_none() {
        return;
    }
    let dir = common::samples_dir().join("pydicom-data");
    conform(&dir, include_str!("data/pydicom-data-corpus.tsv"), 60);
}

/// Checks every row of `table` against the files of `dir`, and that every file of `dir`
/// is in the table.
fn conform(dir: &Path, table: &str, at_least: usize) {
    let dir = dir.to_path_buf();
    let rows: Vec<Row> = table::rows(table);
    assert!(
        rows.len() > at_least,
        "the table lists {} files",
        rows.len()
    );
    let mut failures = Vec::new();
    for row in &rows {
        if let Some(why) = table::check(row, &dir) {
            failures.push(format!("{}: {why}", row.file));
        }
    }
    // Every file on disk is in the table (a new pydicom adds files: re-run the script).
    let listed: std::collections::BTreeSet<&str> = rows.iter().map(|r| r.file).collect();
    let mut stack = vec![dir.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if e.file_name().to_string_lossy().starts_with('.') {
                // fetch-samples' completion marker.
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(&dir).unwrap().to_string_lossy().into_owned();
                if !listed.contains(rel.as_str()) {
                    failures.push(format!("{rel}: not in the table"));
                }
            }
        }
    }
    let read = rows.iter().filter(|r| r.expect == "read").count();
    let lossy = rows.iter().filter(|r| table::tolerance(r) > 0).count();
    eprintln!(
        "{}: {} files, {read} read ({lossy} of them lossy JPEG within a tolerance), {} refused",
        dir.display(),
        rows.len(),
        rows.len() - read
    );
    assert!(
        failures.is_empty(),
        "{} of {} files disagree with pydicom:\n{}",
        failures.len(),
        rows.len(),
        failures.join("\n")
    );
}
