//! What every tile of one render shares: the vertices projected to the sample grid,
//! and the triangles binned by band (a row of tiles).

use rayon::prelude::*;

use super::{cull, SurfaceSettings, Surfaces, TILE_PIXELS};
use glint_core::camera::{Camera, Projection};
use glint_core::Vec3;

/// A vertex in sample space: `x`, `y` in samples (sample centres at integers),
/// `key` larger when nearer (1/z perspective, -z orthographic, both linear in screen
/// space), `w` the perspective weight 1/z (1 orthographic). `w` is NaN for vertices
/// behind the near plane.
#[derive(Clone, Copy, Debug)]
pub(super) struct ScreenVertex {
    pub(super) x: f32,
    pub(super) y: f32,
    pub(super) key: f32,
    pub(super) w: f32,
}

/// A triangle binned to a band: its index and its sample-space bounding box clipped
/// to the image, `[x0, y0, x1, y1]` inclusive (sample coordinates are below
/// 4 x [`MAX_IMAGE_SIDE`](glint_core::MAX_IMAGE_SIDE) = 2^16).
#[derive(Clone, Copy, Debug)]
pub(super) struct Binned {
    pub(super) id: u32,
    pub(super) bbox: [u16; 4],
}

/// Per chunk of triangles, per band: the triangles whose bounding box meets the band,
/// in index order.
pub(super) type Bands = Vec<Vec<Vec<Binned>>>;

/// Everything the tiles of one render share.
pub(super) struct Frame {
    pub(super) camera: Camera,
    pub(super) verts: Vec<ScreenVertex>,
    /// Image plane of the sample grid (`Camera::image_plane`).
    pub(super) plane: [f32; 4],
    pub(super) ssaa: usize,
    /// Sample grid size.
    pub(super) sw: usize,
    pub(super) sh: usize,
    /// Tile edge in samples, a power of two, and its log2 (shifts rather than
    /// divisions in the per-triangle and per-sample loops).
    pub(super) tile: usize,
    pub(super) tile_shift: u32,
    /// log2 of `ssaa` (1, 2 or 4).
    pub(super) ssaa_shift: u32,
    pub(super) tiles_x: usize,
    pub(super) tiles_y: usize,
    /// Image width in pixels.
    pub(super) width: usize,
    /// Per mesh: what culls its back faces (`cull::cull_signs`), all 0 for none.
    cull: Vec<f32>,
}

impl Frame {
    pub(super) fn new(s: &Surfaces, camera: &Camera, settings: &SurfaceSettings) -> Frame {
        let ssaa = settings.ssaa as usize;
        let (width, height) = (settings.width as usize, settings.height as usize);
        let (sw, sh) = (width * ssaa, height * ssaa);
        let plane = camera.image_plane(sw as u32, sh as u32);
        // Vertices nearer the eye than this (mm) are dropped with their triangles:
        // the camera frames the bounding sphere from outside, so only extreme zooms
        // or hand-placed cameras get here.
        let near = 1e-4 * s.radius.max(1e-3);
        let verts = s
            .positions
            .par_iter()
            .with_min_len(4096)
            .map(|&p| project(camera, plane, near, p))
            .collect();
        let tile = TILE_PIXELS as usize * ssaa;
        // Twice `near`: a margin for rounding, the corners' depths against the
        // vertices'.
        let cull = cull::cull_signs(camera, plane, 2.0 * near, &s.closures);
        Frame {
            camera: *camera,
            verts,
            plane,
            ssaa,
            sw,
            sh,
            tile,
            tile_shift: tile.trailing_zeros(),
            ssaa_shift: ssaa.trailing_zeros(),
            tiles_x: sw.div_ceil(tile),
            tiles_y: sh.div_ceil(tile),
            width,
            cull,
        }
    }

