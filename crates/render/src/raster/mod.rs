//! A CPU triangle rasterizer for surfaces ([`glint_io::Mesh`]): z-buffer, normals
//! interpolated perspective-correctly so the lobe is evaluated per pixel, two-sided
//! lighting, supersampling, per-vertex scalars through a [`ColorMap`](crate::ColorMap),
//! tiles in parallel.
//!
//! Each tile is drawn in two passes (deferred shading): the first keeps, per sample,
//! the nearest triangle; the second lights every covered sample once. A sample is lit
//! at most once however many triangles overlap it.

mod shade;

use glint_io::{IoError, Mesh};
use rayon::prelude::*;

use crate::camera::{Camera, CameraSpec, Projection};
use crate::colormap::ScalarColors;
use crate::error::RenderError;
use crate::image::Image;
use crate::math::Vec3;
use crate::raycast::{RenderStats, MAX_IMAGE_SIDE};
use crate::shading::Shader;

/// Supersampling factors (samples per pixel along each axis) a surface render takes.
pub const SSAA_FACTORS: [u32; 3] = [1, 2, 4];

/// Tile edge in output pixels: 32 x 32 pixels (up to 128 x 128 samples at 4x SSAA)
/// keeps a tile's depth and triangle buffers (8 bytes a sample) within L2.
const TILE_PIXELS: u32 = 32;

/// Default surface colour, linear RGB: a light bone white (sRGB about 0.93, 0.89, 0.82).
pub const SURFACE_COLOR: [f32; 3] = [0.85, 0.77, 0.64];

/// How to render surfaces.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel along each axis: 1, 2 or 4 (box-filtered).
    pub ssaa: u32,
    /// Camera placement around the meshes' bounding sphere.
    pub camera: CameraSpec,
    /// Background colour, linear RGB.
    pub background: [f32; 3],
    /// Colour of surfaces without scalars, linear RGB.
    pub color: [f32; 3],
    /// Colour of each mesh (in the order given to [`Surfaces::new`]) without scalars,
    /// linear RGB; meshes past the end get `color`.
    pub mesh_colors: Vec<[f32; 3]>,
}

impl Default for SurfaceSettings {
    fn default() -> Self {
        SurfaceSettings {
            width: 512,
            height: 512,
            ssaa: 2,
            camera: CameraSpec::default(),
            background: [0.0; 3],
            color: SURFACE_COLOR,
            mesh_colors: Vec::new(),
        }
    }
}

impl SurfaceSettings {
    /// Checks the size, supersampling factor and colours.
    pub fn validate(&self) -> Result<(), RenderError> {
        if !(1..=MAX_IMAGE_SIDE).contains(&self.width)
            || !(1..=MAX_IMAGE_SIDE).contains(&self.height)
        {
            return Err(RenderError::Parameter(format!(
                "image size {}x{}: expected 1..={MAX_IMAGE_SIDE} on each side",
                self.width, self.height
            )));
        }
        if !SSAA_FACTORS.contains(&self.ssaa) {
            return Err(RenderError::Parameter(format!(
                "ssaa {}: expected 1, 2 or 4",
                self.ssaa
            )));
        }
        let colours = self
            .background
            .iter()
            .chain(&self.color)
            .chain(self.mesh_colors.iter().flatten());
        if colours.into_iter().any(|c| !c.is_finite() || *c < 0.0) {
            return Err(RenderError::Parameter(
                "background and surface colours must be finite and >= 0".into(),
            ));
        }
        Ok(())
    }
}

/// One or more meshes ready to render: positions, unit vertex normals, scalars and
/// triangles of all of them in one index space.
#[derive(Clone, Debug)]
pub struct Surfaces {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    /// Per-vertex scalars; NaN for vertices of meshes without them.
    scalars: Option<Vec<f32>>,
    triangles: Vec<[u32; 3]>,
    /// Per-vertex fixed colours (label colours), NaN where a vertex has none.
    colors: Option<Vec<[f32; 3]>>,
    /// First vertex and first triangle of each mesh.
    mesh_starts: Vec<(u32, u32)>,
    center: Vec3,
    radius: f32,
}

