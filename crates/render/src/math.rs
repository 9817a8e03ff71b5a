//! Plain `Copy` vector math for the renderer (glam-style, no hidden allocation).
//!
//! Hand-written rather than a dependency: the caster needs a dozen operations on one
//! three-component type, and keeping them here lets every hot loop inline them.

use std::ops::{Add, Mul, Neg, Sub};

/// A 3-vector of `f32`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec3 {
    /// x component.
    pub x: f32,
    /// y component.
    pub y: f32,
    /// z component.
    pub z: f32,
}

impl Vec3 {
    /// A vector from its components.
    #[inline]
    pub const fn new(x: f32, y: f32, z: f32) -> Self {
        Vec3 { x, y, z }
    }

    /// The zero vector.
    pub const ZERO: Vec3 = Vec3::new(0.0, 0.0, 0.0);

    /// Dot product.
    #[inline]
    pub fn dot(self, o: Vec3) -> f32 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product.
    #[inline]
    pub fn cross(self, o: Vec3) -> Vec3 {
        Vec3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// Euclidean length.
    #[inline]
    pub fn length(self) -> f32 {
        self.dot(self).sqrt()
    }

    /// The unit vector along `self`, or zero for a zero/non-finite vector.
    #[inline]
    pub fn normalize_or_zero(self) -> Vec3 {
        let len = self.length();
        if len.is_finite() && len > 0.0 {
            self * (1.0 / len)
        } else {
            Vec3::ZERO
        }
    }

    /// As an array, for glint-lobe's geometry functions.
    #[inline]
    pub fn to_array(self) -> [f32; 3] {
        [self.x, self.y, self.z]
    }

    /// Component `a` (0, 1 or 2).
    #[inline]
    pub fn get(self, a: usize) -> f32 {
        match a {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    #[inline]
    fn add(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Sub for Vec3 {
    type Output = Vec3;
    #[inline]
    fn sub(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Mul<f32> for Vec3 {
    type Output = Vec3;
    #[inline]
    fn mul(self, s: f32) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Neg for Vec3 {
    type Output = Vec3;
    #[inline]
    fn neg(self) -> Vec3 {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}

/// A 3x3 matrix of `f64`, row-major, for affine transforms.
pub type Mat3 = [[f64; 3]; 3];

/// The 3x3 part of a 4x4 row-major affine.
pub fn linear_part(affine: &[[f64; 4]; 4]) -> Mat3 {
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
        let m = [[2.0, 0.5, 0.0], [0.0, 1.0, -1.0], [0.3, 0.0, 3.0]];
        let inv = inverse3(&m).unwrap();
        for c in 0..3 {
            let mut e = [0.0; 3];
            e[c] = 1.0;
            let back = mul3(&m, mul3(&inv, e));
            for r in 0..3 {
                assert!((back[r] - e[r]).abs() < 1e-12);
            }
        }
        assert!(inverse3(&[[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]]).is_none());
    }

    #[test]
    fn cross_follows_right_hand_rule() {
        let x = Vec3::new(1.0, 0.0, 0.0);
        let y = Vec3::new(0.0, 1.0, 0.0);
        assert_eq!(x.cross(y), Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(Vec3::ZERO.normalize_or_zero(), Vec3::ZERO);
    }
}
