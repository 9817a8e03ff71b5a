//! CIEDE2000 colour difference per pixel and its summary.
//!
//! The formula is the `palette` crate's (`Ciede2000`), checked here against the test
//! data of Sharma, Wu and Dalal, "The CIEDE2000 color-difference formula:
//! implementation notes, supplementary test data, and mathematical observations",
//! Color Res. Appl. 30(1), 2005, Table 1. Colours go sRGB → linear → XYZ → CIELAB with
//! the D65 white of sRGB (IEC 61966-2-1).

use palette::color_difference::Ciede2000;
use palette::white_point::D65;
use palette::{FromColor, Lab, Srgb};

use super::{check_mask, same_size, Srgb8Image};
use crate::error::AnalysisError;

/// The just-noticeable difference of CIELAB, ΔE ≈ 2.3 (Sharma, "Digital Color Imaging
/// Handbook", 2003, Sec. 1.7.2; Mahy et al. 1994); shares above it and above 1 are
/// reported.
pub const JND_DELTA_E: f64 = 2.3;

/// The percentile reported beside mean and max (nearest rank: the smallest value
/// with at least 99% of the pixels at or below it).
pub const PERCENTILE: f64 = 0.99;

/// CIELAB (D65) of an 8-bit sRGB colour.
pub fn lab_of(p: [u8; 3]) -> Lab<D65, f64> {
    let s: Srgb<f64> = Srgb::new(p[0], p[1], p[2]).into_format();
    Lab::from_color(s.into_linear())
}

/// CIEDE2000 ΔE of every pixel of `test` against `reference`, row-major.
pub fn delta_e_map(reference: &Srgb8Image, test: &Srgb8Image) -> Result<Vec<f64>, AnalysisError> {
    same_size(reference, test)?;
    Ok(reference
        .pixels()
        .iter()
        .zip(test.pixels())
        .map(|(&a, &b)| {
            if a == b {
                0.0
            } else {
                lab_of(a).difference(lab_of(b))
            }
        })
        .collect())
}

/// Summary of a ΔE map over a set of pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeltaEStats {
    /// How many pixels were summarised.
    pub pixels: usize,
    /// Mean ΔE.
    pub mean: f64,
    /// 99th percentile ([`PERCENTILE`], nearest rank).
    pub p99: f64,
    /// Largest ΔE.
    pub max: f64,
    /// Share of pixels (0..1) with ΔE > 1.
    pub above_1: f64,
    /// Share of pixels (0..1) with ΔE > [`JND_DELTA_E`].
    pub above_jnd: f64,
}

impl DeltaEStats {
    /// Summarises `map` over all pixels or those where `mask` is true; `None` if no
    /// pixel counts.
    pub fn of(map: &[f64], mask: Option<&[bool]>) -> Option<DeltaEStats> {
        let mut v: Vec<f64> = match mask {
            Some(m) => map
                .iter()
                .zip(m)
                .filter(|(_, &k)| k)
                .map(|(&e, _)| e)
                .collect(),
            None => map.to_vec(),
        };
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let rank = ((PERCENTILE * n as f64).ceil() as usize).clamp(1, n);
        let share = |t: f64| v.iter().filter(|&&e| e > t).count() as f64 / n as f64;
        Some(DeltaEStats {
            pixels: n,
            mean: v.iter().sum::<f64>() / n as f64,
            p99: v[rank - 1],
            max: v[n - 1],
            above_1: share(1.0),
            above_jnd: share(JND_DELTA_E),
        })
    }

