//! Raw volumes: caller-described samples, round trips and bad parameters.

use glint_io::{raw, Endian, IoError, RawParams, ReadOptions, Samples, ScalarType, Volume};

fn options(dims: [usize; 3], scalar: ScalarType, endian: Endian, offset: u64) -> ReadOptions {
    ReadOptions {
        raw: Some(RawParams {
            dims,
            scalar,
            spacing: [0.5, 1.0, 2.0],
            endian,
            offset,
        }),
        ..ReadOptions::default()
    }
}

#[test]
fn round_trip_every_type_and_byte_order() {
    let dir = tempfile::tempdir().unwrap();
    let all = [
        Samples::U8(vec![0, 1, 255, 7, 8, 9]),
        Samples::I8(vec![-128, 1, 127, -7, 8, 9]),
        Samples::U16(vec![0, 1, 65535, 7, 8, 9]),
        Samples::I16(vec![-32768, 1, 32767, 7, -8, 9]),
        Samples::U32(vec![0, 1, u32::MAX, 7, 8, 9]),
        Samples::I32(vec![i32::MIN, 1, i32::MAX, 7, 8, 9]),
        Samples::F32(vec![0.5, -1.25, f32::MAX, 7.0, 8.0, 9.0]),
        Samples::F64(vec![0.5, -1.25, f64::MIN_POSITIVE, 7.0, 8.0, 9.0]),
    ];
    for samples in all {
        for endian in [Endian::Little, Endian::Big] {
            let vol = Volume::new([3, 2, 1], [0.5, 1.0, 2.0], samples.clone()).unwrap();
            let p = dir
                .path()
                .join(format!("{}-{endian:?}.raw", samples.type_name()));
            raw::write(&p, &vol, endian).unwrap();
            let ty = ScalarType::of(&samples);
            let back = glint_io::read_volume(&p, &options([3, 2, 1], ty, endian, 0)).unwrap();
            assert_eq!(back, vol, "{p:?}");
        }
    }
}

#[test]
fn offset_and_byte_order_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("h.img");
    // 3 header bytes to skip, then big-endian u16 0x0102 and 0xFFFE.
    std::fs::write(&p, [9, 9, 9, 0x01, 0x02, 0xFF, 0xFE]).unwrap();
    let v =
        glint_io::read_volume(&p, &options([2, 1, 1], ScalarType::U16, Endian::Big, 3)).unwrap();
    assert_eq!(v.samples, Samples::U16(vec![0x0102, 0xFFFE]));
    assert_eq!(v.spacing, [0.5, 1.0, 2.0]);
}

fn expect_err(bytes: &[u8], opts: &ReadOptions) -> IoError {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("vol.raw");
    std::fs::write(&p, bytes).unwrap();
    let err = glint_io::read_volume(&p, opts).unwrap_err();
    assert!(
        err.to_string().contains("vol.raw"),
        "error does not name the file: {err}"
    );
    err
}

#[test]
fn size_mismatch() {
    let err = expect_err(
        &[0; 15],
        &options([2, 2, 2], ScalarType::U16, Endian::Little, 0),
    );
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
    let err = expect_err(
        &[0; 17],
        &options([2, 2, 2], ScalarType::U16, Endian::Little, 0),
    );
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
}

#[test]
fn overflow_and_limit() {
    let err = expect_err(
        &[0; 8],
        &options([usize::MAX, 2, 2], ScalarType::U8, Endian::Little, 0),
    );
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
    let mut opts = options([4, 4, 4], ScalarType::F64, Endian::Little, 0);
    opts.max_voxels = 10;
    let err = expect_err(&[0; 512], &opts);
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
    let err = expect_err(
        &[0; 8],
        &options([0, 2, 2], ScalarType::U8, Endian::Little, 0),
    );
    assert!(matches!(err, IoError::Invalid { .. }), "{err}");
}

#[test]
fn nan_and_negative_spacing() {
    for bad in [f64::NAN, -1.0, 0.0, f64::INFINITY] {
        let mut opts = options([2, 2, 2], ScalarType::U8, Endian::Little, 0);
        opts.raw.as_mut().unwrap().spacing[1] = bad;
        let err = expect_err(&[0; 8], &opts);
        assert!(matches!(err, IoError::Geometry { .. }), "{bad}: {err}");
    }
}

#[test]
fn raw_extension_without_parameters_is_refused() {
    let err = expect_err(&[0; 8], &ReadOptions::default());
    assert!(matches!(err, IoError::Unsupported { .. }), "{err}");
}

#[test]
fn scalar_type_names() {
    for (s, t) in [
        ("u8", ScalarType::U8),
        ("int16", ScalarType::I16),
        ("float", ScalarType::F32),
        ("F64", ScalarType::F64),
    ] {
        assert_eq!(s.parse::<ScalarType>().unwrap(), t);
    }
    assert!("complex".parse::<ScalarType>().is_err());
}

/// Review defect 9: positive spacings whose voxel volume underflows to zero
/// (1e-300 mm cubed) are a degenerate geometry, not a volume.
#[test]
fn degenerate_tiny_spacing() {
    let mut opts = options([2, 2, 2], ScalarType::U8, Endian::Little, 0);
    opts.raw.as_mut().unwrap().spacing = [1e-300; 3];
    let err = expect_err(&[0; 8], &opts);
    assert!(matches!(err, IoError::Geometry { .. }), "{err}");
    // Small but sane voxels (1 micrometre) are still read.
    opts.raw.as_mut().unwrap().spacing = [1e-3; 3];
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("v.raw");
    std::fs::write(&p, [0u8; 8]).unwrap();
    let v = glint_io::read_volume(&p, &opts).unwrap();
    assert_eq!(v.spacing, [1e-3; 3]);
}
