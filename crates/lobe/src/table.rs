//! A lobe given as a table over a quantised cosine: the value for every fixed-point
//! code of `cos γ`, as a hardware unit with a `Q1.f` cosine input computes it.
//!
//! The code of a cosine `c` is `round(c · 2^f)` with ties away from zero (the rounding
//! of `glint_hw::Unit::cos_code`), `c` first clamped to `[-1, 1]`; NaN gives 0, like
//! [`Lobe::eval`](crate::Lobe::eval). Whoever builds the table (e.g. `glint_hw`'s
//! `Unit::cos_table`) decides what each code's value is; this module only looks
//! values up, fast.
//!
//! Rounding is computed as `t = trunc(x)`, `t ± 1` where the exact remainder `x - t` is
//! at least one half: `x = c · 2^f` is exact (a power-of-two scale), and so is `x - t`
//! (Sterbenz), so every path rounds exactly as `f64::round` does, with no `+0.5`
//! double rounding.

use std::fmt;
use std::sync::Arc;

use crate::{KernelPath, Lobe};

/// Largest number of fraction bits of a table's cosine code: `2^(f+1) + 1` codes, so
/// `f = 20` is at most 2,097,153 entries (8 MiB of f32). glint-hw's default unit has
/// `f = 14` (Q1.14); wider inputs than Q1.20 gain nothing in an f32 renderer whose
/// cosines near 1 carry 24 significant bits.
pub const MAX_TABLE_FRAC_BITS: u32 = 20;

/// Why a [`CosTable`] could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TableError {
    /// The cosine code has more fraction bits than [`MAX_TABLE_FRAC_BITS`].
    #[error("a cosine table with {0} fraction bits has 2^({0}+1) + 1 entries; at most {MAX_TABLE_FRAC_BITS} fraction bits are supported")]
    FracBits(u32),
    /// A value is not a lobe value (finite, in `[0, 1]`).
    #[error("cosine table value {value} at code {code} is not in [0, 1]")]
    Value {
        /// The cosine code.
        code: i32,
        /// Its value.
        value: f32,
    },
}

/// A lobe as a table: one value per cosine code `-2^f ..= 2^f` (`c = code / 2^f`).
///
/// The leading run of equal values (the zeros of a narrow lobe, usually most of the
/// table) is stored once, so a table for a large `n` fits the L1 cache.
///
/// ```
/// use glint_lobe::CosTable;
///
/// // Q1.2 codes -4 ..= 4 (c = -1, -0.75, ..., 1); the value is c^2 for c > 0.
/// let t = CosTable::from_fn(2, |code| {
///     let c = code as f32 / 4.0;
///     if c > 0.0 { c * c } else { 0.0 }
/// })
/// .unwrap();
/// assert_eq!(t.eval(1.0), 1.0);
/// assert_eq!(t.eval(0.8), 0.75 * 0.75); // 3.2 rounds to code 3
/// assert_eq!(t.eval(0.875), 1.0); // 3.5 rounds away from zero, to 4
/// assert_eq!(t.eval(-0.3), 0.0);
/// assert_eq!(t.eval(f32::NAN), 0.0);
/// ```
#[derive(Clone, PartialEq)]
pub struct CosTable {
    frac_bits: u32,
    /// `2^frac_bits`.
    scale: f32,
    /// The code of `values[0]`; every code below it has that value too.
    lo: i32,
    /// Values for codes `lo ..= 2^frac_bits`.
    values: Vec<f32>,
    /// The shininess `n` and `v` the table was made for, if its builder said so: a
    /// [`SpecularSampler`](crate::SpecularSampler) samples the table as K_v(n).
    shininess: Option<(f64, u32)>,
}

impl fmt::Debug for CosTable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CosTable")
            .field("frac_bits", &self.frac_bits)
            .field("lo", &self.lo)
            .field("stored", &self.values.len())
            .field("shininess", &self.shininess)
            .finish()
    }
}

impl CosTable {
    /// Builds the table of `value(code)` for every code `-2^frac_bits ..= 2^frac_bits`.
    ///
    /// Errors if `frac_bits` exceeds [`MAX_TABLE_FRAC_BITS`] or a value is not finite
    /// in `[0, 1]`.
    pub fn from_fn(
        frac_bits: u32,
        mut value: impl FnMut(i32) -> f32,
    ) -> Result<CosTable, TableError> {
        if frac_bits > MAX_TABLE_FRAC_BITS {
            return Err(TableError::FracBits(frac_bits));
        }
        let one = 1i32 << frac_bits;
        let mut values = Vec::with_capacity(2 * one as usize + 1);
        for code in -one..=one {
            let v = value(code);
            if !(0.0..=1.0).contains(&v) {
                return Err(TableError::Value { code, value: v });
            }
            values.push(v);
        }
        // Keep one entry of the leading run of equal values.
        let run = values.iter().take_while(|&&v| v == values[0]).count();
        values.drain(..run - 1);
        values.shrink_to_fit();
        Ok(CosTable {
            frac_bits,
            scale: one as f32,
            lo: one - (values.len() as i32 - 1),
            values,
            shininess: None,
        })
    }

