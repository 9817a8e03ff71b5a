//! The shadowed batch form's columns (`shadowed.rs`), held by `ShadeBatch` between
//! batches.

/// The shadowed form's columns, kept between batches.
#[derive(Clone, Debug, Default)]
pub(super) struct ShadowScratch {
    /// Per sample: gradient magnitude, whether it passes the gate, `N·V`, and the
    /// diffuse and specular sums.
    pub(super) magnitude: Vec<f32>,
    pub(super) usable: Vec<bool>,
    pub(super) n_dot_v: Vec<f32>,
    pub(super) diffuse: Vec<f32>,
    pub(super) specular: Vec<f32>,
    /// Per light and sample (light-major): `N·L`, the lobe's cosine, the lobe's value.
    pub(super) n_dot_l: Vec<f32>,
    pub(super) cos: Vec<f32>,
    pub(super) lobe: Vec<f32>,
    /// Per light and sample (light-major) the transmittance, per sample the ambient
    /// occlusion and the phase sum.
    pub(super) transmittance: Vec<f32>,
    pub(super) occlusion: Vec<f32>,
    pub(super) phase: Vec<f32>,
}
