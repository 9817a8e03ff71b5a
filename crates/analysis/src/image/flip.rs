//! ꟻLIP (Andersson et al., "ꟻLIP: A Difference Evaluator for Alternating Images",
//! Proc. ACM CGIT 3(2), 2020): NVIDIA's reference C++ implementation of LDR-ꟻLIP,
//! through the `nv-flip` crate.

use super::{check_mask, same_size, Srgb8Image};
use crate::error::AnalysisError;

/// The ꟻLIP error of every pixel of `test` against `reference` (0 = no visible
/// difference, 1 = the largest), row-major. Viewing condition: the reference
/// implementation's default of 67 pixels per degree (a 0.7 m wide 4K monitor seen
/// from 0.7 m).
pub fn flip_map(reference: &Srgb8Image, test: &Srgb8Image) -> Result<Vec<f32>, AnalysisError> {
    same_size(reference, test)?;
    let (w, h) = (reference.width(), reference.height());
    // Sizes are checked equal above, which is what nv_flip::flip asserts.
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &reference.to_bytes());
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &test.to_bytes());
    Ok(nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec())
}

/// The mean of a ꟻLIP map over all pixels or those where `mask` is true (`None` if
/// none). The mean is the single number the ꟻLIP authors recommend.
pub fn mean_flip(map: &[f32], mask: Option<&[bool]>) -> Option<f64> {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (i, &e) in map.iter().enumerate() {
        if mask.is_none_or(|m| m[i]) {
            sum += e as f64;
            n += 1;
        }
    }
    (n > 0).then(|| sum / n as f64)
}

/// The mean ꟻLIP error of `test` against `reference` (see [`flip_map`], [`mean_flip`]).
pub fn flip(
    reference: &Srgb8Image,
    test: &Srgb8Image,
    mask: Option<&[bool]>,
) -> Result<Option<f64>, AnalysisError> {
    if let Some(m) = mask {
        check_mask(reference, m)?;
    }
    Ok(mean_flip(&flip_map(reference, test)?, mask))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(w: u32, h: u32, p: [u8; 3]) -> Srgb8Image {
        Srgb8Image::new(w, h, vec![p; (w * h) as usize]).unwrap()
    }

    #[test]
    fn identical_images_have_no_error() {
        let px: Vec<[u8; 3]> = (0..32 * 32)
            .map(|i| [(i % 251) as u8, 40, (i / 7) as u8])
            .collect();
        let a = Srgb8Image::new(32, 32, px).unwrap();
        assert_eq!(flip(&a, &a, None).unwrap(), Some(0.0));
    }

    #[test]
    fn error_grows_with_the_difference_and_stays_in_range() {
        let a = flat(24, 24, [128, 128, 128]);
        let mut last = 0.0;
        for d in [4u8, 16, 64, 127] {
            let e = flip(&a, &flat(24, 24, [128 + d, 128, 128]), None)
                .unwrap()
                .unwrap();
            assert!(e > last && e <= 1.0, "+{d}: {e} after {last}");
            last = e;
        }
        let bw = flip(&flat(24, 24, [0; 3]), &flat(24, 24, [255; 3]), None)
            .unwrap()
            .unwrap();
        assert!(bw > 0.5 && bw <= 1.0, "black against white {bw}");
    }

    #[test]
    fn mask_restricts_the_mean() {
        assert_eq!(mean_flip(&[0.25, 0.5, 0.75], None), Some(0.5));
        assert_eq!(
            mean_flip(&[0.25, 0.5, 0.75], Some(&[false, true, true])),
            Some(0.625)
        );
        assert_eq!(mean_flip(&[0.25], Some(&[false])), None);
        let a = flat(4, 4, [0; 3]);
        assert!(flip(&a, &flat(4, 5, [0; 3]), None).is_err());
        assert!(flip(&a, &a, Some(&[true])).is_err());
    }
}
