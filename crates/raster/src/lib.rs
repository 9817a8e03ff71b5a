//! A CPU triangle rasterizer for surfaces ([`glint_io::Mesh`]): z-buffer, normals
//! interpolated perspective-correctly so the lobe is evaluated per pixel, two-sided
//! lighting, supersampling, per-vertex scalars through a [`ColorMap`](glint_core::ColorMap),
//! tiles in parallel.
//!
//! Each tile is drawn in two passes (deferred shading): the first keeps, per sample,
//! the nearest triangle; the second lights every covered sample once. A sample is lit
//! at most once however many triangles overlap it.
//!
//! ```
//! use glint_core::{Light, Material, Shader};
//! use glint_io::Mesh;
//! use glint_lobe::{Geometry, LobeKind};
//! use glint_raster::{SurfaceSettings, Surfaces};
//!
//! // A tetrahedron, lit by the headlight with the paper's lobe.
//! let mesh = Mesh {
//!     positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
//!     triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
//!     normals: None,
//!     scalars: None,
//! };
//! let surfaces = Surfaces::new([&mesh]).unwrap();
//! let settings = SurfaceSettings { width: 32, height: 32, ..SurfaceSettings::default() };
//! let camera = surfaces.camera(&settings).unwrap();
//! let shader = Shader::new(LobeKind::EnergyFit, 40.0, 4, Geometry::Phong,
//!     Material::default(), vec![Light::HEADLIGHT], 0.0).unwrap();
//! let image = surfaces.render(&camera, &shader, &settings, None).unwrap();
//! assert_eq!(image.alpha[16 * 32 + 16], 1.0);
//! assert_eq!(image.alpha[0], 0.0);
//! ```

#![warn(missing_docs)]

#[cfg(target_arch = "x86_64")]
mod avx2;
mod clip;
mod ctx;
mod cull;
mod frame;
mod pick;
mod rect;
mod shade;
mod tile;

use std::mem::MaybeUninit;

use glint_io::{IoError, Mesh};
use rayon::prelude::*;

pub use self::pick::SurfaceHit;

use self::ctx::Ctx;
use self::frame::Frame;
use self::tile::{Out, Scratch};
use glint_core::camera::{Camera, CameraSpec};
use glint_core::Image;
use glint_core::RenderError;
use glint_core::ScalarColors;
use glint_core::Shader;
use glint_core::Vec3;
use glint_core::{RenderStats, MAX_IMAGE_SIDE};

/// Supersampling factors (samples per pixel along each axis) a surface render takes.
pub const SSAA_FACTORS: [u32; 3] = [1, 2, 4];

