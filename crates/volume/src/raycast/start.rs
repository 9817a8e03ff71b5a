//! Where rays start: the image footprints of the blocks of visible macro cells.

use rayon::prelude::*;

use glint_core::camera::Camera;
use glint_core::Vec3;

use super::caster::IndexRays;
use super::TILE;

/// A block's footprint on the image: the pixels whose rays may meet it, and a lower
/// bound on the ray parameter (mm) at which they can.
#[derive(Clone, Copy)]
pub(super) struct Splat {
    pub(super) x: (usize, usize),
    pub(super) y: (usize, usize),
    pub(super) t: f32,
}

/// Per image tile, the blocks whose footprints overlap it: rays start at the nearest
/// block's bound instead of the clip box, which saves most of the leaps through the
/// empty space in front of the data (the CPU form of starting rays at the rasterised
/// front faces of non-empty bricks; Hadwiger et al., "Real-Time Volume Graphics",
/// 2006, section 8.1).
pub(super) struct StartBounds {
    /// Tile `i`'s splats are `splats[offsets[i]..offsets[i + 1]]`.
    pub(super) offsets: Vec<usize>,
    pub(super) splats: Vec<Splat>,
}

impl StartBounds {
    pub(super) fn new(
        blocks: &[[Vec3; 8]],
        rays: &IndexRays,
        camera: &Camera,
        w: usize,
        h: usize,
    ) -> Self {
        let (tiles_x, tiles_y) = (w.div_ceil(TILE), h.div_ceil(TILE));
        let full = Splat {
            x: (0, w - 1),
            y: (0, h - 1),
            t: 0.0,
        };
        let splats: Vec<Splat> = blocks
            .par_iter()
            .filter_map(|corners| {
                let center = corners.iter().fold(Vec3::ZERO, |a, &c| a + c) * 0.125;
                let radius = corners
                    .iter()
                    .map(|&c| (c - center).length())
                    .fold(0.0f32, f32::max);
                let rel = center - camera.eye;
                // Every point of the block is within `radius` of its centre, so a ray
                // (unit direction, t in mm from the eye or the image plane) reaches it
                // no earlier than this; a margin covers rounding.
                let t = if rays.perspective {
                    rel.length() - radius
                } else {
                    rel.dot(camera.forward) - radius
                };
                let t = (t - 1e-3 * (1.0 + t.abs())).max(0.0);
                // Image-plane coordinates of the corners; the block's projection lies in
                // their bounding box when all are in front of the eye.
                let mut ulo = f32::INFINITY;
                let mut uhi = f32::NEG_INFINITY;
                let mut vlo = f32::INFINITY;
                let mut vhi = f32::NEG_INFINITY;
                for &c in corners {
                    let r = c - camera.eye;
                    let (mut u, mut v) = (r.dot(camera.right), r.dot(camera.up));
                    if rays.perspective {
                        let z = r.dot(camera.forward);
                        // Behind or at the eye (or NaN): the footprint is unbounded.
                        if z.is_nan() || z <= 1e-3 {
                            return Some(full);
                        }
                        (u, v) = (u / z, v / z);
                    }
                    (ulo, uhi) = (ulo.min(u), uhi.max(u));
                    (vlo, vhi) = (vlo.min(v), vhi.max(v));
                }
                // Pixel x has u = u0 + x du (du > 0), pixel y has v = v0 + y dv (dv < 0);
                // one pixel of margin on each side.
                let px = |u: f32| (u - rays.u0) / rays.du;
                let py = |v: f32| (v - rays.v0) / rays.dv;
                let (x0, x1) = (px(ulo).floor() - 1.0, px(uhi).ceil() + 1.0);
                let (y0, y1) = (py(vhi).floor() - 1.0, py(vlo).ceil() + 1.0);
                if !(x1 >= 0.0 && y1 >= 0.0 && x0 <= (w - 1) as f32 && y0 <= (h - 1) as f32) {
                    // Off the image (or not finite): no ray meets it.
                    return None;
                }
                let clamp = |a: f32, n: usize| a.clamp(0.0, (n - 1) as f32) as usize;
                Some(Splat {
                    x: (clamp(x0, w), clamp(x1, w)),
                    y: (clamp(y0, h), clamp(y1, h)),
                    t,
                })
            })
            .collect();
        // Bin by tile (counting sort).
        let tile_range = |s: &Splat| (s.x.0 / TILE..=s.x.1 / TILE, s.y.0 / TILE..=s.y.1 / TILE);
        let mut offsets = vec![0usize; tiles_x * tiles_y + 1];
        for s in &splats {
            let (xr, yr) = tile_range(s);
            for ty in yr {
                for tx in xr.clone() {
                    offsets[tx + tiles_x * ty + 1] += 1;
                }
            }
        }
        for i in 1..offsets.len() {
            offsets[i] += offsets[i - 1];
        }
        let mut fill = offsets.clone();
        let mut binned = vec![full; offsets[tiles_x * tiles_y]];
        for s in &splats {
            let (xr, yr) = tile_range(s);
            for ty in yr {
                for tx in xr.clone() {
                    let slot = &mut fill[tx + tiles_x * ty];
                    binned[*slot] = *s;
                    *slot += 1;
                }
            }
        }
        StartBounds {
            offsets,
            splats: binned,
        }
    }

