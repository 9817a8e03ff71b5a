//! The classified volume as a participating medium: extinction and colour per value,
//! and an extinction bound per macro cell (the majorant grid of delta and ratio
//! tracking).

use glint_core::color::srgb_to_linear;
use glint_core::Vec3;

use super::lut::LUT_SIZE;
use super::tf::TransferFunction;
use crate::field::Field;

/// Largest opacity per unit length the extinction is taken from (`alpha = 1` would be
/// an infinite extinction): one unit of it lets one part in a million through, as the
/// pre-integrated tables' bound (`crate::preint`).
pub(crate) const MAX_ALPHA: f64 = 1.0 - 1e-6;

/// Extinction (per mm) and linear colour over the value range, tabulated on the bins
/// of [`crate::Lut`] (the same `LUT_SIZE` nearest-entry bins over the field's range),
/// and a majorant per macro cell.
///
/// The transfer function's opacity `alpha` is per `unit` mm of matter (the
/// classification's opacity unit), so the extinction is `-ln(1 - alpha) / unit`: a
/// ray-cast step of `dt` mm then has the opacity `1 - exp(-σ dt)` the ray caster's
/// corrected table gives it (Engel et al., Real-Time Volume Graphics, 2006, sec.
/// 9.1.3), and the path tracer sees the same matter the ray caster does.
pub(crate) struct Medium {
    lo: f32,
    scale: f32,
    /// Per bin: extinction per mm.
    sigma: Vec<f32>,
    /// Per bin: linear colour (the scattering colour).
    color: Vec<[f32; 3]>,
    /// Macro-cell grid dimensions and per cell the largest extinction a sample in it
    /// can take (0: the cell is empty).
    pub(crate) cell_dims: [usize; 3],
    pub(crate) majorant: Vec<f32>,
    /// The largest majorant.
    pub(crate) max_majorant: f32,
}

impl Medium {
    /// The medium of `field` classified by `tf`, whose opacity is per `unit_mm`.
    pub(crate) fn new(field: &Field, tf: &TransferFunction, unit_mm: f64) -> Medium {
        let (lo, hi) = field.range();
        let hi = if hi > lo { hi } else { lo + 1.0 };
        // The bins of `Lut::new`.
        let scale = (LUT_SIZE - 1) as f32 / (hi - lo);
        let (sigma, color): (Vec<f32>, Vec<[f32; 3]>) = (0..LUT_SIZE)
            .map(|i| {
                let x = lo as f64 + i as f64 / scale as f64;
                let a = tf.opacity_at(x).clamp(0.0, MAX_ALPHA);
                let s = -(-a).ln_1p() / unit_mm;
                (s as f32, tf.color_at(x).map(|c| srgb_to_linear(c) as f32))
            })
            .unzip();
        let mut medium = Medium {
            lo,
            scale,
            sigma,
            color,
            cell_dims: [0; 3],
            majorant: Vec::new(),
            max_majorant: 0.0,
        };
        let (cell_dims, ranges) = field.macro_cells();
        let table = RangeMax::new(&medium.sigma);
        medium.majorant = ranges
            .iter()
            .map(|&(a, b)| table.max(medium.bin(a), medium.bin(b)))
            .collect();
        medium.cell_dims = cell_dims;
        medium.max_majorant = medium.majorant.iter().fold(0.0, |m, &x| m.max(x));
        medium
    }

    /// The bin of value `v`: [`crate::Lut::index`]'s arithmetic.
    #[inline(always)]
    pub(crate) fn bin(&self, v: f32) -> usize {
        let x = ((v - self.lo) * self.scale + 0.5)
            .max(0.0)
            .min((LUT_SIZE - 1) as f32);
        x as usize
    }

    /// Extinction per mm at value `v`.
    #[inline(always)]
    pub(crate) fn sigma(&self, v: f32) -> f32 {
        self.sigma[self.bin(v)]
    }

    /// Linear colour at value `v`.
    #[inline(always)]
    pub(crate) fn color(&self, v: f32) -> [f32; 3] {
        self.color[self.bin(v)]
    }

    /// Extinction per mm at index-space point `p` of `field`.
    #[inline(always)]
    pub(crate) fn sigma_at(&self, field: &Field, p: Vec3) -> f32 {
        self.sigma(field.value(p))
    }
}

/// Range maxima over a table in O(1) per query: the sparse table of Bender and
/// Farach-Colton ("The LCA problem revisited", LATIN 2000), `log2(n)` levels of
/// maxima over windows of `2^k` entries. Written here: the few lines are smaller than
/// a dependency for one query type.
struct RangeMax {
    levels: Vec<Vec<f32>>,
}

impl RangeMax {
    fn new(values: &[f32]) -> RangeMax {
        let mut levels = vec![values.to_vec()];
        let mut width = 1;
        while 2 * width <= values.len() {
            let prev = levels.last().expect("one level at least");
            let next = (0..=values.len() - 2 * width)
                .map(|i| prev[i].max(prev[i + width]))
                .collect();
            levels.push(next);
            width *= 2;
        }
        RangeMax { levels }
    }

    /// The largest value in `a..=b` (in either order).
    fn max(&self, a: usize, b: usize) -> f32 {
        let (a, b) = (a.min(b), a.max(b));
        let k = (usize::BITS - 1 - (b - a + 1).leading_zeros()) as usize;
        let level = &self.levels[k];
        level[a].max(level[b + 1 - (1 << k)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_maxima_match_a_scan() {
        let v: Vec<f32> = (0..300).map(|i| ((i * 7919) % 301) as f32).collect();
        let t = RangeMax::new(&v);
        for a in (0..300).step_by(7) {
            for b in (a..300).step_by(5) {
                let want = v[a..=b].iter().fold(f32::MIN, |m, &x| m.max(x));
                assert_eq!(t.max(a, b), want, "{a}..={b}");
                assert_eq!(t.max(b, a), want);
            }
        }
    }
}
