//! DICOM: series directories and multi-frame files written with dicom-object in every
//! uncompressed transfer syntax, and the bad-input cases.

mod common;

use std::path::Path;

use dicom_core::value::{DataSetSequence, PixelFragmentSequence, PrimitiveValue, Value};
use dicom_core::{dicom_value, DataElement, Tag, VR};
use dicom_dictionary_std::tags;
use dicom_object::InMemDicomObject;
use glint_io::{IoError, ReadOptions, Samples};
use glint_testkit::dicom::{
    ds, put, ImageHeader, CT_STORAGE, EXPLICIT_BE, EXPLICIT_LE, IMPLICIT_LE,
};

/// A grayscale CT image header: `cols` x `rows`, 16-bit, with pixel spacing (row,
/// column) 0.5 x 0.75 mm and the axial orientation.
fn image(rows: u16, cols: u16, series: &str, instance: u32, signed: bool) -> InMemDicomObject {
    let mut o = ImageHeader {
        instance: format!("1.2.3.4.{instance}"),
        series: series.to_string(),
        signed,
        ..ImageHeader::ct(rows, cols)
    }
    .object();
    put(&mut o, tags::PIXEL_SPACING, VR::DS, ds(&[0.5, 0.75]));
    put(
        &mut o,
        tags::IMAGE_ORIENTATION_PATIENT,
        VR::DS,
        ds(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
    );
    o
}

fn write(path: &Path, obj: InMemDicomObject, ts: &str) {
    glint_testkit::dicom::write(path, obj, CT_STORAGE, ts);
}

/// Pixel value of CT slice `k` at column `i`, row `j`: negative and positive.
fn ct_value(i: usize, j: usize, k: usize) -> i16 {
    (100 * k as i16) + 10 * j as i16 + i as i16 - 150
}

/// Writes a 3-column, 2-row CT series of `zs.len()` slices at z = zs (file names in
/// reverse order so the reader must sort), HU = stored - 1024.
fn ct_series(dir: &Path, zs: &[f64], ts: &str) {
    for (k, &z) in zs.iter().enumerate() {
        let mut o = image(2, 3, "1.2.3.99", k as u32, true);
        put(
            &mut o,
            tags::IMAGE_POSITION_PATIENT,
            VR::DS,
            ds(&[-20.0, 30.0, z]),
        );
        put(&mut o, tags::RESCALE_SLOPE, VR::DS, ds(&[1.0]));
        put(&mut o, tags::RESCALE_INTERCEPT, VR::DS, ds(&[-1024.0]));
        put(&mut o, tags::RESCALE_TYPE, VR::LO, dicom_value!(Str, "HU"));
        let px: Vec<u16> = (0..6).map(|p| ct_value(p % 3, p / 3, k) as u16).collect();
        put(
            &mut o,
            tags::PIXEL_DATA,
            VR::OW,
            PrimitiveValue::U16(px.into()),
        );
        write(&dir.join(format!("slice{:02}.dcm", zs.len() - k)), o, ts);
    }
}

#[test]
fn ct_series_in_every_uncompressed_transfer_syntax() {
    for ts in [EXPLICIT_LE, IMPLICIT_LE, EXPLICIT_BE] {
        let dir = tempfile::tempdir().unwrap();
        // Slices given out of order along z.
        ct_series(dir.path(), &[12.5, 10.0, 17.5, 15.0], ts);
        std::fs::write(dir.path().join("README.txt"), "not dicom").unwrap();
        let f = glint_io::open_volume(dir.path(), &ReadOptions::default()).unwrap();
        let v = &f.volume;
        assert_eq!(v.dims, [3, 2, 4], "{ts}");
        // Column spacing 0.75 along i, row spacing 0.5 along j, 2.5 mm between slices.
        assert_eq!(v.spacing, [0.75, 0.5, 2.5]);
        // LPS (-20, 30, 10) is RAS (20, -30, 10); x and y axes flip.
        let want = [
            [-0.75, 0.0, 0.0, 20.0],
            [0.0, -0.5, 0.0, -30.0],
            [0.0, 0.0, 2.5, 10.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        assert_eq!(v.affine, want, "{ts}");
        assert_eq!((v.slope, v.intercept), (1.0, -1024.0));
        assert_eq!(v.units.as_deref(), Some("HU"));
        assert!(matches!(v.samples, Samples::I16(_)));
        // Sorted by z: slice k of the volume is the file written with z = 10 + 2.5 k,
        // which was index [1, 0, 3, 2][k] in the list above.
        for (k, src) in [1usize, 0, 3, 2].into_iter().enumerate() {
            for j in 0..2 {
                for i in 0..3 {
                    assert_eq!(
                        v.value(i, j, k),
                        f64::from(ct_value(i, j, src)) - 1024.0,
                        "{ts} {i} {j} {k}"
                    );
                }
            }
        }
        assert!(f.notes.iter().any(|n| n.contains("skipped 1 non-DICOM")));
    }
}

#[test]
fn sagittal_orientation_sorts_along_the_normal() {
    // Rows along +y (anterior->posterior in LPS), columns along -z: the normal
    // row x col = (0,1,0) x (0,0,-1) = (-1, 0, 0).
    let dir = tempfile::tempdir().unwrap();
    for (k, x) in [1.0, 5.0, 3.0].into_iter().enumerate() {
        let mut o = image(2, 2, "1.2.3.7", k as u32, false);
        put(
            &mut o,
            tags::IMAGE_ORIENTATION_PATIENT,
            VR::DS,
            ds(&[0.0, 1.0, 0.0, 0.0, 0.0, -1.0]),
        );
        put(
            &mut o,
            tags::IMAGE_POSITION_PATIENT,
            VR::DS,
            ds(&[x, 4.0, 6.0]),
        );
        put(
            &mut o,
            tags::PIXEL_DATA,
            VR::OW,
            PrimitiveValue::U16(vec![x as u16; 4].into()),
        );
        write(&dir.path().join(format!("{k}.dcm")), o, EXPLICIT_LE);
    }
    let v = glint_io::read_volume(dir.path(), &ReadOptions::default()).unwrap();
    // Along the normal (-x): x = 5, then 3, then 1; step (-2, 0, 0) in LPS.
    assert_eq!(v.value(0, 0, 0), 5.0);
    assert_eq!(v.value(0, 0, 2), 1.0);
    // LPS columns (0, 0.75, 0), (0, 0, -0.5), (-2, 0, 0), origin (5, 4, 6); RAS negates
    // the x and y rows.
    let want = [
        [0.0, 0.0, 2.0, -5.0],
        [-0.75, 0.0, 0.0, -4.0],
        [0.0, -0.5, 0.0, 6.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    assert_eq!(v.affine, want);
    assert_eq!(v.units, Some("HU".into())); // CT modality without RescaleType
}

#[test]
fn gap_and_duplicate_slices_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    ct_series(dir.path(), &[0.0, 2.0, 4.0, 8.0], EXPLICIT_LE);
    let err = glint_io::read_volume(dir.path(), &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Geometry { .. }) && err.to_string().contains("missing slice"),
        "{err}"
    );
    let dir = tempfile::tempdir().unwrap();
    ct_series(dir.path(), &[0.0, 2.0, 2.0, 4.0], EXPLICIT_LE);
    let err = glint_io::read_volume(dir.path(), &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Geometry { .. }) && err.to_string().contains("same position"),
        "{err}"
    );
}

/// A directory with two series reads the larger with a note naming the other, or the
/// one `series` names; an unknown UID is an error listing the series there.
#[test]
fn mixed_series_read_the_largest_or_the_one_named() {
    let dir = tempfile::tempdir().unwrap();
    ct_series(dir.path(), &[0.0, 2.0], EXPLICIT_LE);
    let mut o = image(2, 3, "1.2.3.100", 50, true);
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[-20.0, 30.0, 4.0]),
    );
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(vec![0; 6].into()),
    );
    write(&dir.path().join("other.dcm"), o, EXPLICIT_LE);
    let f = glint_io::open_volume(dir.path(), &ReadOptions::default()).unwrap();
    assert_eq!(f.volume.dims[2], 2);
    let note = f.notes.iter().find(|n| n.contains("image series here"));
    let note = note.unwrap_or_else(|| panic!("{:?}", f.notes));
    assert!(
        note.contains("the largest") && note.contains("1.2.3.100"),
        "{note}"
    );
    let other = ReadOptions {
        series: Some("1.2.3.100".into()),
        ..ReadOptions::default()
    };
    let v = glint_io::read_volume(dir.path(), &other).unwrap();
    assert_eq!(v.dims, [3, 2, 1]);
    let none = ReadOptions {
        series: Some("9.9".into()),
        ..ReadOptions::default()
    };
    let err = glint_io::read_volume(dir.path(), &none).unwrap_err();
    assert!(
        err.to_string().contains("no series 9.9") && err.to_string().contains("1.2.3.100"),
        "{err}"
    );
}

