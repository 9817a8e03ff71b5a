//! The CPU ray caster: tiles of rays in parallel (rayon), trilinear samples at a fixed
//! step, empty-space skipping over macro cells, early ray termination.

use std::str::FromStr;

use std::sync::Arc;

use rayon::prelude::*;

use crate::camera::{Camera, CameraSpec};
use crate::error::RenderError;
use crate::field::{Field, Loc, MACRO_CELL};
use crate::image::Image;
use crate::math::Vec3;
use crate::preint::{Last, Sampling};
use crate::shading::{RayLighting, Shader};
use crate::tf::{Lut, TransferFunction};

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
use avx2::Scratch;
/// The SIMD loops' per-thread buffers (none without them).
#[cfg(not(target_arch = "x86_64"))]
type Scratch = ();

/// How samples along a ray make a pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// Front-to-back compositing of shaded, classified samples.
    Composite,
    /// The first point where the value reaches `threshold`, shaded and opaque.
    Iso {
        /// The iso value.
        threshold: f32,
    },
    /// Maximum intensity projection, coloured by the transfer function.
    Mip,
}

impl FromStr for Mode {
    type Err = RenderError;
    /// `composite`, `mip` or `iso` (the threshold is set separately).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "composite" | "dvr" => Ok(Mode::Composite),
            "mip" => Ok(Mode::Mip),
            "iso" | "isosurface" => Ok(Mode::Iso { threshold: 0.0 }),
            _ => Err(RenderError::Parameter(format!(
                "unknown mode '{s}': expected composite, iso or mip"
            ))),
        }
    }
}

/// Largest image side accepted.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Accumulated opacity at which a ray stops (early ray termination, Levoy 1990).
pub const TERMINATION_OPACITY: f32 = 0.99;

/// Bisection steps refining an iso hit between two samples (2^-8 of a step).
const ISO_REFINE_STEPS: u32 = 8;

/// Edge of the square image tiles rendered as parallel tasks (a tile's rays read a
/// compact block of the volume that stays in the core's L2 cache).
const TILE: usize = 16;

/// What a [`Classification`] depends on besides the transfer function: the mode, the
/// sample step and empty-space skipping. Changing any of them means classifying again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClassifySettings {
    /// Compositing mode.
    pub mode: Mode,
    /// Sample distance in voxels (of the smallest spacing).
    pub step: f64,
    /// Empty-space skipping on (it never changes the image, only the speed).
    pub skip_empty: bool,
    /// Composite mode: the transfer function at samples or integrated between them.
    pub sampling: Sampling,
    /// The length of matter, in mm, whose opacity the transfer function gives (VTK's
    /// scalar opacity unit distance); `None`: one voxel of the smallest spacing, so a
    /// finer grid of the same object is denser per millimetre.
    pub opacity_unit: Option<f64>,
}

impl Default for ClassifySettings {
    fn default() -> Self {
        ClassifySettings {
            mode: Mode::Composite,
            step: 0.5,
            skip_empty: true,
            sampling: Sampling::default(),
            opacity_unit: None,
        }
    }
}

impl ClassifySettings {
    /// Checks the step and the iso threshold.
    pub fn validate(&self) -> Result<(), RenderError> {
        if !self.step.is_finite() || !(0.01..=100.0).contains(&self.step) {
            return Err(RenderError::Parameter(format!(
                "step {}: expected 0.01..=100 voxels",
                self.step
            )));
        }
        if let Mode::Iso { threshold } = self.mode {
            if !threshold.is_finite() {
                return Err(RenderError::Parameter(format!(
                    "iso threshold {threshold} is not finite"
                )));
            }
        }
        if let Some(u) = self.opacity_unit {
            if !u.is_finite() || !(1e-3..=1e4).contains(&u) {
                return Err(RenderError::Parameter(format!(
                    "opacity unit {u}: expected 0.001..=10000 mm"
                )));
            }
        }
        Ok(())
    }
}

/// What one frame of a [`Classification`] depends on besides the [`Shader`]: image
/// size, camera, background and the compositing loop. Changing them never classifies
/// again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Camera placement.
    pub camera: CameraSpec,
    /// Background colour, linear RGB.
    pub background: [f32; 3],
    /// Which compositing loop runs.
    pub kernel: Kernel,
}

impl Default for FrameSettings {
    fn default() -> Self {
        FrameSettings {
            width: 512,
            height: 512,
            camera: CameraSpec::default(),
            background: [0.0; 3],
            kernel: Kernel::Auto,
        }
    }
}

impl FrameSettings {
    /// Checks the image size and the background.
    pub fn validate(&self) -> Result<(), RenderError> {
        if self.width == 0
            || self.height == 0
            || self.width > MAX_IMAGE_SIDE
            || self.height > MAX_IMAGE_SIDE
        {
            return Err(RenderError::Parameter(format!(
                "image size {}x{}: each side must be 1..={MAX_IMAGE_SIDE}",
                self.width, self.height
            )));
        }
        if self.background.iter().any(|c| !c.is_finite()) {
            return Err(RenderError::Parameter("background is not finite".into()));
        }
        Ok(())
    }
}

/// The compositing loop a render uses. Both give the same image: bit-identical for
/// every lobe but `exact` and `gauss`, whose vectorised pow/exp differ from libm by at
/// most 2 ulp.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Kernel {
    /// The SIMD loop (eight samples at a time) when the CPU has AVX2 and FMA, else
    /// the scalar loop.
    #[default]
    Auto,
    /// The portable scalar loop, one sample at a time (the reference).
    Scalar,
}

impl Kernel {
    /// Whether [`Kernel::Auto`] runs the SIMD loop on this CPU (AVX2 and FMA).
    pub fn simd_available() -> bool {
        simd_supported()
    }
}

