//! Isosurfaces of volumes: marching cubes (Lorensen and Cline 1987) with a table that
//! resolves ambiguous faces consistently, so the surface is watertight; vertex normals
//! from the volume's gradient (central differences, as VTK's vtkFlyingEdges3D and
//! vtkMarchingCubes compute them); optional Taubin smoothing.
//!
//! The passes over the volume are those of flying edges (isosurface/flying.rs): parallel
//! over rows of voxels, the output written at offsets from a prefix sum, so the mesh
//! is the same bytes whatever the number of threads.

mod flying;
mod table;

use glint_io::{IoError, Mesh, Samples, Volume};
use rayon::prelude::*;

use glint_io::affine::{det3, inverse3, linear_part, transpose3, Mat3};

use crate::normals::vertex_normals;
use crate::{MeshError, MAX_VOXELS};

/// Taubin's λ|μ smoothing (Taubin 1995, "A signal processing approach to fair
/// surface design"): a shrinking step of `lambda` then an inflating step of `mu`
/// towards the neighbours' mean, `iterations` times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Taubin {
    /// λ|μ pairs of steps.
    pub iterations: u32,
    /// The shrinking factor, in (0, 1).
    pub lambda: f32,
    /// The inflating factor, negative, with |μ| > λ.
    pub mu: f32,
}

impl Default for Taubin {
    /// λ = 0.5, μ = -0.53: pass-band frequency 1/λ + 1/μ ≈ 0.1, in the range Taubin
    /// recommends (0.01 to 0.1); 10 iterations.
    fn default() -> Self {
        Taubin {
            iterations: 10,
            lambda: 0.5,
            mu: -0.53,
        }
    }
}

impl Taubin {
    /// Checks `0 < λ < 1`, `μ < -λ` and at most 1000 iterations.
    pub fn validate(&self) -> Result<(), MeshError> {
        let ok = self.lambda.is_finite()
            && self.mu.is_finite()
            && self.lambda > 0.0
            && self.lambda < 1.0
            && self.mu < -self.lambda
            && self.mu > -1.0
            && self.iterations <= 1000;
        if ok {
            Ok(())
        } else {
            Err(MeshError::Parameter(format!(
                "Taubin smoothing λ = {}, μ = {}, {} iterations: expected 0 < λ < 1, -1 < μ < -λ, at most 1000 iterations",
                self.lambda, self.mu, self.iterations
            )))
        }
    }
}

/// The isosurface of `volume` at `iso` (physical values): triangles counter-clockwise
/// seen from the side of lower values, unit normals pointing there (down the
/// gradient), positions in world mm. Values at least `iso` are inside; NaN samples are
/// outside. Closed wherever the surface does not reach the volume's border.
///
/// Reads the stored samples in place (integers scaled by a positive slope, or f32
/// without scaling); other volumes are converted to f32 first.
pub fn extract(volume: &Volume, iso: f32) -> Result<Mesh, MeshError> {
    if volume.len() > MAX_VOXELS {
        return Err(MeshError::Volume(format!(
            "{} voxels: at most {MAX_VOXELS}",
            volume.len()
        )));
    }
    let frame = Frame::new(volume.dims, &volume.affine, iso)?;
    let (s, b) = (volume.slope, volume.intercept);
    let scaled = s.is_finite() && s > 0.0 && b.is_finite();
    match &volume.samples {
        Samples::U8(v) if scaled => extract_ints(v, s, b, &frame),
        Samples::I8(v) if scaled => extract_ints(v, s, b, &frame),
        Samples::U16(v) if scaled => extract_ints(v, s, b, &frame),
        Samples::I16(v) if scaled => extract_ints(v, s, b, &frame),
        Samples::U32(v) if scaled => extract_ints(v, s, b, &frame),
        Samples::I32(v) if scaled => extract_ints(v, s, b, &frame),
        Samples::F32(v) if s == 1.0 && b == 0.0 => extract_f32(v, &frame),
        _ => extract_f32(&volume.to_f32(), &frame),
    }
}

/// The isosurface of `values` (f32 samples, i fastest, on a `dims` grid placed by
/// `affine`) at `iso`, like [`extract`]: e.g. a renderer's reconstruction values, whose
/// NaN samples it replaced (they count as outside otherwise).
pub fn extract_grid(
    values: &[f32],
    dims: [usize; 3],
    affine: &[[f64; 4]; 4],
    iso: f32,
) -> Result<Mesh, MeshError> {
    let count = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    if count != Some(values.len()) {
        return Err(MeshError::Volume(format!(
            "{} values for dims {dims:?}",
            values.len()
        )));
    }
    if values.len() > MAX_VOXELS {
        return Err(MeshError::Volume(format!(
            "{} voxels: at most {MAX_VOXELS}",
            values.len()
        )));
    }
    extract_f32(values, &Frame::new(dims, affine, iso)?)
}

/// The grid's shape and placement, the iso value, and what the vertices need.
struct Frame {
    dims: [usize; 3],
    iso: f32,
    affine: [[f64; 4]; 4],
    /// Index-space gradient to world gradient: the inverse transpose of the affine's
    /// linear part.
    grad_to_world: [[f32; 3]; 3],
    /// The affine mirrors (negative determinant): reverse the triangles.
    flip: bool,
}

