//! What the tiles of a render read.

use glint_core::{ScalarColors, Shader};

use super::frame::Frame;
use super::{SurfaceSettings, Surfaces};

/// What the tiles of a render read: the meshes, the lighting and the colours.
pub(super) struct Ctx<'a> {
    pub(super) s: &'a Surfaces,
    pub(super) frame: &'a Frame,
    /// The shader with its lights placed for the frame's camera.
    pub(super) shader: &'a Shader,
    pub(super) colors: Option<&'a ScalarColors>,
    pub(super) settings: &'a SurfaceSettings,
    /// The background is black: each band is zeroed first (one memset over its
    /// rows, faster than [`Ctx::write_empty`]'s stores), which leaves the tiles no
    /// triangle meets written.
    pub(super) zeroed: bool,
    /// Rasterise with the AVX2 loop ([`super::avx2`]).
    pub(super) avx2: bool,
}
