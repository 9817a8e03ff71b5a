//! Denoising of `path` images ([`Denoise`]): the built-in edge-avoiding à-trous
//! wavelet filter ([`atrous`]) and Intel Open Image Denoise (loaded at run time where
//! scripts/fetch-oidn or the system put it), both on the linear HDR radiance (before the tone curve and the
//! 8-bit encoding) and guided by the frame's feature buffers
//! ([`glint_volume::PathFeatures`]: albedo, normal and depth of a deterministic first
//! hit, clean at 1 sample per pixel).

use serde::{Deserialize, Serialize};

use glint_core::{Image, RenderError};
use glint_volume::PathFeatures;

mod atrous;
#[allow(unsafe_code)]
mod oidn;

pub use atrous::{atrous, AtrousSettings, MAX_RADIANCE};

/// Whether Intel Open Image Denoise loads on this machine (its library in
/// `$OIDN_DIR/lib`, where scripts/fetch-oidn puts it, or on the system's library
/// path); loaded once, on the first call.
pub fn has_oidn() -> bool {
    oidn::available()
}

/// The one line `oidn` gives on a machine without the library: where it was looked
/// for and how to get it.
pub fn no_oidn() -> String {
    oidn::missing()
}

/// How a `path` image is denoised (a scene's `lighting.denoise`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Denoise {
    /// Not denoised: the mean of the samples, as always.
    #[default]
    None,
    /// The built-in edge-avoiding à-trous wavelet filter ([`atrous`]): fast (tens of
    /// milliseconds at 512x512), in every build.
    Atrous,
    /// Intel Open Image Denoise (its `RT` filter, HDR, with albedo and normal, CPU
    /// device): where its library loads ([`has_oidn`]).
    Oidn,
    /// `oidn` where its library loads, else `atrous`.
    Auto,
}

impl Denoise {
    /// Every choice, the default first.
    pub const ALL: [Denoise; 4] = [Denoise::None, Denoise::Atrous, Denoise::Oidn, Denoise::Auto];

    /// The name scenes and the command line use.
    pub fn name(self) -> &'static str {
        match self {
            Denoise::None => "none",
            Denoise::Atrous => "atrous",
            Denoise::Oidn => "oidn",
            Denoise::Auto => "auto",
        }
    }

    /// The denoiser this machine runs for the choice (`auto` resolved); for `oidn`
    /// without its library, the one line saying how to get it ([`no_oidn`]).
    pub fn effective(self) -> Result<Denoise, RenderError> {
        match self {
            Denoise::Oidn if !has_oidn() => Err(RenderError::Parameter(no_oidn())),
            Denoise::Auto if has_oidn() => Ok(Denoise::Oidn),
            Denoise::Auto => Ok(Denoise::Atrous),
            d => Ok(d),
        }
    }
}

impl std::str::FromStr for Denoise {
    type Err = RenderError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Denoise::ALL
            .into_iter()
            .find(|d| d.name() == s)
            .ok_or_else(|| {
                RenderError::Parameter(format!(
                    "unknown denoiser '{s}': expected none, atrous, oidn or auto"
                ))
            })
    }
}

/// `image` (a `path` frame, linear RGB) denoised by `how` guided by `features` (the
/// frame's, the same size) and, for `atrous`, by `variance`, each pixel's variance of
/// its mean luminance ([`glint_volume::PathImage::variance_of_mean`]; NaN where
/// unknown): the image itself for [`Denoise::None`]. Every output value is finite.
pub fn denoise(
    image: &Image,
    features: &PathFeatures,
    variance: &[f32],
    how: Denoise,
) -> Result<Image, RenderError> {
    if [features.width, features.height] != [image.width, image.height] {
        return Err(RenderError::Parameter(format!(
            "{}x{} feature buffers for a {}x{} image",
            features.width, features.height, image.width, image.height
        )));
    }
    match how.effective()? {
        Denoise::None | Denoise::Auto => Ok(image.clone()),
        Denoise::Atrous => Ok(atrous(
            image,
            features,
            variance,
            &AtrousSettings::default(),
        )),
        Denoise::Oidn => oidn::denoise(image, features),
    }
}

#[cfg(test)]
mod tests;
