//! The `shadows` model's light volumes: per light, the transmittance from every point
//! of a coarse grid to the light, propagated plane by plane through the volume along
//! the light's direction (the sweep of Behrens and Ratering, "Adding shadows to a
//! texture-based volume renderer", VolVis 1998, and of Ropinski et al.'s light
//! volumes, "Interactive volumetric lighting simulating scattering and shadowing",
//! PacificVis 2010, here on the CPU): each grid point's transmittance is the one of the
//! point a plane nearer the light (bilinear on that plane) times the extinction of the
//! segment between them. One pass per light and frame, whatever the image size; the
//! shaded samples then read it trilinearly.
//!
//! The extinction is the classified field's (`-ln(1 - alpha)` per unit, as the ray
//! caster composites it) averaged over each grid cell by a `[1 2 1]/4` tent per axis,
//! so thin matter casts its shadow instead of falling between grid points. Lights are
//! relative to the camera, so the light volumes follow the camera; the averaged
//! extinction and the ambient occlusion depend on the classification alone and are
//! built once for it.
//!
//! A sample reads the transmittance one grid plane nearer the light than itself (a
//! shadow bias, as shadow maps have): the matter a surface sample lies in does not
//! shadow the surface.

use std::sync::Arc;

use rayon::prelude::*;

use glint_core::{RenderError, Shader, Vec3, MAX_LIGHTS};

use super::medium::Medium;
use super::occluders::Occluders;
use super::{grid_len, LIGHT_CELL};
use crate::field::Field;

/// Grid planes between a sample and the point whose transmittance it reads (towards
/// the light).
const SHADOW_BIAS_PLANES: f32 = 1.0;

/// Grid steps each ambient-occlusion direction looks along.
const OCCLUSION_STEPS: usize = 4;

/// What the `shadows` model's light volumes depend on besides the lights.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShadowSettings {
    /// Local ambient occlusion on the ambient term (Hernell, Ljung and Ynnerman,
    /// "Local ambient occlusion in direct volume rendering", IEEE TVCG 16(4), 2010):
    /// the mean transmittance over 14 directions out to 8 voxels.
    pub occlusion: bool,
}

/// The extinction averaged over the light volume's cells, for one classification.
pub(crate) struct DensityGrid {
    pub(crate) dims: [usize; 3],
    pub(crate) sigma: Vec<f32>,
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
            sigma: src,
            step_mm,
        }
    }

    #[inline(always)]
    fn at(&self, [i, j, k]: [usize; 3]) -> f32 {
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
/// point's own cell excluded.
pub(crate) fn occlusion_grid(density: &DensityGrid) -> Vec<f32> {
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
                            tau += density.at(p.map(|x| x as usize)) * len;
                        }
                        sum += (-tau).exp();
                    }
                    slab[i + d[0] * j] = sum / dirs.len() as f32;
                }
            }
        });
    out
}

/// One light's transmittance grid, stored plane by plane along its sweep axis.
struct LightGrid {
    /// The sweep axis, then the two others: storage is `[m][v][u]` with `m` along
    /// `axes[0]`, `v` along `axes[2]`, `u` along `axes[1]`.
    axes: [usize; 3],
    /// Grid extents along `axes`.
    len: [usize; 3],
    t: Vec<f32>,
    /// Added to a sample's grid position before the lookup: the shadow bias, towards
    /// the light.
    offset: Vec3,
}

