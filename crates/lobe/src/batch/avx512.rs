//! Hand-written AVX-512 versions of the `exact` (pow) and `gauss` (exp) kernels.
//!
//! The compiler vectorises the scalar code of `batch.rs` by itself, but it does the
//! 16-entry table lookups with gathers (slow on this core) and keeps one chain in
//! flight. Here each lookup is one `vpermi2pd` from two registers and every loop
//! iteration runs two independent 16-lane chains. The operations, their order and
//! their rounding (FMA where the scalar code calls `mul_add`) are exactly those of
//! `log2_f64`, `exp2_f64`, `round_to_f32`, `exact` and `gauss` in `batch.rs`, so
//! the results are bit-identical to the other paths (tested).

use std::arch::x86_64::*;

use super::{EXP2_POLY, EXP2_TABLE, LOG2_E, LOG2_INVC, LOG2_LOGC, LOG2_OFF, LOG2_POLY};

/// Two registers holding a 16-entry f64 table.
#[derive(Clone, Copy)]
struct Table16(__m512d, __m512d);

impl Table16 {
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn from_f64(t: &[f64; 16]) -> Self {
        // SAFETY: 16 f64 are read from a 16-element array, 8 at a time.
        unsafe {
            Table16(
                _mm512_loadu_pd(t.as_ptr()),
                _mm512_loadu_pd(t.as_ptr().add(8)),
            )
        }
    }

    #[inline]
    #[target_feature(enable = "avx512f")]
    fn from_bits(t: &[u64; 16]) -> Self {
        // SAFETY: as above; u64 and f64 have the same size.
        unsafe {
            let p = t.as_ptr().cast::<f64>();
            Table16(_mm512_loadu_pd(p), _mm512_loadu_pd(p.add(8)))
        }
    }

    /// `t[idx & 15]` per 64-bit lane.
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn get(self, idx: __m512i) -> __m512d {
        _mm512_permutex2var_pd(self.0, idx, self.1)
    }
}

/// Constants of the pow/exp kernels, loaded once per call.
#[derive(Clone, Copy)]
struct Consts {
    invc: Table16,
    logc: Table16,
    exp2: Table16,
}

impl Consts {
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn new() -> Self {
        Consts {
            invc: Table16::from_f64(&LOG2_INVC),
            logc: Table16::from_f64(&LOG2_LOGC),
            exp2: Table16::from_bits(&EXP2_TABLE),
        }
    }
}

#[inline]
#[target_feature(enable = "avx512f")]
fn splat(x: f64) -> __m512d {
    _mm512_set1_pd(x)
}

/// `log2_f64` for the 16 lanes of `c`, as two halves of 8 f64.
#[inline]
#[target_feature(enable = "avx512f,avx512dq")]
fn log2_x16(k: &Consts, c: __m512) -> [__m512d; 2] {
    let tiny = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(c, _mm512_set1_ps(f32::MIN_POSITIVE));
    let scaled = _mm512_sub_epi32(
        _mm512_castps_si512(_mm512_mul_ps(c, _mm512_set1_ps(8_388_608.0))),
        _mm512_set1_epi32(23 << 23),
    );
    let ix = _mm512_mask_blend_epi32(tiny, _mm512_castps_si512(c), scaled);
    let tmp = _mm512_sub_epi32(ix, _mm512_set1_epi32(LOG2_OFF as i32));
    let i = _mm512_srli_epi32::<19>(tmp); // only the low 4 bits are used by vpermi2pd
    let top = _mm512_and_si512(tmp, _mm512_set1_epi32(0xff80_0000u32 as i32));
    let z = _mm512_castsi512_ps(_mm512_sub_epi32(ix, top));
    let e = _mm512_srai_epi32::<23>(tmp);
    let halves = [
        (
            _mm512_castps512_ps256(z),
            _mm512_castsi512_si256(e),
            _mm512_castsi512_si256(i),
        ),
        (
            _mm512_extractf32x8_ps::<1>(z),
            _mm512_extracti32x8_epi32::<1>(e),
            _mm512_extracti32x8_epi32::<1>(i),
        ),
    ];
    halves.map(|(z, e, i)| {
        let z = _mm512_cvtps_pd(z);
        let kf = _mm512_cvtepi32_pd(e);
        let i = _mm512_cvtepu32_epi64(i);
        let r = _mm512_fmadd_pd(z, k.invc.get(i), splat(-1.0));
        let p = LOG2_POLY;
        let r2 = _mm512_mul_pd(r, r);
        let q01 = _mm512_fmadd_pd(splat(p[1]), r, splat(p[0]));
        let q23 = _mm512_fmadd_pd(splat(p[3]), r, splat(p[2]));
        let q45 = _mm512_fmadd_pd(splat(p[5]), r, splat(p[4]));
        let r4 = _mm512_mul_pd(r2, r2);
        let q03 = _mm512_fmadd_pd(q23, r2, q01);
        let q46 = _mm512_fmadd_pd(splat(p[6]), r2, q45);
        let q = _mm512_fmadd_pd(q46, r4, q03);
        _mm512_fmadd_pd(r, q, _mm512_add_pd(k.logc.get(i), kf))
    })
}

