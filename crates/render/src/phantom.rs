//! The built-in analytic phantom: the 3D modified Shepp-Logan head.
//!
//! Ellipsoids from the 3D extension of Shepp and Logan's head phantom (L. A. Shepp and
//! B. F. Logan, "The Fourier reconstruction of a head section", IEEE Trans. Nucl. Sci.
//! 21(3), 1974), with the "modified" contrasts of Toft (P. Toft, "The Radon Transform",
//! PhD thesis, DTU, 1996) as tabulated for 3D by M. Schabel's `phantom3d` (MATLAB
//! Central File Exchange 9416): intensity, semi-axes a b c, centre x0 y0 z0, Euler
//! angles phi theta psi in degrees. Phantom coordinates span [-1, 1]; glint maps x to
//! the patient's right, y to anterior and z to superior (RAS+) at 100 mm per unit.

use glint_io::{Samples, Volume};

use crate::error::RenderError;

/// `[A, a, b, c, x0, y0, z0, phi, theta, psi]` per ellipsoid.
pub const SHEPP_LOGAN_3D: [[f64; 10]; 10] = [
    [1.0, 0.6900, 0.920, 0.810, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-0.8, 0.6624, 0.874, 0.780, 0.0, -0.0184, 0.0, 0.0, 0.0, 0.0],
    [-0.2, 0.1100, 0.310, 0.220, 0.22, 0.0, 0.0, -18.0, 0.0, 10.0],
    [-0.2, 0.1600, 0.410, 0.280, -0.22, 0.0, 0.0, 18.0, 0.0, 10.0],
    [0.1, 0.2100, 0.250, 0.410, 0.0, 0.35, -0.15, 0.0, 0.0, 0.0],
    [0.1, 0.0460, 0.046, 0.050, 0.0, 0.1, 0.25, 0.0, 0.0, 0.0],
    [0.1, 0.0460, 0.046, 0.050, 0.0, -0.1, 0.25, 0.0, 0.0, 0.0],
    [0.1, 0.0460, 0.023, 0.050, -0.08, -0.605, 0.0, 0.0, 0.0, 0.0],
    [0.1, 0.0230, 0.023, 0.020, 0.0, -0.606, 0.0, 0.0, 0.0, 0.0],
    [0.1, 0.0230, 0.046, 0.020, 0.06, -0.605, 0.0, 0.0, 0.0, 0.0],
];

/// Millimetres per phantom unit.
pub const MM_PER_UNIT: f64 = 100.0;

/// Largest grid edge [`shepp_logan`] builds (1024^3 f32 = 4 GiB).
pub const MAX_PHANTOM_SIZE: usize = 1024;

/// Euler rotation matrix of `phantom3d` (rows map world to ellipsoid frame).
fn rotation(phi: f64, theta: f64, psi: f64) -> [[f64; 3]; 3] {
    let (sp, cp) = phi.to_radians().sin_cos();
    let (st, ct) = theta.to_radians().sin_cos();
    let (ss, cs) = psi.to_radians().sin_cos();
    [
        [cs * cp - ct * sp * ss, cs * sp + ct * cp * ss, ss * st],
        [-ss * cp - ct * sp * cs, -ss * sp + ct * cp * cs, cs * st],
        [st * sp, -st * cp, ct],
    ]
}

/// The phantom's value at a point in phantom units: the sum of the intensities of the
/// ellipsoids containing it.
pub fn shepp_logan_value(p: [f64; 3]) -> f64 {
    shepp_logan_blurred(p, 0.0)
}

/// The phantom with each ellipsoid's edge ramped linearly over a width `h` (phantom
/// units) centred on the surface: a partial-volume ("anti-aliased") sampling that
/// gives smooth gradients. `h = 0` is the exact phantom.
///
/// The distance to an ellipsoid is approximated to first order by
/// `(s - 1) / |grad s|` with `s = (x/a)^2 + (y/b)^2 + (z/c)^2`.
pub fn shepp_logan_blurred(p: [f64; 3], h: f64) -> f64 {
    let mut v = 0.0;
    for e in &SHEPP_LOGAN_3D {
        let r = rotation(e[7], e[8], e[9]);
        let q = [
            r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2] - e[4],
            r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2] - e[5],
            r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2] - e[6],
        ];
        let s = (q[0] / e[1]).powi(2) + (q[1] / e[2]).powi(2) + (q[2] / e[3]).powi(2);
        if h <= 0.0 {
            if s <= 1.0 {
                v += e[0];
            }
            continue;
        }
        let grad = (4.0
            * ((q[0] / (e[1] * e[1])).powi(2)
                + (q[1] / (e[2] * e[2])).powi(2)
                + (q[2] / (e[3] * e[3])).powi(2)))
        .sqrt();
        let dist = if grad > 0.0 { (s - 1.0) / grad } else { -1.0 };
        v += e[0] * (0.5 - dist / h).clamp(0.0, 1.0);
    }
    v
}

