//! The transfer function tabulated for one render ([`Lut`]): the per-sample lookup of
//! the ray caster, with its pre-integrated form for segments between samples.

use super::preint::PreIntegrated;
pub use super::preint::LUT_SIZE;
use super::tf::TransferFunction;
use glint_core::color::srgb_to_linear;

/// The transfer function tabulated for one render: linear colour and opacity
/// corrected for the sample step, `alpha' = 1 - (1 - alpha)^(step / unit)` with the
/// unit one voxel (Engel et al., Real-Time Volume Graphics, 2006, sec. 9.1.3).
#[derive(Clone, Debug)]
pub struct Lut {
    pub(crate) lo: f32,
    pub(crate) scale: f32,
    /// `[r, g, b, alpha']` per entry, colour linear.
    pub(crate) entries: Vec<[f32; 4]>,
    /// Per entry, 1 where it has opacity: the SIMD march's per-sample test (4 KiB; a
    /// table of the opacities was 16 KiB and competed with the entries for L1).
    pub(crate) opaque: Vec<u8>,
    /// `nonzero[i]` = number of entries below `i` with alpha' > 0, for O(1) range tests.
    nonzero: Vec<u32>,
    /// The same entries integrated, for compositing segments between samples.
    pub(crate) pre: PreIntegrated,
}

impl Lut {
    /// Tabulates `tf` over `[lo, hi]` (the volume's range) for steps of `step_voxels`.
    pub fn new(tf: &TransferFunction, lo: f32, hi: f32, step_voxels: f64) -> Lut {
        let hi = if hi > lo { hi } else { lo + 1.0 };
        let scale = (LUT_SIZE - 1) as f32 / (hi - lo);
        let (opacity, color): (Vec<f64>, Vec<[f64; 3]>) = (0..LUT_SIZE)
            .map(|i| {
                let x = lo as f64 + i as f64 / scale as f64;
                let a = tf.opacity_at(x).clamp(0.0, 1.0);
                (a, tf.color_at(x).map(srgb_to_linear))
            })
            .unzip();
        let entries: Vec<[f32; 4]> = opacity
            .iter()
            .zip(&color)
            .map(|(&a, c)| {
                let a = 1.0 - (1.0 - a).powf(step_voxels);
                [c[0] as f32, c[1] as f32, c[2] as f32, a as f32]
            })
            .collect();
        let mut nonzero = Vec::with_capacity(LUT_SIZE + 1);
        let mut count = 0u32;
        nonzero.push(0);
        for e in &entries {
            count += (e[3] > 0.0) as u32;
            nonzero.push(count);
        }
        Lut {
            lo,
            scale,
            opaque: entries.iter().map(|e| u8::from(e[3] > 0.0)).collect(),
            entries,
            nonzero,
            pre: PreIntegrated::new(&opacity, &color, step_voxels),
        }
    }

    /// Table coordinate of value `v` for the pre-integrated tables (the crate-private
    /// `PreIntegrated::at`): the argument [`Lut::index`] truncates (the same
    /// operations, so the same entry).
    #[inline(always)]
    pub fn position(&self, v: f32) -> f32 {
        ((v - self.lo) * self.scale + 0.5)
            .max(0.0)
            .min((LUT_SIZE - 1) as f32)
    }

    /// Table index of value `v` (nearest entry, clamped).
    #[inline(always)]
    pub fn index(&self, v: f32) -> usize {
        let x = self.position(v);
        // SAFETY: x is finite (max/min drop NaN) and in [0, LUT_SIZE-1].
        unsafe { x.to_int_unchecked::<u32>() as usize }
    }

    /// `[r, g, b, alpha']` at value `v`.
    #[inline(always)]
    pub fn get(&self, v: f32) -> [f32; 4] {
        self.entries[self.index(v)]
    }

    /// Whether any value in `[lo, hi]` has a non-zero opacity.
    pub fn any_opaque(&self, lo: f32, hi: f32) -> bool {
        let a = self.index(lo);
        let b = self.index(hi);
        self.nonzero[b + 1] > self.nonzero[a]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> TransferFunction {
        TransferFunction::from_flat(
            &[0.0, 0.0, 10.0, 1.0],
            &[0.0, 0.0, 0.0, 0.0, 10.0, 1.0, 0.5, 0.0],
        )
        .unwrap()
    }

    #[test]
    fn opacity_correction_composes_to_the_unit_step() {
        // Two half-voxel steps must absorb as much as one voxel step.
        let tf = ramp();
        let half = Lut::new(&tf, 0.0, 10.0, 0.5).get(5.0)[3] as f64;
        let full = Lut::new(&tf, 0.0, 10.0, 1.0).get(5.0)[3] as f64;
        assert!(
            ((1.0 - half).powi(2) - (1.0 - full)).abs() < 1e-3,
            "{half} {full}"
        );
    }

    #[test]
    fn range_test_finds_opaque_entries() {
        let tf =
            TransferFunction::from_flat(&[0.0, 0.0, 5.0, 0.0, 6.0, 1.0], &[0.0, 1.0, 1.0, 1.0])
                .unwrap();
        let lut = Lut::new(&tf, 0.0, 10.0, 1.0);
        assert!(!lut.any_opaque(0.0, 4.9));
        assert!(lut.any_opaque(0.0, 5.5));
        assert!(lut.any_opaque(7.0, 8.0));
    }
}