/// Tile edge in output pixels: 32 x 32 pixels (up to 128 x 128 samples at 4x SSAA)
/// keeps a tile's depth and triangle buffers (8 bytes a sample) within L2.
/// A power of two, so tile and pixel indices are shifts.
const TILE_PIXELS: u32 = 32;
const _: () = assert!(TILE_PIXELS.is_power_of_two());

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
    /// Per triangle: the orientation of its closed component, 0 where it has none
    /// (`cull::Closure::of`); back faces of closed components are culled.
    facing: Vec<i8>,
    /// Per mesh: its bounding box and the caps of its holes, for culling.
    closures: Vec<cull::Closure>,
    /// What closes the cut of clipped meshes ([`Surfaces::clipped`] with caps).
    caps: Option<clip::Caps>,
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
            facing: Vec::new(),
            closures: Vec::new(),
            caps: None,
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
        let normals: Vec<Vec3> = match &mesh.normals {
            Some(v) => v
                .iter()
                .map(|p| Vec3::new(p[0], p[1], p[2]).normalize_or_zero())
                .collect(),
            None => glint_mesh::vertex_normals(&mesh.positions, &mesh.triangles)
                .into_iter()
                .map(|n| Vec3::new(n[0], n[1], n[2]))
                .collect(),
        };
        self.mesh_starts.push((base, self.triangles.len() as u32));
        let (facing, closure) = cull::Closure::of(&positions, &mesh.triangles);
        self.facing.extend(facing);
        self.closures.push(closure);
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

    /// The corners of every triangle (world mm, as the meshes place them), triangle by
    /// triangle: what light transport voxelises to let the meshes occlude the volume.
    pub fn triangle_corners(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        self.triangles
            .iter()
            .map(|t| t.map(|i| self.positions[i as usize]))
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
        Ok(self
            .render_with(camera, shader, settings, colors, simd(), false)?
            .0)
    }

    /// [`Surfaces::render`], also giving each pixel's distance (mm) to the nearest
    /// surface it shows, along the pixel's ray from the eye (from the image plane for
    /// orthographic cameras), `f32::INFINITY` where it shows none: what a volume drawn
    /// with the same camera is hidden behind
    /// (glint-volume's `Classification::frame`, its `far`).
    pub fn render_layer(
        &self,
        camera: &Camera,
        shader: &Shader,
        settings: &SurfaceSettings,
        colors: Option<&ScalarColors>,
    ) -> Result<(Image, Vec<f32>), RenderError> {
        let (image, far) = self.render_with(camera, shader, settings, colors, simd(), true)?;
        Ok((image, far.expect("asked for")))
    }

    /// [`Surfaces::render`], on the AVX2 loops when `avx2` (which the CPU must
    /// support) or the scalar ones, with the distances of
    /// [`Surfaces::render_layer`] when `with_far`.
    fn render_with(
        &self,
        camera: &Camera,
        shader: &Shader,
        settings: &SurfaceSettings,
        colors: Option<&ScalarColors>,
        avx2: bool,
        with_far: bool,
    ) -> Result<(Image, Option<Vec<f32>>), RenderError> {
        settings.validate()?;
        let shader = &shader.placed(camera);
        let frame = Frame::new(self, camera, settings);
        let bands = frame.bin(self);
        let zeroed = settings.background.iter().all(|&b| b == 0.0);
        let ctx = Ctx {
            s: self,
            frame: &frame,
            shader,
            colors,
            settings,
            avx2,
            zeroed,
        };
        let (w, h) = (settings.width as usize, settings.height as usize);
        // The bands write every pixel once, in parallel, into uninitialised memory:
        // filling the image first (with zeros or the background) would be a serial
        // pass over 16 bytes a pixel.
        let mut rgb: Vec<[f32; 3]> = Vec::with_capacity(w * h);
        let mut alpha: Vec<f32> = Vec::with_capacity(w * h);
        let mut far: Vec<f32> = Vec::with_capacity(if with_far { w * h } else { 0 });
        let band = TILE_PIXELS as usize * w;
        let far_bands: Vec<Option<&mut [MaybeUninit<f32>]>> = if with_far {
            far.spare_capacity_mut()[..w * h]
                .chunks_mut(band)
                .map(Some)
                .collect()
        } else {
            (0..h.div_ceil(TILE_PIXELS as usize))
                .map(|_| None)
                .collect()
        };
        let shaded = rgb.spare_capacity_mut()[..w * h]
            .par_chunks_mut(band)
            .zip(alpha.spare_capacity_mut()[..w * h].par_chunks_mut(band))
            .zip(far_bands)
            .enumerate()
            .map_init(Scratch::default, |scratch, (b, ((rgb, alpha), far))| {
                ctx.band(&bands, b, Out { rgb, alpha, far }, scratch)
            })
            .sum();
        // SAFETY: `Ctx::band` initialises every element of the chunks it is given
        // (every pixel of every tile of its band: `Ctx::write`, `Ctx::write_far`, or
        // zeroed first when `zeroed`), and the chunks cover the first w * h elements
        // of the buffers, which their capacity holds. Had a band panicked, the lengths
        // would have stayed 0.
        unsafe {
            rgb.set_len(w * h);
            alpha.set_len(w * h);
            if with_far {
                far.set_len(w * h);
            }
        }
        let image = Image {
            width: settings.width,
            height: settings.height,
            rgb,
            alpha,
            stats: RenderStats {
                shaded,
                ..RenderStats::default()
            },
        };
        Ok((image, with_far.then_some(far)))
    }
}

#[cfg(test)]
mod tests;

/// Whether renders run the AVX2 loops: the CPU has AVX2 and `GLINT_SIMD` (read by
/// [`glint_lobe::KernelPath::cap`]) does not cap the kernels below it.
fn simd() -> bool {
    simd_within(glint_lobe::KernelPath::cap())
}

/// Whether the AVX2 loops run under the cap `cap` on this CPU.
fn simd_within(cap: glint_lobe::KernelPath) -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        cap >= glint_lobe::KernelPath::Avx2 && avx2::supported()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = cap;
        false
    }
}

/// The smallest box `[lo, hi]` around `positions`.
fn bounding_box(positions: &[Vec3]) -> [Vec3; 2] {
    let (mut lo, mut hi) = (
        Vec3::new(f32::MAX, f32::MAX, f32::MAX),
        Vec3::new(f32::MIN, f32::MIN, f32::MIN),
    );
    for p in positions {
        lo = Vec3::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z));
        hi = Vec3::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z));
    }
    [lo, hi]
}

fn bounding_sphere(positions: &[Vec3]) -> (Vec3, f32) {
    let [lo, hi] = bounding_box(positions);
    let center = (lo + hi) * 0.5;
    (center, ((hi - lo) * 0.5).length())
}
