//! Tables of what pydicom reports for DICOM files (tests/data/pydicom-corpus.tsv from
//! scripts/pydicom-table.py, tests/data/jpeg/reference.tsv from scripts/jpeg-fixtures.py)
//! and the check of glint's reader against one line of them.

use std::path::Path;

use glint_io::{dicom, ReadOptions, Samples, VolumeFile};

/// One line of a table: file (relative), expect (`read` or `refuse`), dims (columns x
/// rows x frames), spacing (mm, 6 significant digits), stored values' min, max, sum and
/// checksum (see [`stats`]), and for `refuse` a substring of glint's message.
pub struct Row<'a> {
    pub file: &'a str,
    pub expect: &'a str,
    pub dims: &'a str,
    pub spacing: &'a str,
    pub min: &'a str,
    pub max: &'a str,
    pub sum: &'a str,
    pub checksum: &'a str,
    pub reason: &'a str,
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

/// The rows of a table (comment lines start with `#`; the header line with `file\t`).
pub fn rows(table: &str) -> Vec<Row<'_>> {
    table
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("file\t"))
        .map(parse)
        .collect()
}

/// (min, max, sum, checksum) of the stored values; the checksum weights each value by
/// its in-plane index (p % 65521 + 1), so it does not depend on the frame order (glint
/// sorts frames along the normal, pydicom keeps file order).
pub fn stats(s: &Samples, frame_len: usize) -> (i128, i128, i128, i128) {
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

/// Dims and spacing of a volume against its row; a description of the disagreement.
pub fn check_geometry(row: &Row, f: &VolumeFile) -> Option<String> {
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
    None
}

/// Checks one file against its row (values exactly); a description of the disagreement.
pub fn check(row: &Row, dir: &Path) -> Option<String> {
    let path = dir.join(row.file);
    let got = dicom::read(&path, &ReadOptions::default());
    match (row.expect, got) {
        ("read", Ok(f)) => {
            if let Some(why) = check_geometry(row, &f) {
                return Some(why);
            }
            let v = &f.volume;
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
