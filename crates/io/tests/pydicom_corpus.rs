//! Conformance: every file of pydicom's test suite data (pydicom 3.0.2, fetched by
//! scripts/fetch-samples into samples/pydicom) through the DICOM reader, checked against
//! tests/data/pydicom-corpus.tsv, which scripts/pydicom-table.py recorded with pydicom
//! (and its pylibjpeg/openjpeg/rle decoders): read with pydicom's dims, spacing and
//! stored values (min, max, sum, a position-weighted checksum), or refused with the
//! expected reason. Fails in CI when the corpus is missing.

mod common;

use common::table::{self, Row};

#[test]
fn pydicom_test_files_match_the_table() {
    let dir = common::samples_dir().join("pydicom");
    // The README is always in the wheel's test_files; its absence means no corpus.
    if common::sample("pydicom/README.txt").is_none() {
        return;
    }
    let rows: Vec<Row> = table::rows(include_str!("data/pydicom-corpus.tsv"));
    assert!(rows.len() > 150, "the table lists {} files", rows.len());
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
    eprintln!(
        "{} files, {read} read, {} refused",
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
