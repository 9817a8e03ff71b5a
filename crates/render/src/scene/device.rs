//! Where a scene's frames are rendered: the CPU, a GPU, or a hardware GPU when there
//! is one ([`Device`]).

use glint_core::RenderError;
use serde::{Deserialize, Serialize};

/// The device a scene renders on (`--device`). `cpu` is the default while the GPU
/// back end renders only the `local` model: `auto` would pick Mesa's software
/// adapter (lavapipe) on a machine without a GPU, which is slower than the CPU path.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "lowercase")]
#[strum(serialize_all = "lowercase", ascii_case_insensitive, parse_err_ty = RenderError, parse_err_fn = glint_core::unknown_name::<Self>)]
pub enum Device {
    /// The CPU ray caster, rasterizer and path tracer (every model).
    #[default]
    Cpu,
    /// A GPU adapter, a software one (lavapipe) included: an error when there is
    /// none or the scene needs what the GPU back end does not render yet.
    Gpu,
    /// A hardware GPU (discrete or integrated) when there is one and the scene is one
    /// it renders; otherwise the CPU, with a note ([`crate::Renderer::device_notes`]).
    Auto,
}

impl Device {
    /// Every device, the default first.
    pub const ALL: &'static [Device] = <Device as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`Device::ALL`].
    pub const NAMES: &'static [&'static str] = <Device as strum::VariantNames>::VARIANTS;

    /// The name scenes and the command line use.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// Whether this is the default, the CPU (a scene leaves it out of its JSON).
    pub fn is_cpu(&self) -> bool {
        *self == Device::Cpu
    }
}

impl glint_lobe::names::Named for Device {
    const WHAT: &'static str = "device";
}
