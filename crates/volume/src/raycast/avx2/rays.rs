//! A tile's rays set up eight at a time: `Caster::ray`'s arithmetic in vectors.
//!
//! A ray's set-up (its direction's length and reciprocal, three slab divisions, three
//! more for the steps per index unit, the jitter, the first and last sample) is a chain
//! of divisions and a square root. Done one ray at a time when a lane needed a ray, it
//! sat on the march's critical path; done for the whole tile before the march, eight
//! rays per vector, the MNI152 bench frame takes about 6% less CPU time
//! (docs/performance.md). The same operations in the same order and without FMA
//! contraction (division and square root are correctly rounded in both forms) give
//! the scalar rays bit for bit: images are compared with the scalar loop's in
//! `crates/render/tests/render.rs`, the sample bounds with `ceil_i64`/`floor_i64` below.

use std::arch::x86_64::*;

use super::*;

/// A ray as a lane takes it ([`Lanes::set`]): `Caster::ray`'s fields the march reads.
#[derive(Clone, Copy, Default)]
pub(in crate::raycast) struct LaneRay {
    pub(super) o: [f32; 3],
    pub(super) d: [f32; 3],
    /// `Ray::inv_dk`.
    pub(super) inv_dk: [f32; 3],
    /// `Ray::face_up`, as all ones or zero.
    pub(super) up: [i32; 3],
    pub(super) j: f32,
    /// First and last sample, clamped to +-2^24 (exact in f32, as `Ray::t` assumes).
    pub(super) k0: i32,
    pub(super) k1: i32,
    /// The ray's pixel, row-major in the tile.
    pub(super) id: u32,
}

/// The sample bound `ceil(x)` (`ceil_i64`) or, with `FLOOR`, `floor(x)` (`floor_i64`),
/// of eight values, as i32. Values beyond +-2^30 are clamped there first (rays of more
/// than a billion steps; [`Lanes::set`] clamps to +-2^24 in any case).
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn bound<const FLOOR: bool>(x: __m256) -> __m256i {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let lim = _mm256_set1_ps((1u32 << 30) as f32);
        let x = _mm256_max_ps(
            _mm256_min_ps(x, lim),
            _mm256_sub_ps(_mm256_setzero_ps(), lim),
        );
        let k = _mm256_cvttps_epi32(x);
        let kf = _mm256_cvtepi32_ps(k);
        // All ones (-1) where the truncation must move: up for ceil, down for floor.
        let adjust = if FLOOR {
            _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GT_OQ>(kf, x))
        } else {
            _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(kf, x))
        };
        if FLOOR {
            _mm256_add_epi32(k, adjust)
        } else {
            _mm256_sub_epi32(k, adjust)
        }
    }
}

/// `v - floor(v)`, as `jitter`'s `fract`.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn fract(v: __m256) -> __m256 {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe { _mm256_sub_ps(v, _mm256_floor_ps(v)) }
}

/// `a + b u + c v` per component, in `Vec3`'s order: (a + b u) + c v. (A function,
/// not a closure: a closure would not inherit the caller's target features, and its
/// intrinsics would be called out of line.)
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn plane(a: Vec3, b: Vec3, c: Vec3, (u, v): (__m256, __m256)) -> [__m256; 3] {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        axes!(|k| _mm256_add_ps(
            _mm256_add_ps(
                _mm256_set1_ps(a.get(k)),
                _mm256_mul_ps(_mm256_set1_ps(b.get(k)), u)
            ),
            _mm256_mul_ps(_mm256_set1_ps(c.get(k)), v),
        ))
    }
}

/// Index-space origins and directions and world directions of the rays through the
/// pixels `(x, y)`: `IndexRays::ray` per lane.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn directions(c: &Caster, x: __m256, y: __m256) -> ([__m256; 3], [__m256; 3], [__m256; 3]) {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let r = &c.rays;
        let u = _mm256_add_ps(_mm256_set1_ps(r.u0), _mm256_mul_ps(x, _mm256_set1_ps(r.du)));
        let v = _mm256_add_ps(_mm256_set1_ps(r.v0), _mm256_mul_ps(y, _mm256_set1_ps(r.dv)));
        let [f, rt, up] = r.index;
        if r.perspective {
            let [wf, wr, wu] = r.world;
            let w = plane(wf, wr, wu, (u, v));
            // `Vec3::length`: (x x + y y) + z z, then the square root.
            let dot = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(w[0], w[0]), _mm256_mul_ps(w[1], w[1])),
                _mm256_mul_ps(w[2], w[2]),
            );
            let inv = _mm256_div_ps(_mm256_set1_ps(1.0), _mm256_sqrt_ps(dot));
            let d = plane(f, rt, up, (u, v));
            (
                axes!(|k| _mm256_set1_ps(r.origin.get(k))),
                axes!(|k| _mm256_mul_ps(d[k], inv)),
                axes!(|k| _mm256_mul_ps(w[k], inv)),
            )
        } else {
            (
                plane(r.origin, rt, up, (u, v)),
                axes!(|k| _mm256_set1_ps(f.get(k))),
                axes!(|k| _mm256_set1_ps(r.world[0].get(k))),
            )
        }
    }
}

