//! A classification's one frame entry ([`Classification::frame`]) under each lighting
//! model ([`Transport`]), and the `shadows` model's light volumes it reads
//! ([`Classification::shadow_field`]): above both the ray caster (`raycast`) and the
//! light transport (`transport`), which it joins.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use glint_core::{EnvMap, Image, RenderError, RenderMode, Shader, Vec3};

use crate::classification::{occlusion_grid, Classification, LIGHT_CELL};
use crate::clip::{IndexClip, CUT_DEPTH_STEPS};
use crate::raycast::{CastLimits, FrameSettings};
use crate::transport::{
    check_spp, Occluders, Pass, PathImage, PathSettings, PathTracer, ShadowField, ShadowSettings,
};

/// How the light of a frame is computed, with what each lighting model
/// ([`LightingModel`](crate::LightingModel)) reads and writes.
pub enum Transport<'a> {
    /// `local`: every light reaches every sample. Every mode.
    Local,
    /// `shadows`: each light at each shaded sample scaled by its transmittance from
    /// these light volumes (built by [`Classification::shadow_field`] for the same
    /// shader and camera), the ambient term by their occlusion, the flat part of each
    /// sample a scattering medium ([`Shader::shade_shadowed`]). Composite and iso
    /// modes.
    Shadows(&'a ShadowField),
    /// `path`: samples added to a progressive path-traced image until it holds `spp`
    /// per pixel (nothing when it already does), or with a time budget
    /// ([`PathSettings::time_budget`]) passes of samples, where the noise is once
    /// each pixel holds a few, until the budget is spent or no pixel below `spp`
    /// is noisy. Composite mode only.
    ///
    /// Each pixel's samples are added in sample order, each from its own generator
    /// (seed, pixel, sample index), so the image is the same bit for bit for a seed
    /// and sample count on any thread count, in one batch or many.
    Path {
        /// The image the samples are added to (its size is the frame's).
        image: &'a mut PathImage,
        /// Samples per pixel it holds when the frame returns (without a time budget;
        /// with one, the most a pixel takes).
        spp: u32,
        /// Bounces, seed and environment.
        settings: PathSettings,
        /// Meshes voxelised on this classification's field ([`Occluders::new`]):
        /// shadow rays and scattered paths end where they enter an occupied cell.
        occluders: Option<&'a Occluders>,
        /// The environment map that replaces the uniform environment
        /// ([`PathSettings::environment`]), when given: next-event estimated and
        /// combined with the scattering model's sampling by MIS.
        environment: Option<&'a EnvMap>,
        /// When set (by another thread: a viewer whose user moved while samples were
        /// being added), rows not yet begun are left and the frame returns
        /// [`RenderError::Cancelled`]; the image then holds part of a batch and must be
        /// dropped, not continued.
        cancel: Option<&'a AtomicBool>,
    },
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

impl Classification {
    /// Renders the classified field lit by `shader` (its lights placed relative to the
    /// camera of `frame`, [`Classification::camera`]) with the size, background and
    /// kernel of `frame`, the light computed as `transport` says.
    ///
    /// `far`, when given, stops each ray at a per-pixel distance: `far[y * width + x]`
    /// is the distance (mm, along the pixel's ray from the camera's eye, or from the
    /// image plane for orthographic cameras) past which the volume is hidden (e.g. by
    /// an opaque surface drawn with the same camera); `f32::INFINITY` where nothing
    /// hides it. `progress` is called (from worker threads) with the number of pixels
    /// finished after each tile or row.
    ///
    /// Returns the frame's image; under [`Transport::Path`], the path image's
    /// ([`PathImage::image`] on the frame's background) once the samples are added.
    pub fn frame(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        far: Option<&[f32]>,
        transport: Transport<'_>,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Image, RenderError> {
        self.frame_cancellable(shader, frame, far, transport, progress, None)
    }

    /// [`Classification::frame`] that stops early when `cancel` is set (by another
    /// thread: a viewer whose client moved or left) under every lighting model: the
    /// ray caster checks it before each tile of 16x16 pixels, the path tracer before
    /// each row (with [`Transport::Path`]'s own flag, when that is given, in its
    /// place). A stopped frame returns [`RenderError::Cancelled`] and no image.
    pub fn frame_cancellable(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        far: Option<&[f32]>,
        transport: Transport<'_>,
        progress: &(dyn Fn(u64) + Sync),
        cancel: Option<&AtomicBool>,
    ) -> Result<Image, RenderError> {
        check_far(frame, far)?;
        let jittered = |shadows| {
            let limits = CastLimits {
                far,
                shadows,
                cancel,
            };
            self.render_jittered(shader, frame, progress, true, limits)
        };
        match transport {
            Transport::Local => jittered(None),
            Transport::Shadows(shadows) => {
                if self.settings().mode == RenderMode::Mip {
                    return Err(RenderError::Parameter(
                        "shadows lighting needs composite or iso mode (MIP is not lit)".into(),
                    ));
                }
                jittered(Some(shadows))
            }
            Transport::Path {
                image,
                spp,
                settings,
                occluders,
                environment,
                cancel: own,
            } => {
                let never = AtomicBool::new(false);
                let paths = Paths {
                    settings,
                    spp,
                    far,
                    occluders,
                    environment,
                    cancel: own.or(cancel).unwrap_or(&never),
                };
                self.trace_paths(shader, frame, image, &paths, progress)?;
                Ok(image.image(frame.background))
            }
        }
    }

    /// The `shadows` model's light volumes for the lights of `shader` placed for the
    /// camera of `frame` ([`ShadowField`], for [`Transport::Shadows`]), with ambient
    /// occlusion when `settings` asks, and the grid points `occluders` occupy (meshes
    /// voxelised by [`Occluders::new`] on this classification's field) opaque when
    /// given: the meshes cast their shadows into the volume. The averaged extinction
    /// and the occlusion are built on first use and kept with the classification; the
    /// light volumes are built here (a cache a viewer keeps while the lights point the
    /// same way, [`ShadowField::is_for`], and the frame's clip is the same: the space
    /// it cuts away casts no shadow).
    pub fn shadow_field(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        settings: &ShadowSettings,
        occluders: Option<&Occluders>,
    ) -> Result<ShadowField, RenderError> {
        let camera = self.camera(frame)?;
        let placed = shader.placed(&camera);
        let field = &**self.field();
        let dirs: Vec<_> = placed
            .world_lights()
            .iter()
            .map(|&(l, _)| field.index_direction(l))
            .collect();
        let clip = self.index_clip(shader, frame);
        // The occlusion of the whole classification is kept with it; a clip's, where
        // the space cut away occludes nothing (as it casts no shadow), is built with
        // the light volumes, which a viewer keeps while the clip is the same.
        let occlusion = settings.occlusion.then(|| match &clip {
            None => self.occlusion(),
            Some(k) => {
                let h = LIGHT_CELL as f32;
                let kept = |p: [usize; 3]| {
                    k.contains(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) * h)
                };
                Arc::new(occlusion_grid(self.density(), kept))
            }
        });
        ShadowField::new(
            self.density(),
            ShadowField::light_bits(&placed),
            &dirs,
            occlusion,
            (occluders, clip.as_ref()),
        )
    }

    /// The clip of `frame` in the field's index space, its cut faces as deep as the
    /// ray caster's ([`CUT_DEPTH_STEPS`] steps) and lit at twice `shader`'s gate.
    pub(crate) fn index_clip(&self, shader: &Shader, frame: &FrameSettings) -> Option<IndexClip> {
        let field = &**self.field();
        let dt = (self.settings().step * field.min_spacing()) as f32;
        IndexClip::new(
            &frame.clip,
            field,
            CUT_DEPTH_STEPS * dt,
            2.0 * shader.gate(),
        )
    }

    /// Adds samples to the path-traced `image` as `paths` says ([`Transport::Path`]).
    fn trace_paths(
        &self,
        shader: &Shader,
        frame: &FrameSettings,
        image: &mut PathImage,
        paths: &Paths,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<(), RenderError> {
        let Paths {
            settings,
            spp,
            far,
            occluders,
            environment,
            cancel,
        } = *paths;
        settings.validate()?;
        check_spp(spp)?;
        frame.validate()?;
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
        if spp == from && settings.time_budget.is_none() {
            return Ok(());
        }
        let camera = self.camera(frame)?;
        let placed = shader.placed(&camera);
        let clip = self.index_clip(shader, frame);
        let tracer = PathTracer::new(self.field(), self.medium(), &placed, camera, size, settings)?
            .occluded_by(occluders)?
            .clipped_by(clip.as_ref())
            .lit_by(environment);
        let pass = Pass {
            far,
            cancel,
            progress,
        };
        image.trace(&tracer, spp, &pass)
    }
}

/// What a path-traced frame adds and what stops its rays besides the volume
/// ([`Transport::Path`] less its image, and the frame's ray limits).
#[derive(Clone, Copy)]
struct Paths<'a> {
    settings: PathSettings,
    spp: u32,
    far: Option<&'a [f32]>,
    occluders: Option<&'a Occluders>,
    environment: Option<&'a EnvMap>,
    cancel: &'a AtomicBool,
}
