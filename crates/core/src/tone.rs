//! Tone mapping: linear scene radiance to display-referred linear light in `[0, 1]`,
//! before the sRGB encoding ([`Image::encode_srgb`](crate::Image::encode_srgb)).
//! An exposure in stops scales the radiance first; the curve then maps it:
//!
//! - `linear`: the identity (the encoding clips at 1): glint's images as they always
//!   were. With exposure 0 nothing is done at all, so the image stays bit for bit.
//! - `aces`: Krzysztof Narkowicz's fit of the ACES reference rendering transform and
//!   output device transform ("ACES Filmic Tone Mapping Curve", 2016):
//!   `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`, per channel, clamped to `[0, 1]`.
//! - `agx`: Troy Sobotka's AgX (the view transform of Blender 4) as Benjamin Wrensch's
//!   minimal fit gives it ("Minimal AgX Implementation", iolite engine blog, 2023):
//!   the inset matrix, log2 encoding over `[-12.47393, 4.026069]` stops, the sixth-order
//!   polynomial fit of the default contrast curve, and the outset matrix. Its output is
//!   display-encoded; it is decoded with the sRGB curve so that the sRGB encoding
//!   gives back exactly the values AgX chose.
//!
//! The curves are a few lines each, from their papers; no crate carries them.

use serde::{Deserialize, Serialize};

use crate::color::srgb_to_linear;
use crate::error::RenderError;
use crate::image::Image;

/// The tone curve applied to linear radiance before the sRGB encoding.
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
pub enum Tone {
    /// The identity: values above 1 clip when encoded (glint's default).
    #[default]
    Linear,
    /// Narkowicz's fit of ACES (RRT + sRGB ODT).
    Aces,
    /// Sobotka's AgX (Blender 4's view transform), Wrensch's minimal fit.
    Agx,
}

impl Tone {
    /// All curves.
    pub const ALL: &'static [Tone] = <Tone as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`Tone::ALL`].
    pub const NAMES: &'static [&'static str] = <Tone as strum::VariantNames>::VARIANTS;

    /// The name users type.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The display-referred linear RGB of radiance `rgb` (already scaled by the
    /// exposure): in `[0, 1]` for `aces` and `agx`; `linear` returns `rgb`.
    #[inline]
    pub fn map(self, rgb: [f32; 3]) -> [f32; 3] {
        match self {
            Tone::Linear => rgb,
            Tone::Aces => rgb.map(aces),
            Tone::Agx => agx(rgb),
        }
    }
}

impl glint_lobe::names::Named for Tone {
    const WHAT: &'static str = "tone curve";
}

/// The largest exposure accepted, in stops either way.
pub const MAX_EXPOSURE_EV: f64 = 20.0;

/// Checks an exposure (finite, within ±[`MAX_EXPOSURE_EV`] stops).
pub fn check_exposure(ev: f64) -> Result<(), RenderError> {
    if !ev.is_finite() || ev.abs() > MAX_EXPOSURE_EV {
        return Err(RenderError::Parameter(format!(
            "exposure = {ev}: expected finite stops within ±{MAX_EXPOSURE_EV}"
        )));
    }
    Ok(())
}

/// Maps `image`'s radiance to display light in place: each pixel scaled by
/// `2^exposure` and mapped by `tone`. Exposure 0 with the `linear` curve leaves the
/// image untouched (bit for bit). Opacity is not changed.
pub fn tone_map(image: &mut Image, exposure: f64, tone: Tone) {
    if exposure == 0.0 && tone == Tone::Linear {
        return;
    }
    let scale = exposure.exp2() as f32;
    for p in &mut image.rgb {
        *p = tone.map(p.map(|c| c * scale));
    }
}

/// Narkowicz's ACES fit of one channel.
#[inline]
fn aces(x: f32) -> f32 {
    let x = x.max(0.0);
    let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
    ((x * (a * x + b)) / (x * (c * x + d) + e)).clamp(0.0, 1.0)
}

/// AgX's inset matrix (rows), from Wrensch's minimal fit.
const AGX_INSET: [[f64; 3]; 3] = [
    [0.842479062253094, 0.0784335999999992, 0.0792237451477643],
    [0.0423282422610123, 0.878468636469772, 0.0791661274605434],
    [0.0423756549057051, 0.0784336, 0.879142973793104],
];

