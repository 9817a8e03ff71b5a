//! One closed, smoothed surface per label: the label's indicator (1 inside, 0
//! outside) blurred with a Gaussian, compared with the blurred indicators of the
//! background and of the other labels, and the zero level of the difference extracted
//! by glint-mesh's marching cubes.
//!
//! Why this way: a label's voxels are a set of cubes, and their boundary, or an
//! isosurface of the raw indicator, shows the voxel stairs; smoothing each surface
//! afterwards (Taubin), or thresholding each blurred indicator at 1/2, moves the two
//! sides of a boundary that two labels share apart (a gap, or an overlap and
//! z-fighting). Classifying each point by the label whose blurred indicator is largest
//! (the "smoothed label map" of 3D Slicer's joint smoothing, here with the other labels
//! lumped into one competitor so one blur of the foreground serves every label) puts a
//! shared boundary where the two blurred indicators are equal, the same points for
//! both labels.

use glint_io::Mesh;
use rayon::prelude::*;

use crate::{LabelError, LabelExtent, LabelGrid};

/// The largest smoothing accepted, in voxels of the grid's coarsest axis.
pub const MAX_SMOOTHING: f32 = 8.0;

/// The smoothing a label map's surfaces get when none is asked for, in voxels of the
/// grid's coarsest axis, from its voxel spacing (mm): 1 for grids whose coarsest axis
/// is at most 1.5 times the finest (isotropic data keep a Gaussian of one voxel), 2
/// from 2.5 times on (thick slices: 2.5 or 3 mm under 0.7 to 0.8 mm pixels), linear
/// between.
///
/// Why: a shallow surface cut by slices `dz` apart is a staircase of steps `dz` high
/// and `dz / slope` wide in plane. A Gaussian of `σ = smoothing · dz` damps the
/// staircase's first harmonic by `exp(-2π² σ² slope²)`: scale-free, so one voxel
/// leaves the same relative ripple on a 1 mm grid as on a 3 mm one, but the thick
/// slices' ripple is three times larger on the same organ, and shows as terrace bands
/// (issue 42, item 6c). On a surface at 11° from the slices (slope 0.19) one voxel
/// leaves 50% of the ripple, two voxels 6%; the cost is
/// structures thinner than about `1.2 σ` in radius against the background (measured
/// in docs/formats.md).
pub fn default_label_smoothing(spacing: [f64; 3]) -> f32 {
    let coarsest = spacing.iter().cloned().fold(0.0, f64::max);
    let finest = spacing.iter().cloned().fold(f64::INFINITY, f64::min);
    if !(finest > 0.0 && coarsest.is_finite()) {
        return 1.0;
    }
    ((coarsest / finest - 0.5).clamp(1.0, 2.0)) as f32
}

/// The blur of a grid: per-axis standard deviations (voxels) and kernels.
struct Blur {
    sigma: [f64; 3],
    kernels: [Vec<f32>; 3],
    /// Kernel radius + 1: the background margin around every crop.
    pad: [usize; 3],
}

impl Blur {
    fn new(grid: &LabelGrid, smoothing: f32) -> Result<Blur, LabelError> {
        if !smoothing.is_finite() || !(0.0..=MAX_SMOOTHING).contains(&smoothing) {
            return Err(LabelError::Parameter(format!(
                "smoothing {smoothing}: expected 0 to {MAX_SMOOTHING} voxels"
            )));
        }
        let spacing = grid.spacing();
        let coarsest = spacing.iter().cloned().fold(0.0, f64::max);
        let sigma = spacing.map(|s| f64::from(smoothing) * coarsest / s);
        let radius = sigma.map(|s| (3.0 * s).ceil() as usize);
        Ok(Blur {
            sigma,
            kernels: std::array::from_fn(|a| gaussian(sigma[a], radius[a])),
            pad: radius.map(|r| r + 1),
        })
    }

    /// Blurs `values` (a `dims` grid) along each axis with a positive sigma.
    fn apply(&self, mut values: Vec<f32>, dims: [usize; 3]) -> Vec<f32> {
        for a in 0..3 {
            if self.sigma[a] > 0.0 {
                values = blur_axis(&values, dims, a, &self.kernels[a]);
            }
        }
        values
    }
}

/// The blurred foreground (every label but 0) on the grid padded by the blur's margin
/// on each side, so every crop's values can be read from it.
struct Foreground {
    dims: [usize; 3],
    values: Vec<f32>,
}

impl Foreground {
    fn new(grid: &LabelGrid, blur: &Blur) -> Result<Foreground, LabelError> {
        let dims: [usize; 3] = std::array::from_fn(|a| grid.dims[a] + 2 * blur.pad[a]);
        let count = checked_count(dims, "the padded grid")?;
        let mut values = vec![0.0f32; count];
        let [nx, ny, _] = grid.dims;
        for (i, &l) in grid.labels.iter().enumerate() {
            if l != 0 {
                let p = [i % nx, i / nx % ny, i / (nx * ny)];
                let q: [usize; 3] = std::array::from_fn(|a| p[a] + blur.pad[a]);
                values[q[0] + dims[0] * (q[1] + dims[1] * q[2])] = 1.0;
            }
        }
        Ok(Foreground {
            dims,
            values: blur.apply(values, dims),
        })
    }
}