impl Surfaces {
    /// Gathers `meshes` into one scene. Fails with [`RenderError::Mesh`] on a
    /// non-finite coordinate, an index out of range, scalars or normals that do not
    /// match the vertices, or when there is no triangle at all. Degenerate triangles
    /// are kept (they cover no sample); vertex normals the files lack are computed
    /// from the triangles.
    pub fn new<'a>(meshes: impl IntoIterator<Item = &'a Mesh>) -> Result<Surfaces, RenderError> {
        let meshes: Vec<&Mesh> = meshes.into_iter().collect();
        let with_scalars = meshes.iter().any(|m| m.scalars.is_some());
        let mut s = Surfaces {
            positions: Vec::new(),
            normals: Vec::new(),
            scalars: with_scalars.then(Vec::new),
            triangles: Vec::new(),
            colors: None,
            mesh_starts: Vec::new(),
            center: Vec3::ZERO,
            radius: 0.0,
        };
        for (k, mesh) in meshes.iter().enumerate() {
            s.append(k, mesh)?;
        }
        if s.triangles.is_empty() {
            return Err(RenderError::Mesh(IoError::Inconsistent(
                "no triangles to render".into(),
            )));
        }
        (s.center, s.radius) = bounding_sphere(&s.positions);
        Ok(s)
    }

    fn append(&mut self, k: usize, mesh: &Mesh) -> Result<(), RenderError> {
        let bad =
            |what: String| RenderError::Mesh(IoError::Inconsistent(format!("mesh {k}: {what}")));
        mesh.validate().map_err(RenderError::Mesh)?;
        let n = mesh.positions.len();
        if mesh.normals.as_ref().is_some_and(|v| v.len() != n)
            || mesh.scalars.as_ref().is_some_and(|v| v.len() != n)
        {
            return Err(bad(format!(
                "normals or scalars do not match the {n} vertices"
            )));
        }
        let base = u32::try_from(self.positions.len())
            .ok()
            .filter(|b| b.checked_add(n as u32).is_some() && n < u32::MAX as usize)
            .ok_or_else(|| bad("more than 2^32 vertices in all".into()))?;
        let positions: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect();
        let normals = match &mesh.normals {
            Some(v) => v
                .iter()
                .map(|p| Vec3::new(p[0], p[1], p[2]).normalize_or_zero())
                .collect(),
            None => vertex_normals(&positions, &mesh.triangles),
        };
        self.mesh_starts.push((base, self.triangles.len() as u32));
        self.positions.extend(positions);
        self.normals.extend(normals);
        if let Some(s) = &mut self.scalars {
            match &mesh.scalars {
                Some(v) => s.extend_from_slice(v),
                None => s.extend(std::iter::repeat_n(f32::NAN, n)),
            }
        }
        self.triangles
            .extend(mesh.triangles.iter().map(|t| t.map(|i| i + base)));
        Ok(())
    }

    /// Gives the vertices of mesh `k` (in the order given to [`Surfaces::new`]) fixed
    /// colours, linear RGB (e.g. a parcellation's label colours), which replace the
    /// scalars' and the mesh colour. Fails when `k` is past the meshes or the colours do
    /// not match its vertices.
    pub fn set_vertex_colors(&mut self, k: usize, colors: &[[f32; 3]]) -> Result<(), RenderError> {
        let (v0, v1) = self.vertex_range(k).ok_or_else(|| {
            RenderError::Parameter(format!(
                "mesh {k}: there are {} meshes",
                self.mesh_starts.len()
            ))
        })?;
        if colors.len() != v1 - v0 {
            return Err(RenderError::Mesh(IoError::Inconsistent(format!(
                "mesh {k}: {} colours for {} vertices",
                colors.len(),
                v1 - v0
            ))));
        }
        let n = self.positions.len();
        let all = self.colors.get_or_insert_with(|| vec![[f32::NAN; 3]; n]);
        all[v0..v1].copy_from_slice(colors);
        Ok(())
    }

    /// Vertex index range of mesh `k`.
    fn vertex_range(&self, k: usize) -> Option<(usize, usize)> {
        let start = self.mesh_starts.get(k)?.0 as usize;
        let end = self
            .mesh_starts
            .get(k + 1)
            .map_or(self.positions.len(), |s| s.0 as usize);
        Some((start, end))
    }

    /// The mesh triangle `id` belongs to.
    #[inline]
    fn mesh_of(&self, id: u32) -> usize {
        self.mesh_starts.partition_point(|s| s.1 <= id) - 1
    }

    /// Number of meshes.
    pub fn mesh_count(&self) -> usize {
        self.mesh_starts.len()
    }

    /// Centre and radius of a sphere around every vertex (the bounding box's).
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        (self.center, self.radius)
    }

    /// The per-vertex scalars of all meshes (NaN where a mesh has none), if any has.
    pub fn scalars(&self) -> Option<&[f32]> {
        self.scalars.as_deref()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The camera `settings` place around the meshes' bounding sphere.
    pub fn camera(&self, settings: &SurfaceSettings) -> Result<Camera, RenderError> {
        settings.validate()?;
        Camera::frame(
            &settings.camera,
            self.center,
            self.radius,
            settings.width,
            settings.height,
        )
    }

    /// Renders the meshes seen by `camera` (from [`Surfaces::camera`]), lit by `shader`
    /// (its lights placed relative to `camera`),
    /// vertices with scalars coloured by `colors` (others get `settings.color`). The
    /// image's RGB is over the background; its alpha is the covered fraction of each
    /// pixel.
    pub fn render(
        &self,
        camera: &Camera,
        shader: &Shader,
        settings: &SurfaceSettings,
        colors: Option<&ScalarColors>,
    ) -> Result<Image, RenderError> {
        Ok(self.render_layer(camera, shader, settings, colors)?.0)
    }

    /// [`Surfaces::render`], also giving each pixel's distance (mm) to the nearest
    /// surface it shows, along the pixel's ray from the eye (from the image plane for
    /// orthographic cameras), `f32::INFINITY` where it shows none: what a volume drawn
    /// with the same camera is hidden behind
    /// ([`Classification::render_in_front`](crate::Classification::render_in_front)).
    pub fn render_layer(
        &self,
        camera: &Camera,
        shader: &Shader,
        settings: &SurfaceSettings,
        colors: Option<&ScalarColors>,
    ) -> Result<(Image, Vec<f32>), RenderError> {
        settings.validate()?;
        let shader = &shader.placed(camera);
        let frame = Frame::new(self, camera, settings);
        let bins = frame.bin(self);
        let tiles: Vec<(usize, TileOut)> = (0..frame.tiles_x * frame.tiles_y)
            .into_par_iter()
            .map(|t| (t, frame.tile(self, &bins, t, shader, colors, settings)))
            .collect();
        let (w, h) = (settings.width as usize, settings.height as usize);
        let mut image = Image {
            width: settings.width,
            height: settings.height,
            rgb: vec![settings.background; w * h],
            alpha: vec![0.0; w * h],
            stats: RenderStats::default(),
        };
        let mut depth = vec![f32::INFINITY; w * h];
        for (t, out) in tiles {
            let (px0, py0) = frame.tile_origin_px(t);
            for (row, (rgb, alpha)) in out
                .rgb
                .chunks(out.w)
                .zip(out.alpha.chunks(out.w))
                .enumerate()
            {
                let k = (py0 + row) * w + px0;
                image.rgb[k..k + out.w].copy_from_slice(rgb);
                image.alpha[k..k + out.w].copy_from_slice(alpha);
                depth[k..k + out.w].copy_from_slice(&out.depth[row * out.w..][..out.w]);
            }
            image.stats.shaded += out.shaded;
        }
        Ok((image, depth))
    }
}

