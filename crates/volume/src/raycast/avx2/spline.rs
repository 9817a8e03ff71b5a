//! The tricubic B-spline of eight samples from their 64 taps, read as rows.
//!
//! A sample's 4^3 taps (voxels `i-1 ..= i+2` per axis around its cell `i`) are the
//! eight 2^3 cubes at cells `i-1` and `i+1` per axis, each inside one brick (its
//! cell's, with the bricks' one-voxel apron). Along x the two cubes of a row are
//! adjacent, so where the row's four voxels lie in one brick slot (the first one's
//! place in its brick at most 13: seven rows in eight) the row is one four-wide load
//! from the first cube's corner; the others ("split" lanes, whose x cubes lie in two
//! bricks) read it as the two cubes' pairs. Each lane's 16 rows then reduce along y
//! and z in 256-bit vectors (two rows per vector) and along x in one dot product:
//! 16 four-wide loads per sample, where Sigg and Hadwiger's eight trilinear fetches
//! (GPU Gems 2, ch. 20; the previous version of this loop) took 32 paired loads and
//! the shuffles to put them in lanes, and eight fetch positions with 18 divisions.
//! The value is the scalar loop's `Field::cubic_value_at` up to float rounding (the
//! same sums, here with FMA). Samples whose taps reach past the volume (clamp to
//! edge) take the scalar evaluation.

use std::arch::x86_64::*;

use crossbeam_epoch::Guard;

use super::reads::{index_local, resolve, Invariants, Memo};
use super::*;
use crate::field::brick::{BRICK_ROW, BRICK_SLICE};
use crate::field::Loc;

/// Four per-lane vectors (tap weights `0..4` of eight lanes) as each lane's four:
/// lane `l`'s at `2 (l & 3) + (l >> 2)` (the order a 256-bit 4x4 transpose leaves
/// them in).
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn per_lane([w0, w1, w2, w3]: [__m256; 4]) -> [[f32; 4]; LANES] {
    // SAFETY: the caller runs with AVX2 (this function's contract); the stores write
    // inside `out`.
    unsafe {
        let a = _mm256_unpacklo_ps(w0, w1);
        let b = _mm256_unpackhi_ps(w0, w1);
        let c = _mm256_unpacklo_ps(w2, w3);
        let d = _mm256_unpackhi_ps(w2, w3);
        let mut out = [[0.0f32; 4]; LANES];
        let o = out.as_mut_ptr().cast::<f32>();
        _mm256_storeu_ps(o, _mm256_shuffle_ps::<0x44>(a, c));
        _mm256_storeu_ps(o.add(8), _mm256_shuffle_ps::<0xEE>(a, c));
        _mm256_storeu_ps(o.add(16), _mm256_shuffle_ps::<0x44>(b, d));
        _mm256_storeu_ps(o.add(24), _mm256_shuffle_ps::<0xEE>(b, d));
        out
    }
}

/// The cubic B-spline weights of the taps at `-1, 0, 1, 2` (`field::cubic::weights`,
/// in Horner form) of the fractions `t`, per lane ([`per_lane`]).
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[inline(always)]
unsafe fn weights(t: __m256) -> [[f32; 4]; LANES] {
    // SAFETY: the caller runs with AVX2 and FMA (this function's contract).
    unsafe {
        let set = _mm256_set1_ps;
        let (mul, fmadd) = (_mm256_mul_ps, _mm256_fmadd_ps);
        let sixth = set(1.0 / 6.0);
        let s = _mm256_sub_ps(set(1.0), t);
        let w0 = mul(mul(mul(s, s), s), sixth);
        // (3 t^3 - 6 t^2 + 4) / 6 and (-3 t^3 + 3 t^2 + 3 t + 1) / 6.
        let w1 = fmadd(mul(fmadd(set(0.5), t, set(-1.0)), t), t, set(2.0 / 3.0));
        let w2 = fmadd(fmadd(fmadd(set(-0.5), t, set(0.5)), t, set(0.5)), t, sixth);
        let w3 = mul(mul(mul(t, t), t), sixth);
        per_lane([w0, w1, w2, w3])
    }
}

/// The derivatives of [`weights`] in `t` (`field::cubic::derivatives`), per lane.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[inline(always)]
unsafe fn derivatives(t: __m256) -> [[f32; 4]; LANES] {
    // SAFETY: the caller runs with AVX2 and FMA (this function's contract).
    unsafe {
        let set = _mm256_set1_ps;
        let (mul, fmadd) = (_mm256_mul_ps, _mm256_fmadd_ps);
        let s = _mm256_sub_ps(set(1.0), t);
        let tt = mul(t, t);
        per_lane([
            mul(set(-0.5), mul(s, s)),
            fmadd(set(1.5), tt, mul(set(-2.0), t)),
            fmadd(set(-1.5), tt, _mm256_add_ps(t, set(0.5))),
            mul(set(0.5), tt),
        ])
    }
}