fn functional_item(tag: Tag, inner: InMemDicomObject) -> DataElement<InMemDicomObject> {
    DataElement::new(tag, VR::SQ, Value::from(DataSetSequence::from(vec![inner])))
}

#[test]
fn enhanced_multi_frame_with_per_frame_positions_and_12_bit_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let mut o = image(1, 2, "1.2.3.8", 1, false);
    put(&mut o, tags::MODALITY, VR::CS, dicom_value!(Str, "MR"));
    put(&mut o, tags::BITS_STORED, VR::US, dicom_value!(U16, [12]));
    put(&mut o, tags::HIGH_BIT, VR::US, dicom_value!(U16, [11]));
    put(
        &mut o,
        tags::NUMBER_OF_FRAMES,
        VR::IS,
        dicom_value!(Str, "3"),
    );
    o.remove_element(tags::IMAGE_ORIENTATION_PATIENT);
    o.remove_element(tags::PIXEL_SPACING);
    // Shared: orientation and pixel measures.
    let mut shared = InMemDicomObject::new_empty();
    let mut orient = InMemDicomObject::new_empty();
    put(
        &mut orient,
        tags::IMAGE_ORIENTATION_PATIENT,
        VR::DS,
        ds(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
    );
    shared.put(functional_item(tags::PLANE_ORIENTATION_SEQUENCE, orient));
    let mut measures = InMemDicomObject::new_empty();
    put(&mut measures, tags::PIXEL_SPACING, VR::DS, ds(&[2.0, 3.0]));
    shared.put(functional_item(tags::PIXEL_MEASURES_SEQUENCE, measures));
    o.put(DataElement::new(
        tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE,
        VR::SQ,
        Value::from(DataSetSequence::from(vec![shared])),
    ));
    // Frames stored at z = 8, 0, 4.
    let per_frame: Vec<InMemDicomObject> = [8.0, 0.0, 4.0]
        .into_iter()
        .map(|z| {
            let mut pos = InMemDicomObject::new_empty();
            put(
                &mut pos,
                tags::IMAGE_POSITION_PATIENT,
                VR::DS,
                ds(&[0.0, 0.0, z]),
            );
            let mut f = InMemDicomObject::new_empty();
            f.put(functional_item(tags::PLANE_POSITION_SEQUENCE, pos));
            f
        })
        .collect();
    o.put(DataElement::new(
        tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE,
        VR::SQ,
        Value::from(DataSetSequence::from(per_frame)),
    ));
    // 12 stored bits; the high nibble holds garbage (0xF000) that must be masked off.
    let px: Vec<u16> = vec![0xF000 | 800, 801, 0xF000, 1, 0xF000 | 400, 401];
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(px.into()),
    );
    let p = dir.path().join("multi.dcm");
    write(&p, o, EXPLICIT_BE);
    let v = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
    assert_eq!(v.dims, [2, 1, 3]);
    assert_eq!(v.samples, Samples::U16(vec![0, 1, 400, 401, 800, 801]));
    assert_eq!(v.spacing, [3.0, 2.0, 4.0]);
    assert_eq!(v.units, None);
}