    /// Records the shininess `n` and `v` the table was made for (a hardware unit's
    /// table of K_v(n), say), so that [`Specular::sampler`] can sample it as K_v(n):
    /// a table has no closed-form inverse CDF of its own. The values are checked when
    /// a sampler is built.
    pub fn with_shininess(mut self, n: f64, v: u32) -> CosTable {
        self.shininess = Some((n, v));
        self
    }

    /// The shininess `n` and `v` given by [`with_shininess`](Self::with_shininess).
    pub fn shininess(&self) -> Option<(f64, u32)> {
        self.shininess
    }

    /// The smallest code whose value is not 0 (`None` for an all-zero table): the
    /// widest angle the table lights.
    pub fn first_nonzero_code(&self) -> Option<i32> {
        let i = self.values.iter().position(|&v| v != 0.0)?;
        // A nonzero leading run stands for every code below `lo` too.
        Some(if i == 0 {
            -(1i32 << self.frac_bits)
        } else {
            self.lo + i as i32
        })
    }

    /// Fraction bits `f` of the cosine code.
    pub fn frac_bits(&self) -> u32 {
        self.frac_bits
    }

    /// The code of `c`: `round(c · 2^f)` (ties away from zero) after clamping `c` to
    /// `[-1, 1]`; `None` for NaN.
    #[inline]
    pub fn code(&self, c: f32) -> Option<i32> {
        if c.is_nan() {
            return None;
        }
        let x = c.clamp(-1.0, 1.0) * self.scale;
        let t = x.trunc();
        let r = x - t;
        // |x| <= 2^20, so t fits an i32 exactly.
        Some(t as i32 + i32::from(r >= 0.5) - i32::from(r <= -0.5))
    }

    /// The value at a cosine code; codes outside `-2^f ..= 2^f` take the nearest end's.
    #[inline]
    pub fn value(&self, code: i32) -> f32 {
        let i = code.saturating_sub(self.lo).max(0) as usize;
        self.values[i.min(self.values.len() - 1)]
    }

    /// The value at `c = cos γ`: the table entry of its code; NaN gives 0.
    #[inline]
    pub fn eval(&self, c: f32) -> f32 {
        match self.code(c) {
            Some(code) => self.value(code),
            None => 0.0,
        }
    }