fn checked_count(dims: [usize; 3], what: &str) -> Result<usize, LabelError> {
    dims.iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d))
        .filter(|&n| n <= glint_mesh::MAX_VOXELS)
        .ok_or_else(|| {
            LabelError::Parameter(format!(
                "{what} ({dims:?}) is over {} voxels",
                glint_mesh::MAX_VOXELS
            ))
        })
}

/// The surface of label `value` (whose `extent` is [`LabelGrid::summary`]'s), and the
/// fraction of the label's voxels whose centres it keeps inside: the zero
/// level of `g = f - max(b, o)`, where `f` is the label's blurred indicator, `b` the
/// blurred background (`1 - F`, `F` the blurred foreground) and `o = F - f` the other
/// labels': the label against its strongest competitor. Where the label meets only the
/// background this is `f = 1/2`; where it meets one other label B, `f = f_B`, and B's
/// surface is the same zero level with the opposite sign (bit for bit: float
/// subtraction is antisymmetric), so the two surfaces share their vertices.
fn label_surface(
    grid: &LabelGrid,
    value: u32,
    extent: &LabelExtent,
    blur: &Blur,
    fg: &Foreground,
) -> Result<(Mesh, f64), LabelError> {
    let pad = blur.pad;
    let size: [usize; 3] = std::array::from_fn(|a| extent.hi[a] - extent.lo[a] + 1 + 2 * pad[a]);
    let count = checked_count(size, &format!("label {value}'s crop"))?;
    let mut values = vec![0.0f32; count];
    let [nx, ny, _] = grid.dims;
    for k in extent.lo[2]..=extent.hi[2] {
        for j in extent.lo[1]..=extent.hi[1] {
            let row = nx * (j + ny * k);
            let out = size[0] * (j - extent.lo[1] + pad[1] + size[1] * (k - extent.lo[2] + pad[2]));
            for i in extent.lo[0]..=extent.hi[0] {
                if grid.labels[row + i] == value {
                    values[out + i - extent.lo[0] + pad[0]] = 1.0;
                }
            }
        }
    }
    let mut values = blur.apply(values, size);
    // The crop's voxel (0, 0, 0) is grid voxel lo - pad, padded-foreground voxel lo.
    for k in 0..size[2] {
        for j in 0..size[1] {
            let row = size[0] * (j + size[1] * k);
            let frow =
                extent.lo[0] + fg.dims[0] * (extent.lo[1] + j + fg.dims[1] * (extent.lo[2] + k));
            for i in 0..size[0] {
                let f = values[row + i];
                let all = fg.values[frow + i];
                values[row + i] = f - (1.0 - all).max(all - f);
            }
        }
    }
    let mut kept = 0u64;
    for k in extent.lo[2]..=extent.hi[2] {
        for j in extent.lo[1]..=extent.hi[1] {
            let row = nx * (j + ny * k);
            let out = size[0] * (j - extent.lo[1] + pad[1] + size[1] * (k - extent.lo[2] + pad[2]));
            for i in extent.lo[0]..=extent.hi[0] {
                if grid.labels[row + i] == value && values[out + i - extent.lo[0] + pad[0]] > 0.0 {
                    kept += 1;
                }
            }
        }
    }
    let kept = kept as f64 / extent.voxels.max(1) as f64;
    let mut affine = grid.affine;
    for row in affine.iter_mut().take(3) {
        row[3] += (0..3)
            .map(|a| row[a] * (extent.lo[a] as f64 - pad[a] as f64))
            .sum::<f64>();
    }
    Ok((glint_mesh::extract_grid(&values, size, &affine, 0.0)?, kept))
}

/// The surfaces of the labels in `values` that the grid holds, in world mm: normals
/// outwards, triangles counter-clockwise seen from outside, closed (crops are padded
/// with background, so labels touching the grid's border are closed there too).
/// `smoothing` is the Gaussian's standard deviation in voxels of the grid's coarsest
/// axis (the same length in mm along every axis); 0 gives the voxels' stairs.
/// Extracted in parallel, in the order of `values`; labels absent from the grid are
/// left out.
pub fn label_surfaces(
    grid: &LabelGrid,
    values: &[u32],
    smoothing: f32,
) -> Result<Vec<(u32, Mesh)>, LabelError> {
    let surfaces = surfaces_at(grid, values, smoothing)?;
    Ok(surfaces.into_iter().map(|(v, m, _)| (v, m)).collect())
}

