//! FreeSurfer MGH/MGZ against nibabel 5.4.2: the fixtures in tests/data/mgh were written
//! by nibabel (scripts/fixtures/mgh-fixtures.py), which also recorded in reference.tsv what
//! nibabel reads back from each (shape, dtype, affine, the first frame's values, the
//! footer's scan parameters). glint must read the same. Then the bad inputs: truncated
//! files, absurd or zero sizes, unknown types, each one typed error on one line.

mod common;

use std::io::Write;
use std::path::{Path, PathBuf};

use glint_io::{mgh, Format, IoError, ReadOptions, Samples};

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mgh")
}

/// One line of reference.tsv.
struct Reference {
    file: String,
    shape: Vec<usize>,
    dtype: String,
    affine: Vec<f64>,
    values: Vec<String>,
    footer: Vec<f64>,
}

fn references() -> Vec<Reference> {
    let path = data_dir().join("reference.tsv");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; run scripts/fixtures/mgh-fixtures.py (nibabel)",
            path.display()
        )
    });
    let list = |s: &str| s.split(',').map(str::to_string).collect::<Vec<_>>();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("file\t"))
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            assert_eq!(f.len(), 6, "bad reference line {l}");
            Reference {
                file: f[0].into(),
                shape: f[1].split('x').map(|x| x.parse().unwrap()).collect(),
                dtype: f[2].trim_start_matches(['>', '<', '|']).into(),
                affine: list(f[3]).iter().map(|x| x.parse().unwrap()).collect(),
                values: list(f[4]),
                footer: list(f[5]).iter().map(|x| x.parse().unwrap()).collect(),
            }
        })
        .collect()
}

/// The values nibabel printed (Python reprs), as the stored type.
fn expected(r: &Reference) -> Samples {
    macro_rules! parse {
        ($v:ident, $t:ty) => {
            Samples::$v(r.values.iter().map(|x| x.parse::<$t>().unwrap()).collect())
        };
    }
    match r.dtype.as_str() {
        "uint8" | "u1" => parse!(U8, u8),
        "i2" => parse!(I16, i16),
        "u2" => parse!(U16, u16),
        "i4" => parse!(I32, i32),
        "f4" => parse!(F32, f32),
        t => panic!("{}: dtype {t} not in the fixtures' list", r.file),
    }
}

#[test]
fn every_nibabel_fixture_reads_as_nibabel_reads_it() {
    let refs = references();
    assert_eq!(refs.len(), 8, "the script writes eight files");
    for r in &refs {
        let path = data_dir().join(&r.file);
        let f = glint_io::open_volume(&path, &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{}: {e}", r.file));
        assert_eq!(f.format, Format::Mgh);
        let v = &f.volume;
        assert_eq!(v.dims.to_vec(), r.shape[..3], "{}", r.file);
        assert_eq!(v.samples, expected(r), "{}", r.file);
        // nibabel computes the affine from the header's float32 fields in float32
        // arithmetic (the offsets end in ...001907 where glint's f64 gives ...000);
        // the two agree to float32 precision of the largest entry.
        for (i, (&g, &w)) in v.affine.iter().flatten().zip(&r.affine).enumerate() {
            assert!((g - w).abs() <= 2e-6, "{} affine[{i}]: {g} vs {w}", r.file);
        }
        if r.shape.len() == 4 {
            let n = format!("read the first of {} frames", r.shape[3]);
            assert!(f.notes.iter().any(|x| x.contains(&n)), "{:?}", f.notes);
        }
        // The footer nibabel wrote: TR, flip angle (radians), TE, TI.
        let tr = format!("TR {} ms", r.footer[0] as f32);
        let flip = format!("flip angle {:.4} deg", r.footer[1].to_degrees());
        let params = f.notes.iter().find(|n| n.starts_with("scan parameters"));
        let params = params.unwrap_or_else(|| panic!("{}: {:?}", r.file, f.notes));
        assert!(params.contains(&tr) && params.contains(&flip), "{params}");
    }
}

#[test]
fn no_good_ras_flag_takes_freesurfer_default_geometry_with_a_note() {
    let f = mgh::read(&data_dir().join("noras.mgh"), &ReadOptions::default()).unwrap();
    assert_eq!(f.volume.spacing, [1.0; 3]);
    assert!(
        f.notes.iter().any(|n| n.contains("goodRASFlag")),
        "{:?}",
        f.notes
    );
}

/// A valid MGH header for `dims` (width, height, depth, frames) and `type_code`.
fn header(dims: [i32; 4], type_code: i32) -> Vec<u8> {
    let mut h = vec![0u8; mgh::DATA_OFFSET];
    h[0..4].copy_from_slice(&1i32.to_be_bytes());
    for (i, d) in dims.iter().enumerate() {
        h[4 + 4 * i..8 + 4 * i].copy_from_slice(&d.to_be_bytes());
    }
    h[20..24].copy_from_slice(&type_code.to_be_bytes());
    h[28..30].copy_from_slice(&1i16.to_be_bytes());
    for i in 0..3 {
        h[30 + 4 * i..34 + 4 * i].copy_from_slice(&1f32.to_be_bytes());
        // Identity direction cosines: x along R, y along A, z along S.
        h[42 + 16 * i..46 + 16 * i].copy_from_slice(&1f32.to_be_bytes());
    }
    h
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::File::create(&p).unwrap().write_all(bytes).unwrap();
    p
}

/// Reads `path`, expecting an error on one line; returns it.
fn refused(path: &Path) -> IoError {
    let e = glint_io::open_volume(path, &ReadOptions::default())
        .map(|f| f.volume.dims)
        .expect_err("expected a refusal");
    assert!(!e.to_string().contains('\n'), "{e}");
    e
}

#[test]
fn a_hand_built_header_places_the_centre_between_voxels() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = header([3, 2, 1, 1], 0);
    b.extend([1, 2, 3, 4, 5, 6]);
    let v =
        glint_io::read_volume(&write(dir.path(), "a.mgh", &b), &ReadOptions::default()).unwrap();
    assert_eq!(v.samples, Samples::U8(vec![1, 2, 3, 4, 5, 6]));
    // Pxyz_c = 0 is the centre (1.5, 1, 0.5) in voxels: the origin is at its negative.
    assert_eq!(
        [v.affine[0][3], v.affine[1][3], v.affine[2][3]],
        [-1.5, -1.0, -0.5]
    );
}

