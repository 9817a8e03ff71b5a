//! Picking: the point of the volume one ray of a frame shows ([`Classification::pick`]),
//! traced with the frame's camera, ray interval ([`Caster::ray`], which clipping
//! narrows), sampling and classification.

use crossbeam_epoch::Guard;
use glint_core::{RenderError, RenderMode, Shader};

use super::caster::{Caster, Ray};
use super::settings::FrameSettings;
use crate::classification::{Last, Sampling};
use crate::field::MACRO_CELL;
use crate::Classification;

/// Accumulated opacity at which a composite pick stops when the caller gives none:
/// the first point where the ray is more than half hidden (glint's choice, as
/// ParaView's and 3D Slicer's volume picking stop at a visible fraction).
pub const PICK_OPACITY: f32 = 0.5;

/// Sub-steps a composite pick marches the step in which the opacity crosses its
/// threshold: the point is found to a sixteenth of a step rather than a step.
const REFINE: u32 = 16;

/// Where one ray of a frame shows the volume ([`Classification::pick`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeHit {
    /// Distance along the ray, mm: from the eye (perspective) or from the image
    /// plane (orthographic), as [`Classification::frame`]'s `far` measures it.
    pub depth: f32,
    /// The point, voxel index units (continuous).
    pub index: [f64; 3],
    /// The point, world mm (RAS+).
    pub world: [f64; 3],
    /// The reconstruction value there (the prefiltered field the frame classifies,
    /// in the volume's units).
    pub value: f32,
    /// The ray's accumulated opacity at the point: composite, where it crossed the
    /// threshold (interpolated); iso 1; MIP, the maximum's classified opacity.
    pub opacity: f32,
}

impl Classification {
    /// The point of the volume the ray through image point `(x, y)` of a frame of
    /// `settings` shows, traced as the frame traces it (its camera, its jittered
    /// sampling, its classification and empty-space skipping, and its ray interval,
    /// stopped at `end` mm when a surface hides what lies behind): in composite mode
    /// the point where the accumulated opacity first reaches `threshold` (in 0..1;
    /// the step it crosses in marched again at a sixteenth of the step), in iso mode the iso surface's hit, in MIP the first sample holding the
    /// ray's maximum. `None` when the ray shows nothing there (it misses the volume,
    /// stays below the threshold, or meets no iso surface).
    ///
    /// `(x, y)` are the frame's pixel index coordinates: pixel `(i, j)`'s ray (its
    /// centre) is `(i, j)`, row 0 at the top; points off the image are refused.
    pub fn pick(
        &self,
        shader: &Shader,
        settings: &FrameSettings,
        (x, y): (f32, f32),
        end: f32,
        threshold: f32,
    ) -> Result<Option<VolumeHit>, RenderError> {
        let camera = self.camera(settings)?;
        let (w, h) = (settings.width as f32, settings.height as f32);
        if !(-0.5..w - 0.5).contains(&x) || !(-0.5..h - 0.5).contains(&y) {
            // Reported in the corner-based coordinates front ends take.
            return Err(RenderError::OffImage {
                x: f64::from(x) + 0.5,
                y: f64::from(y) + 0.5,
                width: settings.width,
                height: settings.height,
            });
        }
        if threshold.is_nan() || threshold <= 0.0 || threshold >= 1.0 {
            return Err(RenderError::Parameter(format!(
                "pick opacity threshold {threshold}: expected a number between 0 and 1 (exclusive)"
            )));
        }
        let shader = shader.placed(&camera);
        // The frame's clip planes and crop box cut this ray as they cut the frame's
        // (`cut_bounds`): a pick never lands in clipped space.
        let clip = self.index_clip(&shader, settings);
        let caster = self.caster(&camera, &shader, settings, true, None, clip.as_ref());
        let mut bounds = (0.0, end);
        if let Some(clip) = &clip {
            let (o, d, _) = caster.rays.ray(x, y);
            bounds = clip.interval(o, d, bounds);
            if bounds.0 > bounds.1 {
                return Ok(None);
            }
        }
        let Some((ray, _)) = caster.ray(x, y, bounds) else {
            return Ok(None);
        };
        let guard = crossbeam_epoch::pin();
        let hit = match self.settings.mode {
            RenderMode::Composite => caster.opacity_crossing(&ray, threshold, &guard),
            RenderMode::Iso => caster
                .iso_hit(&ray, self.settings.iso, &guard)
                .map(|t| (t, 1.0)),
            RenderMode::Mip => caster
                .mip_max(&ray, &guard)
                .map(|(best, t)| (caster.peak(&ray, t, &guard), self.lut.get(best)[3])),
            RenderMode::Surface => None,
        };
        let field = &*self.field;
        let hit = hit.map(|(t, opacity)| {
            let p = ray.at(t);
            let index = [p.x, p.y, p.z].map(f64::from);
            VolumeHit {
                depth: t,
                index,
                world: field.index_to_world(index),
                value: field.value_in(p, &guard),
                opacity,
            }
        });
        if let Some(problem) = field.problem() {
            return Err(RenderError::Volume(problem));
        }
        Ok(hit)
    }
}

