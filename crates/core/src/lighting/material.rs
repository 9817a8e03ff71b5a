//! Material coefficients: how much of each term of the lighting model a sample takes.

use serde::{Deserialize, Serialize};

use crate::error::RenderError;

/// Phong-style material coefficients, as in VTK's `vtkVolumeProperty` (and 3D Slicer's
/// presets): `colour · (ambient + diffuse · N·L) + specular · lobe`. The specular power
/// is not here: it is the lobe's `n` (a preset's power is its default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Ambient coefficient.
    pub ambient: f32,
    /// Diffuse coefficient.
    pub diffuse: f32,
    /// Specular coefficient.
    pub specular: f32,
    /// Whether to shade at all; unshaded samples show the transfer-function colour.
    pub shade: bool,
}

impl Default for Material {
    /// VTK's usual volume defaults as used by most Slicer CT presets: 0.1, 0.9, 0.2.
    fn default() -> Self {
        Material {
            ambient: 0.1,
            diffuse: 0.9,
            specular: 0.2,
            shade: true,
        }
    }
}

impl Material {
    /// Checks that the coefficients are finite and non-negative.
    pub fn validate(&self) -> Result<(), RenderError> {
        for (name, x) in [
            ("ambient", self.ambient),
            ("diffuse", self.diffuse),
            ("specular", self.specular),
        ] {
            if !x.is_finite() || !(0.0..=10_000.0).contains(&x) {
                return Err(RenderError::Parameter(format!(
                    "{name} = {x}: expected a finite number in 0..=10000"
                )));
            }
        }
        Ok(())
    }
}

/// Material fields a scene or a JSON transfer function may set; unset fields come from
/// the preset.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialOverrides {
    /// Ambient coefficient.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ambient: Option<f32>,
    /// Diffuse coefficient.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diffuse: Option<f32>,
    /// Specular coefficient.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub specular: Option<f32>,
    /// Shading on or off.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shade: Option<bool>,
}

impl MaterialOverrides {
    /// `base` with the fields that are set replaced.
    pub fn apply(&self, base: Material) -> Material {
        Material {
            ambient: self.ambient.unwrap_or(base.ambient),
            diffuse: self.diffuse.unwrap_or(base.diffuse),
            specular: self.specular.unwrap_or(base.specular),
            shade: self.shade.unwrap_or(base.shade),
        }
    }
}
