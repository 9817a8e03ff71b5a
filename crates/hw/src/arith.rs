//! The cheaper circuits of the K_v design space: `a(n)` without ROM1 (a constant
//! multiplier, or two small tables and an adder) and truncated squarers, each with the
//! bit-exact model the Verilog emitter follows.
//!
//! `a(n) = (n+1)/(2^v+1)` is a constant multiple of `n + 1`; 1/17 = 0.000011110000111…
//! in binary (period 8), so a canonical-signed-digit (CSD) constant needs two non-zero
//! digits per 8 bits. The circuits here carry `guard` extra fraction bits and round once
//! at the end; [`CoefCircuit::new`] picks the fewest guard bits for which every word
//! equals ROM1's, so the three sources are the same function and share the widths
//! `glint hw sweep` finds.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use crate::fixed::requantize;
use crate::{CoefSource, HwError, Rom, Rounding};

/// Largest guard tried before giving up (a bug: 6 bits always suffice for the table,
/// `n_bits + 6` for the constant, since `(n+1)·2^f/(2^v+1)` is never closer than
/// `1/(2·(2^v+1))` to a rounding boundary unless it is one).
const MAX_GUARD: u32 = 24;

/// How `a(n)` is computed, with the constants of its circuit.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CoefCircuit {
    /// ROM1 (the words themselves).
    Rom,
    /// `a = rq((n+1)·k, frac + guard → frac)`.
    Const {
        /// The constant, `2^(frac+guard)/(2^v+1)` rounded (up for truncating ROMs).
        k: u128,
        /// Guard bits.
        guard: u32,
        /// Its canonical signed digits: `(shift, +1/-1)`, lowest first.
        csd: Vec<(u32, i8)>,
    },
    /// `a = rq(hi[n >> lo_bits] + lo[n mod 2^lo_bits], frac + guard → frac)`.
    Table {
        /// Address bits of the low table.
        lo_bits: u32,
        /// Guard bits.
        guard: u32,
        /// `round(h·2^lo_bits·2^(frac+guard)/(2^v+1))`.
        hi: Vec<u64>,
        /// `round((l+1)·2^(frac+guard)/(2^v+1))`.
        lo: Vec<u64>,
    },
}

/// Canonical signed digits of `k` (non-adjacent form), lowest first.
pub fn csd_digits(mut k: u128) -> Vec<(u32, i8)> {
    let mut out = Vec::new();
    let mut shift = 0u32;
    while k != 0 {
        if k & 1 == 1 {
            // k mod 4 = 3: digit -1 (k + 1 clears a run of ones); 1: digit +1.
            if k & 3 == 3 {
                out.push((shift, -1));
                k += 1;
            } else {
                out.push((shift, 1));
                k -= 1;
            }
        }
        k >>= 1;
        shift += 1;
    }
    out
}

/// `num / den` rounded as a truncating (up) or nearest ROM needs it.
fn div_round(num: u128, den: u128, up: bool) -> u128 {
    if up {
        num.div_ceil(den)
    } else {
        (2 * num + den) / (2 * den)
    }
}

impl CoefCircuit {
    /// The circuit of `source` for the energy-fit ROM `rom` (its words are the target),
    /// with the fewest guard bits that reproduce every word.
    pub fn new(source: CoefSource, rom: &Rom) -> Result<CoefCircuit, HwError> {
        let f = rom.frac_bits();
        let m = (1u128 << rom.v()) + 1;
        let up = rom.rounding() == Rounding::Truncate;
        let nb = rom.n_bits();
        for guard in 0..=MAX_GUARD {
            let scale = 1u128 << (f + guard);
            let c = match source {
                CoefSource::Rom => return Ok(CoefCircuit::Rom),
                CoefSource::Const => {
                    let k = div_round(scale, m, up);
                    CoefCircuit::Const {
                        k,
                        guard,
                        csd: csd_digits(k),
                    }
                }
                CoefSource::Table => {
                    let lo_bits = nb.div_ceil(2);
                    let hi = (0..1u128 << (nb - lo_bits))
                        .map(|h| div_round((h << lo_bits) * scale, m, up) as u64)
                        .collect();
                    let lo = (0..1u128 << lo_bits)
                        .map(|l| div_round((l + 1) * scale, m, up) as u64)
                        .collect();
                    CoefCircuit::Table {
                        lo_bits,
                        guard,
                        hi,
                        lo,
                    }
                }
            };
            let all_equal = rom
                .words()
                .iter()
                .enumerate()
                .all(|(n, &w)| c.word(n as u32, f, rom.rounding()) == w);
            if all_equal {
                return Ok(c);
            }
        }
        Err(HwError::Internal(format!(
            "no {} circuit with up to {MAX_GUARD} guard bits reproduces ROM1",
            source.name()
        )))
    }

