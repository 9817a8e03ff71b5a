//! Image metrics: how far a rendered image is from a reference, as a viewer sees it.
//!
//! Every metric works on the displayed image: 8-bit sRGB, exactly the samples a PNG
//! written by the renderer holds ([`Srgb8Image::from_linear`] encodes linear light the
//! same way: clamp to [0, 1], sRGB transfer function, round). The metrics:
//!
//! - PSNR over the three 8-bit channels, peak 255 ([`psnr`]);
//! - SSIM on luma (Wang et al. 2004, 11x11 Gaussian window, σ 1.5, K1 0.01, K2 0.03;
//!   [`ssim`]);
//! - CIEDE2000 ΔE per pixel, sRGB → XYZ (D65) → CIELAB ([`delta_e_map`]), summarised as
//!   mean, 99th percentile, max and the share of pixels above 1 and 2.3 ([`DeltaEStats`]);
//! - the mean ꟻLIP error (LDR-ꟻLIP, NVIDIA's reference implementation through the
//!   `nv-flip` crate; [`flip_map`]).
//!
//! [`compare`] computes all of them, over the whole image and, given a mask, over the
//! masked pixels only ([`highlight_mask`] makes the mask of the issue: where the
//! exact image's specular term exceeds 10% of its maximum).

mod compare;
mod delta_e;
mod figure;
mod flip;
mod psnr;
mod ssim;

pub use compare::{compare, highlight_mask, ImageMetrics, HIGHLIGHT_FRACTION};
pub use delta_e::{delta_e_map, lab_of, DeltaEStats, JND_DELTA_E, PERCENTILE};
pub use figure::{comparison_png, sweep_plot, ComparisonRow, SweepSeries, DELTA_E_SCALE_MAX};
pub use flip::{flip, flip_map, mean_flip};
pub use psnr::psnr;
pub use ssim::{ssim, ssim_map, SsimMap, SSIM_C1, SSIM_C2, SSIM_SIGMA, SSIM_WINDOW};

use palette::{LinSrgb, Srgb};

use crate::error::AnalysisError;

pub use crate::MAX_IMAGE_SIDE as MAX_SIDE;

/// An 8-bit sRGB image (no alpha: the renderer composites over its background), row 0
/// at the top, row-major.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Srgb8Image {
    width: u32,
    height: u32,
    pixels: Vec<[u8; 3]>,
}

impl Srgb8Image {
    /// An image from its sRGB samples; `pixels.len()` must be `width * height`.
    pub fn new(width: u32, height: u32, pixels: Vec<[u8; 3]>) -> Result<Self, AnalysisError> {
        check_size(width, height, pixels.len())?;
        Ok(Srgb8Image {
            width,
            height,
            pixels,
        })
    }

    /// An image from packed RGB bytes (3 per pixel, as `Image::encode_srgb` gives them).
    pub fn from_bytes(width: u32, height: u32, bytes: &[u8]) -> Result<Self, AnalysisError> {
        if !bytes.len().is_multiple_of(3) {
            return Err(AnalysisError::ImageSize {
                width,
                height,
                pixels: bytes.len() / 3,
            });
        }
        let pixels = bytes.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Self::new(width, height, pixels)
    }

    /// Encodes linear-light RGB for display as the renderer's PNGs do: each channel
    /// clamped to [0, 1] (NaN counts as 0), the sRGB transfer function, rounded to 8 bits.
    pub fn from_linear(width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<Self, AnalysisError> {
        check_size(width, height, rgb.len())?;
        let clamp = |c: f32| if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
        let pixels = rgb
            .iter()
            .map(|p| {
                let lin = LinSrgb::new(clamp(p[0]) as f64, clamp(p[1]) as f64, clamp(p[2]) as f64);
                let s: Srgb<u8> = Srgb::<f64>::from_linear(lin).into_format();
                [s.red, s.green, s.blue]
            })
            .collect();
        Ok(Srgb8Image {
            width,
            height,
            pixels,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixels, row-major.
    pub fn pixels(&self) -> &[[u8; 3]] {
        &self.pixels
    }

    /// The pixels as packed RGB bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        self.pixels.iter().flatten().copied().collect()
    }

    /// Fails unless `other` has the same size.
    pub(crate) fn check_same_size(&self, width: u32, height: u32) -> Result<(), AnalysisError> {
        if (self.width, self.height) == (width, height) {
            Ok(())
        } else {
            Err(AnalysisError::SizeMismatch {
                a_width: self.width,
                a_height: self.height,
                b_width: width,
                b_height: height,
            })
        }
    }
}

fn check_size(width: u32, height: u32, pixels: usize) -> Result<(), AnalysisError> {
    let ok = (1..=MAX_SIDE).contains(&width)
        && (1..=MAX_SIDE).contains(&height)
        && width as usize * height as usize == pixels;
    if ok {
        Ok(())
    } else {
        Err(AnalysisError::ImageSize {
            width,
            height,
            pixels,
        })
    }
}

/// Two images of the same size.
pub(crate) fn same_size(a: &Srgb8Image, b: &Srgb8Image) -> Result<(), AnalysisError> {
    a.check_same_size(b.width, b.height)
}

/// Fails unless the mask has one entry per pixel.
pub(crate) fn check_mask(img: &Srgb8Image, mask: &[bool]) -> Result<(), AnalysisError> {
    if mask.len() == img.pixels.len() {
        Ok(())
    } else {
        Err(AnalysisError::ImageSize {
            width: img.width,
            height: img.height,
            pixels: mask.len(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_checked() {
        assert!(Srgb8Image::new(2, 2, vec![[0; 3]; 3]).is_err());
        assert!(Srgb8Image::new(0, 0, vec![]).is_err());
        assert!(Srgb8Image::new(MAX_SIDE + 1, 1, vec![[0; 3]; MAX_SIDE as usize + 1]).is_err());
        assert!(Srgb8Image::from_bytes(1, 1, &[1, 2]).is_err());
        let img = Srgb8Image::from_bytes(2, 1, &[1, 2, 3, 4, 5, 6]).unwrap();
        assert_eq!(img.pixels(), &[[1, 2, 3], [4, 5, 6]]);
        assert_eq!(img.to_bytes(), vec![1, 2, 3, 4, 5, 6]);
    }

    /// The sRGB encoding of IEC 61966-2-1: 12.92·c below 0.0031308, else
    /// 1.055·c^(1/2.4) − 0.055; 0.5 linear is 0.7354 → 188 (187.5 rounds up), 0.2 is
    /// 0.4845 → 124, 0.001 is 0.012920 → 3.
    #[test]
    fn linear_is_encoded_like_the_png_writer() {
        let img = Srgb8Image::from_linear(
            3,
            2,
            &[
                [0.5, 0.2, 0.001],
                [1.0, 0.0, -1.0],
                [2.0, f32::NAN, 1.0],
                [0.0; 3],
                [1.0; 3],
                [0.5; 3],
            ],
        )
        .unwrap();
        assert_eq!(img.pixels()[0], [188, 124, 3]);
        assert_eq!(img.pixels()[1], [255, 0, 0]);
        assert_eq!(img.pixels()[2], [255, 0, 255]);
    }
}