/// Area-weighted unit vertex normals of a triangle mesh (the cross product of two
/// edges is twice the area times the unit normal, so summing them weights by area).
/// Vertices of degenerate triangles only get a zero normal.
pub fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] = normals[i as usize] + n;
        }
    }
    normals.iter().map(|n| n.normalize_or_zero()).collect()
}

fn bounding_sphere(positions: &[Vec3]) -> (Vec3, f32) {
    let (mut lo, mut hi) = (
        Vec3::new(f32::MAX, f32::MAX, f32::MAX),
        Vec3::new(f32::MIN, f32::MIN, f32::MIN),
    );
    for p in positions {
        lo = Vec3::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z));
        hi = Vec3::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z));
    }
    let center = (lo + hi) * 0.5;
    (center, ((hi - lo) * 0.5).length())
}

/// A vertex in sample space: `x`, `y` in samples (sample centres at integers),
/// `key` larger when nearer (1/z perspective, -z orthographic, both linear in screen
/// space), `w` the perspective weight 1/z (1 orthographic). `w` is NaN for vertices
/// behind the near plane.
#[derive(Clone, Copy, Debug)]
struct ScreenVertex {
    x: f32,
    y: f32,
    key: f32,
    w: f32,
}

/// Everything the tiles of one render share.
struct Frame {
    camera: Camera,
    verts: Vec<ScreenVertex>,
    /// Image plane of the sample grid (`Camera::image_plane`).
    plane: [f32; 4],
    ssaa: usize,
    /// Sample grid size.
    sw: usize,
    sh: usize,
    /// Tile edge in samples.
    tile: usize,
    tiles_x: usize,
    tiles_y: usize,
    width: usize,
    height: usize,
}

