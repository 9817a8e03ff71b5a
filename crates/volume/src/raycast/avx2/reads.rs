//! Eight samples located at once: positions, cells, bricks, trilinear values, table
//! coordinates.

use std::arch::x86_64::*;
use std::sync::atomic::{AtomicI32, Ordering};

use crossbeam_epoch::Guard;

use super::*;
use crate::field::brick::{BRICK, BRICK_ROW, BRICK_SHIFT, BRICK_SLICE};
use crate::field::cache::ABSENT;

/// Each lane's last brick and its slot's offset: a ray stays in a brick for many
/// samples, so the page table is read only when a lane enters another brick.
pub(super) struct Memo {
    index: [i32; LANES],
    off: [i32; LANES],
}

impl Default for Memo {
    /// No brick; offset 0, the dummy slot.
    fn default() -> Memo {
        Memo {
            index: [-1; LANES],
            off: [0; LANES],
        }
    }
}

/// Each lane's corner-000 voxel in the brick pool: its brick's slot (from `memo`, or
/// the page table, the brick built now if absent) plus the voxel's place in the brick,
/// for the lanes `mask`; and each lane's brick index in the grid. Every other lane gets its place in the last slot it used (or
/// the dummy slot 0), so all loads stay inside the pool. `None` when a brick could not
/// be built (the cache is full of bricks in use).
///
/// # Safety
/// The CPU must support AVX2; `ijk` must be clamped to the field's cells; `guard` must
/// stay alive while the returned voxels are read, and `memo` must have been filled
/// under the same guard.
#[inline(always)]
pub(super) unsafe fn bases(
    c: &Caster,
    inv: &Invariants,
    ijk: [__m256i; 3],
    (mask, memo): (u8, &mut Memo),
    guard: &Guard,
) -> Option<([i32; LANES], [i32; LANES])> {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let (index, local) = index_local(inv, ijk);
        let base = resolve(c, inv, (index, local), (mask, memo), guard)?;
        let mut bricks = [0i32; LANES];
        _mm256_storeu_si256(bricks.as_mut_ptr().cast(), index);
        Some((base, bricks))
    }
}

/// The grid index of the brick holding each lane's cell `ijk`, and the cell's corner
/// voxel's place in the brick's slot.
///
/// # Safety
/// The CPU must support AVX2 (inlined into [`composite_lanes`]).
#[inline(always)]
pub(super) unsafe fn index_local(inv: &Invariants, ijk: [__m256i; 3]) -> (__m256i, __m256i) {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        const SHIFT: i32 = BRICK_SHIFT as i32;
        let b = axes!(|a| _mm256_srli_epi32::<SHIFT>(ijk[a]));
        let l = axes!(|a| _mm256_and_si256(ijk[a], inv.brick_mask));
        let index = _mm256_add_epi32(
            b[0],
            _mm256_mullo_epi32(
                inv.bdx,
                _mm256_add_epi32(b[1], _mm256_mullo_epi32(inv.bdy, b[2])),
            ),
        );
        let local = _mm256_add_epi32(
            l[0],
            _mm256_add_epi32(
                _mm256_mullo_epi32(l[1], inv.brick_row),
                _mm256_mullo_epi32(l[2], inv.brick_slice),
            ),
        );
        (index, local)
    }
}

/// Each lane's voxel in the brick pool: the slot of its brick `index` (from `memo`, or
/// the page table, the brick built now if absent) plus `local`, for the lanes `mask`;
/// every other lane gets its place in the last slot it used (or the dummy slot 0).
/// `None` when a brick could not be built.
///
/// # Safety
/// As for [`bases`]: `index` and `local` from [`index_local`] of clamped cells.
#[inline(always)]
pub(super) unsafe fn resolve(
    c: &Caster,
    inv: &Invariants,
    (index, local): (__m256i, __m256i),
    (mask, memo): (u8, &mut Memo),
    guard: &Guard,
) -> Option<[i32; LANES]> {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let known = _mm256_cmpeq_epi32(index, _mm256_loadu_si256(memo.index.as_ptr().cast()));
        let mut enter = mask & !(_mm256_movemask_ps(_mm256_castsi256_ps(known)) as u8);
        if enter != 0 {
            let mut bi = [0i32; LANES];
            _mm256_storeu_si256(bi.as_mut_ptr().cast(), index);
            while enter != 0 {
                let l = enter.trailing_zeros() as usize;
                enter &= enter - 1;
                let b = bi[l] as usize;
                // SAFETY: the cells are clamped, so the brick index is below the count.
                let entry = (*inv.page.add(b)).load(Ordering::Acquire);
                memo.off[l] = if entry != ABSENT {
                    entry
                } else {
                    let f = c.field;
                    let bd = f.brick_dims;
                    let coords = [b % bd[0], b / bd[0] % bd[1], b / (bd[0] * bd[1])];
                    f.cache.build(b, coords, &f.recipe, guard)?
                };
                memo.index[l] = bi[l];
            }
        }
        let base = _mm256_add_epi32(_mm256_loadu_si256(memo.off.as_ptr().cast()), local);
        let mut out = [0i32; LANES];
        _mm256_storeu_si256(out.as_mut_ptr().cast(), base);
        Some(out)
    }
}

