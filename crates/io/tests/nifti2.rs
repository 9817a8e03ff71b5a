//! NIfTI-2 and `.hdr`/`.img` pairs, against fixtures written by nibabel 5.4.2
//! (scripts/fixtures/nifti-fixtures.py): 4 x 3 x 2 int16, value(i, j, k) = i + 10 j + 100 k - 50.

mod common;

use std::path::{Path, PathBuf};

use common::assert_affine_eq;
use glint_io::{nifti, Endian, IoError, ReadOptions, Samples, Volume};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// The stored values the script wrote, i fastest.
fn expected() -> Vec<i16> {
    let mut v = Vec::new();
    for k in 0..2 {
        for j in 0..3 {
            for i in 0..4 {
                v.push(i + 10 * j + 100 * k - 50);
            }
        }
    }
    v
}

/// The script's affine.
const AFFINE: [[f64; 4]; 4] = [
    [0.0, 0.0, -2.5, 10.0],
    [1.5, 0.0, 0.0, -4.0],
    [0.0, 2.0, 0.0, 7.25],
    [0.0, 0.0, 0.0, 1.0],
];

#[test]
fn nifti2_from_nibabel_every_variant() {
    for name in ["n2.nii", "n2.nii.gz", "n2_big.nii"] {
        let f = glint_io::open_volume(&data(name), &ReadOptions::default()).unwrap();
        let v = &f.volume;
        assert_eq!(v.dims, [4, 3, 2], "{name}");
        assert_eq!(v.samples, Samples::I16(expected()), "{name}");
        assert_affine_eq(&v.affine, &AFFINE, 0.0);
        // The script sets slope 2, intercept 1; nibabel rewrote the byte-swapped copy's
        // scaling to 1, 0 (bytes 176..192 of the files, read with Python's struct).
        let scaling = if name == "n2_big.nii" {
            (1.0, 0.0)
        } else {
            (2.0, 1.0)
        };
        assert_eq!((v.slope, v.intercept), scaling, "{name}");
        assert_eq!(v.spacing, [1.5, 2.0, 2.5], "{name}");
        assert!(f.notes.iter().any(|n| n == "NIfTI-2"), "{:?}", f.notes);
    }
}

#[test]
fn nifti1_pair_from_nibabel() {
    let f = glint_io::open_volume(&data("n1pair.hdr"), &ReadOptions::default()).unwrap();
    assert_eq!(f.volume.samples, Samples::I16(expected()));
    assert_affine_eq(&f.volume.affine, &AFFINE, 1e-6);
    assert!(f.notes[0].contains("pair"), "{:?}", f.notes);
}

#[test]
fn analyze_pair_from_nibabel() {
    let f = glint_io::open_volume(&data("analyze.hdr"), &ReadOptions::default()).unwrap();
    assert_eq!(f.volume.samples, Samples::I16(expected()));
    // ANALYZE has no orientation: the pixdim diagonal.
    assert_eq!(f.volume.spacing, [1.5, 2.0, 2.5]);
    assert_eq!(f.volume.affine[0][0], 1.5);
    assert_eq!(f.volume.affine[0][1], 0.0);
    assert!(f.notes[0].contains("ANALYZE"), "{:?}", f.notes);
}

#[test]
fn pair_without_image_or_with_single_file_magic() {
    let dir = tempfile::tempdir().unwrap();
    let hdr = dir.path().join("lonely.hdr");
    std::fs::copy(data("n1pair.hdr"), &hdr).unwrap();
    let err = glint_io::read_volume(&hdr, &ReadOptions::default()).unwrap_err();
    assert!(err.to_string().contains("no image file"), "{err}");
    // A .nii whose magic says "pair".
    let mut b = std::fs::read(data("n1pair.hdr")).unwrap();
    b.extend(std::fs::read(data("n1pair.img")).unwrap());
    let nii = dir.path().join("pairmagic.nii");
    std::fs::write(&nii, b).unwrap();
    let err = glint_io::read_volume(&nii, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::Invalid { .. }), "{err}");
}

/// Byte-level check of the writer against nifti2.h offsets, then a read back; and a
/// volume over NIfTI-1's 32767 voxels a side.
#[test]
fn nifti2_writer_layout_and_large_dims() {
    let dir = tempfile::tempdir().unwrap();
    let mut vol = Volume::new([40000, 1, 2], [1.0; 3], Samples::U8(vec![0; 80000])).unwrap();
    vol.affine = AFFINE;
    if let Samples::U8(s) = &mut vol.samples {
        s[79999] = 9;
    }
    let p = dir.path().join("wide.nii");
    assert!(nifti::write(&p, &vol, false, Endian::Little).is_err());
    for endian in [Endian::Little, Endian::Big] {
        nifti::write_nifti2(&p, &vol, false, endian).unwrap();
        let b = std::fs::read(&p).unwrap();
        let i64_at = |at: usize| {
            let a: [u8; 8] = b[at..at + 8].try_into().unwrap();
            match endian {
                Endian::Little => i64::from_le_bytes(a),
                Endian::Big => i64::from_be_bytes(a),
            }
        };
        let f64_at = |at: usize| f64::from_bits(i64_at(at) as u64);
        assert_eq!(&b[4..12], b"n+2\0\r\n\x1a\n");
        assert_eq!(i64_at(16), 3); // dim[0]
        assert_eq!(i64_at(24), 40000); // dim[1]
        assert_eq!(i64_at(168), 544); // vox_offset
        assert_eq!(f64_at(400 + 24), 10.0); // srow_x[3]
        assert_eq!(f64_at(432), 1.5); // srow_y[0]
        assert_eq!(b.len(), 544 + 80000);
        let back = glint_io::read_volume(&p, &ReadOptions::default()).unwrap();
        assert_eq!(back.dims, [40000, 1, 2]);
        assert_eq!(back.samples, vol.samples);
        assert_affine_eq(&back.affine, &AFFINE, 0.0);
    }
    let gz = dir.path().join("wide.nii.gz");
    nifti::write_nifti2(&gz, &vol, true, Endian::Little).unwrap();
    assert_eq!(
        glint_io::read_volume(&gz, &ReadOptions::default())
            .unwrap()
            .samples,
        vol.samples
    );
}

#[test]
fn nifti2_hostile_dims() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = std::fs::read(data("n2.nii")).unwrap();
    // dim[1] = 2^62: refused by the voxel limit, before any allocation.
    b[24..32].copy_from_slice(&(1i64 << 62).to_le_bytes());
    let p = dir.path().join("huge.nii");
    std::fs::write(&p, &b).unwrap();
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
    b[24..32].copy_from_slice(&(-3i64).to_le_bytes());
    std::fs::write(&p, &b).unwrap();
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::Invalid { .. }), "{err}");
    // Truncated inside the 540-byte header.
    std::fs::write(&p, &b[..400]).unwrap();
    let err = glint_io::read_volume(&p, &ReadOptions::default()).unwrap_err();
    assert!(matches!(err, IoError::Truncated { .. }), "{err}");
}

/// Issue 12: the time spent inflating is measured for a gzip file and only for one.
#[test]
fn inflate_time_is_reported_for_compressed_files_only() {
    let gz = glint_io::open_volume(&data("n2.nii.gz"), &ReadOptions::default()).unwrap();
    assert!(gz.inflate.is_some());
    let plain = glint_io::open_volume(&data("n2.nii"), &ReadOptions::default()).unwrap();
    assert_eq!(plain.inflate, None);
    assert_eq!(gz.volume.samples, plain.volume.samples);
}
