//! Conformance: every file of pydicom's test suite data (pydicom 3.0.2, fetched by
//! scripts/fetch-samples into samples/pydicom) through the DICOM reader, checked against
//! tests/data/pydicom-corpus.tsv, which scripts/pydicom-table.py recorded with pydicom
//! (and its pylibjpeg/openjpeg/rle decoders): read with pydicom's dims, spacing and
//! stored values (min, max, sum, a position-weighted checksum), or refused with the
//! expected reason. Fails in CI when the corpus is missing.

mod common;

use glint_io::{dicom, ReadOptions, Samples};

/// One line of the table.
struct Row<'a> {
    file: &'a str,
    expect: &'a str,
    dims: &'a str,
    spacing: &'a str,
    min: &'a str,
    max: &'a str,
    sum: &'a str,
    checksum: &'a str,
    reason: &'a str,
}

fn parse(line: &str) -> Row<'_> {
    let f: Vec<&str> = line.split('\t').collect();
    assert_eq!(f.len(), 9, "bad table line: {line}");
    Row {
        file: f[0],
        expect: f[1],
        dims: f[2],
        spacing: f[3],
        min: f[4],
        max: f[5],
        sum: f[6],
        checksum: f[7],
        reason: f[8],
    }
}

/// (min, max, sum, checksum) of the stored values; the checksum weights each value by
/// its in-plane index (p % 65521 + 1), so it does not depend on the frame order (glint
/// sorts frames along the normal, pydicom keeps file order).
fn stats(s: &Samples, frame_len: usize) -> (i128, i128, i128, i128) {
    let (mut lo, mut hi, mut sum, mut check) = (i128::MAX, i128::MIN, 0i128, 0i128);
    for i in 0..s.len() {
        let v = s.get(i) as i128;
        lo = lo.min(v);
        hi = hi.max(v);
        sum += v;
        check += ((i % frame_len) % 65521 + 1) as i128 * v;
    }
    (lo, hi, sum, check)
}

/// Checks one file against its row; returns a description of the disagreement.
fn check(row: &Row, dir: &std::path::Path) -> Option<String> {
    let path = dir.join(row.file);
    let got = dicom::read(&path, &ReadOptions::default());
    match (row.expect, got) {
        ("read", Ok(f)) => {
            let v = &f.volume;
            let dims = format!("{}x{}x{}", v.dims[0], v.dims[1], v.dims[2]);
            if dims != row.dims {
                return Some(format!("dims {dims}, pydicom {}", row.dims));
            }
            let want: Vec<f64> = row.spacing.split(',').map(|x| x.parse().unwrap()).collect();
            // The table holds 6 significant digits.
            if v.spacing
                .iter()
                .zip(&want)
                .any(|(g, w)| (g - w).abs() > 1e-5 * w.abs().max(1.0))
            {
                return Some(format!("spacing {:?}, pydicom {want:?}", v.spacing));
            }
            let (lo, hi, sum, check) = stats(&v.samples, v.dims[0] * v.dims[1]);
            let got = [lo, hi, sum, check].map(|x| x.to_string());
            let want = [row.min, row.max, row.sum, row.checksum];
            (got != want).then(|| format!("min/max/sum/checksum {got:?}, pydicom {want:?}"))
        }
        ("read", Err(e)) => Some(format!("refused: {e}")),
        ("refuse", Ok(f)) => Some(format!(
            "read ({:?}), expected a refusal containing {:?}",
            f.volume.dims, row.reason
        )),
        ("refuse", Err(e)) => {
            let msg = e.to_string();
            if msg.contains('\n') {
                return Some(format!("multi-line message: {msg:?}"));
            }
            (!msg.contains(row.reason))
                .then(|| format!("refused with {msg:?}, expected {:?}", row.reason))
        }
        (other, _) => Some(format!("bad expectation {other:?}")),
    }
}

#[test]
fn pydicom_test_files_match_the_table() {
    let dir = common::samples_dir().join("pydicom");
    // The README is always in the wheel's test_files; its absence means no corpus.
    if common::sample("pydicom/README.txt").is_none() {
        return;
    }
    let table = include_str!("data/pydicom-corpus.tsv");
    let rows: Vec<Row> = table
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("file\t"))
        .map(parse)
        .collect();
    assert!(rows.len() > 150, "the table lists {} files", rows.len());
    let mut failures = Vec::new();
    for row in &rows {
        if let Some(why) = check(row, &dir) {
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