impl Frame {
    /// Checks the dims (at least 2 samples per axis), the iso value and the affine.
    fn new(dims: [usize; 3], affine: &[[f64; 4]; 4], iso: f32) -> Result<Frame, MeshError> {
        if dims.iter().any(|&d| d < 2) {
            return Err(MeshError::Volume(format!(
                "dims {dims:?}: an isosurface needs at least 2 samples along each axis"
            )));
        }
        if !iso.is_finite() {
            return Err(MeshError::Parameter(format!(
                "iso value {iso}: expected a finite number"
            )));
        }
        let m = linear_part(affine);
        let det = det3(&m);
        let inv = inverse3(&m)
            .filter(|_| det.is_finite() && det != 0.0)
            .ok_or_else(|| MeshError::Volume("the voxel-to-world affine is singular".into()))?;
        Ok(Frame {
            dims,
            iso,
            affine: *affine,
            grad_to_world: to_f32(&transpose3(&inv)),
            flip: det < 0.0,
        })
    }
}

fn to_f32(m: &Mat3) -> [[f32; 3]; 3] {
    m.map(|r| r.map(|x| x as f32))
}

/// Integer sample types, with their range.
trait Int: flying::Raw {
    const MIN: i64;
    const MAX: i64;
    /// `x`, which is within `MIN..=MAX`.
    fn from_i64(x: i64) -> Self;
}

macro_rules! int {
    ($($t:ty),*) => {$(
        impl Int for $t {
            const MIN: i64 = <$t>::MIN as i64;
            const MAX: i64 = <$t>::MAX as i64;
            #[inline]
            fn from_i64(x: i64) -> Self {
                x as $t
            }
        }
    )*};
}
int!(u8, i8, u16, i16, u32, i32);

/// Integer samples with physical values `slope * x + intercept`, `slope > 0`: the
/// physical value (computed in f64, rounded to f32) never decreases with `x`, so the
/// inside samples are those at least the smallest inside one, found by bisection.
fn extract_ints<T: Int>(
    values: &[T],
    slope: f64,
    intercept: f64,
    frame: &Frame,
) -> Result<Mesh, MeshError> {
    let inside = |x: i64| (slope * x as f64 + intercept) as f32 >= frame.iso;
    if !inside(T::MAX) {
        return Ok(empty());
    }
    // Invariant: `hi` is inside, `lo` is not (or lo == hi == MIN).
    let (mut lo, mut hi) = (T::MIN, T::MAX);
    if inside(lo) {
        hi = lo;
    }
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if inside(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let src = flying::Scaled {
        slope,
        intercept,
        lo: T::from_i64(hi),
    };
    run(values, src, frame)
}

/// f32 samples, their own physical values.
fn extract_f32(values: &[f32], frame: &Frame) -> Result<Mesh, MeshError> {
    let src = flying::Scaled {
        slope: 1.0,
        intercept: 0.0,
        lo: frame.iso,
    };
    run(values, src, frame)
}

fn run<S: flying::Source>(values: &[S::T], src: S, frame: &Frame) -> Result<Mesh, MeshError> {
    let grid = flying::Grid { values, src, frame };
    let out = grid.extract().map_err(|_| {
        MeshError::Volume("the isosurface has more than 2^32 vertices or triangles".into())
    })?;
    Ok(Mesh {
        positions: out.positions,
        triangles: out.triangles,
        normals: Some(out.normals),
        scalars: None,
    })
}

fn empty() -> Mesh {
    Mesh {
        positions: Vec::new(),
        triangles: Vec::new(),
        normals: Some(Vec::new()),
        scalars: None,
    }
}

/// Smooths `mesh` in place with Taubin's λ|μ steps (each vertex moves towards the
/// mean of its neighbours along triangle edges; an edge shared by two triangles counts
/// twice, which leaves the mean unchanged inside a closed surface), then recomputes
/// the normals from the triangles (the volume's gradient no longer describes the
/// moved surface).
pub fn taubin_smooth(mesh: &mut Mesh, params: &Taubin) -> Result<(), MeshError> {
    params.validate()?;
    mesh.validate().map_err(MeshError::Mesh)?;
    let n = mesh.positions.len();
    if n >= u32::MAX as usize {
        return Err(MeshError::Mesh(IoError::Inconsistent(format!(
            "{n} vertices: too many"
        ))));
    }
    // Neighbour lists in compressed rows.
    let mut start = vec![0u32; n + 1];
    for t in &mesh.triangles {
        for &v in t {
            start[v as usize + 1] += 2;
        }
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut nbr = vec![0u32; start[n] as usize];
    for t in &mesh.triangles {
        for k in 0..3 {
            let v = t[k] as usize;
            for o in [t[(k + 1) % 3], t[(k + 2) % 3]] {
                nbr[fill[v] as usize] = o;
                fill[v] += 1;
            }
        }
    }
    let mut cur = mesh.positions.clone();
    for _ in 0..params.iterations {
        for f in [params.lambda, params.mu] {
            cur = (0..n)
                .into_par_iter()
                .map(|v| {
                    let ns = &nbr[start[v] as usize..start[v + 1] as usize];
                    let p = cur[v];
                    if ns.is_empty() {
                        return p;
                    }
                    let mut mean = [0.0f32; 3];
                    for &o in ns {
                        (0..3).for_each(|d| mean[d] += cur[o as usize][d]);
                    }
                    let inv = 1.0 / ns.len() as f32;
                    std::array::from_fn(|d| p[d] + f * (mean[d] * inv - p[d]))
                })
                .collect();
        }
    }
    mesh.positions = cur;
    mesh.normals = Some(vertex_normals(&mesh.positions, &mesh.triangles));
    Ok(())
}