/// `exp2_f64` on 8 lanes.
#[inline]
#[target_feature(enable = "avx512f")]
fn exp2_x8(k: &Consts, x: __m512d) -> __m512d {
    // `if x < -160 { -160 } else { x }`: VMAXPD returns its second operand on NaN.
    let x = _mm512_max_pd(splat(-160.0), x);
    let shift = splat(1.5 * (1u64 << 48) as f64);
    let kd = _mm512_add_pd(x, shift);
    let ki = _mm512_castpd_si512(kd);
    let kd = _mm512_sub_pd(kd, shift);
    let r = _mm512_sub_pd(x, kd);
    let s = _mm512_castsi512_pd(_mm512_add_epi64(
        _mm512_castpd_si512(k.exp2.get(ki)),
        _mm512_slli_epi64::<48>(ki),
    ));
    let p = EXP2_POLY;
    let r2 = _mm512_mul_pd(r, r);
    let q01 = _mm512_fmadd_pd(splat(p[1]), r, splat(p[0]));
    let q23 = _mm512_fmadd_pd(splat(p[3]), r, splat(p[2]));
    let q = _mm512_fmadd_pd(q23, r2, q01);
    _mm512_mul_pd(s, _mm512_fmadd_pd(r, q, splat(1.0)))
}

/// `round_to_f32` on two halves, joined into 16 f32 lanes.
#[inline]
#[target_feature(enable = "avx512f,avx512dq,avx512vl")]
fn round_x16(y: [__m512d; 2]) -> __m512 {
    let [lo, hi] = y.map(|y| {
        let tiny = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(y, splat(f64::from(f32::MIN_POSITIVE)));
        let normal = _mm512_cvtpd_ps(_mm512_mask_blend_pd(tiny, y, splat(1.0)));
        let scaled = _mm512_fmadd_pd(y, splat(TWO_P149), splat(TWO_P52));
        let sub = _mm256_castsi256_ps(_mm512_cvtepi64_epi32(_mm512_castpd_si512(scaled)));
        _mm256_mask_blend_ps(tiny, normal, sub)
    });
    _mm512_insertf32x8::<1>(_mm512_castps256_ps512(lo), hi)
}

const TWO_P149: f64 = f64::from_bits((1023 + 149) << 52);
const TWO_P52: f64 = f64::from_bits((1023 + 52) << 52);

/// Zeroes the NaN lanes of `c` in `y` (eval: NaN gives 0).
#[inline]
#[target_feature(enable = "avx512f")]
fn zero_nan(c: __m512, y: __m512) -> __m512 {
    _mm512_maskz_mov_ps(_mm512_cmp_ps_mask::<_CMP_ORD_Q>(c, c), y)
}