/// The macro cells of the cells `ijk` (one per lane), their distance-map entries, and
/// the lanes whose cell is visible (entry 0).
///
/// # Safety
/// The CPU must support AVX2 (inlined into [`composite_lanes`]); `ijk` must be
/// clamped to the field's cells.
#[inline(always)]
pub(super) unsafe fn cell_distances(
    c: &Caster,
    inv: &Invariants,
    ijk: [__m256i; 3],
) -> ([__m256i; 3], __m256i, u8) {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let cd = inv.cd;
        let cells = axes!(|a| _mm256_srli_epi32::<2>(ijk[a]));
        const _: () = assert!(MACRO_CELL == 4, "the shift above divides by MACRO_CELL");
        let cell = _mm256_add_epi32(
            cells[0],
            _mm256_mullo_epi32(
                _mm256_set1_epi32(cd[0] as i32),
                _mm256_add_epi32(
                    cells[1],
                    _mm256_mullo_epi32(_mm256_set1_epi32(cd[1] as i32), cells[2]),
                ),
            ),
        );
        // Scalar loads, not a gather (see the module's notes).
        let mut ci = [0i32; LANES];
        _mm256_storeu_si256(ci.as_mut_ptr().cast(), cell);
        let mut dist = [0i32; LANES];
        for (d, &i) in dist.iter_mut().zip(&ci) {
            // SAFETY: positions are clamped to the cells, so each index is a cell.
            *d = i32::from(*c.distance.get_unchecked(i as usize));
        }
        let dist = _mm256_loadu_si256(dist.as_ptr().cast());
        let visible = _mm256_cmpeq_epi32(dist, _mm256_setzero_si256());
        (
            cells,
            dist,
            _mm256_movemask_ps(_mm256_castsi256_ps(visible)) as u8,
        )
    }
}

/// Sample `k` per lane of rays `(o, d, j)`: its position and cell, as `Ray::t`,
/// `Ray::at` and `Field::locate` compute them in the reference loop.
///
/// # Safety
/// The CPU must support AVX2 (inlined into [`composite_lanes`]).
#[inline(always)]
pub(super) unsafe fn positions(
    inv: &Invariants,
    (o, d, j): ([__m256; 3], [__m256; 3], __m256),
    k: __m256i,
) -> ([__m256; 3], [__m256i; 3]) {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let Invariants { dt, hi, zero, .. } = *inv;
        let t = _mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(k), j), dt);
        let p = axes!(|a| _mm256_add_ps(o[a], _mm256_mul_ps(d[a], t)));
        let ijk = axes!(|a| _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(p[a], zero), hi[a])));
        (p, ijk)
    }
}

/// For eight samples at positions `p` in the cells `ijk` (clamped to `[0, dims-2]`)
/// whose corner voxels are `base` in the brick pool ([`bases`]): their fractions in the
/// cell and their table coordinates (`Lut::position` of the trilinear value), with the
/// reference loop's arithmetic.
///
/// # Safety
/// The CPU must support AVX2; `ijk` must be clamped as said; `base` from [`bases`]
/// with its guard alive.
#[inline(always)]
pub(super) unsafe fn values_at(
    inv: &Invariants,
    p: [__m256; 3],
    ijk: [__m256i; 3],
    base: &[i32; LANES],
) -> ([__m256; 3], __m256) {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let fr = fractions(inv, p, ijk);
        let v = trilinear(inv, base, fr);
        (fr, table_coordinate(inv, v))
    }
}

/// The fractions of positions `p` in their cells `ijk`, clamped to `[0, 1]`
/// (`Field::locate`'s).
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
pub(super) unsafe fn fractions(inv: &Invariants, p: [__m256; 3], ijk: [__m256i; 3]) -> [__m256; 3] {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        axes!(|a| {
            let t = _mm256_sub_ps(p[a], _mm256_cvtepi32_ps(ijk[a]));
            _mm256_min_ps(_mm256_max_ps(t, inv.zero), inv.one)
        })
    }
}

/// `Lut::position` of the values `v`.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
pub(super) unsafe fn table_coordinate(inv: &Invariants, v: __m256) -> __m256 {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let Invariants {
            zero,
            lut_lo,
            lut_scale,
            half,
            lut_max,
            ..
        } = *inv;
        let x = _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(v, lut_lo), lut_scale), half);
        _mm256_min_ps(_mm256_max_ps(x, zero), lut_max)
    }
}