/// The transfer function tabulated for `settings` (MIP shows the function's own
/// opacity, not a per-step one).
fn lut_for(field: &Field, tf: &TransferFunction, settings: &ClassifySettings) -> Lut {
    let (lo, hi) = field.range();
    // The opacity correction's exponent: the step in units of the opacity's length.
    let lut_step = match (settings.mode, settings.opacity_unit) {
        (Mode::Mip, _) => 1.0,
        (_, None) => settings.step,
        (_, Some(unit)) => settings.step * field.min_spacing() / unit,
    };
    Lut::new(tf, lo, hi, lut_step)
}

/// Per macro cell: can a sample there show? (composite: some value in the cell's range
/// has opacity; iso: the cell reaches the threshold; MIP: the cell holds more than the
/// volume's minimum).
fn visible_cells(field: &Field, lut: &Lut, mode: Mode) -> Vec<bool> {
    let floor = field.range().0;
    field
        .cells
        .iter()
        .map(|&(cmin, cmax)| match mode {
            Mode::Composite => lut.any_opaque(cmin, cmax),
            Mode::Iso { threshold } => cmax >= threshold,
            Mode::Mip => cmax > floor,
        })
        .collect()
}

/// The `[i, j, k]` of linear index `idx` in a grid of `dims` (i fastest).
fn grid_coords(idx: usize, dims: [usize; 3]) -> [usize; 3] {
    [
        idx % dims[0],
        (idx / dims[0]) % dims[1],
        idx / (dims[0] * dims[1]),
    ]
}

/// World corners of every block of `START_BLOCK`^3 macro cells holding an `active`
/// one. A block's box covers its cells' boxes (cell `c` spans voxels `4c ..= 4c + 4`),
/// so every sample that can show lies inside some block's box.
fn visible_blocks(field: &Field, active: &[bool]) -> Vec<[Vec3; 8]> {
    let cd = field.cell_dims;
    let bd = cd.map(|c| c.div_ceil(START_BLOCK));
    let mut hit = vec![false; bd[0] * bd[1] * bd[2]];
    for (idx, _) in active.iter().enumerate().filter(|(_, v)| **v) {
        let b = grid_coords(idx, cd).map(|x| x / START_BLOCK);
        hit[b[0] + bd[0] * (b[1] + bd[1] * b[2])] = true;
    }
    let span = (START_BLOCK * MACRO_CELL) as f64;
    let mut out = Vec::new();
    for (idx, _) in hit.iter().enumerate().filter(|(_, v)| **v) {
        let b = grid_coords(idx, bd);
        let lo = b.map(|x| x as f64 * span);
        let hi = [0, 1, 2].map(|a| (lo[a] + span).min((field.dims[a] - 1) as f64));
        out.push(std::array::from_fn(|n| {
            let p = [0, 1, 2].map(|a| if n & (1 << a) != 0 { hi[a] } else { lo[a] });
            let w = field.index_to_world(p);
            Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32)
        }));
    }
    out
}

/// A block's footprint on the image: the pixels whose rays may meet it, and a lower
/// bound on the ray parameter (mm) at which they can.
#[derive(Clone, Copy)]
struct Splat {
    x: (usize, usize),
    y: (usize, usize),
    t: f32,
}

/// Per image tile, the blocks whose footprints overlap it: rays start at the nearest
/// block's bound instead of the clip box, which saves most of the leaps through the
/// empty space in front of the data (the CPU form of starting rays at the rasterised
/// front faces of non-empty bricks; Hadwiger et al., "Real-Time Volume Graphics",
/// 2006, section 8.1).
struct StartBounds {
    /// Tile `i`'s splats are `splats[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<usize>,
    splats: Vec<Splat>,
}

