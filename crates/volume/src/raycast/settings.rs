//! What a frame depends on, apart from the classification and the shader.

use glint_core::camera::CameraSpec;
use glint_core::{Clip, RenderError, MAX_IMAGE_SIDE};

/// What one frame of a [`Classification`](crate::Classification) depends on besides the [`Shader`](glint_core::Shader): image
/// size, camera, background, the compositing loop and the clip planes and crop box.
/// Changing them never classifies again.
#[derive(Clone, Debug, PartialEq)]
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
    /// What of world space is kept: samples elsewhere are empty, for the ray caster
    /// and the light transport alike (cut at each ray's interval, never by
    /// reclassifying).
    pub clip: Clip,
}

impl Default for FrameSettings {
    fn default() -> Self {
        FrameSettings {
            width: 512,
            height: 512,
            camera: CameraSpec::default(),
            background: [0.0; 3],
            kernel: Kernel::Auto,
            clip: Clip::default(),
        }
    }
}

impl FrameSettings {
    /// Checks the image size, the background and the clip.
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
        self.clip.validate()
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
        super::simd_supported()
    }
}