#[test]
fn classic_multi_frame_with_slice_spacing_and_signed_8_bit() {
    let dir = tempfile::tempdir().unwrap();
    let mut o = image(1, 2, "1.2.3.9", 1, true);
    put(&mut o, tags::BITS_ALLOCATED, VR::US, dicom_value!(U16, [8]));
    put(&mut o, tags::BITS_STORED, VR::US, dicom_value!(U16, [8]));
    put(&mut o, tags::HIGH_BIT, VR::US, dicom_value!(U16, [7]));
    put(
        &mut o,
        tags::NUMBER_OF_FRAMES,
        VR::IS,
        dicom_value!(Str, "2"),
    );
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, 0.0]),
    );
    put(&mut o, tags::SPACING_BETWEEN_SLICES, VR::DS, ds(&[1.5]));
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OB,
        PrimitiveValue::U8(vec![0xFF, 1, 0x80, 0x7F].into()),
    );
    let p = dir.path().join("classic.dcm");
    write(&p, o, EXPLICIT_LE);
    let v = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
    assert_eq!(v.samples, Samples::I8(vec![-1, 1, -128, 127]));
    assert_eq!(v.spacing, [0.75, 0.5, 1.5]);
}

#[test]
fn not_dicom_truncated_and_short_pixel_data() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("fake.dcm");
    std::fs::write(&p, vec![7u8; 300]).unwrap();
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::BadMagic { .. }) && err.to_string().contains("fake.dcm"),
        "{err}"
    );
    // A whole file cut inside its pixel data.
    ct_series(dir.path(), &[0.0], EXPLICIT_LE);
    let whole = std::fs::read(dir.path().join("slice01.dcm")).unwrap();
    let cut = dir.path().join("cut.dcm");
    std::fs::write(&cut, &whole[..whole.len() - 5]).unwrap();
    let err = glint_io::read_volume(&cut, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Truncated { .. } | IoError::Invalid { .. })
            && err.to_string().contains("cut.dcm"),
        "{err}"
    );
    // Pixel data holding fewer samples than Rows x Columns.
    let mut o = image(4, 4, "1.2.3.10", 1, false);
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, 0.0]),
    );
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(vec![1; 6].into()),
    );
    let short = dir.path().join("short.dcm");
    write(&short, o, EXPLICIT_LE);
    let err = glint_io::read_volume(&short, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
}

#[test]
fn too_many_voxels_refused_before_reading_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let mut o = image(60000, 60000, "1.2.3.11", 1, false);
    put(
        &mut o,
        tags::NUMBER_OF_FRAMES,
        VR::IS,
        dicom_value!(Str, "1000"),
    );
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, 0.0]),
    );
    put(&mut o, tags::SLICE_THICKNESS, VR::DS, ds(&[1.0]));
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(vec![0; 4].into()),
    );
    let p = dir.path().join("huge.dcm");
    write(&p, o, EXPLICIT_LE);
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
    // A 1x1 image claiming 10^12 frames: refused before any per-frame bookkeeping.
    let mut o = image(1, 1, "1.2.3.15", 1, false);
    put(
        &mut o,
        tags::NUMBER_OF_FRAMES,
        VR::IS,
        dicom_value!(Str, "1000000000000"),
    );
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, 0.0]),
    );
    put(&mut o, tags::SLICE_THICKNESS, VR::DS, ds(&[1.0]));
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(vec![0; 2].into()),
    );
    let p = dir.path().join("frames.dcm");
    write(&p, o, EXPLICIT_LE);
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
}

#[test]
fn nan_spacing_and_degenerate_orientation() {
    let dir = tempfile::tempdir().unwrap();
    let mut o = image(2, 2, "1.2.3.12", 1, false);
    put(
        &mut o,
        tags::PIXEL_SPACING,
        VR::DS,
        dicom_value!(Strs, ["NaN", "1"]),
    );
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, 0.0]),
    );
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(vec![0; 4].into()),
    );
    let p = dir.path().join("nan.dcm");
    write(&p, o, EXPLICIT_LE);
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::Geometry { .. }), "{err}");
    // Row and column directions parallel: a singular affine.
    let mut o = image(2, 2, "1.2.3.13", 1, false);
    put(
        &mut o,
        tags::IMAGE_ORIENTATION_PATIENT,
        VR::DS,
        ds(&[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]),
    );
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, 0.0]),
    );
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(vec![0; 4].into()),
    );
    let p = dir.path().join("flat.dcm");
    write(&p, o, EXPLICIT_LE);
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::Geometry { .. }), "{err}");
}

/// A one-slice image whose pixel data is one encapsulated fragment.
fn compressed_slice(rows: u16, cols: u16, z: f64, fragment: Vec<u8>) -> InMemDicomObject {
    let mut o = image(rows, cols, "1.2.3.14", z as u32, false);
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, z]),
    );
    o.put(DataElement::new(
        tags::PIXEL_DATA,
        VR::OB,
        Value::PixelSequence(PixelFragmentSequence::new(vec![], vec![fragment])),
    ));
    o
}

