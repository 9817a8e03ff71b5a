//! One band (a row of tiles) of a surface render: each tile's triangles rasterised
//! into a depth and triangle buffer, then every covered sample lit once (deferred
//! shading, a batch of samples at a time) and box-filtered into the image's pixels.

use std::mem::MaybeUninit;

use super::ctx::Ctx;
use super::frame::{Bands, Binned, Edges, ScreenVertex};
use super::rect::{clip, Rect, LANES, LANE_X};
use super::shade::Batch;
use glint_core::camera::Projection;
use glint_core::Vec3;

/// Buffers a worker reuses from tile to tile and band to band.
#[derive(Default)]
pub(super) struct Scratch {
    /// The band's triangles, per tile.
    tiles: Vec<Vec<Binned>>,
    /// Per sample of the tile (rows of `tw + LANES`): the nearest key and triangle.
    depth: Vec<f32>,
    ids: Vec<u32>,
    batch: Batch,
    /// Per pixel of the tile: the sum of the lit samples and how many there were.
    sum: Vec<[f32; 3]>,
    covered: Vec<u32>,
}

/// A band's rows of pixels, written by [`Ctx::band`].
pub(super) struct Out<'a> {
    pub(super) rgb: &'a mut [MaybeUninit<[f32; 3]>],
    pub(super) alpha: &'a mut [MaybeUninit<f32>],
    /// Per pixel: the distance to the nearest surface it shows
    /// ([`Surfaces::render_layer`]), when asked for.
    pub(super) far: Option<&'a mut [MaybeUninit<f32>]>,
}

