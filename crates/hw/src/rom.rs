//! ROM1: the coefficient `a(n)` for every shininess `n`, quantised to the ROM's word.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::sync::{Arc, Mutex, OnceLock};

use rayon::prelude::*;

use crate::config::{check_register, MAX_N_BITS, MAX_V};
use crate::{Coefficients, HwError, Rounding};

/// The contents of ROM1: one unsigned UQi.f word per address `n`.
#[derive(Clone, Debug, PartialEq)]
pub struct Rom {
    coefficients: Coefficients,
    v: u32,
    n_bits: u32,
    int_bits: u32,
    frac_bits: u32,
    round: Rounding,
    /// The real coefficients `a(n)` the words approximate.
    exact: Arc<Vec<f64>>,
    words: Vec<u64>,
}

/// Minimax coefficients already computed, by `(v, n_bits)`.
type MinimaxCache = HashMap<(u32, u32), Arc<Vec<f64>>>;

/// The real (f64) coefficients `a(n)`, `n = 0 .. 2^n_bits`.
///
/// The energy fit is `(n+1)/(2^v+1)`; the minimax ones come from
/// [`glint_lobe::minimax_coefficient`] (a few ms each, so they are computed in parallel
/// and cached for the life of the process).
pub fn real_coefficients(
    kind: Coefficients,
    v: u32,
    n_bits: u32,
) -> Result<Arc<Vec<f64>>, HwError> {
    if v > MAX_V {
        return Err(HwError::InvalidV(v));
    }
    if n_bits == 0 {
        return Err(HwError::ZeroWidth { field: "n_bits" });
    }
    if n_bits > MAX_N_BITS {
        return Err(HwError::InvalidNBits(n_bits));
    }
    let count = 1usize << n_bits;
    let m1 = f64::from((1u32 << v) + 1);
    match kind {
        Coefficients::EnergyFit => Ok(Arc::new(
            (0..count).map(|n| (n as f64 + 1.0) / m1).collect(),
        )),
        Coefficients::Minimax => {
            static CACHE: OnceLock<Mutex<MinimaxCache>> = OnceLock::new();
            let cache = CACHE.get_or_init(Default::default);
            if let Some(found) = cache
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .get(&(v, n_bits))
            {
                return Ok(found.clone());
            }
            let values: Arc<Vec<f64>> = Arc::new(
                (0..count)
                    .into_par_iter()
                    .map(|n| glint_lobe::minimax_coefficient(n as f64, v))
                    .collect(),
            );
            cache
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .insert((v, n_bits), values.clone());
            Ok(values)
        }
    }
}

/// Integer bits of a ROM1 word: the fewest that hold the largest real coefficient.
pub fn coefficient_int_bits(kind: Coefficients, v: u32, n_bits: u32) -> Result<u32, HwError> {
    let exact = real_coefficients(kind, v, n_bits)?;
    Ok(integer_bits(exact.iter().copied().fold(0.0, f64::max)))
}

/// Number of bits of `floor(x)` (0 for `x < 1`).
fn integer_bits(x: f64) -> u32 {
    let i = x.floor();
    if i < 1.0 {
        0
    } else {
        64 - (i as u64).leading_zeros()
    }
}