/// RLE Lossless (PS3.5 Annex G) of 16-bit samples, encoded here by hand: a 64-byte
/// header (segment count, segment offsets), then one segment of high bytes and one of
/// low bytes, each a single PackBits literal run (control byte n - 1), padded to an even
/// length with the no-op control byte 0x80.
fn rle16(samples: &[u16]) -> Vec<u8> {
    assert!(samples.len() <= 128);
    let segment = |bytes: Vec<u8>| {
        let mut s = vec![(bytes.len() - 1) as u8];
        s.extend(bytes);
        if s.len() % 2 == 1 {
            s.push(0x80);
        }
        s
    };
    let hi = segment(samples.iter().map(|x| (x >> 8) as u8).collect());
    let lo = segment(samples.iter().map(|x| *x as u8).collect());
    let mut out = vec![0u8; 64];
    out[0..4].copy_from_slice(&2u32.to_le_bytes());
    out[4..8].copy_from_slice(&64u32.to_le_bytes());
    out[8..12].copy_from_slice(&(64 + hi.len() as u32).to_le_bytes());
    out.extend(hi);
    out.extend(lo);
    out
}

/// A series of RLE-compressed slices reads like an uncompressed one.
#[test]
fn rle_compressed_series() {
    let dir = tempfile::tempdir().unwrap();
    let zs = [4.0, 0.0, 2.0];
    for (k, z) in zs.into_iter().enumerate() {
        let px: Vec<u16> = (0..6).map(|p| 1000 * k as u16 + p * 257).collect();
        let o = compressed_slice(2, 3, z, rle16(&px));
        write(
            &dir.path().join(format!("{k}.dcm")),
            o,
            "1.2.840.10008.1.2.5",
        );
    }
    let f = glint_io::open_volume(dir.path(), &ReadOptions::default()).unwrap();
    let v = &f.volume;
    assert_eq!(v.dims, [3, 2, 3]);
    assert_eq!(v.spacing, [0.75, 0.5, 2.0]);
    // Sorted by z: 0 (file 1), 2 (file 2), 4 (file 0).
    for (k, src) in [1u16, 2, 0].into_iter().enumerate() {
        for p in 0..6u16 {
            let (i, j) = (usize::from(p % 3), usize::from(p / 3));
            assert_eq!(
                v.value(i, j, k),
                f64::from(1000 * src + p * 257),
                "{i} {j} {k}"
            );
        }
    }
    assert!(
        f.notes.iter().any(|n| n.contains("RLE Lossless")),
        "{:?}",
        f.notes
    );
}

/// Found by fuzzing: an RLE segment that decodes to fewer bytes than Rows x Columns
/// made dicom-rs index past its buffer (a panic); now refused before decoding.
#[test]
fn short_rle_segment_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("rle.dcm");
    // Four samples for a 2x3 image.
    write(
        &p,
        compressed_slice(2, 3, 0.0, rle16(&[1, 2, 3, 4])),
        "1.2.840.10008.1.2.5",
    );
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        err.to_string()
            .contains("segment 0 decodes to 4 bytes, Rows x Columns is 6"),
        "{err}"
    );
    // A segment offset past the end of the frame.
    let mut frame = rle16(&[1; 6]);
    frame[8..12].copy_from_slice(&9999u32.to_le_bytes());
    write(
        &p,
        compressed_slice(2, 3, 0.0, frame),
        "1.2.840.10008.1.2.5",
    );
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        err.to_string().contains("RLE Lossless: segment 0 spans"),
        "{err}"
    );
}

#[test]
fn undecodable_compressed_data_names_the_transfer_syntax() {
    let dir = tempfile::tempdir().unwrap();
    // An empty JPEG stream (SOI, EOI) under JPEG Baseline.
    let p = dir.path().join("jpeg.dcm");
    write(
        &p,
        compressed_slice(2, 2, 0.0, vec![0xFF, 0xD8, 0xFF, 0xD9]),
        "1.2.840.10008.1.2.4.50",
    );
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Invalid { .. }) && err.to_string().contains("JPEG Baseline"),
        "{err}"
    );
    // JPEG-LS without a frame header: refused before CharLS sees it, by name.
    let p = dir.path().join("jpegls.dcm");
    write(
        &p,
        compressed_slice(2, 2, 0.0, vec![0xFF, 0xD8, 0xFF, 0xD9]),
        "1.2.840.10008.1.2.4.80",
    );
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Invalid { .. })
            && err
                .to_string()
                .contains("JPEG-LS pixel data without a frame header"),
        "{err}"
    );
    // A transfer syntax dicom-rs knows but cannot decode (MPEG2).
    let p = dir.path().join("mpeg.dcm");
    write(
        &p,
        compressed_slice(2, 2, 0.0, vec![0; 4]),
        "1.2.840.10008.1.2.4.100",
    );
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Unsupported { .. })
            && err.to_string().contains("1.2.840.10008.1.2.4.100"),
        "{err}"
    );
}

/// A JPEG 2000 codestream declaring more samples than Rows x Columns is refused before
/// the decoder allocates for it (and before dicom-rs copies it into a 2x2 buffer).
#[test]
fn jpeg2000_codestream_larger_than_the_image_is_refused() {
    // SOC, SIZ: Lsiz 41, Rsiz 0, Xsiz = Ysiz = 60000, offsets 0, tiles 60000, 1 component
    // (ISO 15444-1 A.5.1), then the component's Ssiz, XRsiz, YRsiz.
    let mut cs = vec![0xFF, 0x4F, 0xFF, 0x51, 0x00, 41, 0x00, 0x00];
    for v in [60000u32, 60000, 0, 0, 60000, 60000, 0, 0] {
        cs.extend(v.to_be_bytes());
    }
    cs.extend([0x00, 0x01, 0x0F, 0x01, 0x01, 0xFF, 0xD9]);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("j2k.dcm");
    write(
        &p,
        compressed_slice(2, 2, 0.0, cs),
        "1.2.840.10008.1.2.4.90",
    );
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        err.to_string().contains(
            "declares 60000 x 60000 x 1 samples, more than Rows x Columns x SamplesPerPixel = 4"
        ),
        "{err}"
    );
}

