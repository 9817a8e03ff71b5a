//! Eight samples read at once: the trilinear value or the tricubic B-spline
//! ([`super::spline`]), their table entries, and what a kept sample records.

use std::arch::x86_64::*;

use crossbeam_epoch::Guard;

use super::reads::{bases, fractions, table_coordinate, values_at, Invariants, Memos};
use super::spline::cubic;
use super::*;

/// One sample per lane, as [`Lanes::keep_segments`] uses it.
#[derive(Clone, Copy)]
pub(super) struct Reads {
    /// Fractions inside the trilinear cell, per axis.
    pub(super) t: [[f32; LANES]; 3],
    /// Corner-000 voxel in the brick pool, and its brick's grid index.
    pub(super) base: [i32; LANES],
    pub(super) brick: [i32; LANES],
    /// Table coordinate (`Lut::position` of the trilinear value).
    pub(super) u: [f32; LANES],
    /// Sample index.
    pub(super) k: [i32; LANES],
}

/// The samples at positions `p` (cells `ijk`, clamped) with sample indices `k`, read
/// for the lanes `mask` (the others read the dummy brick); `None` when a brick could
/// not be built (the cache is full of bricks in use).
///
/// # Safety
/// The CPU must support AVX2 (inlined into [`composite_lanes`]); `ijk` must be
/// clamped to the field's cells.
#[inline(always)]
pub(super) unsafe fn reads_at<const CUBIC: bool>(
    c: &Caster,
    inv: &Invariants,
    (p, ijk, k): ([__m256; 3], [__m256i; 3], __m256i),
    (mask, memos): (u8, &mut Memos),
    guard: &Guard,
) -> Option<Reads> {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let ((base, brick), fr, uv) = sample::<CUBIC>(c, inv, (p, ijk), (mask, memos), guard)?;
        let mut r = Reads {
            t: [[0.0; LANES]; 3],
            base,
            brick,
            u: [0.0; LANES],
            k: [0; LANES],
        };
        for (a, v) in fr.iter().enumerate() {
            _mm256_storeu_ps(r.t[a].as_mut_ptr(), *v);
        }
        _mm256_storeu_ps(r.u.as_mut_ptr(), uv);
        _mm256_storeu_si256(r.k.as_mut_ptr().cast(), k);
        Some(r)
    }
}

/// One sample per lane: its table entry, corner voxel (in the pool) and brick (in the
/// grid), cell fractions, and which lanes' entries have opacity.
pub(super) struct Probe {
    pub(super) li: [i32; LANES],
    pub(super) base: [i32; LANES],
    pub(super) brick: [i32; LANES],
    pub(super) fr: [__m256; 3],
    pub(super) opaque: u8,
}

/// The samples at positions `p` (cells `ijk`, clamped) for the lanes `mask`: their
/// corner voxels and bricks ([`bases`]), fractions, and table coordinates, of the
/// trilinear value or, with `CUBIC`, of the tricubic B-spline ([`super::spline::cubic`]). `None` when
/// a brick could not be built.
///
/// # Safety
/// The CPU must support AVX2; `ijk` clamped to the field's cells; `memos` filled under
/// `guard`.
#[inline(always)]
#[allow(clippy::type_complexity)]
unsafe fn sample<const CUBIC: bool>(
    c: &Caster,
    inv: &Invariants,
    (p, ijk): ([__m256; 3], [__m256i; 3]),
    (mask, memos): (u8, &mut Memos),
    guard: &Guard,
) -> Option<(([i32; LANES], [i32; LANES]), [__m256; 3], __m256)> {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let (base, brick) = bases(c, inv, ijk, (mask, &mut memos.cell), guard)?;
        let (fr, uv) = if CUBIC {
            let fr = fractions(inv, p, ijk);
            let v = cubic(c, inv, (ijk, fr), (mask, &mut memos.fetch), guard)?;
            (fr, table_coordinate(inv, v))
        } else {
            values_at(inv, p, ijk, &base)
        };
        Some(((base, brick), fr, uv))
    }
}

/// Reads the samples at positions `p` (cells `ijk`, clamped) for the lanes `mask`:
/// the reference loop's trilinear value and `Lut::index`; `None` when a brick could
/// not be built.
///
/// # Safety
/// The CPU must support AVX2 (inlined into [`composite_lanes`]).
#[inline(always)]
pub(super) unsafe fn probe<const CUBIC: bool>(
    c: &Caster,
    inv: &Invariants,
    (p, ijk): ([__m256; 3], [__m256i; 3]),
    (mask, memos): (u8, &mut Memos),
    guard: &Guard,
) -> Option<Probe> {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let ((base, brick), fr, uv) = sample::<CUBIC>(c, inv, (p, ijk), (mask, memos), guard)?;
        let mut li = [0i32; LANES];
        _mm256_storeu_si256(li.as_mut_ptr().cast(), _mm256_cvttps_epi32(uv));
        let mut opaque = 0u8;
        for (l, &i) in li.iter().enumerate() {
            // SAFETY: the index was clamped to the table.
            opaque |= *c.lut.opaque.get_unchecked(i as usize) << l;
        }
        Some(Probe {
            li,
            base,
            brick,
            fr,
            opaque,
        })
    }
}