/// Per triangle-chunk, per tile: the triangles whose bounding box meets the tile.
type Bins = Vec<Vec<Vec<u32>>>;

/// One tile's pixels.
struct TileOut {
    w: usize,
    rgb: Vec<[f32; 3]>,
    alpha: Vec<f32>,
    /// Per pixel: the distance to its nearest covered sample ([`Surfaces::render_layer`]).
    depth: Vec<f32>,
    shaded: u64,
}

impl Frame {
    fn new(s: &Surfaces, camera: &Camera, settings: &SurfaceSettings) -> Frame {
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
            .map(|&p| project(camera, plane, near, p))
            .collect();
        let tile = TILE_PIXELS as usize * ssaa;
        Frame {
            camera: *camera,
            verts,
            plane,
            ssaa,
            sw,
            sh,
            tile,
            tiles_x: sw.div_ceil(tile),
            tiles_y: sh.div_ceil(tile),
            width,
            height,
        }
    }

    fn tile_origin_px(&self, t: usize) -> (usize, usize) {
        let step = TILE_PIXELS as usize;
        ((t % self.tiles_x) * step, (t / self.tiles_x) * step)
    }

    /// The sample-space bounding box of triangle `t` clipped to the image, or `None`
    /// when it covers no sample centre (off screen, behind the eye, degenerate).
    fn bbox(&self, tri: [u32; 3]) -> Option<[usize; 4]> {
        let [a, b, c] = tri.map(|i| self.verts[i as usize]);
        if !(a.w.is_finite() && b.w.is_finite() && c.w.is_finite()) {
            return None;
        }
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area == 0.0 || !area.is_finite() {
            return None;
        }
        let x0 = a.x.min(b.x).min(c.x).ceil().max(0.0);
        let y0 = a.y.min(b.y).min(c.y).ceil().max(0.0);
        let x1 = a.x.max(b.x).max(c.x).floor().min(self.sw as f32 - 1.0);
        let y1 = a.y.max(b.y).max(c.y).floor().min(self.sh as f32 - 1.0);
        (x0 <= x1 && y0 <= y1).then_some([x0 as usize, y0 as usize, x1 as usize, y1 as usize])
    }

    /// Bins the triangles by tile, a chunk of triangles per task.
    fn bin(&self, s: &Surfaces) -> Bins {
        let tiles = self.tiles_x * self.tiles_y;
        let chunk = s
            .triangles
            .len()
            .div_ceil(4 * rayon::current_num_threads())
            .max(1024);
        s.triangles
            .par_chunks(chunk)
            .enumerate()
            .map(|(c, tris)| {
                let mut bins = vec![Vec::new(); tiles];
                for (k, &tri) in tris.iter().enumerate() {
                    let Some([x0, y0, x1, y1]) = self.bbox(tri) else {
                        continue;
                    };
                    let id = (c * chunk + k) as u32;
                    for ty in y0 / self.tile..=y1 / self.tile {
                        for tx in x0 / self.tile..=x1 / self.tile {
                            bins[ty * self.tiles_x + tx].push(id);
                        }
                    }
                }
                bins
            })
            .collect()
    }