/// Issue 17: a 184-byte file whose element has the unknown VR "XX" and a length of
/// 0xF0000000 made dicom-rs allocate and fill 3.9 GB (it reads unknown VRs as UN, with
/// a 32-bit length). Built here byte by byte (PS3.10 7.1, PS3.5 7.1.2), with `first`
/// before the bad element.
fn unknown_vr_file(first: &[u8]) -> Vec<u8> {
    let mut b = vec![0u8; 128];
    b.extend(b"DICM");
    let ts = b"1.2.840.10008.1.2.1\0";
    // (0002,0000) UL 4: the length of the rest of the meta group.
    b.extend([0x02, 0x00, 0x00, 0x00, b'U', b'L', 4, 0]);
    b.extend((8 + ts.len() as u32).to_le_bytes());
    // (0002,0010) UI: explicit VR little endian.
    b.extend([0x02, 0x00, 0x10, 0x00, b'U', b'I', ts.len() as u8, 0]);
    b.extend(ts);
    b.extend(first);
    // (0010,0010) "XX", two reserved bytes, length 0xF0000000.
    b.extend([0x10, 0x00, 0x10, 0x00, b'X', b'X', 0, 0]);
    b.extend(0xF000_0000u32.to_le_bytes());
    b
}

#[test]
fn unknown_vr_with_a_huge_length_is_refused_before_parsing() {
    let dir = tempfile::tempdir().unwrap();
    // As the issue found it: the bad element first in the data set, which (no valid VR
    // after the first tag) is then read as implicit VR, as pydicom does: the "XX" bytes
    // become the length.
    let bytes = unknown_vr_file(&[]);
    assert_eq!(bytes.len(), 184);
    let p = dir.path().join("xx.dcm");
    std::fs::write(&p, &bytes).unwrap();
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Truncated { .. })
            && err.to_string().contains("(0010,0010) declares 22616 bytes"),
        "{err}"
    );
    // After a valid element, (0008,0060) CS "CT": "XX" is read as UN, as dicom-rs does.
    let bytes = unknown_vr_file(&[0x08, 0x00, 0x60, 0x00, b'C', b'S', 2, 0, b'C', b'T']);
    std::fs::write(&p, &bytes).unwrap();
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Truncated { .. })
            && err
                .to_string()
                .contains("(0010,0010) declares 4026531840 bytes, only 0"),
        "{err}"
    );
}

/// Issue 17: 10,000 nested undefined-length sequences (160 kB in implicit VR: each level
/// a sequence header and an item header of 8 bytes) overflowed the stack in dicom-rs's
/// recursive parser. Refused by the nesting bound before parsing; the test runs on the
/// test harness's 2 MB thread stack, so any recursion per level would still overflow.
#[test]
fn deeply_nested_sequences_are_refused_before_parsing() {
    let mut b = vec![0u8; 128];
    b.extend(b"DICM");
    let ts = b"1.2.840.10008.1.2\0";
    b.extend([0x02, 0x00, 0x00, 0x00, b'U', b'L', 4, 0]);
    b.extend((8 + ts.len() as u32).to_le_bytes());
    b.extend([0x02, 0x00, 0x10, 0x00, b'U', b'I', ts.len() as u8, 0]);
    b.extend(ts);
    for _ in 0..10_000 {
        // (0008,1115) ReferencedSeriesSequence, undefined length; an undefined-length item.
        b.extend([0x08, 0x00, 0x15, 0x11, 0xFF, 0xFF, 0xFF, 0xFF]);
        b.extend([0xFE, 0xFF, 0x00, 0xE0, 0xFF, 0xFF, 0xFF, 0xFF]);
    }
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("nested.dcm");
    std::fs::write(&p, &b).unwrap();
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Invalid { .. })
            && err.to_string().contains(&format!(
                "nested more than {} levels",
                glint_io::dicom::MAX_NESTING
            )),
        "{err}"
    );
    // Ten levels (20 with items) inside a real image are fine.
    let mut inner = InMemDicomObject::new_empty();
    for _ in 0..10 {
        let mut item = InMemDicomObject::new_empty();
        item.put(DataElement::new(
            tags::REFERENCED_SERIES_SEQUENCE,
            VR::SQ,
            Value::from(DataSetSequence::from(vec![inner])),
        ));
        inner = item;
    }
    let mut o = slice_with(2, 2, "1.2.3.40", vec![3; 4]);
    o.put(DataElement::new(
        tags::REFERENCED_SERIES_SEQUENCE,
        VR::SQ,
        Value::from(DataSetSequence::from(vec![inner])),
    ));
    let p = dir.path().join("ten.dcm");
    write(&p, o, IMPLICIT_LE);
    let v = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
    assert_eq!(v.samples, Samples::U16(vec![3; 4]));
}

/// Whatever bytes an error quotes (here a transfer syntax UID with a newline and a
/// carriage return), the message is one line.
#[test]
fn error_messages_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("ts.dcm");
    write(&p, slice_with(2, 2, "1.2.3.41", vec![0; 4]), EXPLICIT_LE);
    let mut bytes = std::fs::read(&p).unwrap();
    let at = find_bytes(&bytes, EXPLICIT_LE.as_bytes());
    bytes[at + 5] = b'\n';
    bytes[at + 9] = b'\r';
    std::fs::write(&p, &bytes).unwrap();
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    let msg = err.to_string();
    assert!(
        matches!(err, IoError::Unsupported { .. })
            && !msg.contains('\n')
            && !msg.contains('\r')
            && msg.contains("unknown transfer syntax 1.2.8\\n0.1\\r008"),
        "{msg:?}"
    );
}