impl Ctx<'_> {
    /// Draws band `b` into `out`, its rows of pixels, writing every element; returns
    /// the number of samples lit.
    pub(super) fn band(&self, bands: &Bands, b: usize, out: Out, scratch: &mut Scratch) -> u64 {
        let Out {
            rgb,
            alpha,
            mut far,
        } = out;
        let f = self.frame;
        let Scratch {
            tiles,
            depth,
            ids,
            batch,
            sum,
            covered,
        } = scratch;
        if self.zeroed {
            // SAFETY: all-zero bytes are f32 zeros; the pointers and lengths are the
            // slices'.
            unsafe {
                std::ptr::write_bytes(rgb.as_mut_ptr(), 0, rgb.len());
                std::ptr::write_bytes(alpha.as_mut_ptr(), 0, alpha.len());
            }
        }
        tiles.resize_with(f.tiles_x, Vec::new);
        tiles.iter_mut().for_each(Vec::clear);
        for chunk in bands {
            for t in &chunk[b] {
                let (x0, x1) = (usize::from(t.bbox[0]), usize::from(t.bbox[2]));
                for tile in &mut tiles[x0 >> f.tile_shift..=x1 >> f.tile_shift] {
                    tile.push(*t);
                }
            }
        }
        let y0 = b * f.tile;
        let mut shaded = 0;
        for (tx, tris) in tiles.iter().enumerate() {
            let x0 = tx * f.tile;
            let rect = Rect {
                x0,
                y0,
                w: (f.sw - x0).min(f.tile),
                h: (f.sh - y0).min(f.tile),
            };
            if tris.is_empty() {
                if !self.zeroed {
                    self.write_empty(rect, rgb, alpha);
                }
                if let Some(far) = far.as_deref_mut() {
                    self.write_far(rect, &[], far);
                }
                continue;
            }
            let pixels = (rect.w / f.ssaa) * (rect.h / f.ssaa);
            sum.clear();
            sum.resize(pixels, [0.0; 3]);
            covered.clear();
            covered.resize(pixels, 0);
            let len = rect.stride() * rect.h;
            depth.clear();
            depth.resize(len, f32::NEG_INFINITY);
            ids.clear();
            ids.resize(len, u32::MAX);
            self.raster(tris, rect, depth, ids);
            // The resolve moves the depth of capped samples to their cap's.
            shaded += self.resolve(rect, (ids, depth), batch, sum, covered);
            if let Some(far) = far.as_deref_mut() {
                self.write_far(rect, depth, far);
            }
            self.write(rect, sum, covered, rgb, alpha);
        }
        shaded
    }

    /// Rasterises `tris` in order into the tile's `depth` and `ids`.
    fn raster(&self, tris: &[Binned], rect: Rect, depth: &mut [f32], ids: &mut [u32]) {
        let (verts, triangles) = (&self.frame.verts, &self.s.triangles);
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when the CPU supports AVX2
            // (`super::avx2::supported`).
            unsafe { super::avx2::raster(verts, triangles, tris, rect, depth, ids) };
            #[cfg(test)]
            super::tests::AVX2_TILES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            return;
        }
        for t in tris {
            let tri = triangles[t.id as usize].map(|i| verts[i as usize]);
            raster_scalar(tri, t, rect, depth, ids);
        }
        #[cfg(test)]
        super::tests::SCALAR_TILES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }

    /// Writes the pixels of a tile no triangle meets: what [`Ctx::write`] makes of
    /// pixels without samples.
    fn write_empty(
        &self,
        rect: Rect,
        rgb: &mut [MaybeUninit<[f32; 3]>],
        alpha: &mut [MaybeUninit<f32>],
    ) {
        let f = self.frame;
        let n = f.ssaa;
        let per_pixel = (n * n) as f32;
        let bg = self
            .settings
            .background
            .map(|b| (0.0 + per_pixel * b) * (1.0 / per_pixel));
        let (pw, ph) = (rect.w / n, rect.h / n);
        let px0 = rect.x0 / n;
        for row in 0..ph {
            let k = row * f.width + px0;
            rgb[k..k + pw].iter_mut().for_each(|o| {
                o.write(bg);
            });
            alpha[k..k + pw].iter_mut().for_each(|a| {
                a.write(0.0);
            });
        }
    }

    /// Writes, for every pixel of the tile, the distance along its ray to the nearest
    /// of its covered samples (`f32::INFINITY` where none is), from the tile's depth
    /// keys `keys` (rows of [`Rect::stride`]; empty for a tile with no triangle).
    fn write_far(&self, rect: Rect, keys: &[f32], far: &mut [MaybeUninit<f32>]) {
        let f = self.frame;
        let n = f.ssaa;
        let (pw, ph) = (rect.w / n, rect.h / n);
        let [u0, du, v0, dv] = f.plane;
        let perspective = f.camera.projection == Projection::Perspective;
        for py in 0..ph {
            let k = py * f.width + rect.x0 / n;
            for (px, o) in far[k..k + pw].iter_mut().enumerate() {
                let mut t = f32::INFINITY;
                for sy in py * n..(py + 1) * n {
                    for sx in px * n..(px + 1) * n {
                        let key = keys.get(sy * rect.stride() + sx).copied();
                        let Some(key) = key.filter(|&k| k != f32::NEG_INFINITY) else {
                            continue;
                        };
                        // key = 1/z (perspective; the ray's direction is forward + u
                        // right + v up, an orthonormal frame) or -z (orthographic).
                        let d = if perspective {
                            let u = u0 + (rect.x0 + sx) as f32 * du;
                            let v = v0 + (rect.y0 + sy) as f32 * dv;
                            (1.0 + u * u + v * v).sqrt() / key
                        } else {
                            -key
                        };
                        t = t.min(d);
                    }
                }
                o.write(t);
            }
        }
    }

    /// Box-filters the tile's pixel sums into the band's rows of pixels, writing every
    /// pixel of the tile.
    fn write(
        &self,
        rect: Rect,
        sum: &[[f32; 3]],
        covered: &[u32],
        rgb: &mut [MaybeUninit<[f32; 3]>],
        alpha: &mut [MaybeUninit<f32>],
    ) {
        let f = self.frame;
        let n = f.ssaa;
        let per_pixel = (n * n) as f32;
        // Exactly the division by per_pixel: it is a power of two (1, 4 or 16).
        let scale = 1.0 / per_pixel;
        let bg = self.settings.background;
        let pw = rect.w / n;
        let px0 = rect.x0 / n;
        for (row, (sum, covered)) in sum.chunks(pw).zip(covered.chunks(pw)).enumerate() {
            let k = row * f.width + px0;
            let (out, out_alpha) = (&mut rgb[k..k + pw], &mut alpha[k..k + pw]);
            for (((o, a), c), &k) in out.iter_mut().zip(out_alpha).zip(sum).zip(covered) {
                let empty = per_pixel - k as f32;
                o.write([
                    (c[0] + empty * bg[0]) * scale,
                    (c[1] + empty * bg[1]) * scale,
                    (c[2] + empty * bg[2]) * scale,
                ]);
                a.write(k as f32 * scale);
            }
        }
    }

    /// Lights every covered sample of the tile, adding it to its pixel's `sum` and
    /// `covered`; returns the number of samples lit. A sample showing the inside of a
    /// cut closed mesh, when the surfaces draw caps, is lit as its cap instead, and
    /// its key in `depth` becomes the cap's.
    fn resolve(
        &self,
        rect: Rect,
        (ids, depth): (&[u32], &mut [f32]),
        batch: &mut Batch,
        sum: &mut [[f32; 3]],
        covered: &mut [u32],
    ) -> u64 {
        let f = self.frame;
        let n = f.ssaa;
        let pw = rect.w / n;
        let mut tri = TriCache::EMPTY;
        let mut shaded = 0u64;
        batch.clear();
        for (y, row) in ids.chunks(rect.stride()).enumerate() {
            let fy = (rect.y0 + y) as f32;
            let prow = (y >> f.ssaa_shift) * pw;
            for (x, &id) in row[..rect.w].iter().enumerate() {
                if id == u32::MAX {
                    continue;
                }
                if id != tri.id {
                    tri = self.tri(id);
                }
                let fx = (rect.x0 + x) as f32;
                let (mut normal, base) = self.surface_at(&tri, fx, fy);
                if tri.cap {
                    if let Some((key, n)) = self.cap_at(fx, fy) {
                        depth[y * rect.stride() + x] = key;
                        normal = n;
                    }
                }
                batch.push(
                    id,
                    (prow + (x >> f.ssaa_shift)) as u32,
                    fx,
                    fy,
                    normal,
                    base,
                );
                if batch.is_full() {
                    shaded += batch.flush(self, sum, covered);
                }
            }
        }
        shaded + batch.flush(self, sum, covered)
    }

    /// What the resolve needs of triangle `id`.
    #[inline]
    fn tri(&self, id: u32) -> TriCache {
        let s = self.s;
        let idx = s.triangles[id as usize].map(|i| i as usize);
        let [a, b, c] = idx.map(|i| self.frame.verts[i]);
        let color = *self
            .settings
            .mesh_colors
            .get(s.mesh_of(id))
            .unwrap_or(&self.settings.color);
        TriCache {
            id,
            e: Edges::new(a, b, c),
            idx,
            normals: idx.map(|i| s.normals[i]),
            color,
            cap: self.shows_inside(id),
        }
    }

    /// Whether triangle `id` is a back face of a cut closed mesh whose cut the
    /// surfaces cap: the eye sees the inside of the solid through it.
    #[inline]
    fn shows_inside(&self, id: u32) -> bool {
        let s = self.s;
        let Some(caps) = &s.caps else {
            return false;
        };
        let o = caps.facing[id as usize];
        if o == 0 {
            return false;
        }
        let [pa, pb, pc] = s.triangles[id as usize].map(|i| s.positions[i as usize]);
        // The outward normal (the mesh's orientation turns the winding's normal out
        // of the matter) faces away from the eye.
        let out = (pb - pa).cross(pc - pa) * f32::from(o);
        let cam = &self.frame.camera;
        match cam.projection {
            Projection::Perspective => out.dot(pa - cam.eye) > 0.0,
            Projection::Orthographic => out.dot(cam.forward) > 0.0,
        }
    }

    /// The cap seen at sample `(x, y)`: the depth key where the sample's ray enters
    /// the kept region and the cap's normal there (facing the eye); `None` when the
    /// ray enters it through no plane in front of the eye.
    #[inline]
    fn cap_at(&self, x: f32, y: f32) -> Option<(f32, Vec3)> {
        let caps = self.s.caps.as_ref()?;
        let f = self.frame;
        let cam = &f.camera;
        let [u0, du, v0, dv] = f.plane;
        let (u, v) = (u0 + x * du, v0 + y * dv);
        let lateral = cam.right * u + cam.up * v;
        match cam.projection {
            // The ray's direction has a unit forward part: t is the depth z.
            Projection::Perspective => {
                let (t, n) = caps.entry(cam.eye, cam.forward + lateral)?;
                (t > 0.0).then(|| ((1.0 / t) as f32, n))
            }
            Projection::Orthographic => {
                let (t, n) = caps.entry(cam.eye + lateral, cam.forward)?;
                Some((-t as f32, n))
            }
        }
    }

    /// The normal interpolated perspective-correctly, not yet normalised (the batch
    /// does it, [`Batch::flush`]), and the unlit colour of the triangle at sample
    /// `(x, y)`.
    #[inline]
    fn surface_at(&self, tri: &TriCache, x: f32, y: f32) -> (Vec3, [f32; 3]) {
        let s = self.s;
        let e = &tri.e;
        let (w0, w1, w2) = e.at(x, y);
        // Perspective-correct barycentrics: screen weights times 1/z, renormalised.
        let (p0, p1, p2) = (w0 * e.a.w, w1 * e.b.w, w2 * e.c.w);
        let [n0, n1, n2] = tri.normals;
        if s.colors.is_none() && (s.scalars.is_none() || self.colors.is_none()) {
            // The batch normalises the normal, so the weights' common factor
            // 1 / (p0 + p1 + p2) (positive: the edge functions are signed to be
            // non-negative inside, 1/z positive) can be left out, and with it a
            // division per sample.
            return (n0 * p0 + n1 * p1 + n2 * p2, tri.color);
        }
        let inv = 1.0 / (p0 + p1 + p2);
        let beta = [p0 * inv, p1 * inv, p2 * inv];
        let normal = n0 * beta[0] + n1 * beta[1] + n2 * beta[2];
        let [i0, i1, i2] = tri.idx;
        let fixed = s.colors.as_ref().map(|c| {
            // The colour of the vertex nearest the sample: labels do not blend.
            let k = if beta[0] >= beta[1] && beta[0] >= beta[2] {
                i0
            } else if beta[1] >= beta[2] {
                i1
            } else {
                i2
            };
            c[k]
        });
        let scalar = match (&s.scalars, self.colors) {
            (Some(v), Some(map)) => {
                let sc = v[i0] * beta[0] + v[i1] * beta[1] + v[i2] * beta[2];
                (!sc.is_nan()).then(|| map.color(sc))
            }
            _ => None,
        };
        let base = match (fixed, scalar) {
            (Some(c), _) if !c[0].is_nan() => c,
            (_, Some(c)) => c,
            _ => tri.color,
        };
        (normal, base)
    }
}