impl StartBounds {
    fn new(blocks: &[[Vec3; 8]], rays: &IndexRays, camera: &Camera, w: usize, h: usize) -> Self {
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
    fn tile(&self, tile: usize, xs: (usize, usize), ys: (usize, usize)) -> [f32; TILE * TILE] {
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

/// The index-space box (voxel-centre coordinates) covering the `active` macro cells,
/// `None` when none is.
fn active_bounds(field: &Field, active: &[bool]) -> Option<([f64; 3], [f64; 3])> {
    let cd = field.cell_dims;
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    for (idx, _) in active.iter().enumerate().filter(|(_, v)| **v) {
        let c = grid_coords(idx, cd);
        for a in 0..3 {
            lo[a] = lo[a].min(c[a] * MACRO_CELL);
            hi[a] = hi[a].max(((c[a] + 1) * MACRO_CELL).min(field.dims[a] - 1));
        }
    }
    (lo[0] != usize::MAX).then(|| (lo.map(|x| x as f64), hi.map(|x| x as f64)))
}

/// A field classified by a transfer function for one mode and sample step: the
/// tabulated transfer function, the empty-space map (per macro cell, the chessboard
/// distance to the nearest cell that can show a sample) and the boxes rays are clipped
/// to and cameras framed on.
///
/// Building it reads every macro cell; rendering only reads it. An interactive viewer
/// builds it once per transfer function and renders every frame that changes only the
/// camera, lights, lobe or image size from it (VTK's ray-cast mapper likewise keeps its
/// min-max volume until the transfer function changes).
pub struct Classification {
    field: Arc<Field>,
    lut: Lut,
    settings: ClassifySettings,
    /// Per macro cell: 0 where a sample can contribute, else the chessboard distance in
    /// cells to the nearest such cell (capped at 255); every cell closer than that is
    /// empty. All 0 when skipping is off.
    distance: Vec<u8>,
    /// Index-space box of the cells that can show a sample (`None`: no such cell).
    visible_box: Option<([f64; 3], [f64; 3])>,
    /// Index-space box rays are clipped to.
    clip_box: ([f64; 3], [f64; 3]),
    /// World corners of the blocks of `START_BLOCK`^3 macro cells that hold a cell
    /// that can show a sample, for the rays' start bounds (empty when skipping is off
    /// or in MIP, whose leaps depend on the ray's maximum so far).
    blocks: Vec<[Vec3; 8]>,
}

/// Edge, in macro cells, of the blocks whose projections bound where rays start (2:
/// 8 voxels; on the MNI152 scene 1 and 4 were 2% and 10% slower single-threaded,
/// from more splats to project and looser bounds respectively).
const START_BLOCK: usize = 2;

impl Classification {
    /// Classifies `field` by `tf` for the mode, step and empty-space skipping of
    /// `settings`. The classification keeps the field, so frames can be rendered from
    /// it alone (a viewer or a Python object holds it across frames).
    pub fn new(
        field: Arc<Field>,
        tf: &TransferFunction,
        settings: &ClassifySettings,
    ) -> Result<Classification, RenderError> {
        settings.validate()?;
        tf.validate()?;
        let lut = lut_for(&field, tf, settings);
        let visible = visible_cells(&field, &lut, settings.mode);
        let visible_box = active_bounds(&field, &visible);
        let full_box = ([0.0; 3], field.dims.map(|d| (d - 1) as f64));
        let (distance, clip_box) = if settings.skip_empty {
            let clip_box = if settings.mode == Mode::Mip {
                full_box
            } else {
                visible_box.unwrap_or(([0.0; 3], [-1.0; 3]))
            };
            (chessboard_distance(&visible, field.cell_dims), clip_box)
        } else {
            (vec![0; visible.len()], full_box)
        };
        let blocks = if settings.skip_empty && settings.mode != Mode::Mip {
            visible_blocks(&field, &visible)
        } else {
            Vec::new()
        };
        Ok(Classification {
            field,
            lut,
            blocks,
            settings: *settings,
            distance,
            visible_box,
            clip_box,
        })
    }

    /// The field it classifies.
    pub fn field(&self) -> &Arc<Field> {
        &self.field
    }

    /// The settings it was built for.
    pub fn settings(&self) -> &ClassifySettings {
        &self.settings
    }

    /// The camera [`Classification::render`] uses for `settings`: it frames the
    /// bounding sphere of what can be seen (the macro cells that can show a sample), or
    /// of the whole volume when nothing can.
    pub fn camera(&self, settings: &FrameSettings) -> Result<Camera, RenderError> {
        settings.validate()?;
        let field = &*self.field;
        let (lo, hi) = self
            .visible_box
            .unwrap_or(([0.0; 3], field.dims.map(|d| (d - 1) as f64)));
        let mut corners = Vec::with_capacity(8);
        for n in 0..8 {
            let p = [0, 1, 2].map(|a| if n & (1 << a) != 0 { hi[a] } else { lo[a] });
            corners.push(field.index_to_world(p));
        }
        let mut wlo = [f64::INFINITY; 3];
        let mut whi = [f64::NEG_INFINITY; 3];
        for c in &corners {
            for a in 0..3 {
                wlo[a] = wlo[a].min(c[a]);
                whi[a] = whi[a].max(c[a]);
            }
        }
        let center = Vec3::new(
            ((wlo[0] + whi[0]) / 2.0) as f32,
            ((wlo[1] + whi[1]) / 2.0) as f32,
            ((wlo[2] + whi[2]) / 2.0) as f32,
        );
        let radius = corners
            .iter()
            .map(|c| (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) - center).length())
            .fold(0.0f32, f32::max);
        // Place the camera for the bounding sphere, then tighten to the box's extent
        // across the view (the sphere of a box's corners wastes much of the image),
        // with a margin for perspective.
        let (w, h) = (settings.width, settings.height);
        let first = Camera::frame(&settings.camera, center, radius, w, h)?;
        let aspect = w as f32 / h as f32;
        let extent = corners
            .iter()
            .map(|c| {
                let d = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) - center;
                let (x, y) = (d.dot(first.right).abs(), d.dot(first.up).abs());
                // In units of the shorter image side.
                (x / aspect.max(1.0)).max(y * aspect.min(1.0))
            })
            .fold(0.0f32, f32::max);
        let margin = match settings.camera.projection {
            crate::camera::Projection::Perspective => 1.1,
            crate::camera::Projection::Orthographic => 1.02,
        };
        Camera::frame(&settings.camera, center, extent * margin, w, h)
    }

    /// Renders the classified field lit by `shader` (its lights placed relative to the
    /// camera of `settings`) with the size, background and kernel of `settings`.
    /// `progress` is called with the number of pixels finished after each tile (from
    /// worker threads).
    pub fn render(
        &self,
        shader: &Shader,
        settings: &FrameSettings,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Image, RenderError> {
        self.render_jittered(shader, settings, progress, true, None)
    }

    /// [`Classification::render`] with each ray stopped at a per-pixel distance:
    /// `far[y * width + x]` is the distance (mm, along the pixel's ray from the
    /// camera's eye, or from the image plane for orthographic cameras) past which the
    /// volume is hidden (e.g. by an opaque surface drawn with the same camera);
    /// `f32::INFINITY` where nothing hides it.
    pub fn render_in_front(
        &self,
        shader: &Shader,
        settings: &FrameSettings,
        progress: &(dyn Fn(u64) + Sync),
        far: &[f32],
    ) -> Result<Image, RenderError> {
        let pixels = settings.width as usize * settings.height as usize;
        if far.len() != pixels {
            return Err(RenderError::Parameter(format!(
                "{} ray limits for {pixels} pixels",
                far.len()
            )));
        }
        self.render_jittered(shader, settings, progress, true, Some(far))
    }

    /// [`Classification::render`] with the per-pixel [`jitter`] on or off (off only
    /// in tests that compare the two), and rays stopped at `far` when given
    /// ([`Classification::render_in_front`]; `width * height` long).
    pub(crate) fn render_jittered(
        &self,
        shader: &Shader,
        settings: &FrameSettings,
        progress: &(dyn Fn(u64) + Sync),
        jitter: bool,
        far: Option<&[f32]>,
    ) -> Result<Image, RenderError> {
        let camera = self.camera(settings)?;
        let shader = &shader.placed(&camera);
        let field = &*self.field;
        let (w, h) = (settings.width as usize, settings.height as usize);
        let rays = IndexRays::new(&camera, field, settings.width, settings.height);
        let starts =
            (!self.blocks.is_empty()).then(|| StartBounds::new(&self.blocks, &rays, &camera, w, h));
        let caster = Caster {
            field,
            lut: &self.lut,
            distance: &self.distance,
            clip_box: (
                self.clip_box.0.map(|x| x as f32),
                self.clip_box.1.map(|x| x as f32),
            ),
            rays,
            shader,
            frame: settings,
            mode: self.settings.mode,
            skip_empty: self.settings.skip_empty,
            dt: (self.settings.step * field.min_spacing()) as f32,
            simd: settings.kernel == Kernel::Auto && simd_supported(),
            jitter,
            sampling: self.settings.sampling,
        };
        let (tiles_x, tiles_y) = (w.div_ceil(TILE), h.div_ceil(TILE));
        let tiles: Vec<(Vec<[f32; 3]>, Vec<f32>, RenderStats)> = (0..tiles_x * tiles_y)
            .into_par_iter()
            .map_init(Scratch::default, |_scratch, t| {
                let (x0, y0) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
                let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                let n = (x1 - x0) * (y1 - y0);
                let start = match &starts {
                    Some(s) => s.tile(t, (x0, x1), (y0, y1)),
                    None => [0.0; TILE * TILE],
                };
                let mut end = [f32::INFINITY; TILE * TILE];
                if let Some(far) = far {
                    let tw = x1 - x0;
                    for (y, row) in (y0..y1).zip(end.chunks_mut(tw)) {
                        row.copy_from_slice(&far[y * w + x0..y * w + x1]);
                    }
                }
                let mut rgb = Vec::with_capacity(n);
                let mut alpha = Vec::with_capacity(n);
                let mut stats = RenderStats::default();
                let px = Pixels {
                    xs: (x0, x1),
                    ys: (y0, y1),
                    start: &start,
                    end: &end,
                };
                #[cfg(target_arch = "x86_64")]
                if caster.simd {
                    // SAFETY: `simd` is set only when avx2::supported() is true.
                    unsafe { caster.tile_avx2(&px, _scratch, &mut rgb, &mut alpha, &mut stats) };
                } else {
                    caster.tile(&px, &mut rgb, &mut alpha, &mut stats);
                }
                #[cfg(not(target_arch = "x86_64"))]
                caster.tile(&px, &mut rgb, &mut alpha, &mut stats);
                progress(n as u64);
                (rgb, alpha, stats)
            })
            .collect();
        let mut rgb = vec![[0.0f32; 3]; w * h];
        let mut alpha = vec![0.0f32; w * h];
        let mut stats = RenderStats::default();
        for (t, (trgb, talpha, tstats)) in tiles.into_iter().enumerate() {
            let (x0, y0) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
            let tw = (x0 + TILE).min(w) - x0;
            for (r, (crow, arow)) in trgb.chunks(tw).zip(talpha.chunks(tw)).enumerate() {
                let o = (y0 + r) * w + x0;
                rgb[o..o + tw].copy_from_slice(crow);
                alpha[o..o + tw].copy_from_slice(arow);
            }
            stats.samples += tstats.samples;
            stats.shaded += tstats.shaded;
            stats.skips += tstats.skips;
        }
        Ok(Image {
            width: settings.width,
            height: settings.height,
            rgb,
            alpha,
            stats,
        })
    }
}

/// Per-render state shared by all rays.
struct Caster<'a> {
    field: &'a Field,
    lut: &'a Lut,
    /// [`Classification::distance`].
    distance: &'a [u8],
    /// [`Classification::clip_box`] in f32.
    clip_box: ([f32; 3], [f32; 3]),
    /// The camera's rays in index space.
    rays: IndexRays,
    shader: &'a Shader,
    frame: &'a FrameSettings,
    /// [`ClassifySettings::mode`].
    mode: Mode,
    /// [`ClassifySettings::skip_empty`].
    skip_empty: bool,
    /// Step in mm.
    dt: f32,
    /// Run the AVX2 compositing loop.
    simd: bool,
    /// Offset each ray's samples by [`jitter`].
    jitter: bool,
    /// [`ClassifySettings::sampling`].
    sampling: Sampling,
}

/// Whether the CPU runs the SIMD compositing loop.
fn simd_supported() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        avx2::supported()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Chessboard (L-infinity) distance from every macro cell to the nearest `active` one,
/// in cells, saturating at 255: the exact two-pass chamfer transform with the 26
/// neighbours (Rosenfeld and Pfaltz 1966), O(cells). Each row takes the minimum over
/// its 12 neighbours in earlier (later) rows in one vectorisable sweep, then the one
/// along the row in a short serial sweep.
fn chessboard_distance(active: &[bool], dims: [usize; 3]) -> Vec<u8> {
    // Padded by one cell on every side (never active) so neighbours need no checks.
    let [px, py, pz] = dims.map(|d| d + 2);
    let row = |y: usize, z: usize| px * (y + py * z);
    let mut d = vec![u8::MAX; px * py * pz];
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            let src = &active[dims[0] * (y + dims[1] * z)..][..dims[0]];
            let dst = &mut d[row(y + 1, z + 1) + 1..][..dims[0]];
            for (o, &a) in dst.iter_mut().zip(src) {
                *o = if a { 0 } else { u8::MAX };
            }
        }
    }
    // Minimum of row `r` at x-1, x, x+1 into `m[x-1]` for x = 1..px-1.
    let min3 = |m: &mut [u8], r: &[u8]| {
        for (((o, &a), &b), &c) in m.iter_mut().zip(r).zip(&r[1..]).zip(&r[2..]) {
            *o = (*o).min(a.min(b).min(c));
        }
    };
    let mut m = vec![u8::MAX; px - 2];
    for z in 1..pz - 1 {
        for y in 1..py - 1 {
            let start = row(y, z);
            let (before, after) = d.split_at_mut(start);
            m.fill(u8::MAX);
            for ny in y - 1..=y + 1 {
                min3(&mut m, &before[row(ny, z - 1)..][..px]);
            }
            min3(&mut m, &before[row(y - 1, z)..][..px]);
            let cur = &mut after[..px];
            for (c, &n) in cur[1..px - 1].iter_mut().zip(&m) {
                *c = (*c).min(n.saturating_add(1));
            }
            for x in 1..px - 1 {
                cur[x] = cur[x].min(cur[x - 1].saturating_add(1));
            }
        }
    }
    for z in (1..pz - 1).rev() {
        for y in (1..py - 1).rev() {
            let start = row(y, z);
            let base = start + px;
            let (before, after) = d.split_at_mut(base);
            m.fill(u8::MAX);
            for ny in y - 1..=y + 1 {
                min3(&mut m, &after[row(ny, z + 1) - base..][..px]);
            }
            min3(&mut m, &after[row(y + 1, z) - base..][..px]);
            let cur = &mut before[start..];
            for (c, &n) in cur[1..px - 1].iter_mut().zip(&m) {
                *c = (*c).min(n.saturating_add(1));
            }
            for x in (1..px - 1).rev() {
                cur[x] = cur[x].min(cur[x + 1].saturating_add(1));
            }
        }
    }
    let mut out = Vec::with_capacity(active.len());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            out.extend_from_slice(&d[row(y + 1, z + 1) + 1..][..dims[0]]);
        }
    }
    out
}

