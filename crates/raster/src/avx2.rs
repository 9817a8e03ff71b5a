//! The rasterizer's inner loop on AVX2: eight samples of a row per step, each lane
//! the arithmetic of the scalar loop ([`super::tile`]'s `raster_scalar`) in the same
//! order and without FMA, so coverage, depth and the triangle kept are bit-identical
//! to it. Written with `std::arch` intrinsics: stable Rust has no portable SIMD, and
//! the compiler does not vectorise the scalar loop's masked updates by itself.

use std::arch::x86_64::*;

use super::frame::{Binned, EdgeRow, Edges, ScreenVertex};
use super::rect::{clip, Rect, LANES, LANE_X};

/// Whether this CPU can run [`raster`].
pub(super) fn supported() -> bool {
    is_x86_feature_detected!("avx2")
}

/// An edge function along a row, broadcast: `(r - d (x - px)) sign`.
struct EdgeVec {
    r: __m256,
    d: __m256,
    px: __m256,
}

impl EdgeVec {
    /// # Safety
    /// Only for callers compiled with AVX2.
    #[inline(always)]
    unsafe fn new(e: EdgeRow) -> EdgeVec {
        // SAFETY: the caller runs with AVX2 (this function's contract).
        unsafe {
            EdgeVec {
                r: _mm256_set1_ps(e.r),
                d: _mm256_set1_ps(e.d),
                px: _mm256_set1_ps(e.px),
            }
        }
    }

    /// # Safety
    /// Only for callers compiled with AVX2.
    #[inline(always)]
    unsafe fn at(&self, x: __m256, sign: __m256) -> __m256 {
        // SAFETY: the caller runs with AVX2 (this function's contract).
        unsafe {
            _mm256_mul_ps(
                _mm256_sub_ps(self.r, _mm256_mul_ps(self.d, _mm256_sub_ps(x, self.px))),
                sign,
            )
        }
    }
}

/// [`super::tile`]'s `raster_scalar` for each triangle of `tris` in order, eight
/// samples at a time.
///
/// # Safety
/// The CPU must support AVX2 ([`supported`]).
#[target_feature(enable = "avx2")]
pub(super) unsafe fn raster(
    verts: &[ScreenVertex],
    triangles: &[[u32; 3]],
    tris: &[Binned],
    rect: Rect,
    depth: &mut [f32],
    ids: &mut [u32],
) {
    for t in tris {
        let tri = triangles[t.id as usize].map(|i| verts[i as usize]);
        // SAFETY: this function runs with AVX2 (its contract).
        unsafe { raster_one(tri, t, rect, depth, ids) };
    }
}

/// One triangle of [`raster`].
///
/// # Safety
/// The CPU must support AVX2.
#[inline(always)]
unsafe fn raster_one(
    [a, b, c]: [ScreenVertex; 3],
    t: &Binned,
    rect: Rect,
    depth: &mut [f32],
    ids: &mut [u32],
) {
    let Some([x0, y0, x1, y1]) = clip(t, rect) else {
        return;
    };
    let e = Edges::new(a, b, c);
    let stride = rect.stride();
    // SAFETY: the caller runs with AVX2 (this function's contract); every load and
    // store is of LANES elements of a slice just bounds-checked to hold them.
    unsafe {
        let sign = _mm256_set1_ps(e.sign);
        let inv_area = _mm256_set1_ps(e.inv_area());
        let (ak, bk, ck) = (
            _mm256_set1_ps(a.key),
            _mm256_set1_ps(b.key),
            _mm256_set1_ps(c.key),
        );
        let lane_x = _mm256_loadu_ps(LANE_X.as_ptr());
        let zero = _mm256_setzero_ps();
        let id = _mm256_set1_epi32(t.id as i32);
        let neg_inf = _mm256_set1_ps(f32::NEG_INFINITY);
        for y in y0..=y1 {
            let [e0, e1, e2] = e.row(y as f32);
            let (e0, e1, e2) = (EdgeVec::new(e0), EdgeVec::new(e1), EdgeVec::new(e2));
            let row = (y - rect.y0) * stride;
            let mut xs = x0;
            while xs <= x1 {
                let k = row + xs - rect.x0;
                let d = &mut depth[k..k + LANES];
                let i = &mut ids[k..k + LANES];
                let x = _mm256_add_ps(_mm256_set1_ps(xs as f32), lane_x);
                let last = _mm256_set1_ps((x1 - xs) as f32);
                let w0 = e0.at(x, sign);
                let w1 = e1.at(x, sign);
                let w2 = e2.at(x, sign);
                let key = _mm256_mul_ps(
                    _mm256_add_ps(
                        _mm256_add_ps(_mm256_mul_ps(w0, ak), _mm256_mul_ps(w1, bk)),
                        _mm256_mul_ps(w2, ck),
                    ),
                    inv_area,
                );
                let old = _mm256_loadu_ps(d.as_ptr());
                let hit = _mm256_and_ps(
                    _mm256_and_ps(
                        _mm256_cmp_ps::<_CMP_LE_OQ>(lane_x, last),
                        _mm256_cmp_ps::<_CMP_GE_OQ>(w0, zero),
                    ),
                    _mm256_and_ps(
                        _mm256_and_ps(
                            _mm256_cmp_ps::<_CMP_GE_OQ>(w1, zero),
                            _mm256_cmp_ps::<_CMP_GE_OQ>(w2, zero),
                        ),
                        _mm256_cmp_ps::<_CMP_GT_OQ>(key, old),
                    ),
                );
                // The updates are written as max and xor rather than blends: LLVM turns
                // a blend of the loaded value into a masked store (vmaskmovps), which
                // costs tens of cycles on AMD's cores. `hit` implies key > old, so the
                // max is the blend.
                let candidate = _mm256_blendv_ps(neg_inf, key, hit);
                _mm256_storeu_ps(d.as_mut_ptr(), _mm256_max_ps(old, candidate));
                let old_id = _mm256_loadu_si256(i.as_ptr().cast::<__m256i>());
                let new_id = _mm256_xor_si256(
                    old_id,
                    _mm256_and_si256(_mm256_xor_si256(old_id, id), _mm256_castps_si256(hit)),
                );
                _mm256_storeu_si256(i.as_mut_ptr().cast::<__m256i>(), new_id);
                xs += LANES;
            }
        }
    }
}
