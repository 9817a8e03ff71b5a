//! How a scene becomes a picture: the one mode enum of scenes, the ray caster and the
//! front ends.

use serde::{Deserialize, Serialize};

use crate::error::RenderError;

/// How samples along a ray make a pixel, or whether the scene is rasterised. The iso
/// value of [`RenderMode::Iso`] and [`RenderMode::Surface`] is kept beside the mode
/// (a scene's `iso`, the ray caster's `ClassifySettings::iso`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RenderMode {
    /// Front-to-back compositing of shaded, classified samples.
    #[default]
    Composite,
    /// The first point where the value reaches the iso value, shaded and opaque.
    Iso,
    /// Maximum intensity projection, coloured by the transfer function.
    Mip,
    /// The scene's meshes and the volume's isosurface at the iso value, rasterised
    /// (the mode of every scene with meshes only).
    Surface,
}

impl RenderMode {
    /// Every mode, in the order `--help` lists them.
    pub const ALL: [RenderMode; 4] = [
        RenderMode::Composite,
        RenderMode::Iso,
        RenderMode::Mip,
        RenderMode::Surface,
    ];

    /// The name users type.
    pub fn name(self) -> &'static str {
        match self {
            RenderMode::Composite => "composite",
            RenderMode::Iso => "iso",
            RenderMode::Mip => "mip",
            RenderMode::Surface => "surface",
        }
    }
}

impl std::str::FromStr for RenderMode {
    type Err = RenderError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let key = s.trim().to_ascii_lowercase();
        RenderMode::ALL
            .into_iter()
            .find(|m| m.name() == key)
            .ok_or_else(|| {
                RenderError::Parameter(format!(
                    "unknown mode '{s}': expected composite, iso, mip or surface"
                ))
            })
    }
}
