//! Bricks: the field's derived data (reconstruction values and quantised world
//! gradients) for blocks of `BRICK`^3 trilinear cells, built from the source on first
//! use.
//!
//! Brick `b` holds voxels `b·BRICK ..= b·BRICK + BRICK` along each axis (one voxel of
//! overlap with the next brick, the "apron"), so every trilinear sample of a cell in the
//! brick reads only voxels the brick holds, and the ray caster's loads stay inside one
//! compact block (Hadwiger et al., "Real-Time Volume Graphics", 2006, sec. 17.4: bricks
//! with duplicated border voxels for interpolation without neighbour lookups). A brick
//! at the volume's far faces holds fewer voxels; the rest of its slot is never read.

use std::cell::RefCell;
use std::sync::Arc;

use super::filter::{
    binomial_box_into, quantise, row_gradients, row_quantised_diagonal, span, Neighbours,
};
use super::source::Source;
use super::Prefilter;

/// log2 of [`BRICK`].
pub(crate) const BRICK_SHIFT: u32 = 4;

/// Trilinear cells per brick edge: 16, a multiple of the macro cell (4) so a macro cell
/// lies in one brick. 8 costs 1.95x the voxels in aprons ((9/8)^3 = 1.42 of storage and
/// (13/8)^3 of source reads per brick) for finer laziness; 16 keeps the apron at
/// (17/16)^3 = 1.2.
pub(crate) const BRICK: usize = 1 << BRICK_SHIFT;

/// Voxels per brick row (with the apron).
pub(crate) const BRICK_ROW: usize = BRICK + 1;

/// Voxels per brick slice.
pub(crate) const BRICK_SLICE: usize = BRICK_ROW * BRICK_ROW;

/// Voxels per brick.
pub(crate) const BRICK_VOXELS: usize = BRICK_SLICE * BRICK_ROW;

/// Bytes of one brick: its values (f32) and gradients (`[i16; 4]`).
pub(crate) const BRICK_BYTES: u64 = (BRICK_VOXELS * (4 + 8)) as u64;

const _: () = assert!(BRICK.is_multiple_of(super::MACRO_CELL));

/// Bricks along each axis of a volume of `dims` (cells `0 ..= dims - 2`).
pub(crate) fn brick_dims(dims: [usize; 3]) -> [usize; 3] {
    dims.map(|d| (d - 1).div_ceil(BRICK))
}

/// What building a brick needs: the source, the prefilter, and the volume-wide
/// constants of the values and gradients.
pub(crate) struct Recipe {
    pub(crate) source: Arc<dyn Source>,
    pub(crate) dims: [usize; 3],
    pub(crate) prefilter: Prefilter,
    /// The value that replaces NaN and infinite samples (the smallest finite one);
    /// `None` when the source has none.
    pub(crate) fill: Option<f32>,
    /// Index-space to world gradients (inverse transpose of the affine's 3x3 part).
    pub(crate) to_world_gradient: [[f32; 3]; 3],
    /// `1 / gradient_scale`.
    pub(crate) inv_scale: f32,
    /// The diagonal of `to_world_gradient` when it is diagonal and no difference of
    /// two values can overflow: bricks then take [`row_quantised_diagonal`], the same
    /// stored gradients without the matrix's zero products.
    pub(crate) axis_aligned: Option<[f32; 3]>,
}

/// Reusable buffers for [`Recipe::values_into`]: the physical values read and the
/// prefilter's slices. A pass over many boxes keeps one per thread, so their memory is
/// paged in once rather than afresh for each box.
#[derive(Default)]
pub(crate) struct Scratch {
    raw: Vec<f32>,
    filter: Vec<f32>,
}

impl Scratch {
    /// Buffers for boxes of up to `voxels` voxels with their padding, so that a pass
    /// over boxes of slightly different sizes does not grow them (a grown buffer is a
    /// new one, paged in afresh, with the old one's pages still resident).
    pub(crate) fn with_capacity(voxels: usize) -> Self {
        Scratch {
            raw: Vec::with_capacity(voxels),
            filter: Vec::new(),
        }
    }

    /// Voxels the read buffer holds without growing.
    pub(crate) fn capacity(&self) -> usize {
        self.raw.capacity()
    }

    /// Bytes the buffers hold.
    pub(crate) fn bytes(&self) -> usize {
        std::mem::size_of::<f32>() * (self.raw.capacity() + self.filter.capacity())
    }
}

impl Recipe {
    /// Reconstruction values (the physical values, non-finite ones replaced, then
    /// prefiltered) of the voxels `lo ..= hi` (inclusive, inside the volume), i
    /// fastest.
    pub(crate) fn values(&self, lo: [usize; 3], hi: [usize; 3]) -> Vec<f32> {
        let mut out = Vec::new();
        self.values_into(lo, hi, false, &mut Scratch::default(), &mut out);
        out
    }