impl Rom {
    /// Builds ROM1 for `2^n_bits` addresses with `coef_bits`-wide words.
    ///
    /// The integer width `i` is the fewest bits holding the largest real coefficient;
    /// the fraction width is `coef_bits - i`. A coefficient that rounds up past the
    /// largest word saturates to it. Energy-fit words are computed exactly with integer
    /// division (`round((n+1)·2^f / (2^v+1))`); minimax words quantise the f64
    /// coefficient exactly (scaling by `2^f` is exact in f64).
    pub fn new(
        coefficients: Coefficients,
        v: u32,
        n_bits: u32,
        coef_bits: u32,
        round: Rounding,
    ) -> Result<Rom, HwError> {
        if coef_bits == 0 {
            return Err(HwError::ZeroWidth { field: "coef_bits" });
        }
        check_register("ROM1 word = coef_bits", coef_bits.into())?;
        let exact = real_coefficients(coefficients, v, n_bits)?;
        let max = exact.iter().copied().fold(0.0, f64::max);
        let int_bits = integer_bits(max);
        if coef_bits < int_bits {
            return Err(HwError::TooNarrow {
                field: "coef_bits",
                bits: coef_bits,
                reason: "the largest ROM1 coefficient needs more integer bits",
            });
        }
        let frac_bits = coef_bits - int_bits;
        let top: u128 = if coef_bits == 64 {
            u64::MAX as u128
        } else {
            (1u128 << coef_bits) - 1
        };
        let m1 = (1u128 << v) + 1;
        let words = exact
            .iter()
            .enumerate()
            .map(|(n, &a)| {
                let q: u128 = match coefficients {
                    Coefficients::EnergyFit => {
                        let num = (n as u128 + 1) << frac_bits;
                        match round {
                            Rounding::Truncate => num / m1,
                            Rounding::Nearest => (2 * num + m1) / (2 * m1),
                        }
                    }
                    Coefficients::Minimax => {
                        let scaled = a * 2f64.powi(frac_bits as i32);
                        let r = match round {
                            Rounding::Truncate => scaled.floor(),
                            Rounding::Nearest => (scaled + 0.5).floor(),
                        };
                        // f64 -> u128 saturates; the clamp below does the rest.
                        r.max(0.0) as u128
                    }
                };
                q.min(top) as u64
            })
            .collect();
        Ok(Rom {
            coefficients,
            v,
            n_bits,
            int_bits,
            frac_bits,
            round,
            exact,
            words,
        })
    }

    /// Which coefficients the ROM holds.
    pub fn coefficients(&self) -> Coefficients {
        self.coefficients
    }

    /// The `v` the coefficients were fitted for.
    pub fn v(&self) -> u32 {
        self.v
    }

    /// Address width.
    pub fn n_bits(&self) -> u32 {
        self.n_bits
    }

    /// Integer bits of a word (UQi.f).
    pub fn int_bits(&self) -> u32 {
        self.int_bits
    }

    /// Fraction bits of a word (UQi.f).
    pub fn frac_bits(&self) -> u32 {
        self.frac_bits
    }

    /// Word width `i + f`.
    pub fn word_bits(&self) -> u32 {
        self.int_bits + self.frac_bits
    }

    /// How the words were rounded.
    pub fn rounding(&self) -> Rounding {
        self.round
    }

    /// All words, address `n` at index `n`.
    pub fn words(&self) -> &[u64] {
        &self.words
    }

    /// The real coefficients the words approximate, index `n`.
    pub fn exact(&self) -> &[f64] {
        &self.exact
    }

    /// The ROM in Verilog `$readmemh` format: `//` comment lines describing the
    /// contents, then one hexadecimal word per line, address 0 first, each
    /// `ceil(word_bits / 4)` digits wide.
    pub fn to_readmemh(&self) -> String {
        let digits = self.word_bits().div_ceil(4).max(1) as usize;
        let m = 1u64 << self.v;
        let formula = match self.coefficients {
            Coefficients::EnergyFit => format!("a(n) = (n+1)/(2^v+1) = (n+1)/{}", m + 1),
            Coefficients::Minimax => {
                "a(n) = minimax coefficient (min max |a-lobe - cos^n| on [0,1])".to_string()
            }
        };
        let mut out = String::with_capacity(self.words.len() * (digits + 1) + 512);
        let _ = writeln!(
            out,
            "// glint ROM1 ({}): {formula}, v = {}",
            self.coefficients, self.v
        );
        let _ = writeln!(
            out,
            "// {} words of {} bits, unsigned UQ{}.{} (value = word / 2^{}), rounding {}",
            self.words.len(),
            self.word_bits(),
            self.int_bits,
            self.frac_bits,
            self.frac_bits,
            self.round
        );
        let _ = writeln!(
            out,
            "// address = n (0..{}), load with $readmemh",
            self.words.len() - 1
        );
        for w in &self.words {
            let _ = writeln!(out, "{w:0digits$x}");
        }
        out
    }
}