#[cfg(test)]
mod start_tests {
    use super::*;
    use crate::camera::{Projection, View};

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

#[cfg(test)]
mod distance_tests {
    use super::{chessboard_distance, grid_coords};

    #[test]
    fn chessboard_distance_matches_brute_force() {
        let dims = [9, 7, 6];
        let n = dims.iter().product::<usize>();
        // Scattered active cells (a fixed pattern), then none at all.
        let scattered: Vec<bool> = (0..n).map(|i| (i * 37) % 101 == 3).collect();
        assert!(scattered.iter().filter(|a| **a).count() >= 3);
        for act in [scattered, vec![false; n]] {
            let d = chessboard_distance(&act, dims);
            let coords = |i: usize| grid_coords(i, dims);
            let cells: Vec<[usize; 3]> = (0..n).filter(|&i| act[i]).map(coords).collect();
            for (i, &di) in d.iter().enumerate() {
                let c = coords(i);
                let expect = cells
                    .iter()
                    .map(|a| (0..3).map(|k| c[k].abs_diff(a[k])).max().unwrap())
                    .min();
                match expect {
                    Some(e) => assert_eq!(di as usize, e, "cell {c:?}"),
                    // Nothing active: every distance is at least the grid's extent.
                    None => assert!(di as usize >= dims[0], "cell {c:?}: {di}"),
                }
            }
        }
    }
}

/// Work counts of one render (for tests and tuning; not timing).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderStats {
    /// Samples classified (composite mode).
    pub samples: u64,
    /// Samples with non-zero opacity, shaded and composited.
    pub shaded: u64,
    /// Macro cells leapt over.
    pub skips: u64,
}

