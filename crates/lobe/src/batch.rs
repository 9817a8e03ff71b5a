//! Batch evaluation of `Lobe<f32>` over slices with the widest vector unit the CPU has.
//!
//! Every kernel is written once, as a per-element loop of plain IEEE operations and
//! branch-free selects, and compiled three times: for AVX-512 (`avx512f`, 16 f32
//! lanes), for AVX2 + FMA (8 lanes) and for the baseline target (the fallback; on
//! x86-64 the compiler may still use SSE2 there). [`KernelPath::best`] picks the
//! widest one the CPU supports at run time (`is_x86_feature_detected!`), so one
//! binary runs everywhere; the environment variable `GLINT_SIMD` (`scalar`, `avx2`,
//! `avx512`) caps it, so a narrower path can be forced on any machine
//! ([`KernelPath::cap`]). This is the `multiversion` crate's technique written out
//! by hand (three wrapper functions and one `match`), to keep glint-lobe free of
//! dependencies. The AVX-512 `exact` and `gauss` kernels are hand-written with
//! `std::arch` intrinsics (module `avx512`), because the compiler's version used
//! slow gathers for the table lookups.
//!
//! ## Agreement with [`Lobe::eval`]
//! Rust never fuses or reorders floating-point operations, and every path runs the
//! same operations in the same order, so:
//! - the power fits (`k`, `g`, `minimax`) and `schlick` are **bit-identical** to
//!   [`Lobe::eval`] on every path (same subtract, multiply, squarings and division;
//!   subnormal results included);
//! - `exact` and `gauss` replace libm's `powf`/`expf` by the vectorised pow below,
//!   which is within 1 ulp of the correctly rounded result; libm's is too, so they
//!   agree with [`Lobe::eval`] within 2 ulp (1 ulp measured), and all paths agree
//!   with each other bit for bit.
//!
//! ## The vectorised pow
//! `c^n = 2^(n·log2 c)`, evaluated in f64 lanes after the design of ARM's
//! optimized-routines `powf` (Szabolcs Nagy, `math/powf.c`): `log2` from a 16-entry
//! table of `1/c_i`, `log2 c_i` plus a degree-7 polynomial in `r = z/c_i - 1`
//! (`|r| < 0.03`, relative error < 4e-12), and `2^x` from a 16-entry table of
//! `2^(i/16)` plus a degree-4 polynomial (`|r| <= 1/32`, relative error < 5e-11),
//! both evaluated with FMA by Estrin's scheme. The f64 result is rounded to f32
//! once (subnormals through an integer path, see `round_to_f32`), so the result is
//! within **1 ulp** of the correctly rounded `c^n`, and in practice correctly rounded
//! except within ~1e-4 ulp of a rounding boundary (tested: 99.998% of 3.4 million
//! cases exactly, the rest 1 ulp), subnormal inputs and results included. The
//! polynomials are Taylor's and the tables were computed with mpmath at 200 bits,
//! not copied from ARM. On the baseline path of an x86-64 CPU without FMA,
//! `mul_add` is a libm call, which makes `exact`/`gauss` slower there than libm.
//!
//! [`Lobe::eval`]: crate::Lobe::eval

use crate::{Lobe, LobeKind, Real};

#[cfg(target_arch = "x86_64")]
mod avx512;
pub mod measure;

