//! The built-in analytic phantoms ([`Phantom`]): glint's smooth head (the default) and
//! the 3D modified Shepp-Logan head.
//!
//! Shepp-Logan: ellipsoids from the 3D extension of Shepp and Logan's head phantom (L. A. Shepp and
//! B. F. Logan, "The Fourier reconstruction of a head section", IEEE Trans. Nucl. Sci.
//! 21(3), 1974), with the "modified" contrasts of Toft (P. Toft, "The Radon Transform",
//! PhD thesis, DTU, 1996) as tabulated for 3D by M. Schabel's `phantom3d` (MATLAB
//! Central File Exchange 9416): intensity, semi-axes a b c, centre x0 y0 z0, Euler
//! angles phi theta psi in degrees. Phantom coordinates span [-1, 1]; glint maps x to
//! the patient's right, y to anterior and z to superior (RAS+) at 100 mm per unit.

use glint_io::{Samples, Volume};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use glint_core::RenderError;

/// A built-in phantom, by name (`head`, `shepp-logan`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "kebab-case")]
#[strum(serialize_all = "kebab-case", ascii_case_insensitive, parse_err_ty = RenderError, parse_err_fn = glint_core::unknown_name::<Self>)]
pub enum Phantom {
    /// glint's head ([`head`]): scalp, a skull shell, two folded hemispheres and
    /// ventricles, all with smooth edges; shown by the `head` preset as shaded anatomy
    /// behind a glassy skull.
    #[default]
    Head,
    /// The 3D modified Shepp-Logan head ([`shepp_logan`]), with the `phantom` preset.
    #[strum(serialize = "shepp_logan")]
    SheppLogan,
}

impl Phantom {
    /// Every phantom, the default first.
    pub const ALL: &'static [Phantom] = <Phantom as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`Phantom::ALL`].
    pub const NAMES: &'static [&'static str] = <Phantom as strum::VariantNames>::VARIANTS;

    /// Grid edge the CLI uses unless told otherwise.
    pub const DEFAULT_SIZE: usize = 128;

    /// The name users type.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The name of the preset made for it ([`crate::preset`]).
    pub fn preset(self) -> &'static str {
        match self {
            Phantom::Head => "head",
            Phantom::SheppLogan => "phantom",
        }
    }

    /// The phantom sampled on a `size`^3 grid spanning 200 mm (errors outside
    /// 2..=[`MAX_PHANTOM_SIZE`]).
    pub fn volume(self, size: usize) -> Result<Volume, RenderError> {
        match self {
            Phantom::Head => head(size),
            Phantom::SheppLogan => shepp_logan(size),
        }
    }
}

impl glint_lobe::names::Named for Phantom {
    const WHAT: &'static str = "phantom";
}

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
    shepp_logan_with_ramp(n, 2.0 * 2.0 / n as f64)
}

/// [`shepp_logan`] with the edges ramped over `ramp` phantom units whatever the grid:
/// the same continuous object sampled on grids of different sizes (docs/performance.md
/// compares its renders to tell reconstruction artefacts from the object's own edges).
pub fn shepp_logan_with_ramp(n: usize, ramp: f64) -> Result<Volume, RenderError> {
    if !(ramp.is_finite() && ramp >= 0.0) {
        return Err(RenderError::Parameter(format!(
            "phantom ramp {ramp}: expected a finite width >= 0"
        )));
    }
    sampled(n, |p| shepp_logan_blurred(p, ramp))
}