/// The trilinear values of the cells whose corner voxels are `base` in the brick pool,
/// at fractions `fr`, with the reference loop's arithmetic (`field::trilinear`).
///
/// # Safety
/// The CPU must support AVX2; `base` from [`bases`] (or [`resolve`]) of clamped cells,
/// with its guard alive.
#[inline(always)]
unsafe fn trilinear(inv: &Invariants, base: &[i32; LANES], fr: [__m256; 3]) -> __m256 {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let values = inv.values;
        // SAFETY: each base is a slot's voxel whose cell lies in the slot, so base +
        // BRICK_SLICE + BRICK_ROW + 1 is inside the pool.
        let mut ptrs = [values; LANES];
        for (p, &b) in ptrs.iter_mut().zip(base) {
            *p = values.add(b as usize);
        }
        let (nx, sxy) = (BRICK_ROW, BRICK_SLICE);
        let (c000, c100) = row(ptrs, 0);
        let (c010, c110) = row(ptrs, nx);
        let (c001, c101) = row(ptrs, sxy);
        let (c011, c111) = row(ptrs, sxy + nx);
        let x00 = lerp(c000, c100, fr[0]);
        let x10 = lerp(c010, c110, fr[0]);
        let x01 = lerp(c001, c101, fr[0]);
        let x11 = lerp(c011, c111, fr[0]);
        let y0 = lerp(x00, x10, fr[1]);
        let y1 = lerp(x01, x11, fr[1]);
        lerp(y0, y1, fr[2])
    }
}

/// The brick look-ups of the cells a sample reads: its own cell's (for the kept
/// sample's record) and, for the tricubic filter, those of the eight 2^3 cubes its
/// 64 taps lie in ([`super::spline::cubic`]), each lane's last brick per cube.
#[derive(Default)]
pub(super) struct Memos {
    pub(super) cell: Memo,
    pub(super) fetch: [Memo; 8],
}

/// The lane steps' values that are the same for every ray of a frame, computed once per
/// tile: the loop then keeps them in registers or on the stack. Read from the caster
/// at each step, they were reloaded and recomputed after every push of a kept sample
/// (a call that may reallocate, after which the compiler cannot assume the field
/// unchanged).
#[derive(Clone, Copy)]
pub(super) struct Invariants {
    pub(super) cd: [usize; 3],
    pub(super) dt: __m256,
    /// The last cell's corner per axis, `dims - 2`.
    pub(super) hi: [__m256; 3],
    pub(super) zero: __m256,
    pub(super) one: __m256,
    /// Bricks along i and j; `BRICK - 1`; voxels per brick row and slice.
    pub(super) bdx: __m256i,
    pub(super) bdy: __m256i,
    pub(super) brick_mask: __m256i,
    pub(super) brick_row: __m256i,
    pub(super) brick_slice: __m256i,
    /// The field's page table.
    pub(super) page: *const AtomicI32,
    pub(super) lut_lo: __m256,
    pub(super) lut_scale: __m256,
    pub(super) half: __m256,
    pub(super) lut_max: __m256,
    /// The brick pool's values.
    pub(super) values: *const f32,
}

impl Invariants {
    /// # Safety
    /// The CPU must support AVX2 (inlined into [`composite_lanes`]).
    #[inline(always)]
    pub(super) unsafe fn new(c: &Caster) -> Invariants {
        // SAFETY: the caller runs with AVX2 (this function's contract).
        unsafe {
            let f = c.field;
            let bd = f.brick_dims;
            Invariants {
                cd: f.cell_dims,
                dt: _mm256_set1_ps(c.dt),
                hi: axes!(|a| _mm256_set1_ps((f.dims[a] - 2) as f32)),
                zero: _mm256_setzero_ps(),
                one: _mm256_set1_ps(1.0),
                // Brick indices fit in i32 (at most 2^33 / 16^3 bricks), as do pool
                // offsets (the pool's size is capped so).
                bdx: _mm256_set1_epi32(bd[0] as i32),
                bdy: _mm256_set1_epi32(bd[1] as i32),
                brick_mask: _mm256_set1_epi32(BRICK as i32 - 1),
                brick_row: _mm256_set1_epi32(BRICK_ROW as i32),
                brick_slice: _mm256_set1_epi32(BRICK_SLICE as i32),
                page: f.cache.page().as_ptr(),
                lut_lo: _mm256_set1_ps(c.lut.lo),
                lut_scale: _mm256_set1_ps(c.lut.scale),
                half: _mm256_set1_ps(0.5),
                lut_max: _mm256_set1_ps((crate::classification::LUT_SIZE - 1) as f32),
                values: f.cache.values(),
            }
        }
    }
}
