//! Colour pixel data to RGB planes, as pydicom 3 returns it (`pixel_array`, whose
//! default `as_rgb=True` converts YBR_FULL and YBR_FULL_422 to RGB), and the grey a
//! colour volume's samples hold.

use crate::{Grey, Samples};

/// pydicom's YBR_FULL to RGB matrix (pydicom/pixels/processing.py
/// `_convert_YBR_FULL_to_RGB`, after PS3.3 C.7.6.3.1.2 and ISO/IEC 10918-5 section 7),
/// in float32 as pydicom computes it: rows are Y, Cb - 128, Cr - 128; columns R, G, B.
const YBR_TO_RGB: [[f32; 3]; 3] = [
    [1.0, 1.0, 1.0],
    [0.0, -0.114 * 1.772 / 0.587, 1.772],
    [1.402, -0.299 * 1.402 / 0.587, 0.0],
];

/// One 8-bit YBR_FULL sample to RGB: the matrix product in float32, `floor(x + 0.5)`,
/// clipped to 0..255 (pydicom's steps, in its order).
pub(super) fn ybr_to_rgb(y: u32, cb: u32, cr: u32) -> [u32; 3] {
    let v = [y as f32, cb as f32 - 128.0, cr as f32 - 128.0];
    std::array::from_fn(|c| {
        let x = v[0] * YBR_TO_RGB[0][c] + v[1] * YBR_TO_RGB[1][c] + v[2] * YBR_TO_RGB[2][c];
        (x + 0.5).floor().clamp(0.0, 255.0) as u32
    })
}

/// Native YBR_FULL_422 (two pixels as Y1 Y2 Cb Cr, PS3.3 C.7.6.3.1.2) to YBR_FULL
/// (Y1 Cb Cr Y2 Cb Cr), each chroma pair shared by its two pixels, as pydicom expands it.
pub(super) fn expand_422(words: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(words.len() / 2 * 3);
    for q in words.chunks_exact(4) {
        out.extend([q[0], q[2], q[3], q[1], q[2], q[3]]);
    }
    out
}

/// The three planes of one frame of `pixels` pixels: interleaved (R G B R G B ...) or
/// planar (all R, all G, all B); YBR_FULL converted to RGB.
pub(super) fn planes(frame: &[u32], pixels: usize, planar: bool, ybr: bool) -> [Vec<u32>; 3] {
    let at = |p: usize, c: usize| {
        if planar {
            frame[c * pixels + p]
        } else {
            frame[3 * p + c]
        }
    };
    let mut out: [Vec<u32>; 3] = std::array::from_fn(|_| Vec::with_capacity(pixels));
    for p in 0..pixels {
        let v = [at(p, 0), at(p, 1), at(p, 2)];
        let v = if ybr { ybr_to_rgb(v[0], v[1], v[2]) } else { v };
        for c in 0..3 {
            out[c].push(v[c]);
        }
    }
    out
}

/// Words of `bits_allocated` (8, 16, 32) as unsigned samples of that size.
pub(super) fn samples(words: Vec<u32>, bits_allocated: u16) -> Samples {
    match bits_allocated {
        8 => Samples::U8(words.into_iter().map(|x| x as u8).collect()),
        16 => Samples::U16(words.into_iter().map(|x| x as u16).collect()),
        _ => Samples::U32(words),
    }
}

/// The grey of RGB planes: one channel, or the BT.601 luma rounded half up (the Y of
/// PS3.3 C.7.6.3.1.2's YBR_FULL), in the channels' type.
pub(super) fn grey(rgb: &[Samples; 3], choice: Grey) -> Samples {
    let channel = match choice {
        Grey::Red => Some(0),
        Grey::Green => Some(1),
        Grey::Blue => Some(2),
        _ => None,
    };
    if let Some(c) = channel {
        return rgb[c].clone();
    }
    let luma = |i: usize| {
        let y = 0.299 * rgb[0].get(i) + 0.587 * rgb[1].get(i) + 0.114 * rgb[2].get(i);
        (y + 0.5).floor()
    };
    let n = rgb[0].len();
    match &rgb[0] {
        Samples::U8(_) => Samples::U8((0..n).map(|i| luma(i) as u8).collect()),
        Samples::U16(_) => Samples::U16((0..n).map(|i| luma(i) as u16).collect()),
        _ => Samples::U32((0..n).map(|i| luma(i) as u32).collect()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ybr_to_rgb_matches_pydicom_on_known_values() {
        // pydicom 3.0.2's answers: convert_color_space(a, "YBR_FULL", "RGB") on a
        // uint8 array of these six triples.
        assert_eq!(ybr_to_rgb(128, 128, 128), [128, 128, 128]);
        assert_eq!(ybr_to_rgb(76, 85, 255), [254, 0, 0]);
        assert_eq!(ybr_to_rgb(150, 44, 21), [0, 255, 1]);
        assert_eq!(ybr_to_rgb(29, 255, 107), [0, 0, 254]);
        assert_eq!(ybr_to_rgb(0, 0, 0), [0, 135, 0]);
        assert_eq!(ybr_to_rgb(255, 255, 255), [255, 121, 255]);
    }

    #[test]
    fn subsampled_chroma_is_shared_and_planes_split() {
        assert_eq!(expand_422(&[1, 2, 30, 40]), vec![1, 30, 40, 2, 30, 40]);
        let inter = [1, 2, 3, 4, 5, 6];
        let [r, g, b] = planes(&inter, 2, false, false);
        assert_eq!((r, g, b), (vec![1, 4], vec![2, 5], vec![3, 6]));
        let [r, g, b] = planes(&inter, 2, true, false);
        assert_eq!((r, g, b), (vec![1, 2], vec![3, 4], vec![5, 6]));
    }

    #[test]
    fn grey_is_the_rounded_luma_or_a_channel() {
        let rgb = [
            Samples::U8(vec![255, 0, 10]),
            Samples::U8(vec![0, 255, 20]),
            Samples::U8(vec![0, 0, 30]),
        ];
        // 0.299 * 255 = 76.245; 0.587 * 255 = 149.685; 2.99 + 11.74 + 3.42 = 18.15.
        assert_eq!(grey(&rgb, Grey::Luminance), Samples::U8(vec![76, 150, 18]));
        assert_eq!(grey(&rgb, Grey::Blue), Samples::U8(vec![0, 0, 30]));
    }
}