/// The slab test of `Caster::ray` against the clip box for rays `o + t d` (t in mm):
/// the entry and exit parameters, `Ray::inv_dk`, `Ray::face_up` (all ones or
/// zero), and the rays not refused by an axis they do not move along (all ones).
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn slabs(c: &Caster, o: [__m256; 3], d: [__m256; 3]) -> Slabs {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let (lo_box, hi_box) = c.clip_box;
        let (mut t0, mut t1) = (_mm256_setzero_ps(), _mm256_set1_ps(f32::INFINITY));
        let mut inv_dk = [_mm256_setzero_ps(); 3];
        let mut up = [_mm256_setzero_ps(); 3];
        let mut inside = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        let abs = _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX));
        for a in 0..3 {
            let (lo, hi) = (_mm256_set1_ps(lo_box[a]), _mm256_set1_ps(hi_box[a]));
            let flat = _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_and_ps(d[a], abs), _mm256_set1_ps(1e-12));
            let outside = _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_LT_OQ>(o[a], lo),
                _mm256_cmp_ps::<_CMP_GT_OQ>(o[a], hi),
            );
            inside = _mm256_andnot_ps(_mm256_and_ps(flat, outside), inside);
            let inv = _mm256_div_ps(_mm256_set1_ps(1.0), d[a]);
            let ta = _mm256_mul_ps(_mm256_sub_ps(lo, o[a]), inv);
            let tb = _mm256_mul_ps(_mm256_sub_ps(hi, o[a]), inv);
            let near = _mm256_max_ps(t0, _mm256_min_ps(ta, tb));
            let far = _mm256_min_ps(t1, _mm256_max_ps(ta, tb));
            t0 = _mm256_blendv_ps(near, t0, flat);
            t1 = _mm256_blendv_ps(far, t1, flat);
            inv_dk[a] = _mm256_blendv_ps(
                _mm256_div_ps(inv, _mm256_set1_ps(c.dt)),
                _mm256_set1_ps(f32::INFINITY),
                flat,
            );
            let rising = _mm256_cmp_ps::<_CMP_GT_OQ>(d[a], _mm256_setzero_ps());
            up[a] = _mm256_or_ps(rising, flat);
        }
        (t0, t1, inv_dk, up, inside)
    }
}

/// [`slabs`]'s result: entry, exit, steps per index unit, face-up masks, inside mask.
type Slabs = (__m256, __m256, [__m256; 3], [__m256; 3], __m256);

/// `jitter` of eight pixels.
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn jitters(x: __m256, y: __m256) -> __m256 {
    // SAFETY: the caller runs with AVX2 (this function's contract).
    unsafe {
        let h = _mm256_add_ps(
            _mm256_mul_ps(_mm256_set1_ps(0.067_110_56), x),
            _mm256_mul_ps(_mm256_set1_ps(0.005_837_15), y),
        );
        fract(_mm256_mul_ps(_mm256_set1_ps(52.982_918), fract(h)))
    }
}