/// The batch entry on the lobe itself: here rather than beside [`Lobe::eval`] so that
/// the kernels depend on the lobe and not the other way round (no module cycle).
impl<T: Real> Lobe<T> {
    /// Evaluates the lobe for every element of `cos`, writing `out`.
    ///
    /// For `f32` this runs the SIMD batch kernels on the widest vector unit the CPU
    /// has (AVX-512, AVX2 + FMA or the scalar fallback, chosen at run time; see
    /// [`KernelPath`](crate::KernelPath)). The power fits and Schlick give exactly
    /// [`eval`](Self::eval)'s values; `exact` and `gauss` use a vectorised pow/exp
    /// within 1 ulp of the correctly rounded value, so within 2 ulp of `eval`'s libm.
    /// For `f64` it is [`eval_slice_scalar`](Self::eval_slice_scalar).
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn eval_slice(&self, cos: &[T], out: &mut [T]) {
        assert_eq!(
            cos.len(),
            out.len(),
            "eval_slice: input and output lengths differ"
        );
        if std::any::TypeId::of::<T>() == std::any::TypeId::of::<f32>() {
            // SAFETY: T is f32 (same TypeId), so `Lobe<T>` is `Lobe<f32>` and the
            // slices are f32 slices of the same lengths; nothing else is reinterpreted.
            let (lobe, cos, out) = unsafe {
                (
                    &*(self as *const Self).cast::<Lobe<f32>>(),
                    std::slice::from_raw_parts(cos.as_ptr().cast::<f32>(), cos.len()),
                    std::slice::from_raw_parts_mut(out.as_mut_ptr().cast::<f32>(), out.len()),
                )
            };
            eval_slice_best(lobe, cos, out);
        } else {
            self.eval_slice_scalar(cos, out);
        }
    }
}

/// One compiled version of the batch kernels (`scalar`, `avx2`, `avx512`).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[strum(serialize_all = "lowercase", ascii_case_insensitive)]
pub enum KernelPath {
    /// The baseline target (x86-64: SSE2); no runtime requirement.
    Scalar,
    /// AVX2 with FMA: 8 f32 lanes.
    Avx2,
    /// AVX-512F (with VL, DQ, BW): 16 f32 lanes.
    Avx512,
}

