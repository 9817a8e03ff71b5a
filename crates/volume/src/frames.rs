//! Frames of a classification under the `shadows` and `path` models: above both the
//! ray caster (`raycast`) and the light transport (`transport`), which it joins.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use glint_core::{Image, RenderError, RenderMode, RenderStats, Shader, Vec3};

use crate::field::Field;
use crate::raycast::{Classification, FrameSettings};
use crate::transport::{
    check_spp, Occluders, PathImage, PathSettings, PathTracer, ShadowField, ShadowSettings,
};

/// The index-space direction (index units per mm) of the world direction `v`.
pub(crate) fn direction_to_index(field: &Field, v: Vec3) -> Vec3 {
    let o = field.world_to_index([0.0; 3]);
    let e = field.world_to_index([v.x as f64, v.y as f64, v.z as f64]);
    Vec3::new(
        (e[0] - o[0]) as f32,
        (e[1] - o[1]) as f32,
        (e[2] - o[2]) as f32,
    )
}

/// Checks that `far`, when given, has one entry per pixel of `frame`.
fn check_far(frame: &FrameSettings, far: Option<&[f32]>) -> Result<(), RenderError> {
    let pixels = frame.width as usize * frame.height as usize;
    match far {
        Some(f) if f.len() != pixels => Err(RenderError::Parameter(format!(
            "{} ray limits for {pixels} pixels",
            f.len()
        ))),
        _ => Ok(()),
    }
}

/// What [`Classification::trace_paths_into`] adds samples to, and what stops its
/// rays besides the volume.
pub struct PathTarget<'a> {
    /// The image the samples are added to.
    pub image: &'a mut PathImage,
    /// Samples per pixel it holds when the call returns.
    pub spp: u32,
    /// Per pixel, where the camera ray stops (mm; the meshes' depth), when given.
    pub far: Option<&'a [f32]>,
    /// Meshes voxelised on this classification's field ([`Occluders::new`]): shadow
    /// rays and scattered paths end where they enter an occupied cell.
    pub occluders: Option<&'a Occluders>,
}

impl Classification {
    /// The `shadows` model's light volumes for the lights of `shader` placed for the
    /// camera of `frame` ([`ShadowField`]), with ambient occlusion when `settings`
    /// asks. The averaged extinction and the occlusion are built on first use and kept
    /// with the classification; the light volumes are built here.
    pub fn shadow_field(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        settings: &ShadowSettings,
    ) -> Result<ShadowField, RenderError> {
        self.shadow_field_occluded(shader, frame, settings, None)
    }

    /// [`Classification::shadow_field`] with the grid points `occluders` occupy
    /// (meshes voxelised by [`Occluders::new`] on this classification's field) opaque:
    /// the meshes cast their shadows into the volume. `None` gives the light volumes
    /// of [`Classification::shadow_field`], bit for bit.
    pub fn shadow_field_occluded(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        settings: &ShadowSettings,
        occluders: Option<&Occluders>,
    ) -> Result<ShadowField, RenderError> {
        let camera = self.camera(frame)?;
        let placed = shader.placed(&camera);
        let field = &**self.field();
        let dirs: Vec<Vec3> = placed
            .world_lights()
            .iter()
            .map(|&(l, _)| direction_to_index(field, l))
            .collect();
        let occlusion = settings.occlusion.then(|| self.occlusion());
        ShadowField::new(
            self.density(),
            ShadowField::light_bits(&placed),
            &dirs,
            occlusion,
            occluders,
        )
    }

    /// [`Classification::render`] (or, with `far`,
    /// [`Classification::render_in_front`]) under the `shadows` model: each light at
    /// each shaded sample scaled by its transmittance from `shadows` (built by
    /// [`Classification::shadow_field`] for the same shader and camera), the ambient
    /// term by the occlusion, the flat part of each sample a scattering medium
    /// ([`Shader::shade_shadowed`]). Composite and iso modes.
    pub fn render_shadowed(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        progress: &(dyn Fn(u64) + Sync),
        far: Option<&[f32]>,
        shadows: &ShadowField,
    ) -> Result<Image, RenderError> {
        if self.settings().mode == RenderMode::Mip {
            return Err(RenderError::Parameter(
                "shadows lighting needs composite or iso mode (MIP is not lit)".into(),
            ));
        }
        check_far(frame, far)?;
        self.render_jittered(shader, frame, progress, true, far, Some(shadows))
    }