    /// The word for address `n` (ROM1's fraction bits `frac`, its rounding).
    pub fn word(&self, n: u32, frac: u32, round: Rounding) -> u64 {
        match self {
            CoefCircuit::Rom => 0,
            CoefCircuit::Const { k, guard, .. } => {
                requantize((u128::from(n) + 1) * k, frac + guard, frac, round) as u64
            }
            CoefCircuit::Table {
                lo_bits,
                guard,
                hi,
                lo,
            } => {
                let s = u128::from(hi[(n >> lo_bits) as usize])
                    + u128::from(lo[(n & ((1 << lo_bits) - 1)) as usize]);
                requantize(s, frac + guard, frac, round) as u64
            }
        }
    }

    /// Guard bits (0 for ROM1).
    pub fn guard(&self) -> u32 {
        match self {
            CoefCircuit::Rom => 0,
            CoefCircuit::Const { guard, .. } | CoefCircuit::Table { guard, .. } => *guard,
        }
    }
}

/// Largest number of dropped columns of a truncated squarer (its model keeps a table
/// of `2^drop` entries).
pub const MAX_TRUNCATED_COLUMNS: u32 = 20;

/// A truncated squarer: `x^2` from the symmetric partial-product array
/// (`x^2 = Σ_i x_i 2^(2i) + Σ_{i<j} x_i x_j 2^(i+j+1)`) without the `drop` lowest
/// columns, plus the constant `comp` (the mean of what was dropped, over every `x`),
/// then rounded like every stage. The dropped bits depend only on `x mod 2^drop`
/// (a product `x_i x_j` lands in column `i+j+1 < drop` only if `i, j < drop`), so the
/// model subtracts `low[x mod 2^drop]`. Error before the rounding: `|low - comp|`,
/// below `(drop/2 + 1)·2^drop` (column `c` holds at most `c/2 + 1` products), i.e.
/// about `(drop/2 + 1)·2^-guard` of the stage's output LSB; the exploration checks
/// every truncated unit exhaustively.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TruncatedSquare {
    /// Columns dropped.
    pub drop: u32,
    /// Compensation constant added at column 0.
    pub comp: u64,
    low: Arc<Vec<u64>>,
}

/// The dropped part for every `x mod 2^drop`, and its mean rounded (the compensation):
/// they depend on `drop` only, so each is built once per process.
fn low_table(drop: u32) -> (Arc<Vec<u64>>, u64) {
    type Tables = HashMap<u32, (Arc<Vec<u64>>, u64)>;
    static CACHE: OnceLock<Mutex<Tables>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    if let Some(t) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&drop) {
        return t.clone();
    }
    // low(x) = low(x without its top bit b) + what bit b adds: x_b 2^(2b) and
    // x_j x_b 2^(j+b+1) for j < b, each where its column is below `drop`.
    let mut low = vec![0u64; 1 << drop];
    for x in 1..low.len() {
        let b = 63 - (x as u64).leading_zeros();
        let rest = x ^ (1 << b);
        let mut add = if 2 * b < drop { 1u64 << (2 * b) } else { 0 };
        for j in 0..b {
            if rest >> j & 1 == 1 && j + b + 1 < drop {
                add += 1 << (j + b + 1);
            }
        }
        low[x] = low[rest] + add;
    }
    let sum: u128 = low.iter().map(|&l| u128::from(l)).sum();
    let count = low.len() as u128;
    let comp = ((2 * sum + count) / (2 * count)) as u64;
    let t = (Arc::new(low), comp);
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(drop, t.clone());
    t
}