impl Caster<'_> {
    /// Renders the pixels of `px`, row by row.
    #[inline(always)]
    fn tile(
        &self,
        px: &Pixels,
        rgb: &mut Vec<[f32; 3]>,
        alpha: &mut Vec<f32>,
        stats: &mut RenderStats,
    ) {
        let bg = self.frame.background;
        let (xs, ys) = (px.xs, px.ys);
        let tw = xs.1 - xs.0;
        for y in ys.0..ys.1 {
            for x in xs.0..xs.1 {
                let i = (y - ys.0) * tw + (x - xs.0);
                let (c, op) = self.cast(x as f32, y as f32, (px.start[i], px.end[i]), stats);
                rgb.push([
                    c[0] + (1.0 - op) * bg[0],
                    c[1] + (1.0 - op) * bg[1],
                    c[2] + (1.0 - op) * bg[2],
                ]);
                alpha.push(op);
            }
        }
    }

    /// [`Caster::tile`] compiled for AVX2 and FMA, with composite rays marched and
    /// lit by the SIMD loops of [`avx2`] (no FMA contraction anywhere, so results are
    /// the scalar loop's).
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn tile_avx2(
        &self,
        px: &Pixels,
        scratch: &mut Scratch,
        rgb: &mut Vec<[f32; 3]>,
        alpha: &mut Vec<f32>,
        stats: &mut RenderStats,
    ) {
        // SAFETY: this function's `# Safety` contract, which its callers uphold,
        // covers every unsafe operation below (CPU features, pointer ranges).
        unsafe {
            if self.mode == Mode::Composite {
                avx2::composite_tile(self, px, scratch, rgb, alpha, stats)
            } else {
                self.tile(px, rgb, alpha, stats)
            }
        }
    }

    /// Premultiplied colour and opacity of the ray through pixel `(x, y)`, whose
    /// samples outside `range` (mm) cannot show.
    #[inline(always)]
    fn cast(&self, x: f32, y: f32, range: (f32, f32), stats: &mut RenderStats) -> ([f32; 3], f32) {
        let Some((ray, view)) = self.ray(x, y, range) else {
            return ([0.0; 3], 0.0);
        };
        match self.mode {
            Mode::Composite => self.composite(&ray, &self.shader.for_ray(view), stats),
            Mode::Iso { threshold } => self.iso(&ray, view, threshold),
            Mode::Mip => self.mip(&ray),
        }
    }

    /// The ray through pixel `(x, y)` in index space with its sample range, and its
    /// view vector (unit, world, towards the eye); `None` when it takes no sample.
    /// Samples before `start` or past `end` (mm) cannot show.
    #[inline(always)]
    fn ray(&self, x: f32, y: f32, (start, end): (f32, f32)) -> Option<(Ray, Vec3)> {
        if start == f32::INFINITY {
            return None;
        }
        let (o, d, dir) = self.rays.ray(x, y);
        // Slab test against the box of voxel centres [0, dims-1], or the box of the
        // cells that can show a sample (samples outside it lie in inactive cells), t in
        // mm.
        let (lo_box, hi_box) = self.clip_box;
        let mut t0 = 0.0f32;
        let mut t1 = f32::INFINITY;
        let mut inv_dk = [f32::INFINITY; 3];
        let mut face_up = [true; 3];
        for a in 0..3 {
            let (lo, hi, oa, da) = (lo_box[a], hi_box[a], o.get(a), d.get(a));
            if da.abs() < 1e-12 {
                if oa < lo || oa > hi {
                    return None;
                }
            } else {
                let inv = 1.0 / da;
                let (ta, tb) = ((lo - oa) * inv, (hi - oa) * inv);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
                inv_dk[a] = inv / self.dt;
                face_up[a] = da > 0.0;
            }
        }
        let t_entry = t0;
        let t0 = t0.max(start);
        let t1 = t1.min(end);
        if t0 > t1 {
            return None;
        }
        // Sample k lies at t = (k + j) dt: the jitter j shifts the ray's samples by a
        // fraction of a step that varies from pixel to pixel.
        let j = if self.jitter { jitter(x, y) } else { 0.0 };
        let k0 = ceil_i64(t0 / self.dt - j);
        let k1 = floor_i64(t1 / self.dt - j);
        if k1 < k0 {
            return None;
        }
        let ray = Ray {
            o,
            d,
            inv_dk,
            face_up,
            k0,
            k1,
            t_entry,
            k_entry: ceil_i64(t_entry / self.dt - j),
            j,
        };
        // The view vector: from the sample towards the eye. Every sample of a ray lies
        // on the line through the eye, so -dir is exact for each (perspective-correct);
        // for orthographic rays it is the same for all.
        Some((ray, -dir))
    }

    /// The macro cell holding index-space point `p`.
    #[inline(always)]
    fn cell_of(&self, p: Vec3) -> ([usize; 3], usize) {
        let cd = self.field.cell_dims;
        let c = [
            ((p.x.max(0.0) as usize) / MACRO_CELL).min(cd[0] - 1),
            ((p.y.max(0.0) as usize) / MACRO_CELL).min(cd[1] - 1),
            ((p.z.max(0.0) as usize) / MACRO_CELL).min(cd[2] - 1),
        ];
        (c, c[0] + cd[0] * (c[1] + cd[1] * c[2]))
    }

    /// Leaps over the empty region around inactive macro cell `c`, whose entry in the
    /// distance map is `dist` (at least 1): the cube of cells closer than `dist` to it
    /// holds no active cell (Cohen and Sheffer 1994, "Proximity clouds"), so one leap
    /// crosses a whole empty region. Returns the first sample index past the cube,
    /// or `k + 1`, whichever is later.
    #[inline(always)]
    fn leap(&self, ray: &Ray, c: [usize; 3], dist: u8, k: i64) -> i64 {
        let r = dist as usize - 1;
        let mut q = f32::INFINITY;
        for (a, &ca) in c.iter().enumerate() {
            let face = if ray.face_up[a] {
                (ca + r + 1) * MACRO_CELL
            } else {
                ca.saturating_sub(r) * MACRO_CELL
            } as f32;
            // In samples; an axis the ray does not move along gives +inf or NaN, which
            // `min` ignores.
            q = q.min((face - ray.o.get(a)) * ray.inv_dk[a]);
        }
        // A sixty-fourth of a step short of the face: rounding can then never carry
        // the leap past the first sample beyond it.
        ceil_i64(q - ray.j - 1.0 / 64.0).max(k + 1)
    }

    /// Front-to-back compositing, one sample at a time (the reference loop). Each
    /// sample composites the pre-integrated segment from the previous sample
    /// ([`crate::preint`]); after a leap, or at the ray's first sample, the previous
    /// sample is read for that alone ([`Caster::before`]).
    fn composite(
        &self,
        ray: &Ray,
        lighting: &RayLighting,
        stats: &mut RenderStats,
    ) -> ([f32; 3], f32) {
        let pre = &self.lut.pre;
        let mut color = [0.0f32; 3];
        let mut alpha = 0.0f32;
        let mut k = ray.k0;
        let mut cached_cell = usize::MAX;
        let mut dist = 0;
        // The last sample read, and its table coordinate.
        let mut prev: Option<(i64, f32)> = None;
        let mut last = Last::default();
        while k <= ray.k1 {
            let p = ray.at(ray.t(k, self.dt));
            let loc = self.field.locate(p);
            let cell = self.field.cell_index(&loc);
            if cell != cached_cell {
                cached_cell = cell;
                dist = self.distance[cell];
            }
            // A sample in empty space still ends the segment from the sample before it,
            // when that one was read (the segment may leave a visible cell); the
            // segments between samples inside the leap's empty cells cross no opacity.
            let leap = dist != 0;
            let front = match prev {
                Some((pk, u)) if pk == k - 1 => Some(u),
                _ => None,
            };
            if self.sampling == Sampling::Point {
                if !leap {
                    stats.samples += 1;
                    let e = self.lut.get(self.field.value_at(&loc));
                    if e[3] > 0.0 && self.add(&loc, e, lighting, &mut color, &mut alpha, stats) {
                        break;
                    }
                }
            } else if !leap || front.is_some() {
                stats.samples += 1;
                let front = front.unwrap_or_else(|| self.before(ray, k));
                let back = self.lut.position(self.field.value_at(&loc));
                prev = Some((k, back));
                if let Some(e) = pre.segment(front, back, &mut last) {
                    if self.add(&loc, e, lighting, &mut color, &mut alpha, stats) {
                        break;
                    }
                }
            }
            if leap {
                stats.skips += 1;
                k = self.leap(ray, loc.ijk.map(|x| x / MACRO_CELL), dist, k);
            } else {
                k += 1;
            }
        }
        (color, alpha)
    }

    /// Shades the sample at `loc` with colour and opacity `rgba` and adds it behind
    /// `color` and `alpha`; returns whether the ray is now opaque enough to stop.
    #[inline(always)]
    fn add(
        &self,
        loc: &Loc,
        rgba: [f32; 4],
        lighting: &RayLighting,
        color: &mut [f32; 3],
        alpha: &mut f32,
        stats: &mut RenderStats,
    ) -> bool {
        stats.shaded += 1;
        let grad = self.field.gradient_at(loc);
        let rgb = self
            .shader
            .shade([rgba[0], rgba[1], rgba[2]], grad, lighting);
        let w = (1.0 - *alpha) * rgba[3];
        color[0] += w * rgb[0];
        color[1] += w * rgb[1];
        color[2] += w * rgb[2];
        *alpha += w;
        *alpha >= TERMINATION_OPACITY
    }

    /// The table coordinate of sample `k - 1` of `ray`: the front of the segment
    /// ending at sample `k`, when `k - 1` was not read (a leap or the ray's start just
    /// before `k`). The SIMD loop's lanes read it as their first sample of the step
    /// (`Lanes::segment_step`), with the same arithmetic.
    fn before(&self, ray: &Ray, k: i64) -> f32 {
        let loc = self.field.locate(ray.at(ray.t(k - 1, self.dt)));
        self.lut.position(self.field.value_at(&loc))
    }

    fn iso(&self, ray: &Ray, view: Vec3, threshold: f32) -> ([f32; 3], f32) {
        let mut k = ray.k0;
        let mut cached_cell = usize::MAX;
        let mut dist = 0;
        while k <= ray.k1 {
            let t = ray.t(k, self.dt);
            let p = ray.at(t);
            let (c, cell) = self.cell_of(p);
            if cell != cached_cell {
                cached_cell = cell;
                dist = self.distance[cell];
            }
            if dist != 0 {
                k = self.leap(ray, c, dist, k);
                continue;
            }
            if self.field.value(p) >= threshold {
                // Bisect between the previous sample point (below the threshold, or the
                // entry point) and this one.
                let mut lo = (t - self.dt).max(ray.t_entry);
                let mut hi = t;
                if k > ray.k_entry && self.field.value(ray.at(lo)) < threshold {
                    for _ in 0..ISO_REFINE_STEPS {
                        let mid = 0.5 * (lo + hi);
                        if self.field.value(ray.at(mid)) >= threshold {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    // Linear interpolation inside the last bracket.
                    let (vl, vh) = (self.field.value(ray.at(lo)), self.field.value(ray.at(hi)));
                    if vh > vl {
                        hi = lo + (hi - lo) * ((threshold - vl) / (vh - vl)).clamp(0.0, 1.0);
                    }
                }
                let p = ray.at(hi);
                let e = self.lut.get(threshold);
                let g = self.field.gradient(p);
                let lighting = self.shader.for_ray(view);
                let rgb = self.shader.shade([e[0], e[1], e[2]], g, &lighting);
                return (rgb, 1.0);
            }
            k += 1;
        }
        ([0.0; 3], 0.0)
    }

    fn mip(&self, ray: &Ray) -> ([f32; 3], f32) {
        let mut best = f32::NEG_INFINITY;
        let mut k = ray.k0;
        while k <= ray.k1 {
            let p = ray.at(ray.t(k, self.dt));
            if self.skip_empty {
                let (c, cell) = self.cell_of(p);
                // A cell whose maximum cannot beat the current best is skipped.
                if self.field.cells[cell].1 <= best {
                    k = self.leap(ray, c, self.distance[cell].max(1), k);
                    continue;
                }
            }
            best = best.max(self.field.value(p));
            k += 1;
        }
        if !best.is_finite() {
            return ([0.0; 3], 0.0);
        }
        let e = self.lut.get(best);
        ([e[0] * e[3], e[1] * e[3], e[2] * e[3]], e[3])
    }
}

/// A camera's rays ([`Camera::ray`]) expressed in a field's index space: per pixel a
/// few f32 operations, instead of building the world ray and transforming it in f64.
struct IndexRays {
    /// Perspective: the eye; orthographic: the image centre (index units).
    origin: Vec3,
    /// The camera's forward, right and up axes in world units, and in index units.
    world: [Vec3; 3],
    index: [Vec3; 3],
    perspective: bool,
    /// Image-plane coordinate of pixel `(x, y)`: `u = u0 + x du`, `v = v0 + y dv`.
    u0: f32,
    du: f32,
    v0: f32,
    dv: f32,
}

impl IndexRays {
    fn new(camera: &Camera, field: &Field, width: u32, height: u32) -> IndexRays {
        let to_index = |v: Vec3| {
            let d = field.direction_to_index([v.x as f64, v.y as f64, v.z as f64]);
            Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32)
        };
        let e = camera.eye;
        let o = field.world_to_index([e.x as f64, e.y as f64, e.z as f64]);
        let world = [camera.forward, camera.right, camera.up];
        let [u0, du, v0, dv] = camera.image_plane(width, height);
        IndexRays {
            origin: Vec3::new(o[0] as f32, o[1] as f32, o[2] as f32),
            world,
            index: world.map(to_index),
            perspective: camera.projection == crate::camera::Projection::Perspective,
            u0,
            du,
            v0,
            dv,
        }
    }

    /// Index-space origin, index-space direction (index units per mm) and unit world
    /// direction of the ray through pixel `(x, y)`.
    #[inline(always)]
    fn ray(&self, x: f32, y: f32) -> (Vec3, Vec3, Vec3) {
        let (u, v) = (self.u0 + x * self.du, self.v0 + y * self.dv);
        let [f, r, up] = self.index;
        if self.perspective {
            let [wf, wr, wu] = self.world;
            let w = wf + wr * u + wu * v;
            let inv = 1.0 / w.length();
            (self.origin, (f + r * u + up * v) * inv, w * inv)
        } else {
            (self.origin + r * u + up * v, f, self.world[0])
        }
    }
}