/// The spline from a lane's rows: `r[c] = [rows (0, c) | (1, c)], [rows (2, c) |
/// (3, c)]` (row `(b, c)`: the four taps along x at y offset `b`, z offset `c`), and
/// its weights along x, y and z.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[inline(always)]
unsafe fn spline(r: [[__m256; 2]; 4], [wx, wy, wz]: [&[f32; 4]; 3]) -> f32 {
    // SAFETY: the caller runs with AVX2 and FMA (this function's contract); the loads
    // read the weight arrays.
    unsafe {
        let wy = _mm256_castps128_ps256(_mm_loadu_ps(wy.as_ptr()));
        let wy01 = _mm256_permutevar8x32_ps(wy, _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1));
        let wy23 = _mm256_permutevar8x32_ps(wy, _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3));
        let mut total = _mm256_setzero_ps();
        for (c, [r01, r23]) in r.into_iter().enumerate() {
            let slice = _mm256_fmadd_ps(r23, wy23, _mm256_mul_ps(r01, wy01));
            total = _mm256_fmadd_ps(slice, _mm256_broadcast_ss(&wz[c]), total);
        }
        dot(total, _mm_loadu_ps(wx.as_ptr()))
    }
}

/// Rows `(2n, c)` and `(2n + 1, c)` of a lane whose rows each lie in one brick slot:
/// `cube[y + 2 z]` is the pool offset of the corner of its x-first cube at y, z
/// (cells `j-1`/`j+1`, `k-1`/`k+1`).
///
/// # Safety
/// AVX2; each cube's rows must hold four voxels from its corner (its x place in the
/// brick at most 13), valid while the tile's guard lives.
#[inline(always)]
unsafe fn whole_rows(values: *const f32, cube: &[i32; 4], n: usize, c: usize) -> __m256 {
    // SAFETY: this function's contract: both rows lie in a built slot.
    unsafe {
        let p = values.add(cube[n + 2 * (c >> 1)] as usize + (c & 1) * BRICK_SLICE);
        _mm256_loadu2_m128(p.add(BRICK_ROW), p)
    }
}

/// Row `(b, c)` of a lane whose x cubes lie in two bricks: the pair of the first cube
/// (corner `lo[y + 2 z]`) then the pair of the second (`hi[y + 2 z]`).
///
/// # Safety
/// AVX2; the cubes' corners from [`resolve`] of the lane's cells, valid while the
/// tile's guard lives.
#[inline(always)]
unsafe fn split_row(
    values: *const f32,
    (lo, hi): (&[i32; 4], &[i32; 4]),
    b: usize,
    c: usize,
) -> __m128 {
    // SAFETY: this function's contract: each pair lies in its cube, in a built slot.
    unsafe {
        let off = (b & 1) * BRICK_ROW + (c & 1) * BRICK_SLICE;
        let k = (b >> 1) + 2 * (c >> 1);
        let first = _mm_load_sd(values.add(lo[k] as usize + off).cast::<f64>());
        let p = _mm_loadh_pd(first, values.add(hi[k] as usize + off).cast::<f64>());
        _mm_castpd_ps(p)
    }
}

/// A lane's 16 rows as [`spline`] takes them, from its cubes' corners (`hi` for a
/// split lane).
///
/// # Safety
/// As for [`whole_rows`] and [`split_row`]; AVX2.
#[inline(always)]
unsafe fn lane_rows(
    values: *const f32,
    (lo, hi): (&[i32; 4], Option<&[i32; 4]>),
) -> [[__m256; 2]; 4] {
    // SAFETY: this function's contract.
    unsafe {
        let mut r = [[_mm256_setzero_ps(); 2]; 4];
        match hi {
            None => {
                for (c, rc) in r.iter_mut().enumerate() {
                    *rc = [whole_rows(values, lo, 0, c), whole_rows(values, lo, 1, c)];
                }
            }
            Some(hi) => {
                for (c, rc) in r.iter_mut().enumerate() {
                    for (n, x) in rc.iter_mut().enumerate() {
                        *x = _mm256_set_m128(
                            split_row(values, (lo, hi), 2 * n + 1, c),
                            split_row(values, (lo, hi), 2 * n, c),
                        );
                    }
                }
            }
        }
        r
    }
}