impl TruncatedSquare {
    /// The squarer of a `w`-bit input whose product has `2·in_frac` fraction bits and
    /// is rounded to `out_frac`, keeping `guard` columns below the output LSB. `None`
    /// if nothing would be dropped.
    pub fn new(in_frac: u32, out_frac: u32, guard: u32) -> Option<TruncatedSquare> {
        let drop = (2 * in_frac)
            .saturating_sub(out_frac + guard)
            .min(MAX_TRUNCATED_COLUMNS);
        if drop == 0 {
            return None;
        }
        let (low, comp) = low_table(drop);
        Some(TruncatedSquare { drop, comp, low })
    }

    /// The truncated, compensated square of `x` (before the stage's rounding).
    #[inline]
    pub fn square(&self, x: u64) -> u128 {
        let low = self.low[(x & ((1 << self.drop) - 1)) as usize];
        u128::from(x) * u128::from(x) - u128::from(low) + u128::from(self.comp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Coefficients;

    #[test]
    fn csd_digits_rebuild_the_constant() {
        for k in [1u128, 3, 7, 15, 0x0F0F, 0x1E1E_1E1E, 12345, (1 << 40) / 17] {
            let d = csd_digits(k);
            let back: i128 = d.iter().map(|&(s, g)| i128::from(g) << s).sum();
            assert_eq!(back, k as i128, "{k}");
            // Non-adjacent: no two digits in neighbouring positions.
            assert!(d.windows(2).all(|w| w[1].0 > w[0].0 + 1), "{k}: {d:?}");
        }
        // 1/17 = 0.00001111 00001111...: 15·2^k per byte is 16 - 1, two digits.
        assert_eq!(csd_digits(0x0F0F).len(), 4);
    }

    #[test]
    fn circuits_reproduce_rom1() {
        for (v, f, round) in [
            (4, 12, Rounding::Nearest),
            (3, 9, Rounding::Nearest),
            (5, 10, Rounding::Truncate),
            (4, 28, Rounding::Nearest),
        ] {
            let rom = Rom::new(Coefficients::EnergyFit, v, 10, 7 + f, round).unwrap();
            for src in [CoefSource::Const, CoefSource::Table] {
                let c = CoefCircuit::new(src, &rom).unwrap();
                for (n, &w) in rom.words().iter().enumerate() {
                    assert_eq!(
                        c.word(n as u32, rom.frac_bits(), round),
                        w,
                        "{src:?} v={v} n={n}"
                    );
                }
            }
        }
    }

    #[test]
    fn truncated_square_is_the_square_less_its_low_columns() {
        let t = TruncatedSquare::new(8, 6, 2).unwrap();
        assert_eq!(t.drop, 8);
        for x in 0..=256u64 {
            // By hand, over ordered pairs: x_i x_j (i != j) sits in the symmetric
            // array once, doubled, at column i+j+1; x_i x_i at column 2i.
            let mut low = 0u64;
            for i in 0..9 {
                for j in 0..9 {
                    let (bi, bj) = (x >> i & 1, x >> j & 1);
                    let col = if i == j { 2 * i } else { i + j + 1 };
                    if col < 8 {
                        low += (bi * bj) << (i + j);
                    }
                }
            }
            let exact = u128::from(x * x);
            assert_eq!(
                t.square(x),
                exact - u128::from(low) + u128::from(t.comp),
                "{x}"
            );
            // Column c < 8 holds at most c/2 + 1 partial products.
            let bound = (8u128 / 2 + 1) << 8;
            assert!((t.square(x) as i128 - exact as i128).unsigned_abs() < bound);
        }
    }
}