#[test]
fn truncated_mgz_and_mgh_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let full = std::fs::read(data_dir().join("i32.mgz")).unwrap();
    // Cut inside the compressed samples: the inflater runs dry.
    let cut = write(dir.path(), "cut.mgz", &full[..full.len() / 2]);
    let e = refused(&cut);
    assert!(
        matches!(e, IoError::Truncated { .. } | IoError::Invalid { .. }),
        "{e}"
    );
    // Cut inside the header of a plain file.
    let plain = std::fs::read(data_dir().join("i16.mgh")).unwrap();
    let e = refused(&write(dir.path(), "head.mgh", &plain[..100]));
    assert!(matches!(e, IoError::Truncated { .. }), "{e}");
    // Cut inside the samples: the size is checked before reading.
    let e = refused(&write(dir.path(), "data.mgh", &plain[..300]));
    assert!(matches!(e, IoError::SizeMismatch { .. }), "{e}");
    // A 4D file whose later frames are missing (gzip: found while skipping them).
    let mut b = header([2, 2, 2, 3], 0);
    b.extend([7u8; 8 * 2]);
    let e = refused(&write(dir.path(), "frames.mgz", &common::gzip(&b)));
    assert!(e.to_string().contains("frames 2..3"), "{e}");
}

#[test]
fn absurd_zero_and_unknown_headers_are_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    // 2^31-1 cubed: far past the voxel limit; refused from the header alone.
    let e = refused(&write(
        dir.path(),
        "huge.mgh",
        &header([i32::MAX, i32::MAX, i32::MAX, 1], 3),
    ));
    assert!(matches!(e, IoError::TooLarge { .. }), "{e}");
    // A plausible frame but 2^31-1 frames: the data cannot be in a 300-byte file.
    let e = refused(&write(
        dir.path(),
        "frames.mgh",
        &header([64, 64, 64, i32::MAX], 3),
    ));
    assert!(matches!(e, IoError::SizeMismatch { .. }), "{e}");
    // The same gzip-compressed: the first frame is not there.
    let e = refused(&write(
        dir.path(),
        "frames.mgz",
        &common::gzip(&header([64, 64, 64, i32::MAX], 3)),
    ));
    assert!(matches!(e, IoError::Truncated { .. }), "{e}");
    let e = refused(&write(dir.path(), "zero.mgh", &header([4, 0, 4, 1], 0)));
    assert!(e.to_string().contains("is not a size"), "{e}");
    let e = refused(&write(dir.path(), "neg.mgh", &header([4, 4, 4, -2], 0)));
    assert!(e.to_string().contains("is not a size"), "{e}");
    let e = refused(&write(dir.path(), "type.mgh", &header([1, 1, 1, 1], 6)));
    assert!(e.to_string().contains("MGH data type 6 (tensor)"), "{e}");
    let mut bad = header([1, 1, 1, 1], 0);
    bad[3] = 2;
    let e = refused(&write(dir.path(), "version.mgh", &bad));
    assert!(matches!(e, IoError::BadMagic { .. }), "{e}");
    let mut nan = header([1, 1, 1, 1], 0);
    nan[30..34].copy_from_slice(&f32::NAN.to_be_bytes());
    nan.push(0);
    let e = refused(&write(dir.path(), "nan.mgh", &nan));
    assert!(matches!(e, IoError::Geometry { .. }), "{e}");
    // The caller's limit applies as to every reader.
    let mut small = header([4, 4, 4, 1], 0);
    small.extend([0u8; 64]);
    let path = write(dir.path(), "small.mgh", &small);
    let opts = ReadOptions {
        max_voxels: 63,
        ..ReadOptions::default()
    };
    assert!(matches!(
        mgh::read(&path, &opts),
        Err(IoError::TooLarge { .. })
    ));
}
