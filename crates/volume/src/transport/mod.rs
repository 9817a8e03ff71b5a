//! Light transport on the classified field: how much of each light reaches a sample,
//! and where scattered light comes from. The shading itself is glint-core's one
//! lighting model ([`glint_core::Shader`]); this module decides its inputs.
//!
//! Three models ([`LightingModel`]):
//! - `local`: the ray caster's lighting as it always was (every light reaches every
//!   sample);
//! - `shadows`: each light's transmittance through the volume, from a light volume
//!   propagated once per frame and light ([`ShadowField`]), scales that light at every
//!   shaded sample; optional local ambient occlusion scales the ambient term; the
//!   flat part of each sample scatters by the Henyey-Greenstein phase function.
//!   Deterministic: the same scene gives the same image bit for bit;
//! - `path`: progressive Monte Carlo volume path tracing ([`PathImage`],
//!   [`Transport::Path`](crate::Transport::Path)): delta
//!   tracking against the macro cells' majorants, the lights by next-event estimation
//!   with ratio tracking, a uniform environment or an environment map (next-event
//!   estimated, combined with the scattering model's sampling by MIS), importance-sampled lobe and phase
//!   function, Russian roulette; the first dimensions of each path from an
//!   Owen-scrambled Sobol sequence by default ([`Sampler`]). The same seed, sampler
//!   and sample count give the same image bit for bit on any thread count.

use std::time::Duration;

use glint_core::RenderError;

mod arealight;
mod envlight;
mod occluders;
mod path;
mod rng;
mod shadows;
mod tracking;

#[cfg(test)]
mod area_tests;
#[cfg(test)]
mod envmap_shadow_tests;
#[cfg(test)]
mod tests;

pub(crate) use crate::classification::grid_len;
pub use crate::classification::LIGHT_CELL;
pub use crate::light::ShadowField;
pub use occluders::Occluders;
pub use path::PathImage;
pub(crate) use path::{Pass, PathTracer};
pub use path::{ADAPTIVE_MIN_SAMPLES, ADAPTIVE_THRESHOLD};
pub use rng::{Sampler, SOBOL_DIMS};
pub use shadows::ShadowSettings;

/// Most samples per pixel a path-traced image takes.
pub const MAX_SPP: u32 = 1 << 16;

/// Most scattering events a path takes.
pub const MAX_BOUNCES: u32 = 256;

/// How the light of a render is computed (a scene's `lighting.model`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum LightingModel {
    /// Every light reaches every sample: ambient + diffuse + specular, as always.
    #[default]
    Local,
    /// Each light's transmittance through the volume reaches each sample; optional
    /// local ambient occlusion; a scattering medium where the gradient is weak.
    Shadows,
    /// Progressive Monte Carlo path tracing.
    Path,
}

impl LightingModel {
    /// Every model, the default first.
    pub const ALL: [LightingModel; 3] = [
        LightingModel::Local,
        LightingModel::Shadows,
        LightingModel::Path,
    ];

    /// The name scenes and the command line use.
    pub fn name(self) -> &'static str {
        match self {
            LightingModel::Local => "local",
            LightingModel::Shadows => "shadows",
            LightingModel::Path => "path",
        }
    }
}

impl std::str::FromStr for LightingModel {
    type Err = RenderError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        LightingModel::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                RenderError::Parameter(format!(
                    "unknown lighting '{s}': expected local, shadows or path"
                ))
            })
    }
}

/// What a path-traced image depends on besides the classification, the shader and
/// the frame (the sample count is the [`PathImage`]'s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    /// Most scattering events of a path (at least 1: single scattering).
    pub bounces: u32,
    /// The seed of every pixel's generators.
    pub seed: u64,
    /// Radiance of the uniform white environment that paths leaving the volume see.
    pub environment: f32,
    /// Where the paths' random numbers come from.
    pub sampler: Sampler,
    /// Whether camera rays that meet no matter see the environment (opaque) rather
    /// than the frame's background.
    pub show_environment: bool,
    /// With a time budget a frame adds passes of samples, spent where the noise is,
    /// until the budget is spent ([`check_time_budget`]); without one every pixel
    /// takes the frame's samples.
    pub time_budget: Option<Duration>,
}

impl PathSettings {
    /// Checks the bounces and the environment.
    pub fn validate(&self) -> Result<(), RenderError> {
        if !(1..=MAX_BOUNCES).contains(&self.bounces) {
            return Err(RenderError::Parameter(format!(
                "bounces {}: expected 1..={MAX_BOUNCES}",
                self.bounces
            )));
        }
        if !self.environment.is_finite() || !(0.0..=100.0).contains(&self.environment) {
            return Err(RenderError::Parameter(format!(
                "environment {}: expected 0..=100",
                self.environment
            )));
        }
        if let Some(b) = self.time_budget {
            check_time_budget(b.as_secs_f64() * 1000.0)?;
        }
        Ok(())
    }
}

/// The longest time budget a frame takes: one hour.
pub const MAX_TIME_BUDGET_MS: f64 = 3_600_000.0;

/// A time budget of `ms` milliseconds, checked: more than 0, at most
/// [`MAX_TIME_BUDGET_MS`].
pub fn check_time_budget(ms: f64) -> Result<Duration, RenderError> {
    if !(ms > 0.0 && ms <= MAX_TIME_BUDGET_MS) {
        return Err(RenderError::Parameter(format!(
            "time budget {ms} ms: expected more than 0 and at most {MAX_TIME_BUDGET_MS} (one hour)"
        )));
    }
    Ok(Duration::from_secs_f64(ms / 1000.0))
}

/// Checks a sample count.
pub fn check_spp(spp: u32) -> Result<(), RenderError> {
    if !(1..=MAX_SPP).contains(&spp) {
        return Err(RenderError::Parameter(format!(
            "spp {spp}: expected 1..={MAX_SPP}"
        )));
    }
    Ok(())
}