/// The triangle the resolve last met (samples along a row mostly share one).
struct TriCache {
    id: u32,
    e: Edges,
    idx: [usize; 3],
    normals: [Vec3; 3],
    /// The colour of its mesh.
    color: [f32; 3],
    /// Whether its samples show a cap (`Ctx::shows_inside`).
    cap: bool,
}

impl TriCache {
    const EMPTY: TriCache = {
        let v = ScreenVertex {
            x: 0.0,
            y: 0.0,
            key: 0.0,
            w: 0.0,
        };
        TriCache {
            id: u32::MAX,
            e: Edges {
                a: v,
                b: v,
                c: v,
                sign: 1.0,
            },
            idx: [0; 3],
            normals: [Vec3::ZERO; 3],
            color: [0.0; 3],
            cap: false,
        }
    };
}

/// Keeps, per sample of `rect`, the nearer of triangle `t` (vertices `[a, b, c]`) and
/// what `depth`/`ids` hold. Samples on an edge belong to both triangles (no cracks;
/// the depth test picks one, the first drawn on a tie). Each sample's edge functions
/// are [`Edges::at`]'s, so the resolve's barycentrics agree with the coverage. The
/// reference of the AVX2 loop ([`super::avx2`]), which takes [`LANES`] samples of a
/// row at a time like this loop.
fn raster_scalar(
    [a, b, c]: [ScreenVertex; 3],
    t: &Binned,
    rect: Rect,
    depth: &mut [f32],
    ids: &mut [u32],
) {
    let Some([x0, y0, x1, y1]) = clip(t, rect) else {
        return;
    };
    let e = Edges::new(a, b, c);
    let inv_area = e.inv_area();
    let stride = rect.stride();
    let id = t.id;
    for y in y0..=y1 {
        let [e0, e1, e2] = e.row(y as f32);
        let row = (y - rect.y0) * stride;
        let mut xs = x0;
        while xs <= x1 {
            let k = row + xs - rect.x0;
            let (d, i) = (&mut depth[k..k + LANES], &mut ids[k..k + LANES]);
            let fx = xs as f32;
            let last = (x1 - xs) as f32;
            for l in 0..LANES {
                let x = fx + LANE_X[l];
                let w0 = e0.at(x, e.sign);
                let w1 = e1.at(x, e.sign);
                let w2 = e2.at(x, e.sign);
                let key = (w0 * a.key + w1 * b.key + w2 * c.key) * inv_area;
                let hit = LANE_X[l] <= last && w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 && key > d[l];
                if hit {
                    d[l] = key;
                    i[l] = id;
                }
            }
            xs += LANES;
        }
    }
}