impl LightGrid {
    /// Propagates the transmittance towards the light of index-space direction `d`
    /// (index units per mm, towards the light); grid points `occluders` occupy are
    /// opaque (transmittance 0, and what lies behind them reads it).
    fn new(density: &DensityGrid, d: Vec3, occluders: Option<&Occluders>) -> LightGrid {
        let da = [d.x, d.y, d.z];
        let a = (0..3)
            .max_by(|&x, &y| da[x].abs().total_cmp(&da[y].abs()))
            .expect("three axes");
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let axes = [a, b, c];
        let gd = density.dims;
        let len = [gd[a], gd[b], gd[c]];
        let h = LIGHT_CELL as f32;
        let mut t = vec![1.0f32; len.iter().product()];
        let offset_of = |x: f32| Vec3::new(x * da[0], x * da[1], x * da[2]);
        if da[a] == 0.0 {
            return LightGrid {
                axes,
                len,
                t,
                offset: Vec3::ZERO,
            };
        }
        // One plane nearer the light: s mm along the light, +-1 grid step along a and
        // e_b, e_c (|e| <= 1) along the others.
        let s = h / da[a].abs();
        let (eb, ec) = (da[b] * s / h, da[c] * s / h);
        let sign: i64 = if da[a] > 0.0 { 1 } else { -1 };
        let plane = len[1] * len[2];
        let sigma_at = |m: usize, u: usize, v: usize| {
            let mut p = [0; 3];
            (p[a], p[b], p[c]) = (m, u, v);
            density.at(p)
        };
        let order: Vec<usize> = if sign > 0 {
            (0..len[0]).rev().collect()
        } else {
            (0..len[0]).collect()
        };
        let occupied = |m: usize, u: usize, v: usize| {
            occluders.is_some_and(|o| {
                let mut p = [0; 3];
                (p[a], p[b], p[c]) = (m, u, v);
                o.occupied(p)
            })
        };
        if let Some(&first) = order.first() {
            for (i, x) in t[plane * first..][..plane].iter_mut().enumerate() {
                if occupied(first, i % len[1], i / len[1]) {
                    *x = 0.0;
                }
            }
        }
        for w in order.windows(2) {
            let (up, m) = (w[0], w[1]);
            let (done, rest) = t.split_at_mut(plane * up.max(m));
            let (upstream, current) = if up < m {
                (&done[plane * up..], &mut rest[..plane])
            } else {
                (&rest[..plane], &mut done[plane * m..][..plane])
            };
            current
                .par_chunks_mut(len[1])
                .enumerate()
                .for_each(|(v, row)| {
                    for (u, out) in row.iter_mut().enumerate() {
                        let (x, y) = (u as f32 + eb, v as f32 + ec);
                        let (tu, su) = bilinear(upstream, len[1], len[2], x, y, |uu, vv| {
                            sigma_at(up, uu, vv)
                        });
                        let tau = s * 0.5 * (sigma_at(m, u, v) + su);
                        *out = if occupied(m, u, v) {
                            0.0
                        } else {
                            tu * (-tau).exp()
                        };
                    }
                });
        }
        LightGrid {
            axes,
            len,
            t,
            offset: offset_of(s * SHADOW_BIAS_PLANES / h),
        }
    }

    /// Transmittance at grid position `g` (grid units, before the bias).
    #[inline(always)]
    fn at(&self, g: Vec3) -> f32 {
        let g = g + self.offset;
        let q = [
            g.get(self.axes[0]),
            g.get(self.axes[1]),
            g.get(self.axes[2]),
        ];
        trilinear(&self.t, self.len, q)
    }
}

/// Transmittance and extinction on the upstream plane (row length `nu`, `nv` rows) at
/// `(x, y)`, bilinear; corners outside the plane are outside the volume: transmittance
/// 1, extinction 0.
#[inline(always)]
fn bilinear(
    t: &[f32],
    nu: usize,
    nv: usize,
    x: f32,
    y: f32,
    sigma: impl Fn(usize, usize) -> f32,
) -> (f32, f32) {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let mut tr = 0.0f32;
    let mut sg = 0.0f32;
    for (dy, wy) in [(0i64, 1.0 - fy), (1, fy)] {
        for (dx, wx) in [(0i64, 1.0 - fx), (1, fx)] {
            let (u, v) = (x0 + dx, y0 + dy);
            let w = wx * wy;
            if u < 0 || v < 0 || u >= nu as i64 || v >= nv as i64 {
                tr += w;
            } else {
                let (u, v) = (u as usize, v as usize);
                tr += w * t[u + nu * v];
                sg += w * sigma(u, v);
            }
        }
    }
    (tr, sg)
}

/// Trilinear interpolation of `grid` (extents `len`, storage `[q0][q2][q1]`) at `q`,
/// clamped to the grid.
#[inline(always)]
fn trilinear(grid: &[f32], len: [usize; 3], q: [f32; 3]) -> f32 {
    let mut i = [0usize; 3];
    let mut f = [0.0f32; 3];
    for a in 0..3 {
        let top = (len[a] - 1) as f32;
        let x = q[a].max(0.0).min(top);
        let lo = (x as usize).min(len[a].saturating_sub(2));
        i[a] = lo;
        f[a] = if len[a] > 1 { x - lo as f32 } else { 0.0 };
    }
    let (s1, s0) = (len[1], len[1] * len[2]);
    let o1 = if len[1] > 1 { 1 } else { 0 };
    let o2 = if len[2] > 1 { s1 } else { 0 };
    let o0 = if len[0] > 1 { s0 } else { 0 };
    let base = i[0] * s0 + i[2] * s1 + i[1];
    let at = |o: usize| grid[base + o];
    let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
    let c00 = lerp(at(0), at(o1), f[1]);
    let c01 = lerp(at(o2), at(o2 + o1), f[1]);
    let c10 = lerp(at(o0), at(o0 + o1), f[1]);
    let c11 = lerp(at(o0 + o2), at(o0 + o2 + o1), f[1]);
    lerp(lerp(c00, c01, f[2]), lerp(c10, c11, f[2]), f[0])
}