/// A ray in index space with its sample range.
struct Ray {
    o: Vec3,
    /// Direction: index units per mm.
    d: Vec3,
    /// Per axis `1 / (d dt)` (samples per index unit), +inf where the ray does not
    /// move along the axis.
    inv_dk: [f32; 3],
    /// Per axis: the ray moves towards higher indices (or not at all).
    face_up: [bool; 3],
    /// First and last sample index to visit.
    k0: i64,
    k1: i64,
    /// Where the ray enters the clip box (mm), and the first sample index there (the
    /// start bound may put `k0` later).
    t_entry: f32,
    k_entry: i64,
    /// The samples' offset, in steps, from multiples of the step ([`jitter`]).
    j: f32,
}

/// A tile's pixels and their rays' start bounds.
struct Pixels<'a> {
    xs: (usize, usize),
    ys: (usize, usize),
    /// Row-major over the tile: [`StartBounds::tile`].
    start: &'a [f32; TILE * TILE],
    /// Row-major over the tile: where each ray stops (mm; infinite unless a surface
    /// hides what lies behind, [`Classification::render_in_front`]).
    end: &'a [f32; TILE * TILE],
}

/// `ceil(x)` as an integer without libm (baseline x86-64 has no rounding
/// instruction); `x` is finite or saturates.
#[inline(always)]
fn ceil_i64(x: f32) -> i64 {
    let k = x as i64;
    k + ((k as f32) < x) as i64
}