/// The surfaces of `values` at `smoothing`, with the fraction of each label's voxels
/// they keep.
fn surfaces_at(
    grid: &LabelGrid,
    values: &[u32],
    smoothing: f32,
) -> Result<Vec<(u32, Mesh, f64)>, LabelError> {
    let blur = Blur::new(grid, smoothing)?;
    let summary = grid.summary();
    let fg = Foreground::new(grid, &blur)?;
    values
        .par_iter()
        .filter_map(|v| summary.get(v).map(|e| (*v, e)))
        .map(|(v, e)| label_surface(grid, v, e, &blur, &fg).map(|(m, k)| (v, m, k)))
        .collect()
}

/// The least fraction of a label's voxels (their centres) that the default smoothing
/// must keep inside the label's surface; a thinner label keeps one voxel's smoothing
/// ([`label_surfaces_keeping_thin`]).
pub const MIN_KEPT: f64 = 0.8;

/// The surfaces of [`label_surfaces`] at `smoothing`, but each label whose surface
/// would keep less than [`MIN_KEPT`] of its voxels inside (a vessel, a rib, a
/// cartilage a few voxels thick, which a wide Gaussian thins or removes: the blurred
/// indicator of a slab of half-thickness `t` stays above one half only while
/// `t > 0.67 σ`) extracted at `fallback` instead. Returns, per label, the surface and
/// the smoothing it got. Where a thin label meets another, the two surfaces come
/// from different blurs and no longer share their vertices (a sliver of gap or
/// overlap along the contact).
pub fn label_surfaces_keeping_thin(
    grid: &LabelGrid,
    values: &[u32],
    smoothing: f32,
    fallback: f32,
) -> Result<Vec<(u32, Mesh, f32)>, LabelError> {
    let first = surfaces_at(grid, values, smoothing)?;
    let thin: Vec<u32> = (first.iter())
        .filter(|(_, _, kept)| *kept < MIN_KEPT)
        .map(|(v, _, _)| *v)
        .collect();
    let mut again = if thin.is_empty() || fallback == smoothing {
        Vec::new()
    } else {
        surfaces_at(grid, &thin, fallback)?
    }
    .into_iter();
    let mut next = again.next();
    Ok(first
        .into_iter()
        .map(|(v, m, _)| match next.take() {
            Some((w, m2, _)) if w == v => {
                next = again.next();
                (v, m2, fallback)
            }
            other => {
                next = other;
                (v, m, smoothing)
            }
        })
        .collect())
}

/// A normalised Gaussian of standard deviation `sigma` over `-radius..=radius`.
fn gaussian(sigma: f64, radius: usize) -> Vec<f32> {
    if sigma <= 0.0 {
        return vec![1.0];
    }
    let w: Vec<f64> = (0..=2 * radius)
        .map(|k| {
            let x = k as f64 - radius as f64;
            (-0.5 * x * x / (sigma * sigma)).exp()
        })
        .collect();
    let sum: f64 = w.iter().sum();
    w.iter().map(|x| (x / sum) as f32).collect()
}

/// `data` (a `dims` grid, i fastest) convolved along `axis` with `kernel` (odd
/// length, centred), zero outside the grid; rows in parallel.
fn blur_axis(data: &[f32], dims: [usize; 3], axis: usize, kernel: &[f32]) -> Vec<f32> {
    let stride = [1, dims[0], dims[0] * dims[1]][axis];
    let n = dims[axis];
    let r = kernel.len() / 2;
    let mut out = vec![0.0f32; data.len()];
    out.par_chunks_mut(dims[0])
        .enumerate()
        .for_each(|(row, dst)| {
            let base = row * dims[0];
            for (i, d) in dst.iter_mut().enumerate() {
                let idx = base + i;
                let c = [i, row % dims[1], row / dims[1]][axis];
                // Taps t with 0 <= c + t - r < n.
                let t0 = r.saturating_sub(c);
                let t1 = kernel.len().min(n + r - c);
                let mut acc = 0.0f32;
                for (t, w) in kernel.iter().enumerate().take(t1).skip(t0) {
                    acc += w * data[idx + t * stride - r * stride];
                }
                *d = acc;
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blur_keeps_mass_and_symmetry_on_every_axis() {
        let dims = [9, 7, 11];
        for axis in 0..3 {
            let mut data = vec![0.0f32; dims.iter().product()];
            let c = [4, 3, 5];
            data[c[0] + dims[0] * (c[1] + dims[1] * c[2])] = 1.0;
            let data = blur_axis(&data, dims, axis, &gaussian(1.0, 3));
            let sum: f32 = data.iter().sum();
            assert!((sum - 1.0).abs() < 1e-5, "axis {axis}: mass {sum}");
            let stride = [1, dims[0], dims[0] * dims[1]][axis];
            let centre = (c[0] + dims[0] * (c[1] + dims[1] * c[2])) as isize;
            let at = |d: isize| data[(centre + d * stride as isize) as usize];
            // The blurred impulse is the kernel, along `axis` only.
            assert_eq!(at(-1), at(1));
            assert!(
                (at(0) - 0.398_942).abs() < 1e-3,
                "axis {axis}: peak {}",
                at(0)
            );
        }
    }
}