/// The phantom sampled on an `n`^3 grid of voxel centres spanning [-1, 1]^3 (200 mm),
/// in RAS+ millimetres, with edges ramped over two voxels ([`shepp_logan_blurred`]) so
/// trilinear samples and gradients of the thin skull are smooth.
pub fn shepp_logan(n: usize) -> Result<Volume, RenderError> {
    if !(2..=MAX_PHANTOM_SIZE).contains(&n) {
        return Err(RenderError::Parameter(format!(
            "phantom size {n}: expected 2..={MAX_PHANTOM_SIZE}"
        )));
    }
    let unit = 2.0 / n as f64;
    let coord = |i: usize| -1.0 + (i as f64 + 0.5) * unit;
    let mut data = vec![0.0f32; n * n * n];
    use rayon::prelude::*;
    data.par_chunks_mut(n * n)
        .enumerate()
        .for_each(|(k, slab)| {
            for j in 0..n {
                for i in 0..n {
                    slab[i + n * j] =
                        shepp_logan_blurred([coord(i), coord(j), coord(k)], 2.0 * unit) as f32;
                }
            }
        });
    let spacing = unit * MM_PER_UNIT;
    let mut vol = Volume::new([n; 3], [spacing; 3], Samples::F32(data))
        .map_err(|e| RenderError::Volume(e.to_string()))?;
    for a in 0..3 {
        vol.affine[a][3] = coord(0) * MM_PER_UNIT;
    }
    Ok(vol)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // Centre: skull (1) + brain (-0.8) = 0.2 (the ventricles start at |x| ~ 0.1).
        assert!((shepp_logan_value([0.0, 0.0, 0.0]) - 0.2).abs() < 1e-12);
        // In the skull shell along x: inside the outer (0.69) but not the inner (0.6624).
        assert!((shepp_logan_value([0.68, 0.0, 0.0]) - 1.0).abs() < 1e-12);
        // Outside.
        assert_eq!(shepp_logan_value([0.7, 0.0, 0.0]), 0.0);
        // Centre of the large ellipsoid 5 (0, 0.35, -0.15): 0.2 + 0.1.
        assert!((shepp_logan_value([0.0, 0.35, -0.15]) - 0.3).abs() < 1e-12);
    }

    #[test]
    fn volume_is_centred() {
        let v = shepp_logan(16).unwrap();
        // Voxel centres are symmetric about 0: first and last at ±(100 - 6.25) mm.
        assert!((v.affine[0][3] + 93.75).abs() < 1e-9);
        assert!((v.affine[0][0] * 15.0 + v.affine[0][3] - 93.75).abs() < 1e-9);
        assert!(shepp_logan(0).is_err());
        // Far from edges the ramped phantom equals the exact one; on the outer surface
        // (x = 0.69) it is half of the skull's 1.
        assert!((shepp_logan_blurred([0.0, 0.0, 0.0], 0.02) - 0.2).abs() < 1e-12);
        assert!((shepp_logan_blurred([0.69, 0.0, 0.0], 0.02) - 0.5).abs() < 1e-9);
    }
}

/// The built-in phantoms, by the names users type.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phantom {
    /// The 3D modified Shepp-Logan head ([`shepp_logan`]).
    #[default]
    SheppLogan,
}

impl Phantom {
    /// Every phantom.
    pub const ALL: [Phantom; 1] = [Phantom::SheppLogan];

    /// The name users type.
    pub fn name(self) -> &'static str {
        match self {
            Phantom::SheppLogan => "shepp-logan",
        }
    }

    /// The phantom sampled on a `size`^3 grid.
    pub fn volume(self, size: usize) -> Result<Volume, RenderError> {
        match self {
            Phantom::SheppLogan => shepp_logan(size),
        }
    }
}

impl std::fmt::Display for Phantom {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Phantom {
    type Err = RenderError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let key = s.trim().to_ascii_lowercase();
        Phantom::ALL
            .into_iter()
            .find(|p| p.name() == key)
            .ok_or_else(|| {
                let names: Vec<_> = Phantom::ALL.iter().map(|p| p.name()).collect();
                RenderError::Parameter(format!(
                    "unknown phantom '{s}': expected {}",
                    names.join(", ")
                ))
            })
    }
}