/// `floor(x)` as an integer without libm.
#[inline(always)]
fn floor_i64(x: f32) -> i64 {
    let k = x as i64;
    k - ((k as f32) > x) as i64
}

impl Ray {
    #[inline(always)]
    fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }

    /// The ray parameter (mm) of sample `k`: `(k + j) dt` (the SIMD loop computes the
    /// same sum for `k = k0 + lane` as `(k0 + lane) + j`, exact for |k| < 2^24).
    #[inline(always)]
    fn t(&self, k: i64, dt: f32) -> f32 {
        (k as f32 + self.j) * dt
    }
}

/// The first sample's offset for pixel `(x, y)`, in [0, 1) steps: interleaved gradient
/// noise (J. Jimenez, "Next Generation Post Processing in Call of Duty: Advanced
/// Warfare", SIGGRAPH 2014 course), a deterministic low-discrepancy pattern whose
/// neighbouring pixels take well-spread offsets. Samples then no longer lie on the same
/// spheres (planes, orthographic) around the eye for all pixels, whose crossings with
/// the data's surfaces draw concentric "wood-grain" rings; what is left of sampling
/// error becomes fine, unstructured noise.
#[inline(always)]
fn jitter(x: f32, y: f32) -> f32 {
    let fract = |v: f32| v - v.floor();
    fract(52.982_918 * fract(0.067_110_56 * x + 0.005_837_15 * y))
}