    /// The sample-space bounding box of triangle `tri` clipped to the image, or `None`
    /// when it covers no sample centre (off screen, behind the eye, degenerate) or
    /// when its doubled signed area times `cull` is positive: a back face
    /// (`cull::cull_signs`; 0 keeps every triangle).
    #[inline(always)]
    pub(super) fn front_bbox(&self, tri: [u32; 3], cull: f32) -> Option<[u16; 4]> {
        let [a, b, c] = tri.map(|i| self.verts[i as usize]);
        if !(a.w.is_finite() && b.w.is_finite() && c.w.is_finite()) {
            return None;
        }
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area == 0.0 || !area.is_finite() || area * cull > 0.0 {
            return None;
        }
        let x0 = ceil(a.x.min(b.x).min(c.x)).max(0.0);
        let y0 = ceil(a.y.min(b.y).min(c.y)).max(0.0);
        let x1 = floor(a.x.max(b.x).max(c.x)).min(self.sw as f32 - 1.0);
        let y1 = floor(a.y.max(b.y).max(c.y)).min(self.sh as f32 - 1.0);
        // The grid is at most 2^16 samples a side, so the bounds fit in u16.
        (x0 <= x1 && y0 <= y1).then_some([x0 as u16, y0 as u16, x1 as u16, y1 as u16])
    }

    /// What culls triangle `id` of `s` in this frame: positive times its doubled
    /// signed area on the sample grid for a back face that may be left out, 0 when it
    /// is kept whatever its facing.
    #[inline(always)]
    pub(super) fn cull_of(&self, s: &Surfaces, id: u32) -> f32 {
        match s.facing[id as usize] {
            0 => 0.0,
            o => f32::from(o) * self.cull[s.mesh_of(id)],
        }
    }

    /// Bins the triangles by band, a chunk of triangles per task, leaving out the back
    /// faces of closed meshes where the frame culls them.
    pub(super) fn bin(&self, s: &Surfaces) -> Bands {
        let culling = self.cull.iter().any(|&c| c != 0.0);
        let chunk = s
            .triangles
            .len()
            .div_ceil(4 * rayon::current_num_threads())
            .max(4096);
        s.triangles
            .par_chunks(chunk)
            .enumerate()
            .map(|(c, tris)| {
                let mut bands = vec![Vec::new(); self.tiles_y];
                for (k, &tri) in tris.iter().enumerate() {
                    let id = (c * chunk + k) as u32;
                    let cull = if culling { self.cull_of(s, id) } else { 0.0 };
                    let Some(bbox) = self.front_bbox(tri, cull) else {
                        continue;
                    };
                    let (y0, y1) = (usize::from(bbox[1]), usize::from(bbox[3]));
                    for band in &mut bands[y0 >> self.tile_shift..=y1 >> self.tile_shift] {
                        band.push(Binned { id, bbox });
                    }
                }
                bands
            })
            .collect()
    }

    /// The unit vector from the sample `(x, y)` of the image plane towards the eye
    /// (the lighting computes it per sample, a batch at a time: `shade::Batch`).
    #[cfg(test)]
    pub(super) fn view(&self, x: f32, y: f32) -> Vec3 {
        let cam = &self.camera;
        match cam.projection {
            Projection::Perspective => {
                let [u0, du, v0, dv] = self.plane;
                -(cam.forward + cam.right * (u0 + x * du) + cam.up * (v0 + y * dv))
                    .normalize_or_zero()
            }
            Projection::Orthographic => -cam.forward,
        }
    }
}

/// `x.ceil()`, but for zero's sign (-0.5 gives +0), by truncation: without SSE4.1
/// (not in the x86-64 baseline) `f32::ceil` is a library call, 4 of them a triangle.
#[inline(always)]
fn ceil(x: f32) -> f32 {
    // From 2^23 on every f32 is an integer (and NaN fails the test, staying NaN).
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32;
        if t < x {
            t + 1.0
        } else {
            t
        }
    } else {
        x
    }
}

/// `x.floor()` by truncation, like [`ceil`].
#[inline(always)]
fn floor(x: f32) -> f32 {
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32;
        if t > x {
            t - 1.0
        } else {
            t
        }
    } else {
        x
    }
}

