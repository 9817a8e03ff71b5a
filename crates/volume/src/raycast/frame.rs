//! The ray caster's frames of a classification: the camera it frames, and the
//! image of its rays (lit locally or by the `shadows` model's light volumes).

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use glint_core::camera::Camera;
use glint_core::{Image, RenderError, RenderStats, Shader, Vec3};

use super::caster::{Caster, IndexRays, Pixels};
use super::settings::{FrameSettings, Kernel};
use super::start::StartBounds;
use super::{simd_supported, Scratch, TILE};
use crate::classification::Classification;
use crate::clip::IndexClip;
use crate::light::ShadowField;

impl Classification {
    /// The camera [`Classification::frame`] uses for `settings`: it frames the
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

    /// The ray caster of a frame of `settings` seen by `camera` (from
    /// [`Classification::camera`]), lit by `shader` (placed for `camera`): what
    /// the frame's rays and a pick's one ray ([`Classification::pick`]) share.
    pub(super) fn caster<'a>(
        &'a self,
        camera: &Camera,
        shader: &'a Shader,
        settings: &'a FrameSettings,
        jitter: bool,
        shadows: Option<&'a ShadowField>,
        clip: Option<&'a IndexClip>,
    ) -> Caster<'a> {
        let field = &*self.field;
        Caster {
            field,
            lut: &self.lut,
            distance: &self.distance,
            clip_box: (
                self.clip_box.0.map(|x| x as f32),
                self.clip_box.1.map(|x| x as f32),
            ),
            rays: IndexRays::new(camera, field, settings.width, settings.height),
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
            clip,
        }
    }

    /// The ray caster's frame ([`Classification::frame`] under the `local` and
    /// `shadows` models) with the per-pixel [`jitter`](super::caster::jitter) on or off
    /// (off only in tests that compare the two), within `limits`: rays stopped at
    /// `far`, each light scaled by its transmittance from `shadows` (the `shadows`
    /// model), tiles not begun once `cancel` is set left (the frame then returns
    /// [`RenderError::Cancelled`]).
    pub(crate) fn render_jittered(
        &self,
        shader: &Shader,
        settings: &FrameSettings,
        progress: &(dyn Fn(u64) + Sync),
        jitter: bool,
        limits: CastLimits<'_>,
    ) -> Result<Image, RenderError> {
        let CastLimits {
            far,
            shadows,
            cancel,
        } = limits;
        let stopped = || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
        let camera = self.camera(settings)?;
        let shader = &shader.placed(&camera);
        if let Some(s) = shadows {
            s.check_lights(shader)?;
        }
        let field = &*self.field;
        field.make_room();
        let (w, h) = (settings.width as usize, settings.height as usize);
        let clip = self.index_clip(shader, settings);
        let caster = self.caster(&camera, shader, settings, jitter, shadows, clip.as_ref());
        let starts = (!self.blocks.is_empty())
            .then(|| StartBounds::new(&self.blocks, &caster.rays, &camera, w, h));
        let (tiles_x, tiles_y) = (w.div_ceil(TILE), h.div_ceil(TILE));
        let tiles: Vec<(Vec<[f32; 3]>, Vec<f32>, RenderStats)> = (0..tiles_x * tiles_y)
            .into_par_iter()
            .map_init(Scratch::default, |_scratch, t| {
                if stopped() {
                    // Cancelled: the tiles not begun are left empty (the frame is
                    // dropped below).
                    return Default::default();
                }
                // Bricks this tile reads stay in the cache while it holds the guard.
                let guard = crossbeam_epoch::pin();
                let (x0, y0) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
                let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                let n = (x1 - x0) * (y1 - y0);
                let mut start = match &starts {
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
                if let Some(clip) = &clip {
                    cut_bounds(clip, &caster.rays, (x0, x1), (y0, y1), &mut start, &mut end);
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
        // The flag is only ever set during a frame: unset now, no tile was left.
        if stopped() {
            return Err(RenderError::Cancelled);
        }
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

/// What ends a ray-cast frame's rays besides the volume, and the frame itself
/// ([`Classification::frame_cancellable`]).
#[derive(Clone, Copy, Default)]
pub(crate) struct CastLimits<'a> {
    /// Per-pixel distances past which the volume is hidden (`width * height` long,
    /// checked by the caller).
    pub(crate) far: Option<&'a [f32]>,
    /// The `shadows` model's light volumes.
    pub(crate) shadows: Option<&'a ShadowField>,
    /// Set by another thread to stop the frame: tiles not begun are left.
    pub(crate) cancel: Option<&'a AtomicBool>,
}

/// Cuts the start and end bounds of the tile's rays (`xs` x `ys`, row-major) to the
/// part of each ray `clip` keeps: a ray it keeps nothing of starts at +inf (takes no
/// sample), as one that meets no visible block does.
fn cut_bounds(
    clip: &IndexClip,
    rays: &IndexRays,
    xs: (usize, usize),
    ys: (usize, usize),
    start: &mut [f32; TILE * TILE],
    end: &mut [f32; TILE * TILE],
) {
    let tw = xs.1 - xs.0;
    for y in ys.0..ys.1 {
        for x in xs.0..xs.1 {
            let i = (y - ys.0) * tw + (x - xs.0);
            let (o, d, _) = rays.ray(x as f32, y as f32);
            let (a, b) = clip.interval(o, d, (start[i], end[i]));
            if a > b {
                start[i] = f32::INFINITY;
            } else {
                (start[i], end[i]) = (a, b);
            }
        }
    }
}