    /// [`eval`](Self::eval) for every element of `cos`, on the best [`KernelPath`]:
    /// bit-identical to `eval` on every path.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn eval_slice(&self, cos: &[f32], out: &mut [f32]) {
        assert_eq!(cos.len(), out.len(), "eval_slice: lengths differ");
        self.run(KernelPath::best(), cos, out);
    }

    /// [`eval_slice`](Self::eval_slice) on a chosen path (for tests and benchmarks).
    pub fn eval_slice_with(
        &self,
        path: KernelPath,
        cos: &[f32],
        out: &mut [f32],
    ) -> Result<(), crate::BatchError> {
        if cos.len() != out.len() {
            return Err(crate::BatchError::LengthMismatch {
                input: cos.len(),
                output: out.len(),
            });
        }
        if !path.is_supported() {
            return Err(crate::BatchError::Unsupported(path));
        }
        self.run(path, cos, out);
        Ok(())
    }

    fn run(&self, path: KernelPath, cos: &[f32], out: &mut [f32]) {
        match path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: callers pass only supported paths, and both vector paths have
            // AVX2 (`KernelPath::is_supported`).
            KernelPath::Avx2 | KernelPath::Avx512 => unsafe { x86::eval_avx2(self, cos, out) },
            _ => self.eval_scalar(cos, out),
        }
    }

    fn eval_scalar(&self, cos: &[f32], out: &mut [f32]) {
        for (o, &c) in out.iter_mut().zip(cos) {
            *o = self.eval(c);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::CosTable;

    /// [`CosTable::eval`] eight lanes at a time: the same clamp, the same exact
    /// rounding, then one gather (the table is small: for n >= ~40 the stored part is
    /// a few thousand entries, in L1).
    ///
    /// # Safety
    /// The CPU must support AVX2; `cos` and `out` must have the same length.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn eval_avx2(t: &CosTable, cos: &[f32], out: &mut [f32]) {
        debug_assert_eq!(cos.len(), out.len());
        let len = cos.len();
        let body = len - len % 8;
        let scale = _mm256_set1_ps(t.scale);
        let (neg1, pos1) = (_mm256_set1_ps(-1.0), _mm256_set1_ps(1.0));
        let (half, neg_half) = (_mm256_set1_ps(0.5), _mm256_set1_ps(-0.5));
        let lo = _mm256_set1_epi32(t.lo);
        let last = _mm256_set1_epi32(t.values.len() as i32 - 1);
        let zero = _mm256_setzero_si256();
        let base = t.values.as_ptr();
        let mut i = 0;
        while i < body {
            // SAFETY: i + 8 <= body <= len for both slices.
            let c = unsafe { _mm256_loadu_ps(cos.as_ptr().add(i)) };
            let ordered = _mm256_cmp_ps::<_CMP_ORD_Q>(c, c);
            // NaN lanes become -1 here (MAXPS returns its second operand); masked below.
            let x = _mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(c, neg1), pos1), scale);
            let tr = _mm256_cvttps_epi32(x);
            let r = _mm256_sub_ps(x, _mm256_cvtepi32_ps(tr));
            // Compare masks are -1 (all ones) where true: subtract to add 1.
            let up = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GE_OQ>(r, half));
            let down = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OQ>(r, neg_half));
            let code = _mm256_add_epi32(_mm256_sub_epi32(tr, up), down);
            let idx = _mm256_min_epi32(_mm256_max_epi32(_mm256_sub_epi32(code, lo), zero), last);
            // SAFETY: every index is clamped to 0 ..= values.len() - 1.
            let v = unsafe { _mm256_i32gather_ps::<4>(base, idx) };
            // SAFETY: i + 8 <= body <= len, and `out` has the length of `cos`.
            unsafe { _mm256_storeu_ps(out.as_mut_ptr().add(i), _mm256_and_ps(v, ordered)) };
            i += 8;
        }
        t.eval_scalar(&cos[body..], &mut out[body..]);
    }
}

/// The specular term of a renderer: a closed-form [`Lobe`] or a [`CosTable`] (e.g. the
/// output of a fixed-point hardware unit for every cosine code).
///
/// ```
/// use std::sync::Arc;
/// use glint_lobe::{CosTable, Lobe, LobeKind, Specular};
///
/// let k = Specular::from(Lobe::<f32>::new(LobeKind::EnergyFit, 100.0, 4).unwrap());
/// let lobe = Lobe::<f32>::new(LobeKind::EnergyFit, 100.0, 4).unwrap();
/// let table = Specular::Table(Arc::new(
///     CosTable::from_fn(14, |code| lobe.eval(code as f32 / 16384.0)).unwrap(),
/// ));
/// assert_eq!(k.eval(1.0), 1.0);
/// assert_eq!(table.eval(1.0), 1.0);
/// assert!((k.eval(0.99) - table.eval(0.99)).abs() < 1e-3);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum Specular {
    /// A closed-form lobe, evaluated in f32.
    Lobe(Lobe<f32>),
    /// A table over the quantised cosine (shared: one table serves every thread).
    Table(Arc<CosTable>),
}

impl From<Lobe<f32>> for Specular {
    fn from(lobe: Lobe<f32>) -> Self {
        Specular::Lobe(lobe)
    }
}

impl From<CosTable> for Specular {
    fn from(table: CosTable) -> Self {
        Specular::Table(Arc::new(table))
    }
}

impl Specular {
    /// The value at `c = cos γ`, in `[0, 1]`; NaN gives 0.
    #[inline]
    pub fn eval(&self, c: f32) -> f32 {
        match self {
            Specular::Lobe(l) => l.eval(c),
            Specular::Table(t) => t.eval(c),
        }
    }

    /// [`eval`](Self::eval) for every element, on the best SIMD path
    /// ([`Lobe::eval_slice`], [`CosTable::eval_slice`]).
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn eval_slice(&self, cos: &[f32], out: &mut [f32]) {
        match self {
            Specular::Lobe(l) => l.eval_slice(cos, out),
            Specular::Table(t) => t.eval_slice(cos, out),
        }
    }

    /// A sampler for this specular term: the lobe's own (see
    /// [`LobeSampler`](crate::LobeSampler)), or for a table, K_v with the table's
    /// [`shininess`](CosTable::shininess) while `eval` stays the table's (see
    /// [`SpecularSampler`](crate::SpecularSampler)).
    ///
    /// Errors if a table carries no shininess, or an invalid one.
    pub fn sampler(&self) -> Result<crate::SpecularSampler, crate::LobeError> {
        crate::SpecularSampler::new(self)
    }