/// Sets up the rays of the tile's pixels `i0 .. i0 + 8` (those below `n`), as
/// `Caster::ray` does: each that meets a visible cell is appended to `out`, its view
/// vector written to `views`.
///
/// # Safety
/// The CPU must support AVX2; `i0` must be a multiple of 8 below `n <= TILE * TILE`.
#[inline(always)]
pub(super) unsafe fn rays8(
    c: &Caster,
    px: &Pixels,
    (i0, n): (usize, usize),
    out: &mut Vec<LaneRay>,
    views: &mut [Vec3],
) {
    // SAFETY: this function's `# Safety` contract, which its callers uphold,
    // covers every unsafe operation below (CPU features, the 8 entries at i0 of the
    // tile's arrays of TILE * TILE).
    unsafe {
        let start = _mm256_loadu_ps(px.start.as_ptr().add(i0));
        let mut valid = _mm256_cmp_ps::<_CMP_NEQ_UQ>(start, _mm256_set1_ps(f32::INFINITY));
        if _mm256_movemask_ps(valid) == 0 {
            return;
        }
        let end = _mm256_loadu_ps(px.end.as_ptr().add(i0));
        // Pixel i of the tile is (x0 + i % tw, y0 + i / tw): small integers, exact in
        // f32, and so is the floor of their quotient (i < 256, tw <= 16), computed in
        // vectors (eight scalar stores read back as one vector would stall).
        let i = _mm256_add_ps(
            _mm256_set1_ps(i0 as f32),
            _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0),
        );
        let tw = _mm256_set1_ps((px.xs.1 - px.xs.0) as f32);
        let row = _mm256_floor_ps(_mm256_div_ps(i, tw));
        let x = _mm256_add_ps(
            _mm256_set1_ps(px.xs.0 as f32),
            _mm256_sub_ps(i, _mm256_mul_ps(row, tw)),
        );
        let y = _mm256_add_ps(_mm256_set1_ps(px.ys.0 as f32), row);
        let (o, d, dir) = directions(c, x, y);
        let (t0, t1, inv_dk, up, inside) = slabs(c, o, d);
        valid = _mm256_and_ps(valid, inside);
        let t0 = _mm256_max_ps(t0, start);
        let t1 = _mm256_min_ps(t1, end);
        valid = _mm256_andnot_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(t0, t1), valid);
        let j = if c.jitter {
            jitters(x, y)
        } else {
            _mm256_setzero_ps()
        };
        let dt = _mm256_set1_ps(c.dt);
        let k0 = bound::<false>(_mm256_sub_ps(_mm256_div_ps(t0, dt), j));
        let k1 = bound::<true>(_mm256_sub_ps(_mm256_div_ps(t1, dt), j));
        let empty = _mm256_castsi256_ps(_mm256_cmpgt_epi32(k0, k1));
        let valid = _mm256_movemask_ps(_mm256_andnot_ps(empty, valid)) as u32;
        let valid = valid & ((1u32 << (n - i0).min(LANES)) - 1);
        if valid == 0 {
            return;
        }
        let lim = _mm256_set1_epi32(1 << 24);
        let neg = _mm256_sub_epi32(_mm256_setzero_si256(), lim);
        let (k0, k1) = (
            _mm256_max_epi32(_mm256_min_epi32(k0, lim), neg),
            _mm256_max_epi32(_mm256_min_epi32(k1, lim), neg),
        );
        let mut view = [[0.0f32; LANES]; 3];
        let mut lanes = [[0.0f32; LANES]; 16];
        for a in 0..3 {
            _mm256_storeu_ps(lanes[a].as_mut_ptr(), o[a]);
            _mm256_storeu_ps(lanes[3 + a].as_mut_ptr(), d[a]);
            _mm256_storeu_ps(lanes[6 + a].as_mut_ptr(), inv_dk[a]);
            _mm256_storeu_ps(lanes[9 + a].as_mut_ptr(), up[a]);
            _mm256_storeu_ps(view[a].as_mut_ptr(), dir[a]);
        }
        _mm256_storeu_ps(lanes[12].as_mut_ptr(), j);
        _mm256_storeu_ps(lanes[13].as_mut_ptr(), _mm256_castsi256_ps(k0));
        _mm256_storeu_ps(lanes[14].as_mut_ptr(), _mm256_castsi256_ps(k1));
        let mut m = valid;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let at = |q: usize| lanes[q][l];
            out.push(LaneRay {
                o: [at(0), at(1), at(2)],
                d: [at(3), at(4), at(5)],
                inv_dk: [at(6), at(7), at(8)],
                up: [
                    at(9).to_bits() as i32,
                    at(10).to_bits() as i32,
                    at(11).to_bits() as i32,
                ],
                j: at(12),
                k0: at(13).to_bits() as i32,
                k1: at(14).to_bits() as i32,
                id: (i0 + l) as u32,
            });
            // `-dir`: the view vector, from the samples towards the eye.
            *views.get_unchecked_mut(i0 + l) = Vec3::new(-view[0][l], -view[1][l], -view[2][l]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raycast::caster::{ceil_i64, floor_i64};

    #[test]
    fn vector_bounds_are_the_scalar_ceil_and_floor() {
        if !supported() {
            assert!(!glint_testkit::strict(), "no AVX2+FMA in a strict run");
            return;
        }
        let mut xs = vec![0.0f32, -0.0, 0.5, -0.5, 1.0, -1.0, 1e-7, -1e-7, 2.999_999_8];
        xs.extend([
            16_777_215.0,
            16_777_216.0,
            16_777_218.0,
            -16_777_218.0,
            1e9,
            -1e9,
        ]);
        for i in -300..300 {
            let x = i as f32 * 0.37;
            xs.extend([x, x.next_up(), x.next_down()]);
        }
        for chunk in xs.chunks(LANES) {
            let mut v = [0.0f32; LANES];
            v[..chunk.len()].copy_from_slice(chunk);
            let (mut c, mut f) = ([0i32; LANES], [0i32; LANES]);
            // SAFETY: AVX2 is supported (checked above); the stores write eight i32.
            unsafe {
                let x = _mm256_loadu_ps(v.as_ptr());
                _mm256_storeu_si256(c.as_mut_ptr().cast(), bound::<false>(x));
                _mm256_storeu_si256(f.as_mut_ptr().cast(), bound::<true>(x));
            }
            for l in 0..LANES {
                assert_eq!(i64::from(c[l]), ceil_i64(v[l]), "ceil {}", v[l]);
                assert_eq!(i64::from(f[l]), floor_i64(v[l]), "floor {}", v[l]);
            }
        }
    }
}
