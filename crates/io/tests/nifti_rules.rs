//! The NIfTI-1 geometry rules no other test pins (issue 34): the sform wins over a
//! qform that disagrees with it, the 180-degree branch of the quaternion, and the unit
//! scaling of the sform. Headers are hand-built field by field (tests/common) and the
//! expected affines computed here from the header fields by the formulas of nifti1.h
//! (<https://nifti.nimh.nih.gov/pub/dist/src/niftilib/nifti1.h>, "METHOD 2" and
//! "METHOD 3"), not by the reader.

mod common;

use common::{assert_affine_eq, NiftiHeader};
use glint_io::ReadOptions;

/// A 2x2x2 uint8 file with header `h`, read back: its affine.
fn affine(h: &NiftiHeader) -> [[f64; 4]; 4] {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = h.bytes();
    bytes.extend(0..8u8);
    let p = dir.path().join("v.nii");
    std::fs::write(&p, &bytes).unwrap();
    glint_io::read_volume(&p, &ReadOptions::default())
        .unwrap()
        .affine
}

/// The srow matrix of `h` as an affine, times `scale` (the units' factor).
fn srow_affine(h: &NiftiHeader, scale: f64) -> [[f64; 4]; 4] {
    let mut a = [[0.0, 0.0, 0.0, 1.0]; 4];
    for (row, src) in a.iter_mut().zip(&h.srow) {
        for (x, &s) in row.iter_mut().zip(src) {
            *x = f64::from(s) * scale;
        }
    }
    a
}

/// nifti1.h METHOD 2 with the rotation written as the rotation by angle `theta` about
/// the unit axis `u` (Rodrigues' formula), not as the quaternion products the reader
/// uses: R = cos θ I + sin θ [u]x + (1 - cos θ) u uᵀ, columns scaled by pixdim and qfac.
fn qform_affine(
    u: [f64; 3],
    theta: f64,
    pixdim: [f64; 3],
    qfac: f64,
    offset: [f64; 3],
) -> [[f64; 4]; 4] {
    let (s, c) = theta.sin_cos();
    let cross = [[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]];
    let scale = [pixdim[0], pixdim[1], qfac * pixdim[2]];
    let mut a = [[0.0, 0.0, 0.0, 1.0]; 4];
    for r in 0..3 {
        for col in 0..3 {
            let eye = if r == col { 1.0 } else { 0.0 };
            let rot = c * eye + s * cross[r][col] + (1.0 - c) * u[r] * u[col];
            a[r][col] = rot * scale[col];
        }
        a[r][3] = offset[r];
    }
    a
}

/// A header with both an sform and a qform, which disagree (different rotation,
/// spacing and origin).
fn both_forms() -> NiftiHeader {
    let mut h = NiftiHeader::new([2, 2, 2], 2, 8);
    h.sform_code = 2;
    h.srow = [
        [0.0, 0.0, 3.0, 10.0],
        [-2.0, 0.0, 0.0, 20.0],
        [0.0, 1.5, 0.0, -30.0],
    ];
    h.qform_code = 1;
    // 90 degrees about z: (b, c, d) = (0, 0, sin 45°).
    h.quatern = [0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2, 5.0, 6.0, 7.0];
    h.pixdim = [1.0, 2.0, 3.0, 4.0, 1.0, 1.0, 1.0, 1.0];
    h
}

#[test]
fn sform_wins_over_a_disagreeing_qform() {
    let h = both_forms();
    let qform = qform_affine(
        [0.0, 0.0, 1.0],
        std::f64::consts::FRAC_PI_2,
        [2.0, 3.0, 4.0],
        1.0,
        [5.0, 6.0, 7.0],
    );
    let sform = srow_affine(&h, 1.0);
    // The two really disagree, so the check below can tell which one was used.
    assert!((qform[0][1] - sform[0][1]).abs() > 1.0);
    assert_affine_eq(&affine(&h), &sform, 0.0);
    // With the sform code cleared the same header gives its qform.
    let mut q = both_forms();
    q.sform_code = 0;
    assert_affine_eq(&affine(&q), &qform, 1e-6);
}

#[test]
fn a_180_degree_quaternion_takes_the_renormalised_branch() {
    // |(b, c, d)| = 1, so a = sqrt(1 - b² - c² - d²) = 0: a half turn about the axis
    // (b, c, d). In f32, 0.6² + 0.8² is not exactly 1 (1 - sum is about 1e-8, of either
    // sign), which is the case nifti1_io.c renormalises.
    for (axis, qfac) in [
        ([1.0f32, 0.0, 0.0], 1.0),
        ([0.0, 0.6, 0.8], 1.0),
        ([0.6, 0.0, -0.8], -1.0),
        ([0.48, 0.6, 0.64], 1.0),
    ] {
        let mut h = NiftiHeader::new([2, 2, 2], 2, 8);
        h.qform_code = 1;
        h.quatern = [axis[0], axis[1], axis[2], -1.0, 2.0, 3.0];
        h.pixdim = [qfac as f32, 0.5, 1.0, 2.0, 1.0, 1.0, 1.0, 1.0];
        let u = axis.map(f64::from);
        let n = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        let want = qform_affine(
            u.map(|x| x / n),
            std::f64::consts::PI,
            [0.5, 1.0, 2.0],
            qfac,
            [-1.0, 2.0, 3.0],
        );
        assert_affine_eq(&affine(&h), &want, 1e-6);
    }
}

#[test]
fn the_sform_is_scaled_by_its_spatial_units() {
    // xyzt_units & 7: 1 metre, 2 mm, 3 micron (nifti1.h NIFTI_UNITS_*); the time bits
    // (8 = seconds, 16 = ms) do not change the spatial factor. glint works in mm.
    for (units, to_mm) in [
        (1u8, 1000.0),
        (2, 1.0),
        (3, 0.001),
        (1 | 8, 1000.0),
        (2 | 16, 1.0),
        (0, 1.0),
    ] {
        let mut h = NiftiHeader::new([2, 2, 2], 2, 8);
        h.sform_code = 1;
        h.srow = [
            [0.0, 0.0, 0.003, 0.1],
            [-0.002, 0.0, 0.0, 0.2],
            [0.0, 0.0015, 0.0, -0.3],
        ];
        h.xyzt_units = units;
        let want = srow_affine(&h, to_mm);
        assert_affine_eq(&affine(&h), &want, 1e-9 * to_mm);
    }
}
