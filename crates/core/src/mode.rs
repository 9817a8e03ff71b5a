//! How a scene becomes a picture: the one mode enum of scenes, the ray caster and the
//! front ends.

use serde::{Deserialize, Serialize};

use crate::error::RenderError;

/// How samples along a ray make a pixel, or whether the scene is rasterised. The iso
/// value of [`RenderMode::Iso`] and [`RenderMode::Surface`] is kept beside the mode
/// (a scene's `iso`, the ray caster's `ClassifySettings::iso`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "lowercase")]
#[strum(serialize_all = "lowercase", ascii_case_insensitive, parse_err_ty = RenderError, parse_err_fn = crate::error::unknown_name::<Self>)]
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
    pub const ALL: &'static [RenderMode] = <RenderMode as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`RenderMode::ALL`].
    pub const NAMES: &'static [&'static str] = <RenderMode as strum::VariantNames>::VARIANTS;

    /// The name users type.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl glint_lobe::names::Named for RenderMode {
    const WHAT: &'static str = "mode";
}
