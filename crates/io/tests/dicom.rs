//! DICOM: series directories and multi-frame files written with dicom-object in every
//! uncompressed transfer syntax, and the bad-input cases.

use std::path::Path;

use dicom_core::value::{DataSetSequence, PixelFragmentSequence, PrimitiveValue, Value};
use dicom_core::{dicom_value, DataElement, Tag, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
use glint_io::{IoError, ReadOptions, Samples};

const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
const IMPLICIT_LE: &str = "1.2.840.10008.1.2";
const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";
const CT_STORAGE: &str = "1.2.840.10008.5.1.4.1.1.2";

fn ds(v: &[f64]) -> PrimitiveValue {
    PrimitiveValue::Strs(v.iter().map(|x| format!("{x}")).collect())
}

fn put(obj: &mut InMemDicomObject, tag: Tag, vr: VR, v: PrimitiveValue) {
    obj.put(DataElement::new(tag, vr, v));
}

/// A grayscale image header: `cols` x `rows`, 16-bit, with pixel spacing (row, column).
fn image(rows: u16, cols: u16, series: &str, instance: u32, signed: bool) -> InMemDicomObject {
    let mut o = InMemDicomObject::new_empty();
    put(
        &mut o,
        tags::SOP_CLASS_UID,
        VR::UI,
        dicom_value!(Str, CT_STORAGE),
    );
    put(
        &mut o,
        tags::SOP_INSTANCE_UID,
        VR::UI,
        PrimitiveValue::from(format!("1.2.3.4.{instance}")),
    );
    put(
        &mut o,
        tags::SERIES_INSTANCE_UID,
        VR::UI,
        PrimitiveValue::from(series.to_string()),
    );
    put(&mut o, tags::MODALITY, VR::CS, dicom_value!(Str, "CT"));
    put(&mut o, tags::ROWS, VR::US, dicom_value!(U16, [rows]));
    put(&mut o, tags::COLUMNS, VR::US, dicom_value!(U16, [cols]));
    put(
        &mut o,
        tags::SAMPLES_PER_PIXEL,
        VR::US,
        dicom_value!(U16, [1]),
    );
    put(
        &mut o,
        tags::PHOTOMETRIC_INTERPRETATION,
        VR::CS,
        dicom_value!(Str, "MONOCHROME2"),
    );
    put(
        &mut o,
        tags::BITS_ALLOCATED,
        VR::US,
        dicom_value!(U16, [16]),
    );
    put(&mut o, tags::BITS_STORED, VR::US, dicom_value!(U16, [16]));
    put(&mut o, tags::HIGH_BIT, VR::US, dicom_value!(U16, [15]));
    put(
        &mut o,
        tags::PIXEL_REPRESENTATION,
        VR::US,
        dicom_value!(U16, [u16::from(signed)]),
    );
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
    let meta = FileMetaTableBuilder::new()
        .transfer_syntax(ts)
        .media_storage_sop_class_uid(CT_STORAGE);
    obj.with_meta(meta).unwrap().write_to_file(path).unwrap();
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

#[test]
fn mixed_series_are_errors() {
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
    let err = glint_io::read_volume(dir.path(), &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::MixedSeries { .. }), "{err}");
    assert!(err.to_string().contains("1.2.3.100"), "{err}");
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

#[test]
fn compressed_pixel_data_is_unsupported() {
    let dir = tempfile::tempdir().unwrap();
    let mut o = image(2, 2, "1.2.3.14", 1, false);
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, 0.0]),
    );
    o.put(DataElement::new(
        tags::PIXEL_DATA,
        VR::OB,
        Value::PixelSequence(PixelFragmentSequence::new(
            vec![],
            vec![vec![0xFF, 0xD8, 0xFF, 0xD9]],
        )),
    ));
    let p = dir.path().join("jpeg.dcm");
    write(&p, o, "1.2.840.10008.1.2.4.50");
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::Unsupported { .. }), "{err}");
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
