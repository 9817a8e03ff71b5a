//! Peak signal-to-noise ratio on the 8-bit sRGB samples.

use super::{check_mask, same_size, Srgb8Image};
use crate::error::AnalysisError;

/// PSNR in dB of `test` against `reference`: `10·log10(255² / MSE)`, the mean squared
/// error taken over the three 8-bit sRGB channels of every pixel (of the pixels where
/// `mask` is true, if given). `+∞` when the images are equal; `None` for an empty mask.
pub fn psnr(
    reference: &Srgb8Image,
    test: &Srgb8Image,
    mask: Option<&[bool]>,
) -> Result<Option<f64>, AnalysisError> {
    same_size(reference, test)?;
    if let Some(m) = mask {
        check_mask(reference, m)?;
    }
    let mut sum = 0.0f64;
    let mut count = 0usize;
    for (i, (a, b)) in reference.pixels().iter().zip(test.pixels()).enumerate() {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        for c in 0..3 {
            let d = a[c] as f64 - b[c] as f64;
            sum += d * d;
        }
        count += 3;
    }
    if count == 0 {
        return Ok(None);
    }
    let mse = sum / count as f64;
    Ok(Some(10.0 * (255.0f64 * 255.0 / mse).log10()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(w: u32, h: u32, p: [u8; 3]) -> Srgb8Image {
        Srgb8Image::new(w, h, vec![p; (w * h) as usize]).unwrap()
    }

    #[test]
    fn equal_images_are_infinite() {
        let a = flat(4, 3, [10, 20, 30]);
        assert_eq!(psnr(&a, &a, None).unwrap(), Some(f64::INFINITY));
    }

    /// Every sample off by one level: MSE 1, PSNR 20·log10(255) = 48.1308 dB.
    #[test]
    fn one_level_everywhere() {
        let a = flat(5, 5, [100, 100, 100]);
        let b = flat(5, 5, [101, 99, 101]);
        let p = psnr(&a, &b, None).unwrap().unwrap();
        assert!((p - 48.130_803_608_679_1).abs() < 1e-9, "{p}");
    }

    /// One pixel of four off by 30 in one channel: MSE 900/12 = 75, PSNR
    /// 10·log10(65025/75) = 29.3802 dB; masked to that pixel MSE 300, 23.3596 dB;
    /// masked to the others, equal.
    #[test]
    fn known_mse_and_mask() {
        let a = flat(2, 2, [50, 50, 50]);
        let mut px = a.pixels().to_vec();
        px[3] = [80, 50, 50];
        let b = Srgb8Image::new(2, 2, px).unwrap();
        let p = psnr(&a, &b, None).unwrap().unwrap();
        assert!((p - 29.380_190_974_762).abs() < 1e-9, "{p}");
        let m = [false, false, false, true];
        let p = psnr(&a, &b, Some(&m)).unwrap().unwrap();
        assert!((p - 23.359_591_061_482).abs() < 1e-9, "{p}");
        let m = [true, true, true, false];
        assert_eq!(psnr(&a, &b, Some(&m)).unwrap(), Some(f64::INFINITY));
        assert_eq!(psnr(&a, &b, Some(&[false; 4])).unwrap(), None);
        assert!(psnr(&a, &b, Some(&[true; 3])).is_err());
        assert!(psnr(&a, &flat(2, 3, [0; 3]), None).is_err());
    }
}
