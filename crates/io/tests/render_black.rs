//! Issue 47 item 6: values that rendered black without a word are refused with one
//! line (scaling beyond f32, positions beyond any scanner), and an OBJ line too long to
//! hold is refused as it is read.

use std::path::Path;

use glint_io::{nifti, Endian, IoError, ReadOptions, Samples, Volume};

fn nifti_with(dir: &Path, name: &str, samples: Samples, slope: f64, intercept: f64) -> IoError {
    let mut vol = Volume::new([2, 2, 2], [1.0; 3], samples).unwrap();
    vol.slope = slope;
    vol.intercept = intercept;
    let path = dir.join(name);
    nifti::write(&path, &vol, false, Endian::Little).unwrap();
    match glint_io::read_volume(&path, &ReadOptions::default()) {
        Ok(v) => panic!("{name} read: range {:?}", v.range()),
        Err(e) => e,
    }
}

#[test]
fn nifti_scaling_beyond_f32_is_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    // scl_slope 1e38 takes 0..7 to 0..7e38: beyond f32 (3.4e38).
    let e = nifti_with(
        dir.path(),
        "slope.nii",
        Samples::U8((0..8).collect()),
        1e38,
        0.0,
    );
    let line = glint_io::one_line(&e);
    assert!(matches!(e, IoError::Invalid { .. }), "{line}");
    assert!(
        line.contains("scl_slope 1e38 and scl_inter 0e0 scale the stored values 0..7")
            && line.contains("beyond f32's range"),
        "{line}"
    );
    assert_eq!(line.lines().count(), 1);
    // scl_inter -3.4e38 with outliers either side: every value the same f32.
    let outliers = Samples::I16(vec![0, 1, 2, 3, -32768, 32767, 5, 6]);
    let e = nifti_with(dir.path(), "inter.nii", outliers, 1.0, -3.4e38);
    let line = glint_io::one_line(&e);
    assert!(
        line.contains("scl_inter -3.4e38") && line.contains("one f32 value"),
        "{line}"
    );
    // A range wider than f32 holds: -3e38 .. 3e38 (each end within f32).
    let wide = Samples::F32(vec![-1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let e = nifti_with(dir.path(), "wide.nii", wide, 3e38, 0.0);
    assert!(
        glint_io::one_line(&e).contains("a range wider than f32"),
        "{e}"
    );
}

#[test]
fn ordinary_scaling_still_reads() {
    let dir = tempfile::tempdir().unwrap();
    for (name, samples, slope, intercept) in [
        (
            "ct.nii",
            Samples::I16(vec![0, 1, 2, 3, 4, 5, 6, 1000]),
            1.0,
            -1024.0,
        ),
        (
            "pet.nii",
            Samples::U16(vec![0, 9, 8, 7, 6, 5, 4, 65535]),
            1e-3,
            0.0,
        ),
        ("float.nii", Samples::F32(vec![0.5; 8]), 1e30, 1e30),
    ] {
        let mut vol = Volume::new([2, 2, 2], [1.0; 3], samples).unwrap();
        vol.slope = slope;
        vol.intercept = intercept;
        let path = dir.path().join(name);
        nifti::write(&path, &vol, false, Endian::Little).unwrap();
        let back = glint_io::read_volume(&path, &ReadOptions::default()).unwrap();
        assert_eq!(back.slope, f64::from(slope as f32), "{name}");
    }
}

#[test]
fn an_nrrd_origin_beyond_any_scanner_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("far.nrrd");
    let mut bytes = b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\n\
space: left-posterior-superior\nspace directions: (1,0,0) (0,1,0) (0,0,1)\n\
space origin: (3.5e38,0,0)\nencoding: raw\n\n"
        .to_vec();
    bytes.extend(0..8u8);
    std::fs::write(&path, &bytes).unwrap();
    let e = glint_io::read_volume(&path, &ReadOptions::default()).unwrap_err();
    let line = glint_io::one_line(&e);
    assert!(matches!(e, IoError::Geometry { .. }), "{line}");
    assert!(
        line.contains("origin (-3.5e38, 0e0, 0e0) mm lies beyond any scanner"),
        "{line}"
    );
    // 500 mm from the isocentre, as a table shift puts it: read.
    let near = String::from_utf8_lossy(&bytes).replace("3.5e38", "500");
    std::fs::write(&path, near.as_bytes()).unwrap();
    glint_io::read_volume(&path, &ReadOptions::default()).unwrap();
}

#[test]
fn an_obj_line_longer_than_the_bound_is_refused_and_long_polygons_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fan.obj");
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    // A face of 600,000 corners on one 1.2 MB line.
    let face: String = " 1 2 3".repeat(200_000);
    std::fs::write(&path, format!("{head}f{face}\n")).unwrap();
    let Err(e) = glint_io::read_mesh(&path) else {
        panic!("a 1.2 MB line was read");
    };
    let line = glint_io::one_line(&e);
    assert!(
        line.contains(&format!(
            "the line at byte {} is longer than 1 MiB",
            head.len()
        )),
        "{line}"
    );
    // A polygon of 30,000 corners (a 180 kB line) is an OBJ line: read, fanned.
    let face: String = " 1 2 3".repeat(10_000);
    std::fs::write(&path, format!("{head}f{face}\n")).unwrap();
    let mesh = glint_io::read_mesh(&path).unwrap();
    assert_eq!(mesh.triangles.len(), 30_000 - 2);
}
