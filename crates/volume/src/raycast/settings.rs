//! What a classification and a frame depend on, apart from the transfer function
//! and the shader.

use glint_core::camera::CameraSpec;
use glint_core::{RenderError, RenderMode, MAX_IMAGE_SIDE};

use crate::preint::Sampling;

/// What a [`Classification`](crate::Classification) depends on besides the transfer function: the mode, the
/// sample step and empty-space skipping. Changing any of them means classifying again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClassifySettings {
    /// Compositing mode: composite, iso or MIP (a surface scene is rasterised, not
    /// ray cast, and is refused).
    pub mode: RenderMode,
    /// The iso value of [`RenderMode::Iso`] (unused in the other modes).
    pub iso: f32,
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
            mode: RenderMode::Composite,
            iso: 0.0,
            step: 0.5,
            skip_empty: true,
            sampling: Sampling::default(),
            opacity_unit: None,
        }
    }
}

impl ClassifySettings {
    /// Checks the mode, the step and the iso threshold.
    pub fn validate(&self) -> Result<(), RenderError> {
        if !self.step.is_finite() || !(0.01..=100.0).contains(&self.step) {
            return Err(RenderError::Parameter(format!(
                "step {}: expected 0.01..=100 voxels",
                self.step
            )));
        }
        match self.mode {
            RenderMode::Iso if !self.iso.is_finite() => {
                return Err(RenderError::Parameter(format!(
                    "iso threshold {} is not finite",
                    self.iso
                )));
            }
            RenderMode::Surface => {
                return Err(RenderError::Parameter(
                    "surface mode is rasterised, not ray cast".into(),
                ));
            }
            _ => {}
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

/// What one frame of a [`Classification`](crate::Classification) depends on besides the [`Shader`](glint_core::Shader): image
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
        super::simd_supported()
    }
}