/// The index-space gradient of the spline from a lane's rows (as [`spline`] takes
/// them), its weights `w` and their derivatives `d` along x, y and z: all three from
/// the one read (`field::cubic`'s `block`).
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[inline(always)]
unsafe fn spline_gradient(r: [[__m256; 2]; 4], w: [&[f32; 4]; 3], d: [&[f32; 4]; 3]) -> [f32; 3] {
    // SAFETY: the caller runs with AVX2 and FMA (this function's contract); the loads
    // read the weight arrays.
    unsafe {
        let lo = _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1);
        let hi = _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3);
        let wy = _mm256_castps128_ps256(_mm_loadu_ps(w[1].as_ptr()));
        let dy = _mm256_castps128_ps256(_mm_loadu_ps(d[1].as_ptr()));
        let (wy01, wy23) = (
            _mm256_permutevar8x32_ps(wy, lo),
            _mm256_permutevar8x32_ps(wy, hi),
        );
        let (dy01, dy23) = (
            _mm256_permutevar8x32_ps(dy, lo),
            _mm256_permutevar8x32_ps(dy, hi),
        );
        // Along y then z: `x` (weights, weights) for the value and the x derivative,
        // `y` (derivatives, weights), `z` (weights, derivatives).
        let (mut x, mut y, mut z) = (
            _mm256_setzero_ps(),
            _mm256_setzero_ps(),
            _mm256_setzero_ps(),
        );
        for (c, [r01, r23]) in r.into_iter().enumerate() {
            let s = _mm256_fmadd_ps(r23, wy23, _mm256_mul_ps(r01, wy01));
            let ds = _mm256_fmadd_ps(r23, dy23, _mm256_mul_ps(r01, dy01));
            let wz = _mm256_broadcast_ss(&w[2][c]);
            x = _mm256_fmadd_ps(s, wz, x);
            y = _mm256_fmadd_ps(ds, wz, y);
            z = _mm256_fmadd_ps(s, _mm256_broadcast_ss(&d[2][c]), z);
        }
        let (wx, dx) = (_mm_loadu_ps(w[0].as_ptr()), _mm_loadu_ps(d[0].as_ptr()));
        [dot(x, dx), dot(y, wx), dot(z, wx)]
    }
}

/// The two halves of `v` added, dotted with `w`.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn dot(v: __m256, w: __m128) -> f32 {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let x = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
        let m = _mm_mul_ps(x, w);
        let s = _mm_add_ps(m, _mm_movehl_ps(m, m));
        _mm_cvtss_f32(_mm_add_ss(s, _mm_movehdup_ps(s)))
    }
}

/// The cubes' corners of eight samples (`corner[x + 2 y + 4 z][lane]`, pool offsets),
/// and which lanes read them: `inner` (taps inside the volume), `split` (among them,
/// those whose x cubes lie in two bricks; only they have x-second corners).
struct Corners {
    corner: [[i32; LANES]; 8],
    inner: u8,
    split: u8,
}

impl Corners {
    /// Lane `l`'s x-first corners and, for a split lane, its x-second ones.
    #[inline(always)]
    fn lane(&self, l: usize) -> ([i32; 4], Option<[i32; 4]>) {
        let c = &self.corner;
        let lo = [c[0][l], c[2][l], c[4][l], c[6][l]];
        let hi = (self.split & (1 << l) != 0).then(|| [c[1][l], c[3][l], c[5][l], c[7][l]]);
        (lo, hi)
    }
}

/// The cubes' corners of the samples in cells `ijk` (clamped) for the lanes `mask`;
/// `memos` holds each lane's last brick per cube. `None` when a brick could not be
/// built.
///
/// # Safety
/// The CPU must support AVX2; `ijk` clamped to the field's cells; `memos` filled under
/// `guard`.
#[inline(always)]
unsafe fn corners(
    c: &Caster,
    inv: &Invariants,
    ijk: [__m256i; 3],
    (mask, memos): (u8, &mut [Memo; 8]),
    guard: &Guard,
) -> Option<Corners> {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let one = _mm256_set1_epi32(1);
        // Lanes whose taps stay inside the volume (1 <= i <= dims - 3 per axis), and
        // among them those whose x cubes lie in two bricks (the first tap's place in
        // its brick above 13).
        let mut inside = _mm256_set1_epi32(-1);
        let mut cells = [[_mm256_setzero_si256(); 2]; 3];
        for a in 0..3 {
            let last = _mm256_cvttps_epi32(inv.hi[a]);
            let ok = _mm256_and_si256(
                _mm256_cmpgt_epi32(ijk[a], _mm256_setzero_si256()),
                _mm256_cmpgt_epi32(last, ijk[a]),
            );
            inside = _mm256_and_si256(inside, ok);
            cells[a] = [
                _mm256_max_epi32(_mm256_sub_epi32(ijk[a], one), _mm256_setzero_si256()),
                _mm256_min_epi32(_mm256_add_epi32(ijk[a], one), last),
            ];
        }
        let lx = _mm256_and_si256(cells[0][0], inv.brick_mask);
        let split_v = _mm256_cmpgt_epi32(lx, _mm256_set1_epi32(13));
        let inner = mask & _mm256_movemask_ps(_mm256_castsi256_ps(inside)) as u8;
        let split = inner & _mm256_movemask_ps(_mm256_castsi256_ps(split_v)) as u8;
        let mut corner = [[0i32; LANES]; 8];
        for (f, memo) in memos.iter_mut().enumerate() {
            let m = if f & 1 == 0 { inner } else { split };
            if m == 0 {
                continue;
            }
            let cell = [cells[0][f & 1], cells[1][(f >> 1) & 1], cells[2][f >> 2]];
            corner[f] = resolve(c, inv, index_local(inv, cell), (m, memo), guard)?;
        }
        Some(Corners {
            corner,
            inner,
            split,
        })
    }
}

