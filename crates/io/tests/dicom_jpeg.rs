//! JPEG-compressed DICOM (baseline .50, extended .51, lossless .57 and .70) read by glint
//! (dicom-pixeldata 0.10, jpeg-decoder 0.3) and compared with pydicom's decode
//! (pylibjpeg, Thomas Richter's libjpeg) of the same files. The fixtures in
//! tests/data/jpeg/ and their reference.tsv were written by scripts/fixtures/jpeg-fixtures
//! (libjpeg-turbo 3 encoding, pydicom encapsulation and decode): lossless files must
//! match exactly (dims, spacing, min, max, sum, position-weighted checksum); lossy ones
//! (8-bit by jpeg-decoder, 12-bit by libjpeg-turbo 3) voxel by voxel within
//! [`LOSSY_MAX_ABS_DIFF`] of pydicom's decode (NAME.pydicom.raw).

mod common;

use std::path::{Path, PathBuf};

use common::table::{self, Row};
use glint_io::{dicom, ReadOptions, Samples};

/// Largest difference allowed between glint's and pydicom's decode of a lossy (DCT)
/// JPEG, in stored units. Decoders may differ here: ITU T.81 (A.3.3) leaves the IDCT's
/// arithmetic to the implementation, bounded by an accuracy test (IEEE 1180-1990: peak
/// error at most 1 per output sample), and jpeg-decoder's integer IDCT (after stb_image)
/// rounds differently from libjpeg's; two such decoders may disagree by 1 per sample
/// after rounding. Measured on these fixtures: see `lossy_jpeg_within_tolerance`.
const LOSSY_MAX_ABS_DIFF: i64 = 1;

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/jpeg")
}

fn reference() -> String {
    std::fs::read_to_string(dir().join("reference.tsv")).expect("reference.tsv")
}

/// pydicom's decode of a lossy fixture, every voxel, in position order: little-endian
/// samples of the file's bits allocated (8 or 16).
fn pydicom_voxels(row: &Row, bytes_per_sample: usize) -> Vec<i64> {
    let name = row.file.trim_end_matches(".dcm");
    let raw = std::fs::read(dir().join(format!("{name}.pydicom.raw"))).expect("reference voxels");
    match bytes_per_sample {
        1 => raw.iter().map(|&b| i64::from(b)).collect(),
        _ => raw
            .chunks_exact(2)
            .map(|c| i64::from(u16::from_le_bytes([c[0], c[1]])))
            .collect(),
    }
}

fn is_lossy(row: &Row) -> bool {
    dir()
        .join(format!("{}.pydicom.raw", row.file.trim_end_matches(".dcm")))
        .is_file()
}

#[test]
fn lossless_jpeg_equals_pydicom() {
    let table = reference();
    let rows: Vec<Row> = table::rows(&table)
        .into_iter()
        .filter(|r| r.expect == "read" && !is_lossy(r))
        .collect();
    // .70 16-bit, .70 12-bit signed, a .70 series, .57 8-bit and 16-bit.
    assert_eq!(rows.len(), 5, "lossless fixtures in reference.tsv");
    let failures: Vec<String> = rows
        .iter()
        .filter_map(|r| table::check(r, &dir()).map(|why| format!("{}: {why}", r.file)))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn lossy_jpeg_within_tolerance() {
    let table = reference();
    let rows: Vec<Row> = table::rows(&table)
        .into_iter()
        .filter(|r| r.expect == "read" && is_lossy(r))
        .collect();
    // Baseline .50, extended .51 (8-bit, SOF1, two fragments per frame), and extended
    // .51 12-bit (libjpeg-turbo).
    assert_eq!(rows.len(), 3, "lossy fixtures in reference.tsv");
    for row in &rows {
        let f = dicom::read(&dir().join(row.file), &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{}: {e}", row.file));
        if let Some(why) = table::check_geometry(row, &f) {
            panic!("{}: {why}", row.file);
        }
        let s = &f.volume.samples;
        let bytes = if matches!(s, Samples::U8(_) | Samples::I8(_)) {
            1
        } else {
            2
        };
        let want = pydicom_voxels(row, bytes);
        assert_eq!(s.len(), want.len(), "{}: voxel count", row.file);
        let diffs: Vec<i64> = (0..s.len())
            .map(|i| (s.get(i) as i64 - want[i]).abs())
            .collect();
        let worst = diffs.iter().copied().max().unwrap_or(0);
        let differing = diffs.iter().filter(|&&d| d != 0).count();
        eprintln!(
            "{}: max |glint - pydicom| = {worst}, {differing} of {} voxels differ",
            row.file,
            s.len()
        );
        assert!(
            worst <= LOSSY_MAX_ABS_DIFF,
            "{}: max |glint - pydicom| = {worst} > {LOSSY_MAX_ABS_DIFF}",
            row.file
        );
    }
}

/// The fixtures carry full geometry (position, orientation, pixel and slice spacing),
/// so nothing about it is assumed.
#[test]
fn fixtures_need_no_assumed_geometry() {
    let table = reference();
    for row in table::rows(&table).iter().filter(|r| r.expect == "read") {
        let f = dicom::read(&dir().join(row.file), &ReadOptions::default()).unwrap();
        assert!(
            !f.notes.iter().any(|n| n.contains("assumed")),
            "{}: {:?}",
            row.file,
            f.notes
        );
    }
}

#[test]
fn every_fixture_is_in_the_table() {
    let table = reference();
    let listed: Vec<&str> = table::rows(&table).iter().map(|r| r.file).collect();
    for e in std::fs::read_dir(dir()).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name == "reference.tsv" || name.ends_with(".pydicom.raw") {
            continue;
        }
        assert!(
            listed.contains(&name.as_str()),
            "{name} is not in reference.tsv"
        );
    }
}
