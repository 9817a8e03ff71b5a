//! The volume's histogram, drawn under the page's transfer-function editor.

use glint_render::math::Vec3;
use glint_render::Field;
use serde::Serialize;

/// Bins of the histogram the page draws.
pub const HISTOGRAM_BINS: usize = 256;

/// Most voxels counted: a regular subsample beyond this (as the robust range is
/// taken), so a large volume's histogram costs what a 2^21-voxel one does.
const MAX_COUNTED: usize = 1 << 21;

/// A histogram of the volume's values (the reconstruction values the renderer
/// samples) over its value range, in the volume's units.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Histogram {
    /// The values the first bin starts and the last one ends at (the volume's minimum
    /// and maximum).
    pub range: [f32; 2],
    /// Per bin, `ln(1 + count)` of the voxels counted (a few dominant values, such as
    /// a CT's air, do not flatten the rest).
    pub log_counts: Vec<f32>,
    /// Voxels counted (every voxel, or a regular subsample of a large volume).
    pub counted: u64,
}

impl Histogram {
    /// The histogram of `field` in `bins` bins (at least 1) over its range.
    pub fn of(field: &Field, bins: usize) -> Histogram {
        let bins = bins.max(1);
        let (lo, hi) = field.range();
        let dims = field.dims();
        let voxels = dims.iter().product::<usize>();
        // One stride for every axis: its cube divides the voxel count to the limit.
        let stride = ((voxels as f64 / MAX_COUNTED as f64).cbrt().ceil() as usize).max(1);
        let mut counts = vec![0u64; bins];
        let width = (hi - lo).max(f32::MIN_POSITIVE);
        for k in (0..dims[2]).step_by(stride) {
            for j in (0..dims[1]).step_by(stride) {
                for i in (0..dims[0]).step_by(stride) {
                    let v = field.value(Vec3::new(i as f32, j as f32, k as f32));
                    if v.is_finite() {
                        let b = (((v - lo) / width) * bins as f32) as usize;
                        counts[b.min(bins - 1)] += 1;
                    }
                }
            }
        }
        Histogram {
            range: [lo, hi],
            counted: counts.iter().sum(),
            log_counts: counts.iter().map(|&c| (c as f32).ln_1p()).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_io::Volume;
    use glint_render::Prefilter;

    #[test]
    fn counts_every_voxel_in_its_bin() {
        // 4x4x4: half the voxels 0, a quarter 1, a quarter 3 (no prefilter).
        let values: Vec<f32> = (0..64)
            .map(|i| match i % 4 {
                0 | 1 => 0.0,
                2 => 1.0,
                _ => 3.0,
            })
            .collect();
        let volume = Volume::new([4, 4, 4], [1.0; 3], glint_io::Samples::F32(values)).unwrap();
        let field = Field::with_prefilter(&volume, Prefilter::None).unwrap();
        let h = Histogram::of(&field, 4);
        assert_eq!(h.range, [0.0, 3.0]);
        assert_eq!(h.counted, 64);
        let counts: Vec<f32> = h.log_counts.iter().map(|c| c.exp_m1().round()).collect();
        assert_eq!(counts, [32.0, 16.0, 0.0, 16.0]);
    }
}