/// Lenient like pydicom's force=True, GDCM and DCMTK: no preamble, no meta group, and
/// a multi-frame file without positions are read with a note; --strict refuses them.
#[test]
fn lenient_reading_and_strict_refusal() {
    let dir = tempfile::tempdir().unwrap();
    let strict = ReadOptions {
        strict: true,
        ..ReadOptions::default()
    };
    let p = dir.path().join("full.dcm");
    write(
        &p,
        slice_with(2, 2, "1.2.3.42", vec![1, 2, 3, 4]),
        EXPLICIT_LE,
    );
    let full = std::fs::read(&p).unwrap();
    // The meta group's length is the value of (0002,0000) at bytes 140..144.
    let meta_end = 144 + u32::from_le_bytes(full[140..144].try_into().unwrap()) as usize;
    for (name, bytes, note) in [
        ("nopre.dcm", full[128..].to_vec(), "no 128-byte preamble"),
        (
            "nometa.dcm",
            full[meta_end..].to_vec(),
            "no file meta group",
        ),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        let f = glint_io::open_volume(&p, &ReadOptions::default()).unwrap();
        assert_eq!(f.volume.samples, Samples::U16(vec![1, 2, 3, 4]), "{name}");
        assert!(
            f.notes.iter().any(|n| n.contains(note)),
            "{name}: {:?}",
            f.notes
        );
        let err = glint_io::read_volume(&p, &strict).unwrap_err();
        assert!(matches!(err, IoError::BadMagic { .. }), "{name}: {err}");
    }
    // Three frames, no position at all, SpacingBetweenSlices 2.5.
    let mut o = image(1, 2, "1.2.3.43", 1, false);
    put(
        &mut o,
        tags::NUMBER_OF_FRAMES,
        VR::IS,
        dicom_value!(Str, "3"),
    );
    put(&mut o, tags::SPACING_BETWEEN_SLICES, VR::DS, ds(&[2.5]));
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(vec![1, 2, 3, 4, 5, 6].into()),
    );
    let p = dir.path().join("frames.dcm");
    write(&p, o, EXPLICIT_LE);
    let f = glint_io::open_volume(&p, &ReadOptions::default()).unwrap();
    assert_eq!(f.volume.dims, [2, 1, 3]);
    assert_eq!(f.volume.spacing, [0.75, 0.5, 2.5]);
    // Frame order kept.
    assert_eq!(f.volume.samples, Samples::U16(vec![1, 2, 3, 4, 5, 6]));
    assert!(
        f.notes
            .iter()
            .any(|n| n.starts_with("geometry assumed:") && n.contains("SpacingBetweenSlices")),
        "{:?}",
        f.notes
    );
    let err = glint_io::read_volume(&p, &strict).unwrap_err();
    assert!(
        matches!(err, IoError::Geometry { .. }) && err.to_string().contains("--strict"),
        "{err}"
    );
}

/// A one-slice 16-bit image at the origin with `px` as its pixel data.
fn slice_with(rows: u16, cols: u16, series: &str, px: Vec<u16>) -> InMemDicomObject {
    let mut o = image(rows, cols, series, 1, false);
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, 0.0]),
    );
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(px.into()),
    );
    o
}

/// Review defect 1: a 1x1 image announcing 2^31 - 1 frames (within the voxel limit)
/// used to size per-frame vectors (64 GB) before the file-size check and abort the
/// process; it must be refused from the header, since the file cannot hold those pixels.
#[test]
fn frame_count_beyond_the_file_size_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    for with_position in [true, false] {
        let mut o = slice_with(1, 1, "1.2.3.20", vec![0]);
        if !with_position {
            o.remove_element(tags::IMAGE_POSITION_PATIENT);
        }
        put(
            &mut o,
            tags::NUMBER_OF_FRAMES,
            VR::IS,
            dicom_value!(Str, "2147483647"),
        );
        put(&mut o, tags::SLICE_THICKNESS, VR::DS, ds(&[1.0]));
        let p = dir.path().join(format!("frames{with_position}.dcm"));
        write(&p, o, EXPLICIT_LE);
        let opts = ReadOptions {
            max_voxels: u64::MAX,
            ..ReadOptions::default()
        };
        let err = glint_io::read_volume(&p, &opts).unwrap_err();
        assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
    }
}

/// Offset of the first occurrence of `needle` in `hay`.
fn find_bytes(hay: &[u8], needle: &[u8]) -> usize {
    hay.windows(needle.len())
        .position(|w| w == needle)
        .expect("pattern in the file")
}

/// Review defect 2: dicom-rs allocates an element's declared length before reading it,
/// so a few hundred bytes declaring a 4 GB PixelData (or private OB element) cost 4 GB
/// of memory. The declared lengths are now checked against the file size first: the
/// error names the element and its declared length.
#[test]
fn element_lengths_beyond_the_file_are_refused_before_parsing() {
    let dir = tempfile::tempdir().unwrap();
    for ts in [EXPLICIT_LE, IMPLICIT_LE, EXPLICIT_BE] {
        let p = dir.path().join("pix.dcm");
        write(&p, slice_with(2, 2, "1.2.3.21", vec![1; 4]), ts);
        let mut bytes = std::fs::read(&p).unwrap();
        // The length field of PixelData (7FE0,0010): after the tag, plus VR and two
        // reserved bytes in explicit VR.
        let (tag, len_at, huge): (&[u8], usize, [u8; 4]) = match ts {
            EXPLICIT_LE => (&[0xE0, 0x7F, 0x10, 0x00], 8, 0xFFFF_FFF0u32.to_le_bytes()),
            IMPLICIT_LE => (&[0xE0, 0x7F, 0x10, 0x00], 4, 0xFFFF_FFF0u32.to_le_bytes()),
            _ => (&[0x7F, 0xE0, 0x00, 0x10], 8, 0xFFFF_FFF0u32.to_be_bytes()),
        };
        let at = find_bytes(&bytes, tag) + len_at;
        bytes[at..at + 4].copy_from_slice(&huge);
        std::fs::write(&p, &bytes).unwrap();
        let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
        let msg = err.to_string();
        assert!(
            matches!(err, IoError::Truncated { .. }) && msg.contains("declares 4294967280 bytes"),
            "{ts}: {msg}"
        );
    }
    // A private OB element before the pixel data.
    let mut o = slice_with(2, 2, "1.2.3.22", vec![1; 4]);
    put(
        &mut o,
        Tag(0x0029, 0x0010),
        VR::LO,
        dicom_value!(Str, "GLINT"),
    );
    put(
        &mut o,
        Tag(0x0029, 0x1010),
        VR::OB,
        PrimitiveValue::U8(vec![0xAB; 4].into()),
    );
    let p = dir.path().join("private.dcm");
    write(&p, o, EXPLICIT_LE);
    let mut bytes = std::fs::read(&p).unwrap();
    let at = find_bytes(&bytes, &[0x29, 0x00, 0x10, 0x10, b'O', b'B']) + 8;
    bytes[at..at + 4].copy_from_slice(&0xFFFF_FF00u32.to_le_bytes());
    std::fs::write(&p, &bytes).unwrap();
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        err.to_string()
            .contains("(0029,1010) declares 4294967040 bytes"),
        "{err}"
    );
    // The walk accepts the same files unpatched, in every transfer syntax.
    for ts in [EXPLICIT_LE, IMPLICIT_LE, EXPLICIT_BE] {
        let p = dir.path().join("fine.dcm");
        write(&p, slice_with(2, 2, "1.2.3.23", vec![7; 4]), ts);
        let v = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
        assert_eq!(v.samples, Samples::U16(vec![7; 4]), "{ts}");
    }
}

