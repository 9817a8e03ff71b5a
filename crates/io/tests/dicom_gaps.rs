//! The DICOM gaps of issue 33, each against pydicom's decode: fixtures made from
//! pydicom's test files by scripts/fixtures/dicom-gap-fixtures.py (tests/data/dicom-gaps, with
//! pydicom's decode in reference.tsv), and colour files of the pydicom corpus read with
//! each grey choice.

mod common;

use std::path::{Path, PathBuf};

use common::table::{self, Row};
use glint_io::{dicom, Grey, IoError, ReadOptions, Samples};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom-gaps")
}

#[test]
fn gap_fixtures_read_as_pydicom_reads_them() {
    let text = std::fs::read_to_string(dir().join("reference.tsv")).expect("reference.tsv");
    let rows: Vec<Row> = table::rows(&text);
    assert_eq!(rows.len(), 3, "fixtures in reference.tsv");
    let failures: Vec<String> = rows
        .iter()
        .filter_map(|r| table::check(r, &dir()).map(|why| format!("{}: {why}", r.file)))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn empty_first_jpeg2000_fragment_is_skipped() {
    let f = dicom::read(
        &dir().join("j2k_empty_first_fragment.dcm"),
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(f.volume.dims, [64, 64, 1]);
}

#[test]
fn zero_pixel_spacing_is_one_mm_with_a_note_and_refused_when_strict() {
    let p = dir().join("pixel_spacing_zero.dcm");
    let f = dicom::read(&p, &ReadOptions::default()).unwrap();
    assert_eq!(&f.volume.spacing[..2], &[1.0, 1.0]);
    assert!(
        f.notes
            .iter()
            .any(|n| n.contains("PixelSpacing 0\\0, 1 mm")),
        "{:?}",
        f.notes
    );
    let strict = ReadOptions {
        strict: true,
        ..ReadOptions::default()
    };
    let e = dicom::read(&p, &strict).unwrap_err();
    assert!(
        matches!(e, IoError::Geometry { .. }) && e.to_string().contains("PixelSpacing is 0\\0"),
        "{e}"
    );
}

#[test]
fn a_series_option_that_does_not_match_a_single_file_is_an_error() {
    let o = ReadOptions {
        series: Some("9.9.9".into()),
        ..ReadOptions::default()
    };
    let e = dicom::read(&dir().join("pixel_spacing_zero.dcm"), &o).unwrap_err();
    assert!(e.to_string().contains("not 9.9.9"), "{e}");
}

#[test]
fn one_bit_pixels_unpack_across_frames() {
    let f = dicom::read(&dir().join("one_bit_frames.dcm"), &ReadOptions::default()).unwrap();
    let Samples::U8(v) = &f.volume.samples else {
        panic!("{:?}", f.volume.samples.type_name())
    };
    assert_eq!(v.len(), 45);
    assert!(v.iter().all(|&b| b <= 1));
    // pydicom 3.0.2's decode, every pixel (`ds.pixel_array.ravel()`); the frames'
    // order is the file's (the positions are stacked along the normal). PixelData is
    // ce 24 f3 09 51 02: pixel 0 is bit 0 of byte 0, frame 1 starts at bit 7 of byte 1.
    let pydicom: [u8; 45] = [
        0, 1, 1, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 1, 1, 1, 1, 0, 0, 1, 0, 0,
        0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 1, 0, 0, 0,
    ];
    assert_eq!(v.as_slice(), pydicom);
}

/// pydicom's SC_rgb_small_odd.dcm (3 x 3 RGB): the colour planes, and the grey each
/// choice gives.
#[test]
fn colour_volumes_keep_rgb_and_give_the_chosen_grey() {
    let Some(path) = common::sample("pydicom/SC_rgb_small_odd.dcm") else {
        return;
    };
    let f = dicom::read(&path, &ReadOptions::default()).unwrap();
    let v = &f.volume;
    let rgb = v.colour.as_ref().expect("a colour volume");
    assert!(v.is_colour());
    for c in rgb.channels() {
        assert_eq!(c.len(), v.len());
    }
    for i in 0..v.len() {
        let [r, g, b] = rgb.channels().map(|c| c.get(i));
        let luma = (0.299 * r + 0.587 * g + 0.114 * b + 0.5).floor();
        assert_eq!(v.samples.get(i), luma, "voxel {i}");
        assert_eq!(rgb.rgb(i), [r, g, b].map(|x| (x / 255.0) as f32));
    }
    for (grey, channel) in [(Grey::Red, 0), (Grey::Green, 1), (Grey::Blue, 2)] {
        let o = ReadOptions {
            grey,
            ..ReadOptions::default()
        };
        let w = dicom::read(&path, &o).unwrap().volume;
        assert_eq!(&w.samples, rgb.channels()[channel], "{grey:?}");
        assert_eq!(w.colour.as_ref(), Some(rgb));
    }
    assert!("g".parse::<Grey>() == Ok(Grey::Green) && "luminance".parse::<Grey>().is_ok());
    assert!("alpha".parse::<Grey>().is_err());
}
