//! Voxel-to-world affines: the 3x3 helpers every crate that places voxels in the world
//! uses (determinant, inverse, products), and the one check that an affine places
//! voxels in 3-D space, shared by the readers and by callers that take an affine from
//! a user (the Python module).

/// A voxel-to-world affine, 4x4 row-major, last row `[0, 0, 0, 1]`.
pub type Affine = [[f64; 4]; 4];

/// A 3x3 matrix of `f64`, row-major, for affine transforms.
pub type Mat3 = [[f64; 3]; 3];

/// Smallest `|det|` of the 3x3 part relative to the product of its column norms for the
/// voxel axes to span 3-D space: below it voxels collapse to a plane or a line.
pub const SINGULAR_RTOL: f64 = 1e-6;

/// Largest coordinate, in mm, of a volume's origin and of its voxel size that [`check`]
/// accepts: 1 km. A scanner's world is its bore and table (within about 2 m of the
/// isocentre), and atlas and microscopy frames are smaller still, so a larger
/// position is a corrupt or mis-scaled header (the mutants of issue 47 put an NRRD
/// origin at 3.5e38 mm, which renders black). The bound is also where the f32 the
/// renderer places voxels with stops resolving them: at 2^20 mm (1.05e6) one f32 step
/// is 0.125 mm, the size of a fine voxel.
pub const MAX_COORDINATE_MM: f64 = 1e6;

/// Why an affine cannot place voxels in the world ([`check`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AffineError {
    /// An entry is NaN or infinite.
    #[error("the voxel-to-world affine has non-finite entries: {0:?}")]
    // Boxed: the error stays small on the Ok path (clippy::result_large_err).
    NonFinite(Box<Affine>),
    /// The last row is not `[0, 0, 0, 1]`.
    #[error("the voxel-to-world affine's last row must be [0, 0, 0, 1], got {0:?}")]
    LastRow([f64; 4]),
    /// The origin or a voxel axis lies beyond any scanner ([`MAX_COORDINATE_MM`]).
    #[error(
        "the volume's {what} ({:e}, {:e}, {:e}) mm lies beyond any scanner \
         (a coordinate over {MAX_COORDINATE_MM:e} mm)",
        // + 0.0: a negative zero (an LPS origin's 0 flipped) prints as 0.
        value[0] + 0.0, value[1] + 0.0, value[2] + 0.0
    )]
    Far {
        /// `origin`, or `voxel size`.
        what: &'static str,
        /// Its coordinates, or the voxel size along the three axes.
        value: [f64; 3],
    },
    /// The voxel axes do not span 3-D space.
    #[error("the voxel-to-world affine is singular (spacing {spacing:?}, determinant {det:e})")]
    Singular {
        /// The column norms.
        spacing: [f64; 3],
        /// The 3x3 part's determinant.
        det: f64,
    },
}

/// Checks that `affine` is finite, has the last row `[0, 0, 0, 1]`, places its origin
/// and sizes its voxels within [`MAX_COORDINATE_MM`], and is non-singular relative to
/// its column norms ([`SINGULAR_RTOL`]); returns its spacing.
///
/// ```
/// use glint_io::affine;
/// let mut a = [[2.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 3.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
/// assert_eq!(affine::check(&a), Ok([2.0, 1.0, 3.0]));
/// a[2][2] = 0.0;
/// assert!(matches!(affine::check(&a), Err(affine::AffineError::Singular { .. })));
/// ```
pub fn check(affine: &Affine) -> Result<[f64; 3], AffineError> {
    if affine.iter().flatten().any(|x| !x.is_finite()) {
        return Err(AffineError::NonFinite(Box::new(*affine)));
    }
    if affine[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(AffineError::LastRow(affine[3]));
    }
    let origin = [affine[0][3], affine[1][3], affine[2][3]];
    let spacing = spacing(affine);
    for (what, value) in [("origin", origin), ("voxel size", spacing)] {
        if value.iter().any(|x| x.abs() > MAX_COORDINATE_MM) {
            return Err(AffineError::Far { what, value });
        }
    }
    let scale = spacing[0] * spacing[1] * spacing[2];
    let det = det3(&linear_part(affine));
    if scale == 0.0 || det.abs() < SINGULAR_RTOL * scale {
        return Err(AffineError::Singular { spacing, det });
    }
    Ok(spacing)
}