impl KernelPath {
    /// Every path, narrowest first.
    pub const ALL: &'static [KernelPath] = <KernelPath as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`KernelPath::ALL`].
    pub const NAMES: &'static [&'static str] = <KernelPath as strum::VariantNames>::VARIANTS;

    /// A short name: `scalar`, `avx2`, `avx512`.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// f32 lanes per vector on this path (1 for the fallback, which is written for
    /// one lane; the compiler may still use SSE2 there).
    pub fn lanes(self) -> usize {
        match self {
            KernelPath::Scalar => 1,
            KernelPath::Avx2 => 8,
            KernelPath::Avx512 => 16,
        }
    }

    /// Whether this CPU can run the path.
    pub fn is_supported(self) -> bool {
        match self {
            KernelPath::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            KernelPath::Avx2 => {
                std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            KernelPath::Avx512 => {
                std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512vl")
                    && std::arch::is_x86_feature_detected!("avx512dq")
                    && std::arch::is_x86_feature_detected!("avx512bw")
                    && std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The paths this CPU supports, narrowest first.
    pub fn supported() -> Vec<KernelPath> {
        Self::ALL
            .iter()
            .copied()
            .filter(|p| p.is_supported())
            .collect()
    }

    /// The widest path this CPU supports within [`KernelPath::cap`];
    /// [`Lobe::eval_slice`](crate::Lobe::eval_slice) uses it.
    pub fn best() -> KernelPath {
        // Detected once: eval_slice calls this for every slice, however short.
        static BEST: std::sync::OnceLock<KernelPath> = std::sync::OnceLock::new();
        *BEST.get_or_init(|| Self::best_within(Self::cap()))
    }

    /// The widest path this CPU supports that is no wider than `cap`.
    pub fn best_within(cap: KernelPath) -> KernelPath {
        Self::ALL
            .iter()
            .copied()
            .filter(|&p| p <= cap && p.is_supported())
            .max()
            .unwrap_or(KernelPath::Scalar)
    }

    /// The widest path the environment allows: `GLINT_SIMD` (`scalar`, `avx2` or
    /// `avx512`, any case), [`KernelPath::Avx512`] when unset. An unknown value is
    /// ignored, with one note on stderr. Read once per process.
    pub fn cap() -> KernelPath {
        static CAP: std::sync::OnceLock<KernelPath> = std::sync::OnceLock::new();
        *CAP.get_or_init(|| {
            let value = std::env::var("GLINT_SIMD").ok();
            Self::parse_cap(value.as_deref()).unwrap_or_else(|bad| {
                eprintln!(
                    "glint: ignoring GLINT_SIMD={bad:?} (expected one of {})",
                    Self::NAMES.join(", ")
                );
                KernelPath::Avx512
            })
        })
    }

    /// [`KernelPath::cap`] of a value of `GLINT_SIMD`: unset or empty gives the widest
    /// path, a path's name that path, anything else back as the error.
    pub fn parse_cap(value: Option<&str>) -> Result<KernelPath, String> {
        match value.map(str::trim) {
            None | Some("") => Ok(KernelPath::Avx512),
            Some(v) => v.parse().map_err(|_| v.to_string()),
        }
    }
}

/// Why [`eval_slice_with`] refused to run.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BatchError {
    /// The CPU lacks the instructions of the requested path.
    #[error("kernel path '{0}' is not supported by this CPU")]
    Unsupported(KernelPath),
    /// Input and output lengths differ.
    #[error("input has {input} elements but output has {output}")]
    LengthMismatch {
        /// Length of the input slice.
        input: usize,
        /// Length of the output slice.
        output: usize,
    },
}

/// Evaluates `lobe` for every element of `cos` into `out` on a chosen [`KernelPath`].
///
/// Same semantics as [`Lobe::eval`](crate::Lobe::eval) (NaN gives 0, `c` clamped to
/// `[-1, 1]`, result in `[0, 1]`); see the module docs for how closely each lobe
/// agrees with it.
///
/// ```
/// use glint_lobe::{eval_slice_with, KernelPath, Lobe, LobeKind};
///
/// let k = Lobe::<f32>::new(LobeKind::EnergyFit, 100.0, 4).unwrap();
/// let cos = [1.0, 0.99, 0.9, f32::NAN];
/// let mut out = [0.0; 4];
/// for path in KernelPath::supported() {
///     eval_slice_with(&k, path, &cos, &mut out).unwrap();
///     assert_eq!(out, cos.map(|c| k.eval(c)));
/// }
/// ```
pub fn eval_slice_with(
    lobe: &Lobe<f32>,
    path: KernelPath,
    cos: &[f32],
    out: &mut [f32],
) -> Result<(), BatchError> {
    if cos.len() != out.len() {
        return Err(BatchError::LengthMismatch {
            input: cos.len(),
            output: out.len(),
        });
    }
    if !path.is_supported() {
        return Err(BatchError::Unsupported(path));
    }
    run(path, &Params::of(lobe), cos, out);
    Ok(())
}

/// [`Lobe::eval_slice`](crate::Lobe::eval_slice) for f32: the best path.
/// Lengths are checked by the caller.
pub(crate) fn eval_slice_best(lobe: &Lobe<f32>, cos: &[f32], out: &mut [f32]) {
    run(KernelPath::best(), &Params::of(lobe), cos, out);
}

/// `c^n` for every element with the vectorised pow of this module: `out[i] =
/// max(c, 0)^n` on the best path, with `c` clamped to 1 and NaN giving 0, within
/// 1 ulp of the correctly rounded value (`0^0 = 1`).
///
/// This is the `exact` lobe's batch kernel; `n` is any finite value in `0..=MAX_N`.
///
/// # Panics
/// If the slices differ in length.
pub fn pow_slice(cos: &[f32], n: f32, out: &mut [f32]) {
    assert_eq!(cos.len(), out.len(), "pow_slice: lengths differ");
    run(KernelPath::best(), &Params::Exact { n }, cos, out);
}

/// The parameters of a lobe as its kernel needs them (the same f32 values `Lobe`
/// holds in its private form: `a` and `n` rounded from f64 to f32).
#[derive(Clone, Copy, Debug)]
enum Params {
    Exact { n: f32 },
    Power { a: f32, v: u32 },
    Schlick { n: f32 },
    Gauss { n: f32 },
}

impl Params {
    fn of(lobe: &Lobe<f32>) -> Params {
        let n = lobe.n() as f32;
        match lobe.kind() {
            LobeKind::Exact => Params::Exact { n },
            LobeKind::EnergyFit | LobeKind::SlopeFit | LobeKind::Minimax => Params::Power {
                a: lobe.coefficient().unwrap_or(0.0) as f32,
                v: lobe.v(),
            },
            LobeKind::Schlick => Params::Schlick { n },
            LobeKind::Gauss => Params::Gauss { n },
        }
    }
}

fn run(path: KernelPath, params: &Params, cos: &[f32], out: &mut [f32]) {
    debug_assert_eq!(cos.len(), out.len());
    // Vector stores that straddle two cache lines cost two; so the few elements
    // before the first 64-byte boundary of `out` go first, then the aligned rest
    // (measured ~10-15% on the L1 block; `Vec<f32>` is only 16-byte aligned).
    let head = out.as_ptr().align_offset(64);
    if cos.len() >= 64 && head > 0 && head < 16 {
        let (cos_head, cos_rest) = cos.split_at(head);
        let (out_head, out_rest) = out.split_at_mut(head);
        run_aligned(path, params, cos_head, out_head);
        run_aligned(path, params, cos_rest, out_rest);
    } else {
        run_aligned(path, params, cos, out);
    }
}

fn run_aligned(path: KernelPath, params: &Params, cos: &[f32], out: &mut [f32]) {
    #[cfg(test)]
    tests::count_run(path);
    match path {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: callers only pass paths whose `is_supported()` is true.
        KernelPath::Avx512 => unsafe { x86::eval_avx512(params, cos, out) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above.
        KernelPath::Avx2 => unsafe { x86::eval_avx2(params, cos, out) },
        _ => eval_all(params, cos, out),
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::{eval_all, Params};

    /// The kernels compiled for AVX-512.
    ///
    /// # Safety
    /// The CPU must support AVX-512 F, VL, DQ, BW, AVX2 and FMA (checked by the
    /// dispatcher with `is_x86_feature_detected!`).
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2,fma")]
    pub(super) unsafe fn eval_avx512(params: &Params, cos: &[f32], out: &mut [f32]) {
        match *params {
            // Hand-written: vpermi2pd table lookups instead of gathers.
            Params::Exact { n } => super::avx512::exact(n, cos, out),
            Params::Gauss { n } => super::avx512::gauss(n, cos, out),
            _ => eval_all(params, cos, out),
        }
    }

    /// The kernels compiled for AVX2 + FMA.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA (checked by the dispatcher).
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn eval_avx2(params: &Params, cos: &[f32], out: &mut [f32]) {
        eval_all(params, cos, out)
    }
}

/// The body shared by every path; everything below is `inline(always)` so it is
/// compiled with the caller's target features.
#[inline(always)]
fn eval_all(params: &Params, cos: &[f32], out: &mut [f32]) {
    match *params {
        Params::Power { a, v } => power_dispatch(a, v, cos, out),
        Params::Schlick { n } => map(cos, out, |c| schlick(n, c)),
        Params::Gauss { n } => map(cos, out, |c| gauss(n, c)),
        Params::Exact { n } => {
            let at_zero = if n == 0.0 { 1.0 } else { 0.0 };
            let n = f64::from(n);
            map(cos, out, |c| exact(n, at_zero, c))
        }
    }
}

/// The loop the vectoriser sees: one element at a time, no branches.
#[inline(always)]
fn map(cos: &[f32], out: &mut [f32], f: impl Fn(f32) -> f32) {
    for (o, &c) in out.iter_mut().zip(cos) {
        *o = f(c);
    }
}

// Selects written as `if x < y { x } else { y }` compile to one MINPS/MAXPS and have
// x86's NaN rule (the second operand wins), which the kernels use on purpose; Rust's
// `f32::min`/`max` ignore NaN and cost a compare and a blend more.

/// `min(c, 1)`, NaN stays NaN.
#[inline(always)]
fn clamp_hi(c: f32) -> f32 {
    if 1.0 < c {
        1.0
    } else {
        c
    }
}

/// `max(c, -1)`, NaN stays NaN.
#[inline(always)]
fn clamp_lo(c: f32) -> f32 {
    if c < -1.0 {
        -1.0
    } else {
        c
    }
}

/// Dispatches the power fit to a copy specialised for `v` (so the squarings unroll
/// and the loop vectorises) and for whether the lower clamp of `c` is needed.
#[inline(always)]
fn power_dispatch(a: f32, v: u32, cos: &[f32], out: &mut [f32]) {
    // For a >= 0.5 every c <= -1 gives a base 1 - a(1 - c) <= 0, hence 0, with or
    // without clamping c at -1 (an infinite c gives -inf, also 0); so the clamp, one
    // operation of ~9, is skipped. For a < 0.5 the base stays positive and it matters.
    let lo = a < 0.5;
    macro_rules! by_v {
        ($($v:literal)*) => {
            match (v, lo) {
                $(($v, true) => power::<$v, true>(a, cos, out),
                  ($v, false) => power::<$v, false>(a, cos, out),)*
                // Lobe::new rejects v > MAX_V = 10; keep the loop for completeness.
                _ => map(cos, out, |c| power_elem(a, v, clamp_lo(c))),
            }
        };
    }
    by_v!(0 1 2 3 4 5 6 7 8 9 10)
}

#[inline(always)]
fn power<const V: u32, const LO: bool>(a: f32, cos: &[f32], out: &mut [f32]) {
    map(cos, out, |c| {
        let c = if LO { clamp_lo(c) } else { c };
        power_elem(a, V, c)
    })
}

/// `max(0, 1 - a(1 - c))^(2^v)` with the operations of `Lobe::eval`.
#[inline(always)]
fn power_elem(a: f32, v: u32, c: f32) -> f32 {
    let c = clamp_hi(c);
    let b = 1.0 - a * (1.0 - c);
    // MAXPS(b, 0): NaN (from a NaN c) gives 0, as eval does.
    let mut b = if b > 0.0 { b } else { 0.0 };
    for _ in 0..v {
        b *= b;
    }
    b
}

/// Schlick's `c / (n(1 - c) + c)` for `c > 0`, else 0, with the operations of `eval`.
#[inline(always)]
fn schlick(n: f32, c: f32) -> f32 {
    let c = clamp_lo(clamp_hi(c));
    let y = c / (n * (1.0 - c) + c);
    let y = if c > 0.0 { y } else { 0.0 };
    // eval's final clamp to [0, 1] (y >= 0 already).
    if 1.0 < y {
        1.0
    } else {
        y
    }
}

/// `exp(n (c - 1))`: the argument with eval's f32 operations, the exponential in f64.
#[inline(always)]
fn gauss(n: f32, c: f32) -> f32 {
    let cc = clamp_lo(clamp_hi(c));
    let t = n * (cc - 1.0);
    let x = f64::from(t) * LOG2_E;
    let y = round_to_f32(exp2_f64(x));
    let y = if 1.0 < y { 1.0 } else { y };
    if c.is_nan() {
        0.0
    } else {
        y
    }
}

/// `max(c, 0)^n` for `n > 0` (`at_zero` = 0) or `n = 0` (`at_zero` = 1).
#[inline(always)]
fn exact(n: f64, at_zero: f32, c: f32) -> f32 {
    let cc = clamp_hi(c);
    let y = round_to_f32(exp2_f64(n * log2_f64(cc)));
    // c <= 0 and NaN take the else branch; NaN is then zeroed below.
    let y = if cc > 0.0 { y } else { at_zero };
    if c.is_nan() {
        0.0
    } else {
        y
    }
}

/// `y as f32` for `0 <= y <= 1`, without ever producing a subnormal in an FP
/// instruction: on Intel cores a subnormal (or underflowing) result of a vector
/// conversion takes a microcode assist of ~100+ cycles, which made the kernels
/// slower than libm on inputs whose `c^n` underflows. Below 2^-126 the f32 result is
/// the integer `round(y · 2^149)` (round to nearest even, as the conversion would),
/// read off the low bits of `y · 2^149 + 2^52`; that is the subnormal's bit pattern.
#[inline(always)]
fn round_to_f32(y: f64) -> f32 {
    const TWO_M126: f64 = f64::from_bits((1023 - 126) << 52);
    const TWO_P149: f64 = f64::from_bits((1023 + 149) << 52);
    const TWO_P52: f64 = f64::from_bits((1023 + 52) << 52);
    let tiny = y < TWO_M126;
    let normal = (if tiny { 1.0 } else { y }) as f32;
    let sub = f32::from_bits((y * TWO_P149 + TWO_P52).to_bits() as u32);
    if tiny {
        sub
    } else {
        normal
    }
}

/// `log2(e)` rounded to f64.
const LOG2_E: f64 = std::f64::consts::LOG2_E;

/// The log2 reduction interval starts at this f32 bit pattern (0.69921875); the 16
/// subintervals of `[OFF, 2·OFF)` are equal in bit space (ARM optimized-routines).
const LOG2_OFF: u32 = 0x3f33_0000;

/// `1/c_i` for the centre `c_i` of each subinterval, except 1.0 for the one holding
/// 1.0 (index 9), so that `r = z - 1` is exact there and `log2` keeps full relative
/// precision near `c = 1`. Generated with mpmath (200 bits), rounded to f64.
const LOG2_INVC: [f64; 16] = [
    1.3989071038251366,
    1.3403141361256545,
    1.2864321608040201,
    1.2367149758454106,
    1.1906976744186046,
    1.147982062780269,
    1.1082251082251082,
    1.0711297071129706,
    1.0364372469635628,
    1.0,
    0.9481481481481482,
    0.8951048951048951,
    0.847682119205298,
    0.8050314465408805,
    0.7664670658682635,
    0.7314285714285714,
];

/// `-log2(LOG2_INVC[i])` (of the stored f64 value), mpmath at 200 bits, rounded.
const LOG2_LOGC: [f64; 16] = [
    -0.4843001617159575,
    -0.4225711719642514,
    -0.3633753794563512,
    -0.3065130425006747,
    -0.2518071504105397,
    -0.19910010007969525,
    -0.14825095858394247,
    -0.09913319201925132,
    -0.05163276841532236,
    0.0,
    0.07681559705083084,
    0.1598713367783894,
    0.2384047393250789,
    0.3128829552843553,
    0.38370429247405213,
    0.4512111118323288,
];

/// Taylor coefficients of `log2(1 + r) = Σ (-1)^(j+1) r^j / (j ln 2)`, j = 1..=7.
/// With `|r| < 0.0297` the truncation error is below `r^8/(8 ln 2) < 1.2e-13`.
const LOG2_POLY: [f64; 7] = [
    std::f64::consts::LOG2_E,
    -0.7213475204444817,
    0.4808983469629878,
    -0.36067376022224085,
    0.28853900817779266,
    -0.2404491734814939,
    0.2060992915555662,
];

/// `log2(c)` for `c > 0` (f32, subnormals included), in f64, relative error < 4e-12.
/// Other inputs give garbage that the callers mask out.
#[inline(always)]
fn log2_f64(c: f32) -> f64 {
    // Subnormal c: scale by 2^23 (exact) and take 23 off the exponent afterwards.
    let ix = if c < f32::MIN_POSITIVE {
        (c * 8_388_608.0).to_bits().wrapping_sub(23 << 23)
    } else {
        c.to_bits()
    };
    // c = 2^k · z with z in [OFF, 2·OFF) and z in subinterval i.
    let tmp = ix.wrapping_sub(LOG2_OFF);
    let i = ((tmp >> 19) & 15) as usize;
    let top = tmp & 0xff80_0000;
    let z = f64::from(f32::from_bits(ix.wrapping_sub(top)));
    let k = f64::from((tmp as i32) >> 23);
    // r = z/c_i - 1 with one rounding, |r| < 0.0297.
    let r = z.mul_add(LOG2_INVC[i], -1.0);
    // log2(1 + r) = r·q(r), q of degree 6 by Estrin's scheme (short dependency chain).
    let p = LOG2_POLY;
    let r2 = r * r;
    let q01 = p[1].mul_add(r, p[0]);
    let q23 = p[3].mul_add(r, p[2]);
    let q45 = p[5].mul_add(r, p[4]);
    let r4 = r2 * r2;
    let q03 = q23.mul_add(r2, q01);
    let q46 = p[6].mul_add(r2, q45);
    let q = q46.mul_add(r4, q03);
    r.mul_add(q, LOG2_LOGC[i] + k)
}

/// `2^(i/16)` as f64 bits minus `i << 48`, so that adding `k << 48` for `k ≡ i (mod
/// 16)` also adds `k/16` to the exponent (ARM optimized-routines' `exp2f` trick).
/// mpmath at 200 bits, rounded to nearest.
const EXP2_TABLE: [u64; 16] = [
    0x3ff0000000000000,
    0x3fefb5586cf9890f,
    0x3fef72b83c7d517b,
    0x3fef387a6e756238,
    0x3fef06fe0a31b715,
    0x3feedea64c123422,
    0x3feebfdad5362a27,
    0x3feeab07dd485429,
    0x3feea09e667f3bcd,
    0x3feea11473eb0187,
    0x3feeace5422aa0db,
    0x3feec49182a3f090,
    0x3feee89f995ad3ad,
    0x3fef199bdd85529c,
    0x3fef5818dcfba487,
    0x3fefa4afa2a490da,
];

/// `(ln 2)^j / j!`, j = 1..=4: Taylor coefficients of `2^r`. With `|r| <= 1/32` the
/// truncation error is below `(r ln 2)^5 / 5! < 4.1e-11` (relative).
const EXP2_POLY: [f64; 4] = [
    std::f64::consts::LN_2,
    0.24022650695910072,
    0.05550410866482158,
    0.009618129107628477,
];

/// `2^x` for `x <= 0` (NaN and `x > 0` give garbage that callers mask out). Below
/// -160 the result rounds to 0 in f32 anyway, so `x` is clamped there to keep the
/// exponent arithmetic in range.
#[inline(always)]
fn exp2_f64(x: f64) -> f64 {
    let x = if x < -160.0 { -160.0 } else { x };
    // kd = round(16 x)/16: adding 1.5·2^48 leaves 4 fraction bits.
    const SHIFT: f64 = 1.5 * (1u64 << 48) as f64;
    let kd = x + SHIFT;
    let ki = kd.to_bits();
    let kd = kd - SHIFT;
    let r = x - kd;
    let s = f64::from_bits(EXP2_TABLE[(ki & 15) as usize].wrapping_add(ki << 48));
    let p = EXP2_POLY;
    let r2 = r * r;
    let q01 = p[1].mul_add(r, p[0]);
    let q23 = p[3].mul_add(r, p[2]);
    let q = q23.mul_add(r2, q01);
    s * r.mul_add(q, 1.0)
}

#[cfg(test)]
mod tests;