    /// The closed-form lobe, if it is one.
    pub fn lobe(&self) -> Option<&Lobe<f32>> {
        match self {
            Specular::Lobe(l) => Some(l),
            Specular::Table(_) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table whose value encodes its code, so a wrong lookup is visible:
    /// `(code + 2^f) / 2^(f+1)` for code > -2^f/2, else 0.
    fn ramp(f: u32) -> CosTable {
        let one = 1i32 << f;
        CosTable::from_fn(f, |code| {
            if code > -one / 2 {
                (code + one) as f32 / (2 * one) as f32
            } else {
                0.0
            }
        })
        .unwrap()
    }

    /// The code by the definition, in f64: round half away from zero.
    fn code_f64(c: f32, f: u32) -> i32 {
        (f64::from(c.clamp(-1.0, 1.0)) * f64::from(1u32 << f)).round() as i32
    }

    #[test]
    fn codes_round_half_away_from_zero_like_f64_round() {
        for f in [0, 1, 2, 7, 14, 20] {
            let t = ramp(f);
            let one = 1i32 << f;
            // Every half-code point and its f32 neighbours, both signs.
            for k in -2 * one..=2 * one {
                let x = k as f32 / (2 * one) as f32;
                for c in [x, x.next_up(), x.next_down()] {
                    assert_eq!(t.code(c), Some(code_f64(c, f)), "f = {f}, c = {c}");
                }
            }
            assert_eq!(t.code(2.5), Some(one));
            assert_eq!(t.code(-7.0), Some(-one));
            assert_eq!(t.code(f32::NAN), None);
        }
    }

    #[test]
    fn lookup_returns_each_codes_value() {
        let f = 6;
        let one = 1i32 << f;
        let t = ramp(f);
        for code in -one..=one {
            let want = if code > -one / 2 {
                (code + one) as f32 / (2 * one) as f32
            } else {
                0.0
            };
            assert_eq!(t.value(code), want, "code {code}");
            assert_eq!(t.eval(code as f32 / one as f32), want, "code {code}");
        }
        // The leading zeros are stored once.
        assert_eq!(t.values.len() as i32, one + one / 2 + 1);
        // The first lit code: -one/2 + 1.
        assert_eq!(t.first_nonzero_code(), Some(-one / 2 + 1));
        assert_eq!(
            CosTable::from_fn(3, |_| 0.5).unwrap().first_nonzero_code(),
            Some(-8)
        );
        assert_eq!(
            CosTable::from_fn(3, |_| 0.0).unwrap().first_nonzero_code(),
            None
        );
        assert_eq!(t.shininess(), None);
        assert_eq!(t.with_shininess(40.0, 4).shininess(), Some((40.0, 4)));
    }

    #[test]
    fn every_path_equals_eval() {
        let t = ramp(14);
        let mut cos: Vec<f32> = (0..20_003)
            .map(|i| -1.1 + 2.2 * i as f32 / 20_000.0)
            .collect();
        cos.extend([f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.0, 0.0, 1.0]);
        let want: Vec<f32> = cos.iter().map(|&c| t.eval(c)).collect();
        for path in KernelPath::supported() {
            let mut out = vec![-1.0; cos.len()];
            t.eval_slice_with(path, &cos, &mut out).unwrap();
            for (i, (&o, &w)) in out.iter().zip(&want).enumerate() {
                assert_eq!(o.to_bits(), w.to_bits(), "{path} at c = {}", cos[i]);
            }
        }
    }

    #[test]
    fn bad_tables_are_rejected() {
        assert_eq!(
            CosTable::from_fn(21, |_| 0.0),
            Err(TableError::FracBits(21))
        );
        assert_eq!(
            CosTable::from_fn(2, |code| if code == 1 { 1.5 } else { 0.0 }),
            Err(TableError::Value {
                code: 1,
                value: 1.5
            })
        );
        assert!(CosTable::from_fn(2, |_| f32::NAN).is_err());
    }

    #[test]
    fn specular_dispatches_to_its_lobe() {
        let lobe = Lobe::<f32>::new(crate::LobeKind::EnergyFit, 30.0, 4).unwrap();
        let s = Specular::from(lobe);
        let cos = [0.9f32, 0.95, 1.0, f32::NAN];
        let mut out = [0.0; 4];
        s.eval_slice(&cos, &mut out);
        assert_eq!(out, cos.map(|c| lobe.eval(c)));
        let t = Specular::from(ramp(3));
        t.eval_slice(&cos, &mut out);
        // 0.9 · 8 = 7.2 -> code 7 -> 15/16; 0.95 · 8 = 7.6 -> 8 -> 1.
        assert_eq!(out, [15.0 / 16.0, 1.0, 1.0, 0.0]);
    }
}