    /// Draws tile `t`: nearest triangle per sample, then lighting, then the box
    /// filter down to pixels.
    fn tile(
        &self,
        s: &Surfaces,
        bins: &Bins,
        t: usize,
        shader: &Shader,
        colors: Option<&ScalarColors>,
        settings: &SurfaceSettings,
    ) -> TileOut {
        let (tx, ty) = (t % self.tiles_x, t / self.tiles_x);
        let (sx0, sy0) = (tx * self.tile, ty * self.tile);
        let (tw, th) = (
            (self.sw - sx0).min(self.tile),
            (self.sh - sy0).min(self.tile),
        );
        let mut depth = vec![f32::NEG_INFINITY; tw * th];
        let mut ids = vec![u32::MAX; tw * th];
        for chunk in bins {
            for &id in &chunk[t] {
                self.raster(
                    s.triangles[id as usize],
                    id,
                    [sx0, sy0, tw, th],
                    &mut depth,
                    &mut ids,
                );
            }
        }
        let mut out = self.resolve(s, [sx0, sy0, tw, th], &ids, shader, colors, settings);
        out.depth = self.pixel_distances([sx0, sy0, tw, th], &depth);
        out
    }

    /// Per pixel of the tile `[x0, y0, w, h]` (samples): the distance along the ray
    /// to the nearest of its covered samples, whose depth keys are `keys`.
    fn pixel_distances(&self, rect: [usize; 4], keys: &[f32]) -> Vec<f32> {
        let [sx0, sy0, tw, th] = rect;
        let n = self.ssaa;
        let (pw, ph) = (tw / n, th / n);
        let [u0, du, v0, dv] = self.plane;
        let mut out = vec![f32::INFINITY; pw * ph];
        for (k, &key) in keys.iter().enumerate() {
            if key == f32::NEG_INFINITY {
                continue;
            }
            let (x, y) = (k % tw, k / tw);
            let t = match self.camera.projection {
                // key = 1/z, z along `forward`; the ray's direction is forward + u right
                // + v up, an orthonormal frame.
                Projection::Perspective => {
                    let (u, v) = (u0 + (sx0 + x) as f32 * du, v0 + (sy0 + y) as f32 * dv);
                    (1.0 + u * u + v * v).sqrt() / key
                }
                Projection::Orthographic => -key,
            };
            let p = &mut out[(y / n) * pw + x / n];
            *p = p.min(t);
        }
        out
    }

    /// Keeps, per sample of the tile `[x0, y0, w, h]`, the nearest of triangle `id`
    /// and what `depth`/`ids` hold. Samples on an edge belong to both triangles (no
    /// cracks; the depth test picks one).
    fn raster(&self, tri: [u32; 3], id: u32, rect: [usize; 4], depth: &mut [f32], ids: &mut [u32]) {
        let [tx0, ty0, tw, th] = rect;
        let Some([x0, y0, x1, y1]) = self.bbox(tri) else {
            return;
        };
        let (x0, y0) = (x0.max(tx0), y0.max(ty0));
        let (x1, y1) = (x1.min(tx0 + tw - 1), y1.min(ty0 + th - 1));
        if x0 > x1 || y0 > y1 {
            return;
        }
        let [a, b, c] = tri.map(|i| self.verts[i as usize]);
        let e = Edges::new(a, b, c);
        for y in y0..=y1 {
            let row = (y - ty0) * tw;
            let (mut w0, mut w1, mut w2) = e.at(x0 as f32, y as f32);
            for x in x0..=x1 {
                if w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 {
                    let key = (w0 * a.key + w1 * b.key + w2 * c.key) * e.inv_area;
                    let k = row + x - tx0;
                    if key > depth[k] {
                        depth[k] = key;
                        ids[k] = id;
                    }
                }
                w0 += e.dx[0];
                w1 += e.dx[1];
                w2 += e.dx[2];
            }
        }
    }

    /// Lights every covered sample of the tile and box-filters samples to pixels.
    fn resolve(
        &self,
        s: &Surfaces,
        rect: [usize; 4],
        ids: &[u32],
        shader: &Shader,
        colors: Option<&ScalarColors>,
        settings: &SurfaceSettings,
    ) -> TileOut {
        let [sx0, sy0, tw, th] = rect;
        let n = self.ssaa;
        let (pw, ph) = (tw / n, th / n);
        let mut sum = vec![[0.0f32; 3]; pw * ph];
        let mut covered = vec![0u32; pw * ph];
        for (k, &id) in ids.iter().enumerate() {
            if id == u32::MAX {
                continue;
            }
            let (x, y) = (k % tw, k / tw);
            let c = self.shade_sample(
                s,
                id,
                (sx0 + x) as f32,
                (sy0 + y) as f32,
                shader,
                colors,
                settings,
            );
            let p = (y / n) * pw + x / n;
            for i in 0..3 {
                sum[p][i] += c[i];
            }
            covered[p] += 1;
        }
        let per_pixel = (n * n) as f32;
        let bg = settings.background;
        let mut shaded = 0u64;
        let rgb = sum
            .iter()
            .zip(&covered)
            .map(|(c, &k)| {
                shaded += u64::from(k);
                let empty = per_pixel - k as f32;
                [0, 1, 2].map(|i| (c[i] + empty * bg[i]) / per_pixel)
            })
            .collect();
        let alpha = covered.iter().map(|&k| k as f32 / per_pixel).collect();
        debug_assert!(pw <= self.width && ph <= self.height);
        TileOut {
            w: pw,
            rgb,
            alpha,
            depth: Vec::new(),
            shaded,
        }
    }