/// The light volumes of one frame: each placed light's transmittance grid, and the
/// classification's ambient occlusion when asked for. Built by
/// [`Classification::shadow_field`](crate::Classification::shadow_field) for a shader
/// placed for a camera, and valid for every frame whose lights point the same way
/// (a viewer keeps it while only the lobe, the material or the size change).
pub struct ShadowField {
    /// The world directions it was built for (bit patterns), in light order.
    pub(crate) dirs: Vec<[u32; 3]>,
    lights: Vec<LightGrid>,
    occlusion: Option<(Arc<Vec<f32>>, [usize; 3])>,
}

impl ShadowField {
    /// Light volumes for the lights of index-space directions `dirs` (world bits in
    /// `world`), from `density`, with `occlusion` when given, the grid points
    /// `occluders` occupy opaque.
    pub(crate) fn new(
        density: &DensityGrid,
        world: Vec<[u32; 3]>,
        dirs: &[Vec3],
        occlusion: Option<Arc<Vec<f32>>>,
        occluders: Option<&Occluders>,
    ) -> Result<ShadowField, RenderError> {
        if dirs.len() > MAX_LIGHTS {
            return Err(RenderError::Parameter(format!(
                "{} lights: at most {MAX_LIGHTS}",
                dirs.len()
            )));
        }
        if let Some(o) = occluders {
            if o.dims() != density.dims {
                return Err(RenderError::Parameter(
                    "the mesh occupancy was built for another volume's grid".into(),
                ));
            }
        }
        Ok(ShadowField {
            dirs: world,
            lights: dirs
                .iter()
                .map(|&d| LightGrid::new(density, d, occluders))
                .collect(),
            occlusion: occlusion.map(|o| (o, density.dims)),
        })
    }

    /// The world directions of `shader`'s placed lights, as [`ShadowField`] keeps them.
    pub(crate) fn light_bits(shader: &Shader) -> Vec<[u32; 3]> {
        shader
            .world_lights()
            .iter()
            .map(|(l, _)| [l.x.to_bits(), l.y.to_bits(), l.z.to_bits()])
            .collect()
    }

    /// Errors unless it was built for the lights of `shader` (placed).
    pub(crate) fn check_lights(&self, shader: &Shader) -> Result<(), RenderError> {
        if ShadowField::light_bits(shader) != self.dirs {
            return Err(RenderError::Parameter(
                "the light volumes were built for other lights (or another camera)".into(),
            ));
        }
        Ok(())
    }

    /// Whether it was built for the lights of `shader` placed for `camera`.
    pub fn is_for(&self, shader: &Shader, camera: &glint_core::Camera) -> bool {
        ShadowField::light_bits(&shader.placed(camera)) == self.dirs
    }

    /// How many lights it holds.
    pub fn lights(&self) -> usize {
        self.lights.len()
    }

    /// Whether it holds ambient occlusion.
    pub fn has_occlusion(&self) -> bool {
        self.occlusion.is_some()
    }

    /// The transmittance of each light to index-space point `p` into `out` (the
    /// first [`ShadowField::lights`] entries), and the ambient occlusion there (1
    /// without it).
    #[inline(always)]
    pub(crate) fn at(&self, p: Vec3, out: &mut [f32; MAX_LIGHTS]) -> f32 {
        let g = p * (1.0 / LIGHT_CELL as f32);
        for (o, l) in out.iter_mut().zip(&self.lights) {
            *o = l.at(g);
        }
        match &self.occlusion {
            Some((ao, d)) => trilinear(ao, [d[2], d[0], d[1]], [g.z, g.x, g.y]),
            None => 1.0,
        }
    }

    /// The transmittance of light `i` at index-space point `p` (tests and reports).
    pub fn transmittance(&self, i: usize, p: [f32; 3]) -> Option<f32> {
        let l = self.lights.get(i)?;
        Some(l.at(Vec3::new(p[0], p[1], p[2]) * (1.0 / LIGHT_CELL as f32)))
    }
}
