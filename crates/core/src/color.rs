//! Colour encodings: sRGB transfer functions (IEC 61966-2-1) and Rec. 709 luminance.

/// Rec. 709 (sRGB) luminance weights of linear R, G and B (ITU-R BT.709-6, item 3.2),
/// also used on encoded values as luma.
pub const REC709_LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Rec. 709 luminance (or luma, of encoded values) of an RGB triple.
///
/// ```
/// assert_eq!(glint_core::luminance([1.0, 1.0, 1.0]), 1.0);
/// ```
#[inline]
pub fn luminance(rgb: [f64; 3]) -> f64 {
    REC709_LUMA[0] * rgb[0] + REC709_LUMA[1] * rgb[1] + REC709_LUMA[2] * rgb[2]
}

/// [`luminance`] in f32: the same weights, rounded to f32 (equal to the f32 literals
/// of the weights: tested), summed left to right.
#[inline]
pub fn luminance_f32(rgb: [f32; 3]) -> f32 {
    REC709_LUMA[0] as f32 * rgb[0] + REC709_LUMA[1] as f32 * rgb[1] + REC709_LUMA[2] as f32 * rgb[2]
}

/// sRGB-encoded component to linear light (IEC 61966-2-1).
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear light to sRGB encoding (IEC 61966-2-1), input clamped to [0, 1].
pub fn linear_to_srgb(c: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_weights_are_the_f32_literals() {
        assert_eq!(REC709_LUMA.map(|w| w as f32), [0.2126f32, 0.7152, 0.0722]);
        assert_eq!(luminance_f32([1.0; 3]), 1.0);
    }

    #[test]
    fn srgb_round_trip() {
        for c in [0.0, 0.01, 0.2, 0.5, 1.0] {
            assert!((linear_to_srgb(srgb_to_linear(c)) - c).abs() < 1e-12);
        }
        // The encoding's known point: linear 0.5 is sRGB ~0.7354.
        assert!((linear_to_srgb(0.5) - 0.735357).abs() < 1e-5);
    }
}
