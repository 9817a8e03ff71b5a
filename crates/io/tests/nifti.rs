//! NIfTI-1: hand-built headers, round trips, bad input, and the MNI152 template.

mod common;

use common::{assert_affine_eq, gzip, NiftiHeader};
use glint_io::{nifti, Endian, IoError, ReadOptions, Samples, Volume};

fn write(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn sform_scaling_and_byte_orders_from_hand_built_headers() {
    let dir = tempfile::tempdir().unwrap();
    for big in [false, true] {
        // 2x3x2 int16, values 0..12 minus 5, in the file's byte order.
        let mut h = NiftiHeader::new([2, 3, 2], 4, 16);
        h.big_endian = big;
        h.sform_code = 1;
        h.srow = [
            [0.0, 0.0, 3.0, 10.0],
            [-2.0, 0.0, 0.0, 20.0],
            [0.0, 1.5, 0.0, -30.0],
        ];
        h.scl_slope = 2.0;
        h.scl_inter = -1.0;
        let mut bytes = h.bytes();
        for v in 0..12i16 {
            let x = v - 5;
            bytes.extend_from_slice(&if big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            });
        }
        let p = write(&dir, &format!("s{big}.nii"), &bytes);
        let vol = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
        assert_eq!(vol.dims, [2, 3, 2]);
        assert_eq!(vol.samples, Samples::I16((0..12).map(|v| v - 5).collect()));
        // Spacing = column norms: |(0,-2,0)| = 2, |(0,0,1.5)| = 1.5, |(3,0,0)| = 3.
        assert_eq!(vol.spacing, [2.0, 1.5, 3.0]);
        let want = [
            [0.0, 0.0, 3.0, 10.0],
            [-2.0, 0.0, 0.0, 20.0],
            [0.0, 1.5, 0.0, -30.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        assert_affine_eq(&vol.affine, &want, 0.0);
        // value = 2 * stored - 1; voxel (1, 2, 1) is index 1 + 2*(2 + 3*1) = 11 -> 6.
        assert_eq!(vol.value(1, 2, 1), 2.0 * 6.0 - 1.0);
        assert_eq!(vol.range(), (2.0 * -5.0 - 1.0, 2.0 * 6.0 - 1.0));
    }
}

#[test]
fn qform_quaternion_with_negative_qfac() {
    // 90 degrees about z: (b, c, d) = (0, 0, sin 45), so R = [[0,-1,0],[1,0,0],[0,0,1]].
    // pixdim (2, 3, 4) and qfac = -1 flip the k column: affine columns are
    // R[:,0]*2 = (0,2,0), R[:,1]*3 = (-3,0,0), R[:,2]*-4 = (0,0,-4).
    let dir = tempfile::tempdir().unwrap();
    let mut h = NiftiHeader::new([2, 2, 2], 2, 8);
    h.qform_code = 1;
    h.quatern = [0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2, 5.0, 6.0, 7.0];
    h.pixdim = [-1.0, 2.0, 3.0, 4.0, 1.0, 1.0, 1.0, 1.0];
    let mut bytes = h.bytes();
    bytes.extend(0..8u8);
    let p = write(&dir, "q.nii", &bytes);
    let vol = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
    let want = [
        [0.0, -3.0, 0.0, 5.0],
        [2.0, 0.0, 0.0, 6.0],
        [0.0, 0.0, -4.0, 7.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    assert_affine_eq(&vol.affine, &want, 1e-6);
    assert!((vol.spacing[0] - 2.0).abs() < 1e-6 && (vol.spacing[2] - 4.0).abs() < 1e-6);
}

#[test]
fn pixdim_fallback_and_metre_units() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = NiftiHeader::new([2, 1, 1], 16, 32);
    h.pixdim = [1.0, 0.5, 0.25, 2.0, 1.0, 1.0, 1.0, 1.0];
    h.xyzt_units = 1; // metres: 0.5 m = 500 mm
    h.scl_slope = 0.0; // zero slope means "no scaling"
    h.scl_inter = 99.0;
    let mut bytes = h.bytes();
    bytes.extend_from_slice(&1.5f32.to_le_bytes());
    bytes.extend_from_slice(&(-2.5f32).to_le_bytes());
    let vol =
        glint_io::read_volume(&write(&dir, "p.nii", &bytes), &ReadOptions::default()).unwrap();
    assert_eq!(vol.spacing, [500.0, 250.0, 2000.0]);
    assert_eq!((vol.slope, vol.intercept), (1.0, 0.0));
    assert_eq!(vol.to_f32(), vec![1.5, -2.5]);
}

fn test_volume(samples: Samples, n: usize) -> Volume {
    let mut vol = Volume::new([n, 2, 3], [1.0; 3], samples).unwrap();
    vol.affine = [
        [0.0, -0.5, 0.0, 1.25],
        [1.5, 0.0, 0.0, -2.0],
        [0.0, 0.0, 2.5, 3.5],
        [0.0, 0.0, 0.0, 1.0],
    ];
    vol.spacing = [1.5, 0.5, 2.5];
    vol.slope = 0.5;
    vol.intercept = 4.0;
    vol
}

/// One volume of every sample type, 4x2x3, with extreme values.
pub fn all_types() -> Vec<Samples> {
    let n = 24;
    vec![
        Samples::U8((0..n).map(|i| (i * 11) as u8).collect()),
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
fn round_trip_every_type_both_orders_gzip_or_not() {
    let dir = tempfile::tempdir().unwrap();
    for samples in all_types() {
        for endian in [Endian::Little, Endian::Big] {
            for gz in [false, true] {
                let vol = test_volume(samples.clone(), 4);
                let name = format!(
                    "{}-{endian:?}-{gz}.nii{}",
                    samples.type_name(),
                    if gz { ".gz" } else { "" }
                );
                let p = dir.path().join(name);
                nifti::write(&p, &vol, gz, endian).unwrap();
                let back = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
                assert_eq!(back.samples, vol.samples, "{p:?}");
                assert_eq!(back.dims, vol.dims);
                assert_affine_eq(&back.affine, &vol.affine, 1e-6);
                assert_eq!((back.slope, back.intercept), (0.5, 4.0));
            }
        }
    }
}

fn expect_err(bytes: &[u8], name: &str, options: &ReadOptions) -> IoError {
    let dir = tempfile::tempdir().unwrap();
    let p = write(&dir, name, bytes);
    let err = glint_io::read_volume(&p, options).unwrap_err();
    assert!(
        err.to_string().contains(name),
        "error does not name the file: {err}"
    );
    err
}

#[test]
fn truncated_header() {
    let bytes = NiftiHeader::new([2, 2, 2], 2, 8).bytes();
    let err = expect_err(&bytes[..200], "short.nii", &ReadOptions::default());
    assert!(matches!(err, IoError::Truncated { .. }), "{err}");
}

#[test]
fn truncated_gzip_data() {
    let mut bytes = NiftiHeader::new([8, 8, 8], 2, 8).bytes();
    bytes.extend(std::iter::repeat_n(7u8, 100)); // 512 announced
    let err = expect_err(&gzip(&bytes), "short.nii.gz", &ReadOptions::default());
    assert!(matches!(err, IoError::Truncated { .. }), "{err}");
}

#[test]
fn corrupt_gzip_stream() {
    let mut z = gzip(&NiftiHeader::new([2, 2, 2], 2, 8).bytes());
    let mid = z.len() / 2;
    for b in &mut z[10..mid] {
        *b ^= 0x5a;
    }
    let err = expect_err(&z, "corrupt.nii.gz", &ReadOptions::default());
    assert!(
        matches!(err, IoError::Invalid { .. } | IoError::Truncated { .. }),
        "{err}"
    );
}

#[test]
fn wrong_magic() {
    let mut h = NiftiHeader::new([2, 2, 2], 2, 8);
    h.magic = *b"xyz\0";
    let mut bytes = h.bytes();
    bytes.extend([0u8; 8]);
    let err = expect_err(&bytes, "magic.nii", &ReadOptions::default());
    assert!(matches!(err, IoError::BadMagic { .. }), "{err}");
    // A PNG renamed to .nii: the size field is wrong.
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.resize(400, 0);
    let err = expect_err(&png, "image.nii", &ReadOptions::default());
    assert!(matches!(err, IoError::BadMagic { .. }), "{err}");
}

#[test]
fn header_data_size_mismatch() {
    let mut bytes = NiftiHeader::new([10, 10, 10], 4, 16).bytes();
    bytes.extend([0u8; 100]); // 2000 announced
    let err = expect_err(&bytes, "mismatch.nii", &ReadOptions::default());
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
}

#[test]
fn unsupported_datatypes() {
    for (code, bitpix) in [(32i16, 64i16), (128, 24), (1024, 64), (99, 8)] {
        let mut bytes = NiftiHeader::new([1, 1, 1], code, bitpix).bytes();
        bytes.extend([0u8; 16]);
        let err = expect_err(&bytes, "type.nii", &ReadOptions::default());
        assert!(matches!(err, IoError::Unsupported { .. }), "{err}");
    }
}

#[test]
fn too_many_voxels_refused_before_reading() {
    // 32767^3 float64 voxels = 281 TB announced by a 352-byte file.
    let bytes = NiftiHeader::new([32767, 32767, 32767], 64, 64).bytes();
    let err = expect_err(&bytes, "huge.nii", &ReadOptions::default());
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
    // A small limit refuses a small volume too.
    let mut bytes = NiftiHeader::new([4, 4, 4], 2, 8).bytes();
    bytes.extend([0u8; 64]);
    let opts = ReadOptions {
        max_voxels: 63,
        ..ReadOptions::default()
    };
    let err = expect_err(&bytes, "limit.nii", &opts);
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
}

#[test]
fn nan_spacing() {
    let mut h = NiftiHeader::new([2, 2, 2], 2, 8);
    h.pixdim[2] = f32::NAN;
    let mut bytes = h.bytes();
    bytes.extend([0u8; 8]);
    let err = expect_err(&bytes, "nan.nii", &ReadOptions::default());
    assert!(matches!(err, IoError::Geometry { .. }), "{err}");
}

#[test]
fn singular_sform() {
    let mut h = NiftiHeader::new([2, 2, 2], 2, 8);
    h.sform_code = 2;
    // Third column equals the first: voxels collapse onto a plane.
    h.srow = [
        [1.0, 0.0, 1.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0],
    ];
    let mut bytes = h.bytes();
    bytes.extend([0u8; 8]);
    let err = expect_err(&bytes, "singular.nii", &ReadOptions::default());
    assert!(matches!(err, IoError::Geometry { .. }), "{err}");
}

#[test]
fn negative_dim() {
    let mut h = NiftiHeader::new([2, 2, 2], 2, 8);
    h.dim[2] = -4;
    let err = expect_err(&h.bytes(), "negdim.nii", &ReadOptions::default());
    assert!(matches!(err, IoError::Invalid { .. }), "{err}");
}

#[test]
fn mni152_template() {
    let Some(path) = common::sample("mni152_t1_09a.nii.gz") else {
        return;
    };
    let vol = glint_io::read_volume(&path, &ReadOptions::default()).unwrap();
    // Header values read with Python's struct module from the nilearn 0.14.1 file:
    // dim = 3 197 233 189, datatype 2 (uint8), sform_code 2,
    // srow = (1 0 0 -98) (0 1 0 -134) (0 0 1 -72).
    assert_eq!(vol.dims, [197, 233, 189]);
    assert_eq!(vol.spacing, [1.0, 1.0, 1.0]);
    assert!(matches!(vol.samples, Samples::U8(_)));
    assert_affine_eq(
        &vol.affine,
        &[
            [1.0, 0.0, 0.0, -98.0],
            [0.0, 1.0, 0.0, -134.0],
            [0.0, 0.0, 1.0, -72.0],
            [0.0, 0.0, 0.0, 1.0],
        ],
        0.0,
    );
    // Values read with Python from the decompressed data (offset 352): voxel (98, 134, 72),
    // the world origin, is 71; the range is 0..255.
    assert_eq!(vol.value(0, 0, 0), 0.0);
    assert_eq!(vol.value(98, 134, 72), 71.0);
    assert_eq!(vol.range(), (0.0, 255.0));
}