/// Review defect 6: direction cosines that are not unit length (2\0\0\0\2\0) used to
/// scale the spacing silently; zero vectors and non-orthogonal ones are errors too, while
/// rounding in the sixth decimal is accepted.
#[test]
fn orientation_must_be_orthonormal() {
    let dir = tempfile::tempdir().unwrap();
    for (k, iop) in [
        [2.0, 0.0, 0.0, 0.0, 2.0, 0.0],
        [0.0; 6],
        [1.0, 0.0, 0.0, 0.6, 0.8, 0.0],
    ]
    .into_iter()
    .enumerate()
    {
        let mut o = slice_with(2, 2, "1.2.3.24", vec![0; 4]);
        put(&mut o, tags::IMAGE_ORIENTATION_PATIENT, VR::DS, ds(&iop));
        let p = dir.path().join(format!("iop{k}.dcm"));
        write(&p, o, EXPLICIT_LE);
        let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
        assert!(
            matches!(err, IoError::Geometry { .. })
                && err.to_string().contains("ImageOrientationPatient"),
            "{iop:?}: {err}"
        );
    }
    let mut o = slice_with(2, 2, "1.2.3.25", vec![0; 4]);
    put(
        &mut o,
        tags::IMAGE_ORIENTATION_PATIENT,
        VR::DS,
        ds(&[1.000001, 0.0, 0.0, 0.0, 0.999999, 0.0]),
    );
    let p = dir.path().join("rounded.dcm");
    write(&p, o, EXPLICIT_LE);
    let v = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
    // PixelSpacing (0.5 row, 0.75 column), one slice of 1 mm assumed; unit directions.
    for (got, want) in v.spacing.iter().zip([0.75, 0.5, 1.0]) {
        assert!((got - want).abs() < 1e-12, "{:?}", v.spacing);
    }
}

/// Review defect 7: slices whose PixelSpacing differs are not one volume.
#[test]
fn pixel_spacing_must_agree_across_slices() {
    let dir = tempfile::tempdir().unwrap();
    for (k, sp) in [[0.5, 0.75], [0.5, 0.8]].into_iter().enumerate() {
        let mut o = slice_with(2, 2, "1.2.3.26", vec![0; 4]);
        put(&mut o, tags::PIXEL_SPACING, VR::DS, ds(&sp));
        put(
            &mut o,
            tags::IMAGE_POSITION_PATIENT,
            VR::DS,
            ds(&[0.0, 0.0, k as f64]),
        );
        write(&dir.path().join(format!("{k}.dcm")), o, EXPLICIT_LE);
    }
    let err = glint_io::read_volume(dir.path(), &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::MixedSeries { .. }) && err.to_string().contains("PixelSpacing"),
        "{err}"
    );
}