    /// The ΔE map of two images summarised (see [`DeltaEStats::of`]).
    pub fn compare(
        reference: &Srgb8Image,
        test: &Srgb8Image,
        mask: Option<&[bool]>,
    ) -> Result<Option<DeltaEStats>, AnalysisError> {
        if let Some(m) = mask {
            check_mask(reference, m)?;
        }
        Ok(Self::of(&delta_e_map(reference, test)?, mask))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sharma, Wu and Dalal (2005), Table 1: L1 a1 b1, L2 a2 b2, ΔE00 (4 decimals).
    #[rustfmt::skip]
    const SHARMA: [[f64; 7]; 34] = [
        [50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425],
        [50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615],
        [50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412],
        [50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669],
        [50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461],
        [50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065],
        [50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492],
        [50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977],
        [50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030],
        [50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000],
        [60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644],
        [63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630],
        [61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731],
        [35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645],
        [22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373],
        [36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146],
        [90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441],
        [90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381],
        [6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377],
        [2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082],
    ];

    #[test]
    fn ciede2000_matches_sharma_wu_dalal() {
        for (i, r) in SHARMA.iter().enumerate() {
            let a = Lab::<D65, f64>::new(r[0], r[1], r[2]);
            let b = Lab::<D65, f64>::new(r[3], r[4], r[5]);
            for d in [a.difference(b), b.difference(a)] {
                // The table gives 4 decimals.
                assert!((d - r[6]).abs() < 5e-5, "pair {}: {d} vs {}", i + 1, r[6]);
            }
        }
    }

    /// sRGB → CIELAB against the published values of the sRGB primaries (D65, e.g.
    /// Lindbloom's calculator): white L 100, red (53.2408, 80.0925, 67.2032), green
    /// (87.7347, -86.1827, 83.1793), blue (32.2970, 79.1875, -107.8602).
    #[test]
    fn srgb_to_lab() {
        let cases = [
            ([255, 255, 255], [100.0, 0.0, 0.0]),
            ([255, 0, 0], [53.2408, 80.0925, 67.2032]),
            ([0, 255, 0], [87.7347, -86.1827, 83.1793]),
            ([0, 0, 255], [32.2970, 79.1875, -107.8602]),
            ([0, 0, 0], [0.0, 0.0, 0.0]),
        ];
        for (rgb, want) in cases {
            let lab = lab_of(rgb);
            for (got, want) in [lab.l, lab.a, lab.b].into_iter().zip(want) {
                assert!((got - want).abs() < 0.02, "{rgb:?}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn stats_follow_their_definitions() {
        // 200 pixels: 0.5 (x100), 1.5 (x90), 3.0 (x8), 10.0 (x2).
        let mut map = vec![0.5; 100];
        map.extend([1.5; 90]);
        map.extend([3.0; 8]);
        map.extend([10.0; 2]);
        let s = DeltaEStats::of(&map, None).unwrap();
        assert_eq!(s.pixels, 200);
        assert!((s.mean - (50.0 + 135.0 + 24.0 + 20.0) / 200.0).abs() < 1e-12);
        // Rank ceil(0.99·200) = 198 is the last 3.0.
        assert_eq!(s.p99, 3.0);
        assert_eq!(s.max, 10.0);
        assert!((s.above_1 - 100.0 / 200.0).abs() < 1e-12);
        assert!((s.above_jnd - 10.0 / 200.0).abs() < 1e-12);
        let mask: Vec<bool> = (0..200).map(|i| i >= 190).collect();
        let m = DeltaEStats::of(&map, Some(&mask)).unwrap();
        assert_eq!((m.pixels, m.max, m.above_jnd), (10, 10.0, 1.0));
        assert!(DeltaEStats::of(&map, Some(&[false; 200])).is_none());
    }

    #[test]
    fn map_of_images() {
        let a = Srgb8Image::new(2, 1, vec![[255, 0, 0], [10, 10, 10]]).unwrap();
        let b = Srgb8Image::new(2, 1, vec![[255, 0, 0], [0, 0, 255]]).unwrap();
        let m = delta_e_map(&a, &b).unwrap();
        assert_eq!(m[0], 0.0);
        let want = lab_of([10, 10, 10]).difference(lab_of([0, 0, 255]));
        assert!(m[1] > 30.0 && m[1] == want);
    }
}
