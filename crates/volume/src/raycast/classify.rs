//! A field classified by a transfer function, and the frames rendered from it.

use std::sync::{Arc, OnceLock};

use rayon::prelude::*;

use glint_core::camera::Camera;
use glint_core::{Image, RenderError, RenderMode, RenderStats, Shader, Vec3};

use super::caster::{Caster, IndexRays, Pixels};
use super::cells::{active_bounds, chessboard_distance, visible_blocks, visible_cells};
use super::colour::ColourVolume;
use super::settings::{ClassifySettings, FrameSettings, Kernel};
use super::start::StartBounds;
use super::{simd_supported, Scratch, TILE};
use crate::field::Field;
use crate::lut::Lut;
use crate::tf::TransferFunction;
use crate::transport::{DensityGrid, Medium, ShadowField};

/// The transfer function tabulated for `settings` (MIP shows the function's own
/// opacity, not a per-step one).
fn lut_for(field: &Field, tf: &TransferFunction, settings: &ClassifySettings) -> Lut {
    let (lo, hi) = table_range(field, tf);
    // The opacity correction's exponent: the step in units of the opacity's length.
    let lut_step = match (settings.mode, settings.opacity_unit) {
        (RenderMode::Mip, _) => 1.0,
        (_, None) => settings.step,
        (_, Some(unit)) => settings.step * field.min_spacing() / unit,
    };
    Lut::new(tf, lo, hi, lut_step)
}

/// How many times wider than the robust range the value range may be before the
/// table covers the transfer function's domain instead (issue 33: a float volume
/// with a few voxels at 1e29 put every other value into the table's first entry, and
/// rendered black). Ordinary scans stay far below it (CT: full range over robust
/// range about 1.5), so their tables, and images, are unchanged.
const OUTLIER_SPAN: f64 = 1000.0;

/// The values the table covers: the volume's range, or, when a few outliers stretch
/// it past [`OUTLIER_SPAN`] times the robust range, the part of it the transfer
/// function's domain covers (lookups beyond the table take its end entries, the
/// function's values beyond its domain).
fn table_range(field: &Field, tf: &TransferFunction) -> (f32, f32) {
    let (lo, hi) = field.range();
    let (rlo, rhi) = field.robust_range();
    let span = f64::from(hi) - f64::from(lo);
    let robust = (f64::from(rhi) - f64::from(rlo)).max(f64::MIN_POSITIVE);
    if span <= OUTLIER_SPAN * robust {
        return (lo, hi);
    }
    let (tlo, thi) = tf.domain();
    let a = (tlo as f32).clamp(lo, hi);
    let b = (thi as f32).clamp(lo, hi);
    if b > a {
        (a, b)
    } else {
        (lo, hi)
    }
}