/// `exact` on 16 lanes.
#[inline]
#[target_feature(enable = "avx512f,avx512dq,avx512vl")]
fn exact_x16(k: &Consts, n: __m512d, at_zero: __m512, c: __m512) -> __m512 {
    let cc = _mm512_min_ps(_mm512_set1_ps(1.0), c);
    let [l0, l1] = log2_x16(k, cc);
    let y = round_x16([
        exp2_x8(k, _mm512_mul_pd(n, l0)),
        exp2_x8(k, _mm512_mul_pd(n, l1)),
    ]);
    let positive = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(cc, _mm512_setzero_ps());
    zero_nan(c, _mm512_mask_blend_ps(positive, at_zero, y))
}

/// `gauss` on 16 lanes.
#[inline]
#[target_feature(enable = "avx512f,avx512dq,avx512vl")]
fn gauss_x16(k: &Consts, n: __m512, c: __m512) -> __m512 {
    let one = _mm512_set1_ps(1.0);
    let cc = _mm512_max_ps(_mm512_set1_ps(-1.0), _mm512_min_ps(one, c));
    let t = _mm512_mul_ps(n, _mm512_sub_ps(cc, one));
    let x0 = _mm512_mul_pd(_mm512_cvtps_pd(_mm512_castps512_ps256(t)), splat(LOG2_E));
    let x1 = _mm512_mul_pd(
        _mm512_cvtps_pd(_mm512_extractf32x8_ps::<1>(t)),
        splat(LOG2_E),
    );
    let y = round_x16([exp2_x8(k, x0), exp2_x8(k, x1)]);
    zero_nan(c, _mm512_min_ps(one, y))
}

/// Runs `f` over `cos` 32 lanes at a time (two independent chains), then the tail
/// with masked loads and stores.
#[inline]
#[target_feature(enable = "avx512f")]
fn drive(cos: &[f32], out: &mut [f32], f: impl Fn(__m512) -> __m512) {
    let len = cos.len().min(out.len());
    let (src, dst) = (cos.as_ptr(), out.as_mut_ptr());
    let mut i = 0;
    // SAFETY: every access is below `len` (full vectors while i + 32 <= len or
    // i + 16 <= len; the tail through a mask of the remaining `len - i < 16` lanes).
    unsafe {
        while i + 32 <= len {
            let a = _mm512_loadu_ps(src.add(i));
            let b = _mm512_loadu_ps(src.add(i + 16));
            let (ya, yb) = (f(a), f(b));
            _mm512_storeu_ps(dst.add(i), ya);
            _mm512_storeu_ps(dst.add(i + 16), yb);
            i += 32;
        }
        while i < len {
            let m: __mmask16 = if len - i >= 16 {
                0xffff
            } else {
                (1u16 << (len - i)) - 1
            };
            let a = _mm512_maskz_loadu_ps(m, src.add(i));
            _mm512_mask_storeu_ps(dst.add(i), m, f(a));
            i += 16;
        }
    }
}

/// The `exact` lobe (`max(c, 0)^n`) over a slice.
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw,avx2,fma")]
pub(super) fn exact(n: f32, cos: &[f32], out: &mut [f32]) {
    let k = Consts::new();
    let at_zero = _mm512_set1_ps(if n == 0.0 { 1.0 } else { 0.0 });
    let n = splat(f64::from(n));
    drive(cos, out, |c| exact_x16(&k, n, at_zero, c));
}

/// The `gauss` lobe (`exp(n (c - 1))`) over a slice.
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw,avx2,fma")]
pub(super) fn gauss(n: f32, cos: &[f32], out: &mut [f32]) {
    let k = Consts::new();
    let n = _mm512_set1_ps(n);
    drive(cos, out, |c| gauss_x16(&k, n, c));
}