/// The tricubic B-spline at cells `ijk` (clamped), fractions `fr`, for the lanes
/// `mask` (the others 0): see the module's notes. `memos` holds each lane's last brick
/// per cube (`x + 2 y + 4 z`). `None` when a brick could not be built.
///
/// # Safety
/// The CPU must support AVX2 and FMA; `ijk` clamped to the field's cells; `memos`
/// filled under `guard`.
#[inline(always)]
pub(super) unsafe fn cubic(
    c: &Caster,
    inv: &Invariants,
    (ijk, fr): ([__m256i; 3], [__m256; 3]),
    (mask, memos): (u8, &mut [Memo; 8]),
    guard: &Guard,
) -> Option<__m256> {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let k = corners(c, inv, ijk, (mask, memos), guard)?;
        let mut out = [0.0f32; LANES];
        if k.inner != 0 {
            let w = axes!(|a| weights(fr[a]));
            let mut m = k.inner;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                let p = 2 * (l & 3) + (l >> 2);
                let (lo, hi) = k.lane(l);
                let rows = lane_rows(inv.values, (&lo, hi.as_ref()));
                out[l] = spline(rows, [&w[0][p], &w[1][p], &w[2][p]]);
            }
        }
        let edge = mask & !k.inner;
        if edge != 0 {
            edge_values(c, (ijk, fr), edge, &mut out, guard);
        }
        Some(_mm256_loadu_ps(out.as_ptr()))
    }
}

/// The index-space gradients of the tricubic B-spline at cells `ijk` (clamped),
/// fractions `fr`, of all eight lanes, and the lanes left out (0 there) because their
/// taps reach past the volume. `None` when a brick could not be built.
///
/// # Safety
/// The CPU must support AVX2 and FMA; `ijk` clamped to the field's cells.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn gradients(
    c: &Caster,
    (ijk, fr): ([__m256i; 3], [__m256; 3]),
    guard: &Guard,
) -> Option<([[f32; LANES]; 3], u8)> {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, pointer ranges).
    unsafe {
        let inv = Invariants::new(c);
        let mut memos: [Memo; 8] = Default::default();
        let k = corners(c, &inv, ijk, (0xff, &mut memos), guard)?;
        let w = axes!(|a| weights(fr[a]));
        let d = axes!(|a| derivatives(fr[a]));
        let mut g = [[0.0f32; LANES]; 3];
        let mut m = k.inner;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let p = 2 * (l & 3) + (l >> 2);
            let (lo, hi) = k.lane(l);
            let rows = lane_rows(inv.values, (&lo, hi.as_ref()));
            let v = spline_gradient(
                rows,
                [&w[0][p], &w[1][p], &w[2][p]],
                [&d[0][p], &d[1][p], &d[2][p]],
            );
            (g[0][l], g[1][l], g[2][l]) = (v[0], v[1], v[2]);
        }
        Some((g, !k.inner))
    }
}

/// The spline of the lanes `edge`, whose taps reach past the volume, by the scalar
/// loop's evaluation (clamp to edge), into `out`.
///
/// # Safety
/// The CPU must support AVX2; `ijk` clamped to the field's cells.
#[cold]
#[inline(never)]
#[target_feature(enable = "avx2,fma")]
unsafe fn edge_values(
    c: &Caster,
    (ijk, fr): ([__m256i; 3], [__m256; 3]),
    edge: u8,
    out: &mut [f32; LANES],
    guard: &Guard,
) {
    // SAFETY: AVX2 (this function's contract); the stores write whole arrays of eight.
    unsafe {
        let mut cell = [[0i32; LANES]; 3];
        let mut t = [[0.0f32; LANES]; 3];
        for a in 0..3 {
            _mm256_storeu_si256(cell[a].as_mut_ptr().cast(), ijk[a]);
            _mm256_storeu_ps(t[a].as_mut_ptr(), fr[a]);
        }
        for (l, o) in out.iter_mut().enumerate() {
            if edge & (1 << l) != 0 {
                let loc = Loc {
                    ijk: [0, 1, 2].map(|a| cell[a][l] as usize),
                    t: [t[0][l], t[1][l], t[2][l]],
                };
                *o = c.field.cubic_value_at(&loc, guard);
            }
        }
    }
}