    /// The lit colour of triangle `id` at sample `(x, y)`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn shade_sample(
        &self,
        s: &Surfaces,
        id: u32,
        x: f32,
        y: f32,
        shader: &Shader,
        colors: Option<&ScalarColors>,
        settings: &SurfaceSettings,
    ) -> [f32; 3] {
        let tri = s.triangles[id as usize];
        let [a, b, c] = tri.map(|i| self.verts[i as usize]);
        let e = Edges::new(a, b, c);
        let (w0, w1, w2) = e.at(x, y);
        // Perspective-correct barycentrics: screen weights times 1/z, renormalised.
        let (p0, p1, p2) = (w0 * a.w, w1 * b.w, w2 * c.w);
        let inv = 1.0 / (p0 + p1 + p2);
        let beta = [p0 * inv, p1 * inv, p2 * inv];
        let [i0, i1, i2] = tri.map(|i| i as usize);
        let mut normal =
            (s.normals[i0] * beta[0] + s.normals[i1] * beta[1] + s.normals[i2] * beta[2])
                .normalize_or_zero();
        if normal == Vec3::ZERO || !normal.x.is_finite() {
            let [pa, pb, pc] = [i0, i1, i2].map(|i| s.positions[i]);
            normal = (pb - pa).cross(pc - pa).normalize_or_zero();
        }
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
        let scalar = match (&s.scalars, colors) {
            (Some(v), Some(map)) => {
                let sc = v[i0] * beta[0] + v[i1] * beta[1] + v[i2] * beta[2];
                (!sc.is_nan()).then(|| map.color(sc))
            }
            _ => None,
        };
        let base = match (fixed, scalar) {
            (Some(c), _) if !c[0].is_nan() => c,
            (_, Some(c)) => c,
            _ => *settings
                .mesh_colors
                .get(s.mesh_of(id))
                .unwrap_or(&settings.color),
        };
        let cam = &self.camera;
        let view = match cam.projection {
            Projection::Perspective => {
                let [u0, du, v0, dv] = self.plane;
                -(cam.forward + cam.right * (u0 + x * du) + cam.up * (v0 + y * dv))
                    .normalize_or_zero()
            }
            Projection::Orthographic => -cam.forward,
        };
        shader.shade_surface(base, normal, view)
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

/// Edge functions of a screen triangle, scaled so they are non-negative inside
/// whatever its winding: at a point they sum to the triangle's (positive) doubled area.
struct Edges {
    a: ScreenVertex,
    b: ScreenVertex,
    c: ScreenVertex,
    sign: f32,
    inv_area: f32,
    /// Change of each edge function per sample to the right.
    dx: [f32; 3],
}

impl Edges {
    #[inline]
    fn new(a: ScreenVertex, b: ScreenVertex, c: ScreenVertex) -> Edges {
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        let sign = if area < 0.0 { -1.0 } else { 1.0 };
        Edges {
            a,
            b,
            c,
            sign,
            inv_area: 1.0 / (area * sign),
            dx: [(b.y - c.y) * sign, (c.y - a.y) * sign, (a.y - b.y) * sign],
        }
    }

    /// The three edge functions at `(x, y)`: `w0` opposite `a`, `w1` opposite `b`,
    /// `w2` opposite `c`.
    #[inline]
    fn at(&self, x: f32, y: f32) -> (f32, f32, f32) {
        let f = |p: ScreenVertex, q: ScreenVertex| {
            ((q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x)) * self.sign
        };
        (f(self.b, self.c), f(self.c, self.a), f(self.a, self.b))
    }
}
