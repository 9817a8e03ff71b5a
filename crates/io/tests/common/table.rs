//! Tables of what pydicom reports for DICOM files (tests/data/pydicom-corpus.tsv from
//! scripts/fixtures/pydicom-table.py, tests/data/jpeg/reference.tsv from scripts/fixtures/jpeg-fixtures.py)
//! and the check of glint's reader against one line of them.

use std::path::Path;

use glint_io::{dicom, ReadOptions, Rgb, Samples, VolumeFile};

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

/// (min, max, sum, checksum) over the three channels of a colour volume: the checksum
/// weights channel c by c + 1 on top of [`stats`]' in-plane weight.
pub fn colour_stats(rgb: &Rgb, frame_len: usize) -> (i128, i128, i128, i128) {
    let (mut lo, mut hi, mut sum, mut check) = (i128::MAX, i128::MIN, 0i128, 0i128);
    for (c, s) in rgb.channels().into_iter().enumerate() {
        for i in 0..s.len() {
            let v = s.get(i) as i128;
            lo = lo.min(v);
            hi = hi.max(v);
            sum += v;
            check += ((i % frame_len) % 65521 + 1) as i128 * (c as i128 + 1) * v;
        }
    }
    (lo, hi, sum, check)
}

/// The largest per-sample difference a row allows: 0, or N for `tolerance N` (lossy
/// DCT JPEG).
pub fn tolerance(row: &Row) -> i128 {
    row.reason
        .strip_prefix("tolerance ")
        .map_or(0, |t| t.parse().expect("tolerance N"))
}

/// Whether stats agree within `t` per sample: min and max within t, sum within t per
/// sample, checksum within t times the sum of the weights (a necessary condition for
/// every sample to be within t).
fn stats_agree(got: [i128; 4], want: [i128; 4], t: i128, n: i128, weights: i128) -> bool {
    (got[0] - want[0]).abs() <= t
        && (got[1] - want[1]).abs() <= t
        && (got[2] - want[2]).abs() <= t * n
        && (got[3] - want[3]).abs() <= t * weights
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
            let frame_len = v.dims[0] * v.dims[1];
            let (lo, hi, sum, check) = match &v.colour {
                Some(rgb) => colour_stats(rgb, frame_len),
                None => stats(&v.samples, frame_len),
            };
            let got = [lo, hi, sum, check];
            let want = [row.min, row.max, row.sum, row.checksum].map(|x| x.parse().unwrap());
            let channels: i128 = if v.colour.is_some() { 3 } else { 1 };
            let n = v.len() as i128 * channels;
            // Sum of the checksum's weights over every sample.
            let frames = (v.len() / frame_len) as i128;
            let per_frame: i128 = (0..frame_len).map(|p| (p % 65521 + 1) as i128).sum();
            let weights = per_frame * frames * if v.colour.is_some() { 6 } else { 1 };
            (!stats_agree(got, want, tolerance(row), n, weights))
                .then(|| format!("min/max/sum/checksum {got:?}, pydicom {want:?}"))
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