/// Whether the affine's axes are far from orthogonal (the cosine of some pair's angle
/// above 0.1, about 84 degrees): scanners' grids, oblique or not, are orthogonal
/// (a CT gantry tilt above about 6 degrees counts too, and is framed the same way).
fn sheared(affine: &[[f64; 4]; 4]) -> bool {
    let col = |c: usize| [affine[0][c], affine[1][c], affine[2][c]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    [(0, 1), (0, 2), (1, 2)].iter().any(|&(i, j)| {
        let (a, b) = (col(i), col(j));
        dot(a, b).abs() > 0.1 * (dot(a, a) * dot(b, b)).sqrt()
    })
}

/// The world box of the voxels whose value the table gives opacity (`None`: none).
fn opaque_world_box(field: &Field, lut: &Lut) -> Option<([f64; 3], [f64; 3])> {
    let [nx, ny, _] = field.dims;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (i, &v) in field.values().iter().enumerate() {
        if lut.opaque[lut.index(v)] == 0 {
            continue;
        }
        let p = [
            (i % nx) as f64,
            (i / nx % ny) as f64,
            (i / (nx * ny)) as f64,
        ];
        let w = field.index_to_world(p);
        for a in 0..3 {
            lo[a] = lo[a].min(w[a]);
            hi[a] = hi[a].max(w[a]);
        }
    }
    (lo[0] <= hi[0]).then_some((lo, hi))
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
    /// For a sheared grid in composite mode: the world box of the voxels the transfer
    /// function gives opacity, which cameras frame ([`sheared`]).
    opaque_world: Option<([f64; 3], [f64; 3])>,
    /// World corners of the blocks of `START_BLOCK`^3 macro cells that hold a cell
    /// that can show a sample, for the rays' start bounds (empty when skipping is off
    /// or in MIP, whose leaps depend on the ray's maximum so far).
    pub(super) blocks: Vec<[Vec3; 8]>,
    /// The transfer function, for light transport's medium.
    tf: TransferFunction,
    /// Built on first use by light transport: the medium (extinction and colour per
    /// value, majorants per macro cell), the extinction on the light volumes' grid,
    /// and its local ambient occlusion.
    medium: OnceLock<Medium>,
    density: OnceLock<DensityGrid>,
    occlusion: OnceLock<Arc<Vec<f32>>>,
    /// [`Classification::with_colour`].
    colour: Option<Arc<ColourVolume>>,
}

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
        let visible = visible_cells(&field, &lut, settings);
        let visible_box = active_bounds(&field, &visible);
        let full_box = ([0.0; 3], field.dims.map(|d| (d - 1) as f64));
        let (distance, clip_box) = if settings.skip_empty {
            let clip_box = if settings.mode == RenderMode::Mip {
                full_box
            } else {
                visible_box.unwrap_or(([0.0; 3], [-1.0; 3]))
            };
            (chessboard_distance(&visible, field.cell_dims), clip_box)
        } else {
            (vec![0; visible.len()], full_box)
        };
        let opaque_world = match settings.mode {
            RenderMode::Composite if sheared(&field.affine()) => opaque_world_box(&field, &lut),
            _ => None,
        };
        let blocks = if settings.skip_empty && settings.mode != RenderMode::Mip {
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
            tf: tf.clone(),
            medium: OnceLock::new(),
            density: OnceLock::new(),
            occlusion: OnceLock::new(),
            opaque_world,
            colour: None,
        })
    }

    /// The classification with each composite or iso sample's colour taken from
    /// `colour` (a colour volume's data, trilinear) instead of the transfer function:
    /// the transfer function of the field's grey values still gives the opacity, and
    /// the field's gradient the normal. MIP keeps the transfer function's colour, and
    /// the `path` model's medium the transfer function's albedo. Frames with colour
    /// run the reference compositing loop (the SIMD loop reads no colour). Refused when
    /// `colour`'s grid is not the field's.
    pub fn with_colour(mut self, colour: Arc<ColourVolume>) -> Result<Classification, RenderError> {
        if colour.dims() != self.field.dims {
            return Err(RenderError::Parameter(format!(
                "colour volume of {:?} voxels for a field of {:?}",
                colour.dims(),
                self.field.dims
            )));
        }
        self.colour = Some(colour);
        Ok(self)
    }

    /// The colours samples take ([`Classification::with_colour`]); `None`: the
    /// transfer function's.
    pub fn colour(&self) -> Option<&Arc<ColourVolume>> {
        self.colour.as_ref()
    }

    /// The classified field as a participating medium (built on first use).
    pub(crate) fn medium(&self) -> &Medium {
        self.medium.get_or_init(|| {
            let unit = self
                .settings
                .opacity_unit
                .unwrap_or_else(|| self.field.min_spacing());
            Medium::new(&self.field, &self.tf, unit)
        })
    }

    /// The extinction on the light volumes' grid (built on first use).
    pub(crate) fn density(&self) -> &DensityGrid {
        self.density
            .get_or_init(|| DensityGrid::new(&self.field, self.medium()))
    }

    /// The local ambient occlusion on the light volumes' grid (built on first use).
    pub(crate) fn occlusion(&self) -> Arc<Vec<f32>> {
        self.occlusion
            .get_or_init(|| Arc::new(crate::transport::occlusion_grid(self.density())))
            .clone()
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
        if let Some((wlo, whi)) = self.opaque_world {
            // A strongly sheared grid's index box spans far more world than the object
            // in it (issue 33): frame the object's own world box.
            for n in 0..8 {
                corners.push([0, 1, 2].map(|a| if n & (1 << a) != 0 { whi[a] } else { wlo[a] }));
            }
        } else {
            for n in 0..8 {
                let p = [0, 1, 2].map(|a| if n & (1 << a) != 0 { hi[a] } else { lo[a] });
                corners.push(field.index_to_world(p));
            }
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
            glint_core::camera::Projection::Perspective => 1.1,
            glint_core::camera::Projection::Orthographic => 1.02,
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
        self.render_jittered(shader, settings, progress, true, None, None)
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
        self.render_jittered(shader, settings, progress, true, Some(far), None)
    }

    /// [`Classification::render`] with the per-pixel [`jitter`] on or off (off only
    /// in tests that compare the two), rays stopped at `far` when given
    /// ([`Classification::render_in_front`]; `width * height` long), and each light
    /// scaled by its transmittance from `shadows` when given (the `shadows` model).
    pub(crate) fn render_jittered(
        &self,
        shader: &Shader,
        settings: &FrameSettings,
        progress: &(dyn Fn(u64) + Sync),
        jitter: bool,
        far: Option<&[f32]>,
        shadows: Option<&ShadowField>,
    ) -> Result<Image, RenderError> {
        let camera = self.camera(settings)?;
        let shader = &shader.placed(&camera);
        if let Some(s) = shadows {
            s.check_lights(shader)?;
        }
        let field = &*self.field;
        field.make_room();
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
            iso_value: self.settings.iso,
            skip_empty: self.settings.skip_empty,
            dt: (self.settings.step * field.min_spacing()) as f32,
            simd: settings.kernel == Kernel::Auto && simd_supported() && self.colour.is_none(),
            jitter,
            sampling: self.settings.sampling,
            shadows,
            colour: self.colour.as_deref(),
        };
        let (tiles_x, tiles_y) = (w.div_ceil(TILE), h.div_ceil(TILE));
        let tiles: Vec<(Vec<[f32; 3]>, Vec<f32>, RenderStats)> = (0..tiles_x * tiles_y)
            .into_par_iter()
            .map_init(Scratch::default, |_scratch, t| {
                // Bricks this tile reads stay in the cache while it holds the guard.
                let guard = crossbeam_epoch::pin();
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
                    unsafe {
                        caster.tile_avx2(&px, _scratch, &mut rgb, &mut alpha, &mut stats, &guard)
                    };
                } else {
                    caster.tile(&px, &mut rgb, &mut alpha, &mut stats, &guard);
                }
                #[cfg(not(target_arch = "x86_64"))]
                caster.tile(&px, &mut rgb, &mut alpha, &mut stats, &guard);
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
        if let Some(problem) = field.problem() {
            return Err(RenderError::Volume(problem));
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