/// Projects world point `p` to the sample grid of `plane`.
fn project(camera: &Camera, plane: [f32; 4], near: f32, p: Vec3) -> ScreenVertex {
    let d = p - camera.eye;
    let (cx, cy, cz) = (d.dot(camera.right), d.dot(camera.up), d.dot(camera.forward));
    let [u0, du, v0, dv] = plane;
    let (u, v, key, w) = match camera.projection {
        Projection::Perspective if cz > near => (cx / cz, cy / cz, 1.0 / cz, 1.0 / cz),
        Projection::Perspective => (0.0, 0.0, 0.0, f32::NAN),
        Projection::Orthographic => (cx, cy, -cz, 1.0),
    };
    ScreenVertex {
        x: (u - u0) / du,
        y: (v - v0) / dv,
        key,
        w,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn ceil_and_floor_by_truncation_are_the_library_ones() {
        let mut xs = vec![0.0f32, -0.0, 0.5, -0.5, 1.0, -1.0, 2.5, -2.5, 1e-30, -1e-30];
        xs.extend([8_388_607.5, -8_388_607.5, 8_388_608.0, 1e10, -1e10]);
        xs.extend([f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN]);
        for k in 0..2000 {
            let x = (k as f32 - 1000.0) * 0.37 + 0.001 * k as f32;
            xs.extend([x, x.next_up(), x.next_down(), x.round()]);
        }
        for x in xs {
            // Equal as numbers: only zero's sign may differ.
            assert_eq!(super::ceil(x), x.ceil(), "ceil {x}");
            assert_eq!(super::floor(x), x.floor(), "floor {x}");
        }
        assert!(super::ceil(f32::NAN).is_nan() && super::floor(f32::NAN).is_nan());
    }
}

/// Edge functions of a screen triangle, scaled so they are non-negative inside
/// whatever its winding: at a point they sum to the triangle's (positive) doubled area.
#[derive(Clone, Copy)]
pub(super) struct Edges {
    pub(super) a: ScreenVertex,
    pub(super) b: ScreenVertex,
    pub(super) c: ScreenVertex,
    pub(super) sign: f32,
}

impl Edges {
    #[inline(always)]
    pub(super) fn new(a: ScreenVertex, b: ScreenVertex, c: ScreenVertex) -> Edges {
        let sign = if Self::area(a, b, c) < 0.0 { -1.0 } else { 1.0 };
        Edges { a, b, c, sign }
    }

    /// The doubled signed area.
    #[inline(always)]
    fn area(a: ScreenVertex, b: ScreenVertex, c: ScreenVertex) -> f32 {
        (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
    }

    /// The reciprocal of the doubled (positive) area, which turns the edge functions
    /// into barycentric weights.
    #[inline(always)]
    pub(super) fn inv_area(&self) -> f32 {
        1.0 / (Self::area(self.a, self.b, self.c) * self.sign)
    }

    /// The three edge functions at `(x, y)`: `w0` opposite `a`, `w1` opposite `b`,
    /// `w2` opposite `c`. The rasterizer evaluates the same expression per sample
    /// ([`EdgeRow`]), so coverage and the resolve's barycentrics agree bit for bit.
    #[inline(always)]
    pub(super) fn at(&self, x: f32, y: f32) -> (f32, f32, f32) {
        let f = |p: ScreenVertex, q: ScreenVertex| {
            ((q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x)) * self.sign
        };
        (f(self.b, self.c), f(self.c, self.a), f(self.a, self.b))
    }

    /// The edge functions along sample row `y`.
    #[inline(always)]
    pub(super) fn row(&self, y: f32) -> [EdgeRow; 3] {
        let f = |p: ScreenVertex, q: ScreenVertex| EdgeRow {
            r: (q.x - p.x) * (y - p.y),
            d: q.y - p.y,
            px: p.x,
        };
        [f(self.b, self.c), f(self.c, self.a), f(self.a, self.b)]
    }
}

/// One edge function along a sample row: `(r - d (x - px)) sign` at `x`, the terms of
/// [`Edges::at`] that do not depend on `x` evaluated once.
#[derive(Clone, Copy)]
pub(super) struct EdgeRow {
    pub(super) r: f32,
    pub(super) d: f32,
    pub(super) px: f32,
}

impl EdgeRow {
    /// The edge function at `x` ([`Edges::at`]'s value, bit for bit).
    #[inline(always)]
    pub(super) fn at(&self, x: f32, sign: f32) -> f32 {
        (self.r - self.d * (x - self.px)) * sign
    }
}