    /// [`Recipe::values`] into `out` (resized; every element overwritten), with the
    /// buffers of `scratch`; when `measure`, returns the (min, max) of the physical
    /// values read for them (the voxels and the faces of the box around them: every
    /// one a voxel of the volume) and whether all of them are finite (after the fill,
    /// if any), else ((0, 0), true).
    pub(crate) fn values_into(
        &self,
        lo: [usize; 3],
        hi: [usize; 3],
        measure: bool,
        scratch: &mut Scratch,
        out: &mut Vec<f32>,
    ) -> ((f32, f32), bool) {
        let size = [0, 1, 2].map(|a| hi[a] - lo[a] + 1);
        let pad = usize::from(self.prefilter == Prefilter::Binomial);
        let read_size = size.map(|s| s + 2 * pad);
        let raw = match self.prefilter {
            Prefilter::None => &mut *out,
            Prefilter::Binomial => &mut scratch.raw,
        };
        raw.resize(read_size.iter().product(), 0.0);
        let start = lo.map(|x| x as isize - pad as isize);
        self.source.read(start, read_size, raw);
        if let Some(fill) = self.fill {
            for v in raw.iter_mut().filter(|v| !v.is_finite()) {
                *v = fill;
            }
        }
        let measured = if measure {
            let range = raw
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            // NaN drops out of min and max; infinities do not.
            let finite = range.0.is_finite() && range.1.is_finite() && !has_nan(raw);
            (range, finite)
        } else {
            ((0.0, 0.0), true)
        };
        if self.prefilter == Prefilter::Binomial {
            binomial_box_into(&scratch.raw, read_size, out, &mut scratch.filter);
        }
        measured
    }

    /// Builds brick `b` into `values` and `gradients` (each [`BRICK_VOXELS`] long, brick
    /// layout: i fastest, rows of [`BRICK_ROW`]).
    pub(crate) fn build(&self, b: [usize; 3], values: &mut [f32], gradients: &mut [[i16; 4]]) {
        let dims = self.dims;
        let lo = b.map(|x| x * BRICK);
        let hi = [0, 1, 2].map(|a| (lo[a] + BRICK).min(dims[a] - 1));
        // The filtered values one voxel around the brick, for central differences.
        let flo = lo.map(|x| x.saturating_sub(1));
        let fhi = [0, 1, 2].map(|a| (hi[a] + 1).min(dims[a] - 1));
        // This thread's buffers from its last brick: a brick's boxes are small, but a
        // frame builds thousands.
        thread_local! {
            static BUFFERS: RefCell<(Scratch, Vec<f32>)> = RefCell::default();
        }
        let (mut scratch, mut f) = BUFFERS.take();
        self.values_into(flo, fhi, false, &mut scratch, &mut f);
        let fs = [0, 1, 2].map(|a| fhi[a] - flo[a] + 1);
        let row = |j: usize, k: usize| &f[fs[0] * ((j - flo[1]) + fs[1] * (k - flo[2]))..][..fs[0]];
        let (ilo, ihi) = (lo[0] - flo[0], hi[0] - flo[0] + 1);
        let faces = (lo[0] == 0, hi[0] == dims[0] - 1);
        let mut out = [[0.0f32; 3]; BRICK_ROW];
        for k in lo[2]..=hi[2] {
            let (km, kp, sk) = span(k, dims[2]);
            for j in lo[1]..=hi[1] {
                let (jm, jp, sj) = span(j, dims[1]);
                let c = row(j, k);
                let n = Neighbours {
                    jm: row(jm, k),
                    jp: row(jp, k),
                    span_j: sj,
                    km: row(j, km),
                    kp: row(j, kp),
                    span_k: sk,
                };
                let len = ihi - ilo;
                let at = BRICK_ROW * (j - lo[1]) + BRICK_SLICE * (k - lo[2]);
                values[at..at + len].copy_from_slice(&c[ilo..ihi]);
                let grads = &mut gradients[at..at + len];
                if let Some(d) = self.axis_aligned {
                    row_quantised_diagonal(c, &n, (ilo, ihi), faces, d, self.inv_scale, grads);
                    continue;
                }
                let g = &self.to_world_gradient;
                row_gradients(c, &n, (ilo, ihi), faces, g, &mut out[..len]);
                let q = |x: f32| quantise(x, self.inv_scale);
                for (o, w) in grads.iter_mut().zip(&out[..len]) {
                    *o = [q(w[0]), q(w[1]), q(w[2]), 0];
                }
            }
        }
        BUFFERS.set((scratch, f));
    }
}

/// Whether `v` holds a NaN, in eight lanes the compiler keeps in one vector register
/// (a loop that stopped at the first would not vectorise).
fn has_nan(v: &[f32]) -> bool {
    let mut lanes = [false; 8];
    let mut chunks = v.chunks_exact(8);
    for chunk in &mut chunks {
        for (m, x) in lanes.iter_mut().zip(chunk) {
            *m |= x.is_nan();
        }
    }
    lanes.contains(&true) || chunks.remainder().iter().any(|x| x.is_nan())
}
