//! NRRD: round trips (attached and detached, raw and gzip, both byte orders), hand-written
//! headers, and bad input.

mod common;

use common::{assert_affine_eq, gzip};
use glint_io::nrrd::{self, Encoding};
use glint_io::{Endian, IoError, ReadOptions, Samples, Volume};

fn sample_volume(samples: Samples) -> Volume {
    let mut vol = Volume::new([4, 3, 2], [1.0; 3], samples).unwrap();
    vol.affine = [
        [0.0, 0.0, -2.0, 10.5],
        [0.75, 0.0, 0.0, -3.0],
        [0.0, 1.25, 0.0, 7.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    vol.spacing = [0.75, 1.25, 2.0];
    vol
}

fn all_types() -> Vec<Samples> {
    let n = 24;
    vec![
        Samples::U8((0..n).map(|i| (i * 10) as u8).collect()),
        Samples::I8((0..n).map(|i| (i as i8) * 5 - 60).collect()),
        Samples::U16((0..n).map(|i| (i as u16) * 2700).collect()),
        Samples::I16((0..n).map(|i| (i as i16) * 1400 - 16000).collect()),
        Samples::U32((0..n).map(|i| (i as u32) * 150_000_000).collect()),
        Samples::I32((0..n).map(|i| i * 90_000_000 - 1_000_000_000).collect()),
        Samples::F32((0..n).map(|i| i as f32 * 0.37 - 3.0).collect()),
        Samples::F64((0..n).map(|i| i as f64 * -1e-3 + 1e10).collect()),
    ]
}

#[test]
fn round_trip_attached_and_detached() {
    let dir = tempfile::tempdir().unwrap();
    for samples in all_types() {
        for enc in [Encoding::Raw, Encoding::Gzip] {
            for endian in [Endian::Little, Endian::Big] {
                let vol = sample_volume(samples.clone());
                let stem = format!("{}-{enc:?}-{endian:?}", samples.type_name());
                let attached = dir.path().join(format!("{stem}.nrrd"));
                nrrd::write(&attached, &vol, enc, endian).unwrap();
                let detached = dir.path().join(format!("{stem}.nhdr"));
                nrrd::write_detached(&detached, &vol, enc, endian).unwrap();
                for p in [attached, detached] {
                    let back = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
                    assert_eq!(back.samples, vol.samples, "{p:?}");
                    assert_eq!(back.dims, vol.dims);
                    assert_affine_eq(&back.affine, &vol.affine, 0.0);
                    assert_eq!(back.spacing, [0.75, 1.25, 2.0]);
                }
            }
        }
    }
}

fn write(dir: &tempfile::TempDir, name: &str, bytes: impl AsRef<[u8]>) -> std::path::PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn lps_space_is_converted_to_ras() {
    // A Slicer-style LPS header: x and y of directions and origin change sign.
    let dir = tempfile::tempdir().unwrap();
    let mut bytes =
        b"NRRD0005\n# comment\ntype: short\ndimension: 3\nspace: left-posterior-superior\n\
        sizes: 2 2 1\nspace directions: (0.5,0,0) (0,0.5,0) (0,0,3)\nkinds: domain domain domain\n\
        endian: big\nencoding: raw\nspace origin: (-10,20,30)\nkey:=value\n\n"
            .to_vec();
    for v in [1i16, -2, 300, -400] {
        bytes.extend_from_slice(&v.to_be_bytes());
    }
    let vol =
        glint_io::read_volume(&write(&dir, "lps.nrrd", bytes), &ReadOptions::default()).unwrap();
    assert_eq!(vol.samples, Samples::I16(vec![1, -2, 300, -400]));
    assert_affine_eq(
        &vol.affine,
        &[
            [-0.5, 0.0, 0.0, 10.0],
            [0.0, -0.5, 0.0, -20.0],
            [0.0, 0.0, 3.0, 30.0],
            [0.0, 0.0, 0.0, 1.0],
        ],
        0.0,
    );
    assert_eq!(vol.spacing, [0.5, 0.5, 3.0]);
}

#[test]
fn text_encoding_spacings_and_skips() {
    let dir = tempfile::tempdir().unwrap();
    let text =
        "NRRD0004\ntype: float\ndimension: 3\nsizes: 3 1 2\nspacings: 0.5 2 4\nencoding: text\n\n\
                1.5 -2 3\n4e2, 5 6.25\n";
    let vol = glint_io::read_volume(&write(&dir, "t.nrrd", text), &ReadOptions::default()).unwrap();
    assert_eq!(
        vol.samples,
        Samples::F32(vec![1.5, -2.0, 3.0, 400.0, 5.0, 6.25])
    );
    assert_eq!(vol.spacing, [0.5, 2.0, 4.0]);
    // Detached header with line skip and byte skip -1 (data at the end of the file).
    let mut data = b"junk line 1\njunk line 2\nmore junk".to_vec();
    data.extend([9u8, 8, 7, 6]);
    write(&dir, "d.bin", data);
    let h = "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 2 2\nencoding: raw\nline skip: 2\n\
             byte skip: -1\ndata file: d.bin\n";
    let vol = glint_io::read_volume(&write(&dir, "d.nhdr", h), &ReadOptions::default()).unwrap();
    assert_eq!(vol.dims, [2, 2, 1]);
    assert_eq!(vol.samples, Samples::U8(vec![9, 8, 7, 6]));
    // Gzip with a byte skip after decompression.
    let mut payload = vec![0xAAu8; 5];
    payload.extend([1u8, 2, 3, 4]);
    let mut bytes =
        b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 1\nencoding: gzip\nbyte skip: 5\n\n"
            .to_vec();
    bytes.extend(gzip(&payload));
    let vol =
        glint_io::read_volume(&write(&dir, "g.nrrd", bytes), &ReadOptions::default()).unwrap();
    assert_eq!(vol.samples, Samples::U8(vec![1, 2, 3, 4]));
}

fn expect_err(bytes: impl AsRef<[u8]>, name: &str, options: &ReadOptions) -> IoError {
    let dir = tempfile::tempdir().unwrap();
    let p = write(&dir, name, bytes);
    let err = glint_io::read_volume(&p, options).unwrap_err();
    assert!(
        err.to_string().contains(name),
        "error does not name the file: {err}"
    );
    err
}

const HEAD: &str =
    "NRRD0004\ntype: short\ndimension: 3\nsizes: 4 4 4\nendian: little\nencoding: raw\n";

#[test]
fn wrong_magic() {
    let err = expect_err(
        "NRRX0004\ntype: short\n\n",
        "m.nrrd",
        &ReadOptions::default(),
    );
    assert!(matches!(err, IoError::BadMagic { .. }), "{err}");
    let err = expect_err(
        [0x89u8, b'P', b'N', b'G', 0, 0],
        "png.nrrd",
        &ReadOptions::default(),
    );
    assert!(matches!(err, IoError::BadMagic { .. }), "{err}");
}

#[test]
fn missing_field_and_malformed_line() {
    let err = expect_err(
        "NRRD0004\ntype: short\ndimension: 3\nencoding: raw\n\n",
        "nosizes.nrrd",
        &ReadOptions::default(),
    );
    assert!(
        matches!(err, IoError::Invalid { .. }) && err.to_string().contains("sizes"),
        "{err}"
    );
    let err = expect_err(
        "NRRD0004\nthis is not a field\n\n",
        "bad.nrrd",
        &ReadOptions::default(),
    );
    assert!(matches!(err, IoError::Invalid { .. }), "{err}");
}

#[test]
fn header_data_size_mismatch_and_truncation() {
    let mut bytes = format!("{HEAD}\n").into_bytes();
    bytes.extend([0u8; 100]); // 128 announced
    let err = expect_err(&bytes, "short.nrrd", &ReadOptions::default());
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
    let mut bytes = HEAD.replace("raw", "gzip").into_bytes();
    bytes.push(b'\n');
    bytes.extend(gzip(&[0u8; 100]));
    let err = expect_err(&bytes, "short.nrrd", &ReadOptions::default());
    assert!(matches!(err, IoError::Truncated { .. }), "{err}");
    let text = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: text\n\n1 2 3\n";
    let err = expect_err(text, "text.nrrd", &ReadOptions::default());
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
    // No blank line and no data file: the header is all there is.
    let err = expect_err(HEAD, "nodata.nrrd", &ReadOptions::default());
    assert!(matches!(err, IoError::Truncated { .. }), "{err}");
}

#[test]
fn unsupported_types_encodings_and_dimensions() {
    for (from, to) in [
        ("short", "int64"),
        ("short", "block"),
        ("raw", "bzip2"),
        ("dimension: 3\nsizes: 4 4 4", "dimension: 4\nsizes: 4 4 4 4"),
    ] {
        let mut bytes = format!("{}\n", HEAD.replace(from, to)).into_bytes();
        bytes.extend([0u8; 1024]);
        let err = expect_err(&bytes, "unsup.nrrd", &ReadOptions::default());
        assert!(matches!(err, IoError::Unsupported { .. }), "{to}: {err}");
    }
}

#[test]
fn too_many_voxels_and_overflow() {
    let h = HEAD.replace("sizes: 4 4 4", "sizes: 100000 100000 100000");
    let err = expect_err(format!("{h}\n"), "huge.nrrd", &ReadOptions::default());
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
    let h = HEAD.replace("sizes: 4 4 4", "sizes: 18446744073709551615 4 4");
    let err = expect_err(format!("{h}\n"), "overflow.nrrd", &ReadOptions::default());
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
}

#[test]
fn nan_spacing_and_singular_directions() {
    let h = format!("{HEAD}spacings: 1 nan 1\n\n");
    let mut bytes = h.into_bytes();
    bytes.extend([0u8; 128]);
    let err = expect_err(&bytes, "nan.nrrd", &ReadOptions::default());
    assert!(matches!(err, IoError::Geometry { .. }), "{err}");
    let h = format!("{HEAD}space: RAS\nspace directions: (1,0,0) (2,0,0) (0,0,1)\n\n");
    let mut bytes = h.into_bytes();
    bytes.extend([0u8; 128]);
    let err = expect_err(&bytes, "singular.nrrd", &ReadOptions::default());
    assert!(matches!(err, IoError::Geometry { .. }), "{err}");
}

#[test]
fn missing_detached_data_file() {
    let h = format!("{HEAD}data file: nowhere.raw\n");
    let dir = tempfile::tempdir().unwrap();
    let err =
        glint_io::read_volume(&write(&dir, "x.nhdr", h), &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(err, IoError::Os { .. }) && err.to_string().contains("nowhere.raw"),
        "{err}"
    );
}

/// Review defect 8: a color axis is reported as a non-spatial axis (it used to fail as
/// "voxel spacing NaN"), and a space origin given with plain spacings is used.
#[test]
fn non_spatial_kinds_and_origin_with_spacings() {
    let head = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 2 2\n\
                kinds: RGB-color domain domain\nspacings: nan 1 1\nencoding: raw\n\n";
    let mut bytes = head.as_bytes().to_vec();
    bytes.extend([0u8; 12]);
    let err = expect_err(&bytes, "rgb.nrrd", &ReadOptions::default());
    assert!(
        matches!(err, IoError::Unsupported { .. }) && err.to_string().contains("non-spatial"),
        "{err}"
    );
    let head = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspace: RAS\n\
                kinds: domain domain domain\nspacings: 1 2 3\nspace origin: (5,6,7)\nencoding: raw\n\n";
    let mut bytes = head.as_bytes().to_vec();
    bytes.extend([0u8; 8]);
    let dir = tempfile::tempdir().unwrap();
    let p = write(&dir, "origin.nrrd", &bytes);
    let v = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
    let want = [
        [1.0, 0.0, 0.0, 5.0],
        [0.0, 2.0, 0.0, 6.0],
        [0.0, 0.0, 3.0, 7.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    assert_eq!(v.affine, want);
}

/// Fuzzing (issue 17, `fuzz/fuzz_targets/nrrd.rs`): a header field with carriage
/// returns inside was quoted into a multi-line error. Every error is one line now.
#[test]
fn fuzz_crash_control_characters_in_a_field_give_a_one_line_error() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz/nrrd-crash-3ebbf80b.nrrd");
    let err = glint_io::read_volume(&path, &glint_io::ReadOptions::default()).unwrap_err();
    let msg = err.to_string();
    assert!(!msg.contains('\n') && !msg.contains('\r'), "{msg:?}");
    assert!(msg.contains("control characters"), "{msg}");
}

/// Issue 12: the time spent inflating is measured for gzip data (attached and detached)
/// and only for it, as for NIfTI.
#[test]
fn inflate_time_is_reported_for_gzip_data_only() {
    let dir = tempfile::tempdir().unwrap();
    let vol = sample_volume(Samples::I16((0..24).map(|i| i * 1000 - 9000).collect()));
    for enc in [Encoding::Raw, Encoding::Gzip] {
        let attached = dir.path().join(format!("{enc:?}.nrrd"));
        nrrd::write(&attached, &vol, enc, Endian::Little).unwrap();
        let detached = dir.path().join(format!("{enc:?}.nhdr"));
        nrrd::write_detached(&detached, &vol, enc, Endian::Little).unwrap();
        for p in [attached, detached] {
            let file = glint_io::open_volume(&p, &ReadOptions::default()).unwrap();
            assert_eq!(file.inflate.is_some(), enc == Encoding::Gzip, "{p:?}");
            assert_eq!(file.volume.samples, vol.samples, "{p:?}");
        }
    }
    let text = "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 2 1\nencoding: text\n\n1 2\n";
    let file =
        glint_io::open_volume(&write(&dir, "t.nrrd", text), &ReadOptions::default()).unwrap();
    assert_eq!(file.inflate, None);
}