/// Voxel spacing: the column norms of the affine's 3x3 part.
pub fn spacing(affine: &Affine) -> [f64; 3] {
    std::array::from_fn(|c| {
        (0..3)
            .map(|r| affine[r][c] * affine[r][c])
            .sum::<f64>()
            .sqrt()
    })
}

/// The 3x3 part of a 4x4 row-major affine.
pub fn linear_part(affine: &Affine) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            m[r][c] = affine[r][c];
        }
    }
    m
}

/// Determinant of a 3x3 matrix.
pub fn det3(m: &Mat3) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Inverse of a 3x3 matrix by the adjugate, `None` when singular or non-finite.
pub fn inverse3(m: &Mat3) -> Option<Mat3> {
    let d = det3(m);
    let scale = m
        .iter()
        .flatten()
        .fold(0.0f64, |acc, x| acc.max(x.abs()))
        .powi(3);
    if !d.is_finite() || scale == 0.0 || d.abs() <= 1e-12 * scale {
        return None;
    }
    let inv_d = 1.0 / d;
    let mut r = [[0.0; 3]; 3];
    r[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * inv_d;
    r[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv_d;
    r[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv_d;
    r[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * inv_d;
    r[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv_d;
    r[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv_d;
    r[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * inv_d;
    r[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv_d;
    r[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv_d;
    Some(r)
}

/// `m · v`.
pub fn mul3(m: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// Transpose of a 3x3 matrix.
pub fn transpose3(m: &Mat3) -> Mat3 {
    let mut t = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            t[r][c] = m[c][r];
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_times_matrix_is_identity() {
        let m = [[0.9, 0.1, 0.0], [-0.2, 1.1, 0.3], [0.05, 0.0, 2.5]];
        let inv = inverse3(&m).unwrap();
        // Column r of the inverse is row r of its transpose.
        for (r, col) in transpose3(&inv).into_iter().enumerate() {
            let e = mul3(&m, col);
            for (c, x) in e.iter().enumerate() {
                assert!((x - f64::from(u8::from(c == r))).abs() < 1e-12, "{e:?}");
            }
        }
        assert_eq!(
            inverse3(&[[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]]),
            None
        );
    }

    #[test]
    fn check_refuses_non_finite_bad_last_row_and_flat_affines() {
        let mut a = [
            [1.0, 0.0, 0.0, 5.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0; 4],
        ];
        assert_eq!(check(&a), Err(AffineError::LastRow([0.0; 4])));
        a[3] = [0.0, 0.0, 0.0, 1.0];
        assert_eq!(check(&a), Ok([1.0; 3]));
        a[0][1] = f64::NAN;
        assert!(matches!(check(&a), Err(AffineError::NonFinite(_))));
        // Two columns nearly parallel: a det below 1e-6 of the column-norm product.
        a[0][1] = 1.0;
        a[1][1] = 1e-7;
        assert!(matches!(check(&a), Err(AffineError::Singular { .. })));
    }

    #[test]
    fn check_refuses_positions_beyond_any_scanner() {
        let mut a = [
            [1.0, 0.0, 0.0, -1e6],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        // 1 km is the bound, included.
        assert_eq!(check(&a), Ok([1.0; 3]));
        a[0][3] = 3.5e38;
        let e = check(&a).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the volume's origin (3.5e38, 0e0, 0e0) mm lies beyond any scanner \
             (a coordinate over 1e6 mm)"
        );
        a[0][3] = 0.0;
        a[2][2] = 2e6;
        assert!(
            matches!(
                check(&a),
                Err(AffineError::Far {
                    what: "voxel size",
                    ..
                })
            ),
            "{:?}",
            check(&a)
        );
    }
}