/// A radiotherapy export: 16 CT slices beside pydicom's RT structure set, plan and a
/// one-frame dose grid, and a README. The CT series is read, with notes naming what was
/// skipped; `dicom::list` names every series and object; the dose grid is read when
/// asked for, scaled by its DoseGridScaling.
#[test]
fn an_export_directory_reads_its_image_series_and_lists_the_rest() {
    let (Some(rtstruct), Some(rtplan), Some(rtdose)) = (
        common::sample("pydicom/rtstruct.dcm"),
        common::sample("pydicom/rtplan.dcm"),
        common::sample("pydicom/rtdose_1frame.dcm"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let zs: Vec<f64> = (0..16).map(|k| 2.5 * k as f64).collect();
    ct_series(dir.path(), &zs, EXPLICIT_LE);
    for p in [&rtstruct, &rtplan, &rtdose] {
        std::fs::copy(p, dir.path().join(p.file_name().unwrap())).unwrap();
    }
    std::fs::write(dir.path().join("README.txt"), "export notes").unwrap();

    let f = glint_io::open_volume(dir.path(), &ReadOptions::default()).unwrap();
    assert_eq!(f.volume.dims, [3, 2, 16]);
    let notes = f.notes.join("\n");
    assert!(
        notes.contains("skipped 2 object(s): rtplan.dcm (not an image: RT Plan Storage); rtstruct.dcm (not an image: RT Structure Set Storage)"),
        "{notes}"
    );
    assert!(
        notes.contains("2 image series here: read 1.2.3.99"),
        "{notes}"
    );
    assert!(notes.contains("RTDOSE"), "{notes}");
    assert!(notes.contains("skipped 1 non-DICOM file(s)"), "{notes}");

    let listing = glint_io::dicom::list(dir.path(), &ReadOptions::default()).unwrap();
    assert_eq!(listing.series.len(), 2);
    assert_eq!(
        (listing.series[0].uid.as_str(), listing.series[0].slices),
        ("1.2.3.99", 16)
    );
    let dose = &listing.series[1];
    assert_eq!(dose.modality.as_deref(), Some("RTDOSE"));
    let names: Vec<String> = listing
        .skipped
        .iter()
        .map(|s| {
            format!(
                "{} {}",
                s.path.file_name().unwrap().to_string_lossy(),
                s.reason
            )
        })
        .collect();
    assert_eq!(names.len(), 3, "{names:?}");
    assert!(
        names[0].starts_with("README.txt not a DICOM file"),
        "{names:?}"
    );
    assert!(names[1].starts_with("rtplan.dcm no PixelData"), "{names:?}");
    assert_eq!(
        listing.skipped[2].class.as_deref(),
        Some("RT Structure Set Storage")
    );

    // The dose grid, by its series UID: stored values times DoseGridScaling, in its
    // DoseUnits (RELATIVE in pydicom's file).
    let obj = dicom_object::open_file(&rtdose).unwrap();
    let scaling = obj
        .element(tags::DOSE_GRID_SCALING)
        .unwrap()
        .to_float64()
        .unwrap();
    let units = obj.element(tags::DOSE_UNITS).unwrap().to_str().unwrap();
    let o = ReadOptions {
        series: Some(dose.uid.clone()),
        ..ReadOptions::default()
    };
    let v = glint_io::read_volume(dir.path(), &o).unwrap();
    assert_eq!(v.dims, [10, 10, 1]);
    assert_eq!(v.slope, scaling);
    assert_eq!(v.units.as_deref(), Some(units.trim()));
}

/// A slice of the chosen series that cannot be read is an error, not a skip.
#[test]
fn a_broken_slice_of_the_read_series_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    ct_series(dir.path(), &[0.0, 2.0, 4.0], EXPLICIT_LE);
    let p = dir.path().join("slice02.dcm");
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() - 4]).unwrap();
    let e = glint_io::read_volume(dir.path(), &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("slice02.dcm"), "{e}");
}

/// Colour photometric interpretations glint does not convert are refused by name.
#[test]
fn unsupported_colour_models_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let mut o = image(2, 2, "1.2.3.7", 1, false);
    put(
        &mut o,
        tags::SAMPLES_PER_PIXEL,
        VR::US,
        dicom_value!(U16, [3]),
    );
    put(
        &mut o,
        tags::PHOTOMETRIC_INTERPRETATION,
        VR::CS,
        dicom_value!(Str, "YBR_PARTIAL_420"),
    );
    put(&mut o, tags::BITS_ALLOCATED, VR::US, dicom_value!(U16, [8]));
    put(&mut o, tags::BITS_STORED, VR::US, dicom_value!(U16, [8]));
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OB,
        PrimitiveValue::U8(vec![0; 12].into()),
    );
    let p = dir.path().join("partial.dcm");
    write(&p, o, EXPLICIT_LE);
    let e = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(e, IoError::Unsupported { .. }) && e.to_string().contains("YBR_PARTIAL_420"),
        "{e}"
    );
}

/// A JPEG-LS frame header declaring more samples than Rows x Columns is refused before
/// CharLS allocates for it.
#[test]
fn jpeg_ls_frame_larger_than_the_image_is_refused() {
    // SOI, SOF55: Lf 11, P 8, Y 60000, X 60000, Nf 1, component 1 (1x1, Tq 0), EOI.
    let mut cs = vec![0xFF, 0xD8, 0xFF, 0xF7, 0x00, 0x0B, 0x08];
    cs.extend(60000u16.to_be_bytes());
    cs.extend(60000u16.to_be_bytes());
    cs.extend([0x01, 0x01, 0x11, 0x00, 0xFF, 0xD9]);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("jls.dcm");
    write(
        &p,
        compressed_slice(2, 2, 0.0, cs),
        "1.2.840.10008.1.2.4.80",
    );
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        err.to_string()
            .contains("JPEG-LS codestream declares 60000 x 60000 x 1 samples"),
        "{err}"
    );
}

/// Found by fuzzing (2026-11-25, `fuzz/artifacts/dicom/oom-db40bb26...`): an item tag
/// with a defined length inside an item. dicom-rs reads it as an element and skips its
/// 13 bytes; the walk took it for a nested item, so the two parted ways and dicom-rs
/// then allocated 4 GB for an element length the walk never saw. The walk now follows
/// dicom-parser's state machine and refuses the length before dicom-rs parses the file.
#[test]
fn fuzz_crash_an_item_tag_inside_an_item_is_walked_as_dicom_rs_reads_it() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/dicom-oom-db40bb26.dcm");
    let e = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(e, IoError::Truncated { .. })
            && e.to_string()
                .contains("element (0051,FF00) declares 4292870399 bytes, only 33852 are left"),
        "{e}"
    );
}

/// Found by fuzzing (2026-11-25, `oom-90e8df68...`): a bare data set with a 38-byte UL
/// value. dicom-rs reads 9 whole values (36 bytes) and the next header 2 bytes early,
/// where it found a length of 0xFFFF0000 and allocated 4 GB; the walk skipped all 38
/// bytes and never saw it. The walk now consumes what dicom-rs consumes.
#[test]
fn fuzz_crash_a_binary_value_of_odd_length_is_walked_as_dicom_rs_reads_it() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/dicom-oom-90e8df68.dcm");
    let e = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(e, IoError::Truncated { .. })
            && e.to_string()
                .contains("element (0000,0000) declares 4294901760 bytes, only 46 are left"),
        "{e}"
    );
}