/// `f` (phantom units in, value out) on an `n`^3 grid of voxel centres spanning
/// [-1, 1]^3, as a RAS+ volume of [`MM_PER_UNIT`] mm per unit.
fn sampled(n: usize, f: impl Fn([f64; 3]) -> f64 + Sync) -> Result<Volume, RenderError> {
    if !(2..=MAX_PHANTOM_SIZE).contains(&n) {
        return Err(RenderError::Parameter(format!(
            "phantom size {n}: expected 2..={MAX_PHANTOM_SIZE}"
        )));
    }
    let unit = 2.0 / n as f64;
    let coord = |i: usize| -1.0 + (i as f64 + 0.5) * unit;
    let mut data = vec![0.0f32; n * n * n];
    data.par_chunks_mut(n * n)
        .enumerate()
        .for_each(|(k, slab)| {
            for j in 0..n {
                for i in 0..n {
                    slab[i + n * j] = f([coord(i), coord(j), coord(k)]) as f32;
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

/// glint's head phantom, in millimetres (RAS+, centre at the origin): nested layers,
/// each `[increment, a, b, c, x0, y0, z0]` (value added inside an ellipsoid of semi-axes
/// a b c centred at x0 y0 z0). Scalp 0.1, skull 0.25, cerebrospinal fluid 0.35, brain
/// 0.6, ventricles 0.85: every boundary separates neighbouring values, so no edge's
/// ramp passes through a third tissue's values (which a transfer function would show as
/// a false shell). The sizes are a rough adult head (skull 6 mm thick), chosen here.
pub const HEAD_LAYERS: [[f64; 7]; 3] = [
    [0.10, 74.0, 96.0, 86.0, 0.0, 0.0, 0.0],
    [0.15, 69.0, 91.0, 81.0, 0.0, 0.0, 0.0],
    [0.10, 63.0, 85.0, 75.0, 0.0, 0.0, 0.0],
];

/// The two hemispheres (value +0.25 inside) of [`head`]: `[a, b, c, x0, y0, z0]`, the
/// second mirrored in x; the gap between them is the longitudinal fissure.
pub const HEAD_HEMISPHERE: [f64; 6] = [27.0, 77.0, 63.0, 30.0, -3.0, 2.0];

/// The lateral ventricles (value +0.25 inside the brain): `[a, b, c, x0, y0, z0]`,
/// mirrored in x.
pub const HEAD_VENTRICLE: [f64; 6] = [5.0, 20.0, 9.0, 13.0, 0.0, 10.0];

/// Depth (mm) of the hemispheres' folds: their surface moves by up to this along its
/// normal, in smooth waves about 30 and 17 mm long (gyri and sulci, stylised).
pub const HEAD_FOLD_MM: f64 = 2.5;

/// Signed distance (mm, first order: `(s - 1) / |grad s|`) from `p` to the surface of
/// the axis-aligned ellipsoid `[a, b, c, x0, y0, z0]`, negative inside.
fn ellipsoid_distance(p: [f64; 3], e: &[f64]) -> f64 {
    let q = [p[0] - e[3], p[1] - e[4], p[2] - e[5]];
    let s: f64 = (0..3).map(|i| (q[i] / e[i]).powi(2)).sum();
    let grad = 2.0
        * (0..3)
            .map(|i| (q[i] / (e[i] * e[i])).powi(2))
            .sum::<f64>()
            .sqrt();
    if grad > 0.0 {
        (s - 1.0) / grad
    } else {
        -e[0].min(e[1]).min(e[2])
    }
}

/// How much of a ramp of width `h` centred on a surface lies inside at signed distance
/// `d`: a smoothstep from 1 (inside) to 0, so the value and its gradient are continuous
/// (smooth normals for shading; a linear ramp's kinks show as bands).
fn inside(d: f64, h: f64) -> f64 {
    let t = (0.5 - d / h).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// [`head`]'s value at `p` (mm) with edges ramped over `h` mm.
pub fn head_value(p: [f64; 3], h: f64) -> f64 {
    let mut v = 0.0;
    for l in &HEAD_LAYERS {
        v += l[0] * inside(ellipsoid_distance(p, &l[1..]), h);
    }
    let folds = HEAD_FOLD_MM
        * (0.65 * (0.21 * p[0] + 0.7).sin() * (0.2 * p[1]).sin() * (0.23 * p[2] + 1.3).sin()
            + 0.35 * (0.37 * p[1] + 0.4).sin() * (0.33 * p[2]).sin());
    let mirrored = |e: [f64; 6], sign: f64| [e[0], e[1], e[2], sign * e[3], e[4], e[5]];
    let hemi = [1.0, -1.0].map(|sx| {
        inside(
            ellipsoid_distance(p, &mirrored(HEAD_HEMISPHERE, sx)) + folds,
            h,
        )
    });
    v += 0.25 * hemi[0].max(hemi[1]);
    let vent =
        [1.0, -1.0].map(|sx| inside(ellipsoid_distance(p, &mirrored(HEAD_VENTRICLE, sx)), h));
    v += 0.25 * vent[0].max(vent[1]);
    v
}

/// Width, in voxels, of the smooth ramps at [`head`]'s edges. Trilinear interpolation
/// is only C0, so an edge's rendered opacity and shading depend on where it falls
/// between voxel planes: a surface facing the camera shows that as concentric
/// "wood-grain" rings. Measured with `Image::ring_measure` (examples/rings.rs, the
/// default 512x512 anterior view, step 0.5): ramps of 2, 3 and 4 voxels gave 1.37, 1.03
/// and 0.77 grey levels, the rest at 4 being the brain's folds.
pub const HEAD_RAMP_VOXELS: f64 = 4.0;

/// glint's head phantom ([`HEAD_LAYERS`]) on an `n`^3 grid spanning 200 mm, edges
/// ramped over [`HEAD_RAMP_VOXELS`].
pub fn head(n: usize) -> Result<Volume, RenderError> {
    head_with_ramp(n, HEAD_RAMP_VOXELS * 2.0 * MM_PER_UNIT / n as f64)
}

/// [`head`] with the edges ramped over `ramp` mm whatever the grid: the same object on
/// grids of different sizes (as [`shepp_logan_with_ramp`]; here the ramp must be
/// wider than 0, the smooth step dividing by it).
pub fn head_with_ramp(n: usize, ramp: f64) -> Result<Volume, RenderError> {
    if !(ramp.is_finite() && ramp > 0.0) {
        return Err(RenderError::Parameter(format!(
            "phantom ramp {ramp} mm: expected a finite width > 0"
        )));
    }
    sampled(n, |p| head_value(p.map(|x| x * MM_PER_UNIT), ramp))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fixed_ramp_is_the_same_object_on_any_grid() {
        // The 32 and 96 grids share voxel centres: 96-grid voxel 3i + 1 is 32-grid voxel i.
        let ramp = 4.0 / 32.0;
        let (a, b) = (
            shepp_logan_with_ramp(32, ramp).unwrap(),
            shepp_logan_with_ramp(96, ramp).unwrap(),
        );
        let (c, d) = (shepp_logan(32).unwrap(), shepp_logan(96).unwrap());
        let (mut ramped, mut own) = (0, 0);
        for k in 0..32 {
            for j in 0..32 {
                for i in 0..32 {
                    let x = a.value(i, j, k);
                    assert_eq!(x, b.value(3 * i + 1, 3 * j + 1, 3 * k + 1), "{i} {j} {k}");
                    let p = [i, j, k].map(|v| -1.0 + (v as f64 + 0.5) * 2.0 / 32.0);
                    ramped += usize::from(x != shepp_logan_value(p) as f32 as f64);
                    own +=
                        usize::from(c.value(i, j, k) != d.value(3 * i + 1, 3 * j + 1, 3 * k + 1));
                }
            }
        }
        // Many shared centres lie in the ramps, and each grid's own ramp differs there.
        assert!(ramped > 1000, "{ramped}");
        assert!(own > 1000, "{own}");
        for bad in [f64::NAN, -0.1, f64::INFINITY] {
            assert!(shepp_logan_with_ramp(8, bad).is_err());
            assert!(head_with_ramp(8, bad).is_err());
        }
        assert!(head_with_ramp(8, 0.0).is_err());
        // The head's default ramp is HEAD_RAMP_VOXELS voxels of its grid.
        let h = head_with_ramp(32, HEAD_RAMP_VOXELS * 200.0 / 32.0).unwrap();
        assert_eq!(h.to_f32(), head(32).unwrap().to_f32());
    }

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

    #[test]
    fn phantoms_by_name() {
        for &p in Phantom::ALL {
            assert_eq!(p.name().parse::<Phantom>().unwrap(), p);
            assert_eq!(p.to_string(), p.name());
            let json = serde_json::to_string(&p).unwrap();
            assert_eq!(json, format!("\"{}\"", p.name()));
            assert!(crate::presets::preset(p.preset()).is_ok());
        }
        assert_eq!(Phantom::default(), Phantom::Head);
        assert_eq!(
            "Shepp_Logan".parse::<Phantom>().unwrap(),
            Phantom::SheppLogan
        );
        assert!("brain".parse::<Phantom>().is_err());
        assert!(Phantom::Head.volume(1).is_err());
    }

    #[test]
    fn head_layers_have_their_values() {
        // Sharp edges (h = 0.01 mm): values from the layer table, by hand.
        let v = |p: [f64; 3]| head_value(p, 0.01);
        assert_eq!(v([0.0, 0.0, 100.0]), 0.0); // outside
        assert!((v([0.0, 0.0, 84.0]) - 0.1).abs() < 1e-12); // scalp (skull ends at 81)
        assert!((v([0.0, 0.0, 78.0]) - 0.25).abs() < 1e-12); // skull (75..81)
        assert!((v([0.0, 0.0, 72.0]) - 0.35).abs() < 1e-12); // CSF above the fissure
        assert!((v([30.0, -3.0, 2.0]) - 0.6).abs() < 1e-12); // a hemisphere's centre
        assert!((v([-13.0, 0.0, 10.0]) - 0.85).abs() < 1e-12); // a ventricle's centre
                                                               // The ramp is half-way on an unfolded surface: the skull's top at z = 81.
        assert!((head_value([0.0, 0.0, 81.0], 4.0) - 0.1 - 0.15 / 2.0).abs() < 1e-9);
        let vol = head(32).unwrap();
        assert_eq!(vol.dims, [32; 3]);
    }
}