#[cfg(test)]
mod jitter_tests {
    use super::*;
    use crate::tf::Material;
    use glint_io::{Samples, Volume};
    use glint_lobe::{Geometry, LobeKind};

    /// Largest per-channel difference (linear RGB, 0..1) allowed between the jittered
    /// and unjittered images of a smooth sphere, away from its silhouette: jitter moves
    /// every sample by less than one step along its ray, which changes the composite
    /// integral of a field smooth on the scale of a step by a small fraction of its
    /// value; the same differences at edges are excluded.
    const JITTER_TOLERANCE: f32 = 0.03;

    #[test]
    fn jittered_and_unjittered_smooth_spheres_agree_away_from_edges() {
        // Value r - |x| (mm from the centre), a cone that is linear along every ray:
        // opacity ramps in over 6 mm inside the surface at radius 20.
        let n = 48;
        let c = (n - 1) as f32 / 2.0;
        let mut v = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let d =
                        ((i as f32 - c).powi(2) + (j as f32 - c).powi(2) + (k as f32 - c).powi(2))
                            .sqrt();
                    v.push(20.0 - d);
                }
            }
        }
        let vol = Volume::new([n; 3], [1.0; 3], Samples::F32(v)).unwrap();
        let field = Arc::new(Field::new(&vol).unwrap());
        let tf =
            TransferFunction::from_flat(&[0.0, 0.0, 6.0, 0.08, 40.0, 0.08], &[0.0, 0.9, 0.7, 0.5])
                .unwrap();
        let settings = FrameSettings {
            width: 64,
            height: 64,
            ..Default::default()
        };
        let class = Classification::new(field, &tf, &ClassifySettings::default()).unwrap();
        let shader = Shader::new(
            LobeKind::Exact,
            10.0,
            0,
            Geometry::Phong,
            Material::default(),
            vec![crate::Light::HEADLIGHT],
            0.0,
        )
        .unwrap();
        let on = class
            .render_jittered(&shader, &settings, &|_| {}, true, None)
            .unwrap();
        let off = class
            .render_jittered(&shader, &settings, &|_| {}, false, None)
            .unwrap();
        assert_ne!(on.rgb, off.rgb, "jitter changed nothing");
        // Away from edges: pixels whose 5x5 neighbourhood is all nearly opaque.
        let (w, h) = (64usize, 64usize);
        let deep = |x: usize, y: usize| {
            (y.saturating_sub(2)..(y + 3).min(h)).all(|yy| {
                (x.saturating_sub(2)..(x + 3).min(w)).all(|xx| off.alpha[yy * w + xx] > 0.9)
            })
        };
        let mut checked = 0;
        for y in 2..h - 2 {
            for x in 2..w - 2 {
                if !deep(x, y) {
                    continue;
                }
                checked += 1;
                let (a, b) = (on.rgb[y * w + x], off.rgb[y * w + x]);
                for ch in 0..3 {
                    assert!(
                        (a[ch] - b[ch]).abs() <= JITTER_TOLERANCE,
                        "pixel ({x}, {y}): {a:?} vs {b:?}"
                    );
                }
            }
        }
        assert!(checked > 200, "only {checked} pixels inside the sphere");
    }

    #[test]
    fn jitter_is_a_fraction_of_a_step_and_deterministic() {
        let mut seen = [false; 10];
        for y in 0..32 {
            for x in 0..32 {
                let j = jitter(x as f32, y as f32);
                assert!((0.0..1.0).contains(&j), "{j}");
                assert_eq!(j.to_bits(), jitter(x as f32, y as f32).to_bits());
                seen[(j * 10.0) as usize] = true;
            }
        }
        // Spread over the whole step.
        assert!(seen.iter().all(|s| *s), "{seen:?}");
    }
}