impl Caster<'_> {
    /// The composite loop's opacity alone ([`Caster::composite`]: the same samples,
    /// segments, leaps and opacities, nothing shaded): the ray parameter (mm) where
    /// the accumulated opacity reaches `threshold` and the opacity there, `None` when
    /// it never does. The segment between the two samples it crosses between is
    /// marched again, finer ([`Caster::crossing`]).
    pub(super) fn opacity_crossing(
        &self,
        ray: &Ray,
        threshold: f32,
        guard: &Guard,
    ) -> Option<(f32, f32)> {
        let pre = &self.lut.pre;
        let mut alpha = 0.0f32;
        let mut k = ray.k0;
        let mut cached_cell = usize::MAX;
        let mut dist = 0;
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
            let leap = dist != 0;
            let front = match prev {
                Some((pk, u)) if pk == k - 1 => Some(u),
                _ => None,
            };
            let mut opacity = None;
            if self.sampling == Sampling::Point {
                if !leap {
                    opacity = Some(self.lut.get(self.field.value_at(&loc, guard))[3]);
                }
            } else if !leap || front.is_some() {
                let front = front.unwrap_or_else(|| self.before(ray, k, guard));
                let back = self.lut.position(self.field.value_at(&loc, guard));
                prev = Some((k, back));
                opacity = pre.segment(front, back, &mut last).map(|e| e[3]);
            }
            if let Some(a) = opacity.filter(|&a| a > 0.0) {
                let next = alpha + (1.0 - alpha) * a;
                if next >= threshold {
                    return Some((self.crossing(ray, k, alpha, threshold, guard), threshold));
                }
                alpha = next;
            }
            if leap {
                k = self.leap(ray, loc.ijk.map(|x| x / MACRO_CELL), dist, k);
            } else {
                k += 1;
            }
        }
        None
    }

    /// The ray parameter of the maximum near sample parameter `t` (the ray's largest
    /// sample): the vertex of the parabola through it and its neighbours, within half
    /// a step of it; `t` at the ray's ends or where the samples do not bend down.
    fn peak(&self, ray: &Ray, t: f32, guard: &Guard) -> f32 {
        let (first, last) = (ray.t(ray.k0, self.dt), ray.t(ray.k1, self.dt));
        if t - self.dt < first || t + self.dt > last {
            return t;
        }
        let value = |t: f32| self.field.value_in(ray.at(t), guard);
        let (a, b, c) = (value(t - self.dt), value(t), value(t + self.dt));
        let bend = a - 2.0 * b + c;
        // Not bending down (or NaN): no vertex to move to.
        if bend.is_nan() || bend >= 0.0 {
            return t;
        }
        t + self.dt * (0.5 * (a - c) / bend).clamp(-0.5, 0.5)
    }

    /// Where between samples `k - 1` and `k` of `ray` the accumulated opacity,
    /// `from` at sample `k - 1`, reaches `threshold`: the segment marched again at
    /// [`REFINE`] times the frame's rate (each sub-step's opacity the frame's
    /// classification of the values there, for its length), the optical depth
    /// `-ln(1 - alpha)` linear inside the sub-step that crosses. Sample `k` when the
    /// finer march does not cross (the frame's coarser one did).
    fn crossing(&self, ray: &Ray, k: i64, from: f32, threshold: f32, guard: &Guard) -> f32 {
        let t_end = ray.t(k, self.dt);
        let t_start = ray.t(k - 1, self.dt).max(ray.t_entry);
        if t_end <= t_start || t_start.is_nan() {
            return t_end;
        }
        let h = (t_end - t_start) / REFINE as f32;
        // Opacity over a sub-step from opacity over a step.
        let scale = h / self.dt;
        let depth = |a: f32| -(1.0 - a.min(1.0 - 1e-7)).ln();
        let value = |t: f32| self.field.value_in(ray.at(t), guard);
        let mut last = Last::default();
        let mut alpha = from;
        let mut front = self.lut.position(value(t_start));
        for i in 1..=REFINE {
            let t = t_start + h * i as f32;
            let v = value(t);
            let back = self.lut.position(v);
            let a = match self.sampling {
                Sampling::Point => self.lut.get(v)[3],
                _ => self
                    .lut
                    .pre
                    .segment(front, back, &mut last)
                    .map_or(0.0, |e| e[3]),
            };
            front = back;
            let a = 1.0 - (1.0 - a.min(1.0 - 1e-7)).powf(scale);
            let next = alpha + (1.0 - alpha) * a;
            if next >= threshold {
                let (d0, d1) = (depth(alpha), depth(next));
                let f = if d1 > d0 {
                    ((depth(threshold) - d0) / (d1 - d0)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                return t - h + h * f;
            }
            alpha = next;
        }
        t_end
    }
}
