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
//! caster composites it) averaged over each grid cell by a `[1 2 1]/4` tent per axis
//! (`classification::density`), so thin matter casts its shadow instead of falling
//! between grid points. Lights are relative to the camera, so the light volumes follow
//! the camera; the averaged extinction and the ambient occlusion depend on the
//! classification alone and are built once for it. This module builds the light
//! volumes; `crate::light` holds them and their lookup.
//!
//! A sample reads the transmittance one grid plane nearer the light than itself (a
//! shadow bias, as shadow maps have): the matter a surface sample lies in does not
//! shadow the surface.

use std::sync::Arc;

use rayon::prelude::*;

use glint_core::{RenderError, Vec3, MAX_LIGHTS};

use super::occluders::Occluders;
use crate::classification::{DensityGrid, LIGHT_CELL};
use crate::clip::IndexClip;
use crate::light::{LightGrid, ShadowField};

/// Grid planes between a sample and the point whose transmittance it reads (towards
/// the light).
const SHADOW_BIAS_PLANES: f32 = 1.0;

/// What the `shadows` model's light volumes depend on besides the lights.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShadowSettings {
    /// Local ambient occlusion on the ambient term (Hernell, Ljung and Ynnerman,
    /// "Local ambient occlusion in direct volume rendering", IEEE TVCG 16(4), 2010):
    /// the mean transmittance over 14 directions out to 8 voxels.
    pub occlusion: bool,
}

impl LightGrid {
    /// Propagates the transmittance towards the light of index-space direction `d`
    /// (index units per mm, towards the light); grid points `occluders` occupy are
    /// opaque (transmittance 0, and what lies behind them reads it); grid points
    /// `clip` does not keep are empty (extinction 0: clipped matter casts no shadow).
    fn new(
        density: &DensityGrid,
        d: Vec3,
        occluders: Option<&Occluders>,
        clip: Option<&IndexClip>,
    ) -> LightGrid {
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
            match clip {
                Some(k) if !k.contains(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) * h) => 0.0,
                _ => density.at(p),
            }
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

impl ShadowField {
    /// Light volumes for the lights of index-space directions `dirs` (world bits in
    /// `world`), from `density`, with `occlusion` when given, the grid points
    /// `occluders` occupy opaque, the space `clip` cuts away empty.
    pub(crate) fn new(
        density: &DensityGrid,
        world: Vec<[u32; 3]>,
        dirs: &[Vec3],
        occlusion: Option<Arc<Vec<f32>>>,
        (occluders, clip): (Option<&Occluders>, Option<&IndexClip>),
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
                .map(|&d| LightGrid::new(density, d, occluders, clip))
                .collect(),
            occlusion: occlusion.map(|o| (o, density.dims)),
        })
    }
}