    /// Per pixel of tile `tile` (`xs` x `ys`, row-major): the start bound, +inf where
    /// no block is in the way.
    pub(super) fn tile(
        &self,
        tile: usize,
        xs: (usize, usize),
        ys: (usize, usize),
    ) -> [f32; TILE * TILE] {
        let mut out = [f32::INFINITY; TILE * TILE];
        let tw = xs.1 - xs.0;
        for s in &self.splats[self.offsets[tile]..self.offsets[tile + 1]] {
            let (x0, x1) = (s.x.0.max(xs.0) - xs.0, s.x.1.min(xs.1 - 1) - xs.0);
            for y in s.y.0.max(ys.0)..=s.y.1.min(ys.1 - 1) {
                let row = &mut out[(y - ys.0) * tw..][x0..=x1];
                for v in row {
                    *v = v.min(s.t);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod start_tests {
    use std::sync::Arc;

    use super::*;
    use crate::classification::START_BLOCK;
    use crate::field::MACRO_CELL;
    use crate::{Classification, ClassifySettings, Field, FrameSettings};
    use glint_core::camera::{CameraSpec, Projection, View};

    /// The exact parameter (mm) at which the ray `o + t d` (index space, `d` in index
    /// units per mm) enters the box `lo..=hi`, if it meets it at `t >= 0`.
    fn entry(o: Vec3, d: Vec3, lo: [f32; 3], hi: [f32; 3]) -> Option<f32> {
        let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
        for a in 0..3 {
            let (oa, da) = (o.get(a), d.get(a));
            if da == 0.0 {
                if oa < lo[a] || oa > hi[a] {
                    return None;
                }
            } else {
                let (ta, tb) = ((lo[a] - oa) / da, (hi[a] - oa) / da);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        (t0 <= t1).then_some(t0)
    }

    #[test]
    fn index_rays_are_the_cameras_rays_in_index_space() {
        let mut volume = crate::phantom::shepp_logan(20).unwrap();
        // A sheared, anisotropic affine.
        volume.affine[0][1] = 0.4;
        volume.affine[2][2] *= 1.7;
        let field = Field::new(&volume).unwrap();
        for projection in [Projection::Perspective, Projection::Orthographic] {
            let spec = CameraSpec {
                view: View::Posterior,
                azimuth: 25.0,
                elevation: 40.0,
                projection,
                ..Default::default()
            };
            let camera = Camera::frame(&spec, Vec3::new(3.0, -2.0, 1.0), 30.0, 64, 48).unwrap();
            let rays = IndexRays::new(&camera, &field, 64, 48);
            for (x, y) in [(0.0, 0.0), (63.0, 0.0), (17.0, 29.0), (63.0, 47.0)] {
                let (wo, wd) = camera.ray(x, y, 64, 48);
                let o = field.world_to_index([wo.x as f64, wo.y as f64, wo.z as f64]);
                let d = field.direction_to_index([wd.x as f64, wd.y as f64, wd.z as f64]);
                let (io, id, dir) = rays.ray(x, y);
                for a in 0..3 {
                    assert!(
                        (io.get(a) as f64 - o[a]).abs() < 1e-3,
                        "{projection:?} origin"
                    );
                    assert!(
                        (id.get(a) as f64 - d[a]).abs() < 1e-5,
                        "{projection:?} direction"
                    );
                    assert!(
                        (dir.get(a) - wd.get(a)).abs() < 1e-6,
                        "{projection:?} world"
                    );
                }
            }
        }
    }

    #[test]
    fn start_bounds_never_pass_a_visible_block() {
        // A grid that is not a whole number of blocks, anisotropic spacing, and views
        // from several sides in both projections; every pixel's start bound must lie
        // at or before the exact entry into every visible block its ray meets, and be
        // +inf only for rays that meet none.
        let mut volume = crate::phantom::shepp_logan(45).unwrap();
        volume.affine[2][2] *= 1.5;
        let field = Arc::new(Field::new(&volume).unwrap());
        let tf = crate::presets::preset("phantom")
            .unwrap()
            .transfer_function(1.0)
            .unwrap();
        let (w, h) = (40usize, 36usize);
        let mut slack = Vec::new();
        for projection in [Projection::Perspective, Projection::Orthographic] {
            for (view, azimuth, zoom) in [
                (View::Left, 0.0, 1.0),
                (View::Anterior, 37.0, 1.7),
                (View::Superior, -20.0, 3.0),
            ] {
                let settings = FrameSettings {
                    width: w as u32,
                    height: h as u32,
                    camera: CameraSpec {
                        view,
                        azimuth,
                        zoom,
                        projection,
                        ..Default::default()
                    },
                    ..Default::default()
                };
                let class =
                    Classification::new(field.clone(), &tf, &ClassifySettings::default()).unwrap();
                assert!(!class.blocks.is_empty());
                let camera = class.camera(&settings).unwrap();
                let rays = IndexRays::new(&camera, &field, w as u32, h as u32);
                let starts = StartBounds::new(&class.blocks, &rays, &camera, w, h);
                let boxes: Vec<([f32; 3], [f32; 3])> = class
                    .blocks
                    .iter()
                    .map(|corners| {
                        let idx = |c: Vec3| {
                            let p = field.world_to_index([c.x as f64, c.y as f64, c.z as f64]);
                            p.map(|x| x as f32)
                        };
                        let (a, b) = (idx(corners[0]), idx(corners[7]));
                        (
                            [0, 1, 2].map(|k| a[k].min(b[k])),
                            [0, 1, 2].map(|k| a[k].max(b[k])),
                        )
                    })
                    .collect();
                let tiles_x = w.div_ceil(TILE);
                for t in 0..tiles_x * h.div_ceil(TILE) {
                    let (x0, y0) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
                    let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                    let bound = starts.tile(t, (x0, x1), (y0, y1));
                    for y in y0..y1 {
                        for x in x0..x1 {
                            let (o, d, _) = rays.ray(x as f32, y as f32);
                            let exact = boxes
                                .iter()
                                .filter_map(|&(lo, hi)| entry(o, d, lo, hi))
                                .fold(f32::INFINITY, f32::min);
                            let b = bound[(y - y0) * (x1 - x0) + (x - x0)];
                            assert!(
                                b <= exact + 1e-3 * (1.0 + exact.abs()),
                                "{projection:?} {view:?} pixel ({x}, {y}): bound {b} > entry {exact}"
                            );
                            if exact.is_finite() {
                                slack.push(exact - b);
                            }
                        }
                    }
                }
            }
        }
        // The bound is useful, not just 0: rays start on average within a block's
        // diagonal of the exact entry (the sphere around a block is that loose).
        let max_spacing = (0..3)
            .map(|c| {
                (0..3)
                    .map(|r| field.to_world[r][c].powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(0.0, f64::max) as f32;
        let diagonal = (START_BLOCK * MACRO_CELL) as f32 * 3f32.sqrt() * max_spacing;
        let mean = slack.iter().sum::<f32>() / slack.len() as f32;
        assert!(
            slack.len() > 100 && mean < diagonal,
            "{} rays, mean slack {mean}",
            slack.len()
        );
    }
}