/// AgX's outset matrix (rows), the inverse of the inset matrix as Wrensch gives it.
const AGX_OUTSET: [[f64; 3]; 3] = [
    [1.19687900512017, -0.0980208811401368, -0.0990297440797205],
    [-0.0528968517574562, 1.15190312990417, -0.0989611768448433],
    [-0.0529716355144438, -0.0980434501171241, 1.15107367264116],
];

/// The log2 range AgX encodes, stops relative to 1.
const AGX_MIN_EV: f64 = -12.47393;
/// See [`AGX_MIN_EV`].
const AGX_MAX_EV: f64 = 4.026069;

fn mul(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    m.map(|r| r[0] * v[0] + r[1] * v[1] + r[2] * v[2])
}

/// Wrensch's sixth-order polynomial fit of AgX's default contrast curve, on the
/// log-encoded value in `[0, 1]`.
#[inline]
fn agx_contrast(x: f64) -> f64 {
    let x2 = x * x;
    let x4 = x2 * x2;
    15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x
        - 0.00232
}

/// AgX of one pixel: display-referred linear RGB in `[0, 1]` (computed in f64).
fn agx(rgb: [f32; 3]) -> [f32; 3] {
    let v = mul(&AGX_INSET, rgb.map(|c| f64::from(c.max(0.0))));
    let encoded = v.map(|c| {
        let ev = c
            .max(f64::MIN_POSITIVE)
            .log2()
            .clamp(AGX_MIN_EV, AGX_MAX_EV);
        agx_contrast((ev - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV))
    });
    mul(&AGX_OUTSET, encoded).map(|c| srgb_to_linear(c.clamp(0.0, 1.0)) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse() {
        assert_eq!(Tone::NAMES, ["linear", "aces", "agx"]);
        assert_eq!("AgX".parse::<Tone>().unwrap(), Tone::Agx);
        let err = "filmic".parse::<Tone>().unwrap_err().to_string();
        assert!(err.contains("linear, aces, agx"), "{err}");
    }

    #[test]
    fn curves_are_monotone_with_black_and_white_points() {
        for tone in [Tone::Aces, Tone::Agx] {
            // Black maps to black (AgX: within its fit's floor), very bright to white.
            let black = tone.map([0.0; 3]);
            assert!(
                black.iter().all(|&c| (0.0..1e-3).contains(&c)),
                "{tone}: {black:?}"
            );
            let white = tone.map([1e4; 3]);
            assert!(
                white.iter().all(|&c| c > 0.97 && c <= 1.0),
                "{tone}: {white:?}"
            );
            // Greys stay grey, and rise (not strictly where the curve saturates).
            let mut last = -1.0f32;
            for k in 0..=4000 {
                let x = 1e-4 * 1.005f32.powi(k);
                let [r, g, b] = tone.map([x; 3]);
                assert!((r - g).abs() < 2e-3 && (g - b).abs() < 2e-3, "{tone} {x}");
                assert!(g >= last, "{tone}: {x} -> {g} below {last}");
                assert!((0.0..=1.0).contains(&g), "{tone}: {x} -> {g}");
                last = g;
            }
        }
        // Mid grey lands in the middle of the display range, not clipped or crushed.
        for tone in [Tone::Aces, Tone::Agx] {
            let g = crate::color::linear_to_srgb(f64::from(tone.map([0.18; 3])[1]));
            assert!((0.3..0.7).contains(&g), "{tone}: {g}");
        }
    }

    #[test]
    fn linear_at_exposure_zero_is_the_identity_and_exposure_scales_by_stops() {
        let rgb = vec![[0.25, 1.5, 0.0], [f32::MIN_POSITIVE, 3.0, 0.7]];
        let mut image = Image {
            width: 2,
            height: 1,
            rgb: rgb.clone(),
            alpha: vec![1.0, 0.5],
            stats: Default::default(),
        };
        tone_map(&mut image, 0.0, Tone::Linear);
        assert_eq!(image.rgb, rgb);
        tone_map(&mut image, 1.0, Tone::Linear);
        assert_eq!(image.rgb[0], [0.5, 3.0, 0.0]);
        tone_map(&mut image, -1.0, Tone::Aces);
        assert_eq!(image.rgb[0][2], 0.0);
        assert_eq!(image.alpha, [1.0, 0.5]);
        assert!(check_exposure(20.0).is_ok());
        assert!(check_exposure(f64::NAN).is_err() && check_exposure(-21.0).is_err());
    }
}
