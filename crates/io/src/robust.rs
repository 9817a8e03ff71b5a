//! A robust value range: percentiles that a few outlier voxels cannot move.

use crate::types::Volume;

/// The percentiles of [`robust_range`]: the 0.5th and 99.5th (glint issue 12: a single
/// voxel at -1.5e37 must not black out a render scaled to the data's range).
pub const ROBUST_PERCENTILES: (f64, f64) = (0.5, 99.5);

/// Most values [`robust_range`] looks at: a regular subsample beyond this (a 2^20-value
/// sample puts a percentile within about 0.01 percentile points).
pub const ROBUST_SAMPLES: usize = 1 << 20;

/// The [`ROBUST_PERCENTILES`] of the finite values among `value(0..count)`, from a
/// regular subsample of at most about [`ROBUST_SAMPLES`] of them. When the two
/// percentiles coincide (over 99% of the values are one value, e.g. a sparse angiogram
/// on zeros) the upper end is the subsample's maximum, so the range is empty only for
/// constant data. `None` when no value is finite.
pub fn robust_range(count: usize, value: impl Fn(usize) -> f64) -> Option<(f64, f64)> {
    let stride = count.div_ceil(ROBUST_SAMPLES).max(1);
    // Sized up front: collecting through the filter grows the vector by doubling, each
    // step a fresh allocation the kernel zeroes (up to twice the subsample's 8 MiB
    // paged in; 19% of an end-to-end MNI152 render's perf samples once).
    let mut v: Vec<f64> = Vec::with_capacity(count.div_ceil(stride));
    v.extend(
        (0..count)
            .step_by(stride)
            .map(value)
            .filter(|x| x.is_finite()),
    );
    if v.is_empty() {
        return None;
    }
    let rank = |p: f64| ((p / 100.0) * (v.len() - 1) as f64).round() as usize;
    let (lo_rank, hi_rank) = (rank(ROBUST_PERCENTILES.0), rank(ROBUST_PERCENTILES.1));
    let lo = *v.select_nth_unstable_by(lo_rank, f64::total_cmp).1;
    let hi = *v.select_nth_unstable_by(hi_rank, f64::total_cmp).1;
    if hi > lo {
        return Some((lo, hi));
    }
    let max = v.iter().cloned().fold(lo, f64::max);
    Some((lo, max))
}

impl Volume {
    /// The robust range of the physical values ([`robust_range`]; NaN samples
    /// ignored), for reports such as `glint info` beside [`Volume::range`].
    pub fn robust_range(&self) -> Option<(f64, f64)> {
        let n = self.samples.len();
        robust_range(n, |i| self.slope * self.samples.get(i) + self.intercept)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::Samples;

    #[test]
    fn outliers_do_not_move_the_robust_range() {
        // 0..=9999 plus one voxel at -1.5e37 and one at 1e30: the 0.5th and 99.5th
        // percentiles of 10002 values are ranks 50 and 9951 (of 0..=10001), which are
        // the values 49 and 9950 once the low outlier takes rank 0.
        let mut v: Vec<f32> = (0..10_000).map(|i| i as f32).collect();
        v.push(-1.5e37);
        v.push(1e30);
        v.push(f32::NAN);
        let n = v.len();
        let vol = Volume::new([n, 1, 1], [1.0; 3], Samples::F32(v)).unwrap();
        let (lo, hi) = vol.robust_range().unwrap();
        assert_eq!((lo, hi), (49.0, 9950.0));
        assert_eq!(vol.range().0, -1.5e37f32 as f64);
    }

    #[test]
    fn sparse_and_empty_data() {
        // 99.9% zeros: the percentiles coincide, the range reaches the maximum.
        let mut v = vec![0u8; 1000];
        v[3] = 200;
        let vol = Volume::new([1000, 1, 1], [1.0; 3], Samples::U8(v)).unwrap();
        assert_eq!(vol.robust_range(), Some((0.0, 200.0)));
        assert_eq!(robust_range(3, |_| f64::NAN), None);
        assert_eq!(robust_range(0, |_| 1.0), None);
    }
}
