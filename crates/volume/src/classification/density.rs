//! The classified field's extinction on the light volumes' grid ([`DensityGrid`],
//! averaged over each grid cell) and its local ambient occlusion: built once per
//! classification, on first use by the `shadows` model.

use std::sync::Arc;

use rayon::prelude::*;

use glint_core::Vec3;

use super::medium::Medium;
use crate::field::Field;

/// Edge of the light volume's cells, in voxels (the grid's spacing). Two voxels: an
/// eighth of the field's points, which one core sweeps in a few milliseconds on the
/// MNI152 scene; docs/lighting.md gives the measured cost and error.
pub const LIGHT_CELL: usize = 2;

/// Grid points along an axis of `d` voxels: `0, h, 2h, ...` up to the last voxel.
pub(crate) fn grid_len(d: usize) -> usize {
    (d - 1).div_ceil(LIGHT_CELL) + 1
}

/// Grid steps each ambient-occlusion direction looks along.
const OCCLUSION_STEPS: usize = 4;

/// The extinction averaged over the light volume's cells, for one classification.
pub(crate) struct DensityGrid {
    pub(crate) dims: [usize; 3],
    /// Shared, so a device can keep what it built from it while it lives.
    pub(crate) sigma: Arc<Vec<f32>>,
    /// mm per grid step along each index axis.
    pub(crate) step_mm: [f32; 3],
}

impl DensityGrid {
    /// The averaged extinction of `medium` on `field`.
    pub(crate) fn new(field: &Field, medium: &Medium) -> DensityGrid {
        let dims = field.dims();
        let [nx, ny, nz] = dims;
        // Extinction at every voxel, then the tent along x, y, z with stride 2.
        let mut voxels = vec![0.0f32; nx * ny * nz];
        voxels
            .par_chunks_mut(nx * ny)
            .enumerate()
            .for_each(|(k, slab)| {
                for j in 0..ny {
                    for i in 0..nx {
                        let p = Vec3::new(i as f32, j as f32, k as f32);
                        slab[i + nx * j] = medium.sigma_at(field, p);
                    }
                }
            });
        let g = dims.map(grid_len);
        let mut src = voxels;
        let mut cur = dims;
        for axis in 0..3 {
            let mut next_dims = cur;
            next_dims[axis] = g[axis];
            src = tent(&src, cur, axis, next_dims);
            cur = next_dims;
        }
        let origin = field.index_to_world([0.0; 3]);
        let step_mm = [0, 1, 2].map(|a| {
            let mut e = [0.0; 3];
            e[a] = LIGHT_CELL as f64;
            let w = field.index_to_world(e);
            ((0..3).map(|c| (w[c] - origin[c]).powi(2)).sum::<f64>()).sqrt() as f32
        });
        DensityGrid {
            dims: g,
            sigma: Arc::new(src),
            step_mm,
        }
    }

    #[inline(always)]
    pub(crate) fn at(&self, [i, j, k]: [usize; 3]) -> f32 {
        self.sigma[i + self.dims[0] * (j + self.dims[1] * k)]
    }
}

/// `src` (dims `dims`) filtered by `[1 2 1]/4` along `axis` and sampled at every
/// second point (the faces clamped), into dims `out`.
fn tent(src: &[f32], dims: [usize; 3], axis: usize, out: [usize; 3]) -> Vec<f32> {
    let n = dims[axis];
    let mut dst = vec![0.0f32; out.iter().product()];
    let plane = out[0] * out[1];
    dst.par_chunks_mut(plane).enumerate().for_each(|(k, slab)| {
        for j in 0..out[1] {
            for i in 0..out[0] {
                let mut at = [i, j, k];
                let c = at[axis] * LIGHT_CELL;
                let mut v = 0.0;
                for (o, w) in [(-1i64, 0.25f32), (0, 0.5), (1, 0.25)] {
                    at[axis] = (c as i64 + o).clamp(0, n as i64 - 1) as usize;
                    v += w * src[at[0] + dims[0] * (at[1] + dims[1] * at[2])];
                }
                slab[i + out[0] * j] = v;
            }
        }
    });
    dst
}

/// Local ambient occlusion per grid point: the mean over 14 directions (the axes and
/// the diagonals) of the transmittance over [`OCCLUSION_STEPS`] grid steps, the
/// point's own cell excluded. Grid points `kept` refuses (a clip cuts them away) are
/// empty: they occlude nothing, as they cast no shadow.
pub(crate) fn occlusion_grid(
    density: &DensityGrid,
    kept: impl Fn([usize; 3]) -> bool + Sync,
) -> Vec<f32> {
    let d = density.dims;
    let mut dirs: Vec<[i64; 3]> = Vec::with_capacity(14);
    for a in 0..3 {
        for s in [-1, 1] {
            let mut e = [0; 3];
            e[a] = s;
            dirs.push(e);
        }
    }
    for x in [-1, 1] {
        for y in [-1, 1] {
            for z in [-1, 1] {
                dirs.push([x, y, z]);
            }
        }
    }
    let lens: Vec<f32> = dirs
        .iter()
        .map(|e| {
            (0..3)
                .map(|a| (e[a] as f32 * density.step_mm[a]).powi(2))
                .sum::<f32>()
                .sqrt()
        })
        .collect();
    let mut out = vec![0.0f32; d.iter().product()];
    out.par_chunks_mut(d[0] * d[1])
        .enumerate()
        .for_each(|(k, slab)| {
            for j in 0..d[1] {
                for i in 0..d[0] {
                    let mut sum = 0.0f32;
                    for (e, &len) in dirs.iter().zip(&lens) {
                        let mut tau = 0.0f32;
                        for s in 1..=OCCLUSION_STEPS as i64 {
                            let p = [
                                i as i64 + s * e[0],
                                j as i64 + s * e[1],
                                k as i64 + s * e[2],
                            ];
                            if (0..3).any(|a| p[a] < 0 || p[a] >= d[a] as i64) {
                                break;
                            }
                            let p = p.map(|x| x as usize);
                            if kept(p) {
                                tau += density.at(p) * len;
                            }
                        }
                        sum += (-tau).exp();
                    }
                    slab[i + d[0] * j] = sum / dirs.len() as f32;
                }
            }
        });
    out
}
