//! What a classification depends on, apart from the transfer function.

use glint_core::{RenderError, RenderMode};

use super::preint::Sampling;

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
