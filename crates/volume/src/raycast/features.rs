//! Feature buffers of a `path` frame for its denoisers ([`Classification::path_features`]):
//! per pixel the classified colour (albedo), the surface normal and the depth of the
//! camera ray's first hit.
//!
//! The hit is deterministic: where the ray's accumulated opacity, marched as the ray
//! caster marches it ([`Caster::opacity_crossing`], a pick's march), first reaches
//! [`FEATURE_OPACITY`]. A volume path tracer's first scattering event is random per
//! sample (delta tracking draws a free path), so features taken from it would be as
//! noisy as the image at 1 sample per pixel, and a denoiser guided by noisy features
//! keeps the noise (Intel Open Image Denoise's `cleanAux` and the edge-stopping
//! weights of an à-trous filter both assume clean guides); averaging them over the
//! samples would be clean only after many. The deterministic hit is clean at 1 spp
//! and costs one opacity march per pixel, once per camera.

use rayon::prelude::*;

use glint_core::{RenderError, RenderMode, Shader, Vec3};

use super::settings::FrameSettings;
use crate::Classification;

/// Accumulated opacity at which the features' first hit is taken: where the ray is
/// half hidden, as a pick stops ([`PICK_OPACITY`](super::PICK_OPACITY)).
pub const FEATURE_OPACITY: f32 = 0.5;

/// The feature buffers of a frame ([`Classification::path_features`]), row-major, one
/// entry per pixel, every value finite.
#[derive(Clone, Debug, PartialEq)]
pub struct PathFeatures {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The classified colour (linear RGB, 0..=1) at the first hit; `[0, 0, 0]` where
    /// the ray has none.
    pub albedo: Vec<[f32; 3]>,
    /// The unit surface normal (world, facing out of denser matter: minus the
    /// gradient, or the cut face's normal on a clip) at the first hit; `[0, 0, 0]`
    /// where the ray has none or the field is flat there.
    pub normal: Vec<[f32; 3]>,
    /// Distance (mm) of the first hit along the ray, as [`VolumeHit::depth`](super::VolumeHit)
    /// measures it; `-1` where the ray has none.
    pub depth: Vec<f32>,
}

impl PathFeatures {
    /// Whether pixel `i`'s ray has a first hit.
    pub fn hit(&self, i: usize) -> bool {
        self.depth[i] >= 0.0
    }
}

/// `v`, or 0 where it is NaN or infinite, clamped to `lo..=hi`: nothing that is not a
/// finite number reaches a denoiser.
fn finite(v: f32, lo: f32, hi: f32) -> f32 {
    if v.is_finite() {
        v.clamp(lo, hi)
    } else {
        0.0
    }
}

impl Classification {
    /// The feature buffers of a frame of `settings` lit by `shader` (composite mode):
    /// per pixel the albedo, normal and depth of the first point where the centre
    /// ray's accumulated opacity reaches [`FEATURE_OPACITY`] (the module's
    /// documentation says why this deterministic hit and not the first scattering
    /// event), the ray stopped at `far[y * width + x]` mm when given (meshes in
    /// front). NaN and infinite values in the data never leak into them: every
    /// entry is finite.
    pub fn path_features(
        &self,
        shader: &Shader,
        settings: &FrameSettings,
        far: Option<&[f32]>,
    ) -> Result<PathFeatures, RenderError> {
        if self.settings().mode != RenderMode::Composite {
            return Err(RenderError::Parameter(format!(
                "path features need composite mode, not {}",
                self.settings().mode.name()
            )));
        }
        let (w, h) = (settings.width as usize, settings.height as usize);
        if far.is_some_and(|f| f.len() != w * h) {
            return Err(RenderError::Parameter(format!(
                "ray limits for {} pixels, not {}",
                far.map_or(0, <[f32]>::len),
                w * h
            )));
        }
        let camera = self.camera(settings)?;
        let shader = shader.placed(&camera);
        let clip = self.index_clip(&shader, settings);
        let caster = self.caster(&camera, &shader, settings, true, None, clip.as_ref());
        let field = &*self.field;
        let medium = self.medium();
        type Row = Vec<([f32; 3], [f32; 3], f32)>;
        let rows: Vec<Row> = (0..h)
            .into_par_iter()
            .map(|y| {
                let guard = crossbeam_epoch::pin();
                (0..w)
                    .map(|x| {
                        let none = ([0.0; 3], [0.0; 3], -1.0);
                        let (xf, yf) = (x as f32, y as f32);
                        let mut bounds = (0.0, far.map_or(f32::INFINITY, |f| f[y * w + x]));
                        if let Some(clip) = &clip {
                            let (o, d, _) = caster.rays.ray(xf, yf);
                            bounds = clip.interval(o, d, bounds);
                            if bounds.0 > bounds.1 {
                                return none;
                            }
                        }
                        let Some((ray, _)) = caster.ray(xf, yf, bounds) else {
                            return none;
                        };
                        let Some((t, _)) = caster.opacity_crossing(&ray, FEATURE_OPACITY, &guard)
                        else {
                            return none;
                        };
                        let p = ray.at(t);
                        let value = field.value_in(p, &guard);
                        let albedo = medium.color(value).map(|c| finite(c, 0.0, 1.0));
                        let mut g = field.gradient_in(p, &guard);
                        if let Some(clip) = &clip {
                            g = clip.cut_gradient(p, g);
                        }
                        (albedo, unit_normal(g), finite(t, 0.0, f32::MAX))
                    })
                    .collect()
            })
            .collect();
        let mut features = PathFeatures {
            width: settings.width,
            height: settings.height,
            albedo: Vec::with_capacity(w * h),
            normal: Vec::with_capacity(w * h),
            depth: Vec::with_capacity(w * h),
        };
        for (a, n, d) in rows.into_iter().flatten() {
            features.albedo.push(a);
            features.normal.push(n);
            features.depth.push(d);
        }
        Ok(features)
    }
}

/// The unit normal facing out of denser matter (minus the gradient `g`), or zero where
/// `g` is too weak (or not finite) to give a direction.
fn unit_normal(g: Vec3) -> [f32; 3] {
    let m = g.length();
    if !m.is_finite() || m < 1e-12 {
        return [0.0; 3];
    }
    let n = g * (-1.0 / m);
    [n.x, n.y, n.z].map(|c| finite(c, -1.0, 1.0))
}