    /// Adds samples to the path-traced `image` of this classification lit by
    /// `shader`, for the camera and size of `frame`, until it holds `spp` samples per
    /// pixel (nothing when it already does). Camera rays stop at `far` when given (mm
    /// per pixel, as [`Classification::render_in_front`]). `progress` is called with
    /// the pixels of each finished row. Composite mode only.
    ///
    /// Each pixel's samples are added in sample order, each from its own generator
    /// (seed, pixel, sample index), so the image is the same bit for bit for a seed
    /// and sample count on any thread count, in one batch or many.
    #[allow(clippy::too_many_arguments)]
    pub fn trace_paths(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        settings: &PathSettings,
        image: &mut PathImage,
        spp: u32,
        far: Option<&[f32]>,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<(), RenderError> {
        let never = AtomicBool::new(false);
        self.trace_paths_until(shader, frame, settings, image, spp, far, progress, &never)
    }

    /// [`Classification::trace_paths`] that stops early when `cancel` is set (by
    /// another thread: a viewer whose user moved while samples were being added): rows
    /// not yet begun are left, and the call returns [`RenderError::Cancelled`]. The
    /// image then holds part of a batch and must be dropped, not continued.
    #[allow(clippy::too_many_arguments)]
    pub fn trace_paths_until(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        settings: &PathSettings,
        image: &mut PathImage,
        spp: u32,
        far: Option<&[f32]>,
        progress: &(dyn Fn(u64) + Sync),
        cancel: &AtomicBool,
    ) -> Result<(), RenderError> {
        let target = PathTarget {
            image,
            spp,
            far,
            occluders: None,
        };
        self.trace_paths_into(shader, frame, settings, target, progress, cancel)
    }

    /// [`Classification::trace_paths_until`] into `target`, which may hold meshes as
    /// occluders: then shadow rays and scattered paths end where they meet them.
    pub fn trace_paths_into(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        settings: &PathSettings,
        target: PathTarget,
        progress: &(dyn Fn(u64) + Sync),
        cancel: &AtomicBool,
    ) -> Result<(), RenderError> {
        let PathTarget {
            image,
            spp,
            far,
            occluders,
        } = target;
        settings.validate()?;
        check_spp(spp)?;
        frame.validate()?;
        check_far(frame, far)?;
        if self.settings().mode != RenderMode::Composite {
            return Err(RenderError::Parameter(format!(
                "path lighting needs composite mode, not {}",
                self.settings().mode.name()
            )));
        }
        let size = [frame.width, frame.height];
        if image.size() != size {
            return Err(RenderError::Parameter(format!(
                "a {}x{} path image for a {}x{} frame",
                image.size()[0],
                image.size()[1],
                size[0],
                size[1]
            )));
        }
        let from = image.samples();
        if spp < from {
            return Err(RenderError::Parameter(format!(
                "the path image holds {from} samples, more than the {spp} asked: start a new one"
            )));
        }
        if spp == from {
            return Ok(());
        }
        let camera = self.camera(frame)?;
        let placed = shader.placed(&camera);
        let tracer = PathTracer::new(
            self.field(),
            self.medium(),
            &placed,
            camera,
            size,
            *settings,
        )?
        .occluded_by(occluders)?;
        let w = frame.width as usize;
        let stats = image
            .sums_mut()
            .par_chunks_mut(w)
            .enumerate()
            .map(|(y, row)| {
                let mut stats = RenderStats::default();
                if cancel.load(Ordering::Relaxed) {
                    return stats;
                }
                for (x, sum) in row.iter_mut().enumerate() {
                    let limit = far.map_or(f32::INFINITY, |f| f[y * w + x]);
                    for s in from..spp {
                        let r = tracer.trace(x as u32, y as u32, s, limit);
                        for (acc, &x) in sum.iter_mut().zip(&r.radiance) {
                            *acc += f64::from(x);
                        }
                        sum[3] += f64::from(r.coverage);
                        stats.samples += 1;
                        stats.shaded += u64::from(r.events);
                    }
                }
                progress(w as u64);
                stats
            })
            .reduce(RenderStats::default, |a, b| RenderStats {
                samples: a.samples + b.samples,
                shaded: a.shaded + b.shaded,
                skips: a.skips + b.skips,
            });
        if cancel.load(Ordering::Relaxed) {
            return Err(RenderError::Cancelled);
        }
        image.finish_batch(spp, stats);
        Ok(())
    }
}
