//! All the metrics of one comparison, and the highlight mask.

use super::delta_e::{delta_e_map, DeltaEStats};
use super::flip::{flip_map, mean_flip};
use super::psnr::psnr;
use super::ssim::ssim_map;
use super::{check_mask, Srgb8Image};
use crate::error::AnalysisError;

/// The highlight of issue 13, item 5: pixels where the exact image's specular term
/// exceeds this fraction of its maximum (the paper's "epicentre" and "bloom" zones).
pub const HIGHLIGHT_FRACTION: f64 = 0.1;

/// Metrics of a test image against a reference over a set of pixels. Every field is
/// `None` when the set is empty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageMetrics {
    /// How many pixels were compared.
    pub pixels: usize,
    /// PSNR in dB on 8-bit sRGB (`+∞` for equal images).
    pub psnr: Option<f64>,
    /// Mean SSIM of the luma.
    pub ssim: Option<f64>,
    /// CIEDE2000 ΔE summary.
    pub delta_e: Option<DeltaEStats>,
    /// Mean ꟻLIP error.
    pub flip: Option<f64>,
}

/// Every metric of `test` against `reference` over the whole image and, if `mask` is
/// given (one entry per pixel), over the masked pixels: `(whole, masked)`. The ΔE,
/// SSIM and ꟻLIP maps are computed once for both.
pub fn compare(
    reference: &Srgb8Image,
    test: &Srgb8Image,
    mask: Option<&[bool]>,
) -> Result<(ImageMetrics, Option<ImageMetrics>), AnalysisError> {
    if let Some(m) = mask {
        check_mask(reference, m)?;
    }
    let de = delta_e_map(reference, test)?;
    let ss = ssim_map(reference, test)?;
    let fl = flip_map(reference, test)?;
    let over = |m: Option<&[bool]>| -> Result<ImageMetrics, AnalysisError> {
        Ok(ImageMetrics {
            pixels: m.map_or(de.len(), |m| m.iter().filter(|&&k| k).count()),
            psnr: psnr(reference, test, m)?,
            ssim: ss.mean(m),
            delta_e: DeltaEStats::of(&de, m),
            flip: mean_flip(&fl, m),
        })
    };
    Ok((over(None)?, mask.map(|m| over(Some(m))).transpose()?))
}

/// The highlight mask: true where `specular` (the specular term's contribution per
/// pixel, any non-negative scale) exceeds [`HIGHLIGHT_FRACTION`] of its maximum.
/// All false when there is no positive specular value; NaN counts as 0.
pub fn highlight_mask(specular: &[f32]) -> Vec<bool> {
    let max = specular
        .iter()
        .copied()
        .filter(|s| s.is_finite())
        .fold(0.0f32, f32::max);
    if max <= 0.0 {
        return vec![false; specular.len()];
    }
    let threshold = HIGHLIGHT_FRACTION * max as f64;
    specular
        .iter()
        .map(|&s| s.is_finite() && s as f64 > threshold)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mask_is_ten_percent_of_the_max() {
        let m = highlight_mask(&[0.0, 0.05, 0.1001, 0.5, 1.0, f32::NAN, 0.09]);
        assert_eq!(m, [false, false, true, true, true, false, false]);
        assert_eq!(highlight_mask(&[0.0, 0.0]), [false, false]);
    }

    /// A dark image whose only difference is a small bright patch: over the whole
    /// image the error is diluted, over the patch (the mask) it is not.
    #[test]
    fn masked_metrics_do_not_hide_behind_the_background() {
        let (w, h) = (40u32, 40u32);
        let idx = |x: u32, y: u32| (y * w + x) as usize;
        let mut a = vec![[10u8, 10, 10]; (w * h) as usize];
        let mut spec = vec![0.0f32; a.len()];
        for y in 15..25 {
            for x in 15..25 {
                a[idx(x, y)] = [230, 230, 230];
                spec[idx(x, y)] = 1.0;
            }
        }
        let mut b = a.clone();
        for y in 15..25 {
            for x in 15..25 {
                b[idx(x, y)] = [200, 200, 200];
            }
        }
        let a = Srgb8Image::new(w, h, a).unwrap();
        let b = Srgb8Image::new(w, h, b).unwrap();
        let mask = highlight_mask(&spec);
        let (whole, hl) = compare(&a, &b, Some(&mask)).unwrap();
        let hl = hl.unwrap();
        assert_eq!((whole.pixels, hl.pixels), (1600, 100));
        let (dw, dh) = (whole.delta_e.unwrap(), hl.delta_e.unwrap());
        // Every masked pixel differs by the same ΔE; the background not at all.
        assert!((dh.mean - dh.max).abs() < 1e-12 && dh.above_jnd == 1.0);
        assert!((dw.mean - dh.mean * 100.0 / 1600.0).abs() < 1e-9);
        assert_eq!(dw.max, dh.max);
        // PSNR: the MSE over the patch is 30² = 900, 16 times that over the image.
        let want = 10.0 * (255.0f64 * 255.0 / 900.0).log10();
        assert!((hl.psnr.unwrap() - want).abs() < 1e-9);
        assert!((whole.psnr.unwrap() - (want + 10.0 * 16f64.log10())).abs() < 1e-9);
        assert!(hl.ssim.unwrap() < whole.ssim.unwrap());
        assert!(hl.flip.unwrap() > whole.flip.unwrap());
        let (none, _) = compare(&a, &a, None).unwrap();
        assert_eq!(none.psnr, Some(f64::INFINITY));
        assert_eq!(none.delta_e.unwrap().max, 0.0);
    }
}
