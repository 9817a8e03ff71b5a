//! The validated unit and its functional (untimed) model.

use crate::arith::{CoefCircuit, TruncatedSquare};
use crate::config::check_register;
use crate::fixed::requantize;
use crate::{Config, HwError, Rom, Squarer};

/// The fixed-point format of every stage, derived from a [`Config`] and its ROM.
/// `*_frac` are fraction bits; all values except `cos` and the Sm2 difference are
/// unsigned.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Formats {
    /// RG1: signed Q1.`cos_frac`, `cos_frac + 2` bits.
    pub cos_frac: u32,
    /// RG2 / ROM1 address: unsigned integer, `n_bits` bits.
    pub n_bits: u32,
    /// ROM1 word: UQ`coef_int`.`coef_frac`.
    pub coef_int: u32,
    /// ROM1 word fraction bits.
    pub coef_frac: u32,
    /// Sm1 output `t = 1 - cos`, saturated at 0: UQ2.`cos_frac` (t <= 3).
    pub t_frac: u32,
    /// MUL output `p = a·t` rounded: UQ(`coef_int + 2`).`mul_frac`.
    pub mul_frac: u32,
    /// Integer bits of the MUL output.
    pub mul_int: u32,
    /// BMUL stage `k` output: UQ1.`square_frac[k]`.
    pub square_frac: Vec<u32>,
    /// The lobe entering the RGB multipliers: UQ1.`lobe_frac` (the last squaring's, or
    /// the base's when `v = 0`).
    pub lobe_frac: u32,
    /// `k_s·I` inputs and outputs: unsigned `out_bits`-bit integers.
    pub out_bits: u32,
}

impl Formats {
    /// Width in bits of the MUL output register.
    pub fn mul_bits(&self) -> u32 {
        self.mul_int + self.mul_frac
    }

    /// Width in bits of the signed Sm2 result (one more than MUL's).
    pub fn sm2_bits(&self) -> u32 {
        self.mul_bits() + 1
    }
}

/// One input word: the three input registers RG1 (`cos`), RG2 (`n`) and the `k_s·I`
/// registers of the colour channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Input {
    /// `cos γ` as a signed Q1.f code (`1.0 = 2^f`).
    pub cos: i64,
    /// Shininess exponent, `0 .. 2^n_bits`.
    pub n: u32,
    /// `k_s·I_R`, `k_s·I_G`, `k_s·I_B` as unsigned `out_bits` codes (full scale
    /// `2^out_bits - 1`).
    pub ks: [u64; 3],
}

/// One output word: the R, G, B specular codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Output {
    /// `round(lobe · k_s·I)` per channel, unsigned `out_bits` codes.
    pub rgb: [u64; 3],
}

/// A validated configuration with its ROM: the unit, ready to evaluate.
#[derive(Clone, Debug)]
pub struct Unit {
    config: Config,
    rom: Rom,
    formats: Formats,
    coef: CoefCircuit,
    truncated: Vec<Option<TruncatedSquare>>,
}

impl Unit {
    /// Validates `config` and builds ROM1.
    ///
    /// Errors: any width of 0, `v > 10`, `n_bits > 13`, a `square_frac` list whose
    /// length is not `v`, a ROM word too narrow for the coefficients' integer part, or
    /// any register wider than 64 bits.
    pub fn new(config: Config) -> Result<Unit, HwError> {
        config.validate()?;
        let rom = Rom::new(
            config.coefficients,
            config.v,
            config.n_bits,
            config.coef_bits,
            config.coef_round,
        )?;
        // validate() bounded every field; the sums are formed in u64 all the same.
        let mul_int = rom.int_bits() + 2;
        let mul_bits = u64::from(mul_int) + u64::from(config.mul_frac);
        check_register("MUL output = coef integer bits + 2 + mul_frac", mul_bits)?;
        check_register("Sm2 = MUL width + 1 (signed)", mul_bits + 1)?;
        let formats = Formats {
            cos_frac: config.cos_frac(),
            n_bits: config.n_bits,
            coef_int: rom.int_bits(),
            coef_frac: rom.frac_bits(),
            t_frac: config.cos_frac(),
            mul_frac: config.mul_frac,
            mul_int,
            square_frac: config.square_frac.clone(),
            lobe_frac: *config.square_frac.last().unwrap_or(&config.mul_frac),
            out_bits: config.out_bits,
        };
        // Every a(n) source gives ROM1's words (checked here), so the models below
        // read the words; the circuit's constants are for the Verilog.
        let coef = CoefCircuit::new(config.coef_source, &rom)?;
        let mut truncated = Vec::with_capacity(config.square_frac.len());
        let mut prev = config.mul_frac;
        for &next in &config.square_frac {
            truncated.push(match config.squarer {
                Squarer::Truncated => TruncatedSquare::new(prev, next, config.square_guard),
                _ => None,
            });
            prev = next;
        }
        Ok(Unit {
            config,
            rom,
            formats,
            coef,
            truncated,
        })
    }

    /// The circuit that forms `a(n)` (its words equal ROM1's).
    pub fn coef_circuit(&self) -> &CoefCircuit {
        &self.coef
    }

    /// BMUL stage `k`'s truncated squarer (`None`: the full square).
    pub fn truncated_square(&self, k: usize) -> Option<&TruncatedSquare> {
        self.truncated.get(k).and_then(Option::as_ref)
    }

    /// BMUL stage `k` (0-based): the square of `s` (UQ1.`in_frac`) rounded to the
    /// stage's fraction bits.
    #[inline]
    pub fn square_stage(&self, k: usize, s: u64, in_frac: u32) -> u64 {
        let sq = match &self.truncated[k] {
            None => u128::from(s) * u128::from(s),
            Some(t) => t.square(s),
        };
        requantize(
            sq,
            2 * in_frac,
            self.formats.square_frac[k],
            self.config.square_round,
        ) as u64
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// ROM1.
    pub fn rom(&self) -> &Rom {
        &self.rom
    }

    /// Every stage's format.
    pub fn formats(&self) -> &Formats {
        &self.formats
    }

    /// Clock cycles from the edge that loads an input into RG1/RG2 to the edge that
    /// loads its result into the output registers: `v + 4` (ROM1/Sm1, MUL, Sm2+SW,
    /// `v` squarings, RGB multipliers).
    pub fn latency(&self) -> u32 {
        self.config.v + 4
    }

    /// Full-scale `k_s·I` code, `2^out_bits - 1`.
    pub fn full_scale(&self) -> u64 {
        if self.config.out_bits >= 64 {
            u64::MAX
        } else {
            (1u64 << self.config.out_bits) - 1
        }
    }

    /// The code `2^f` of `cos = 1.0`.
    pub fn cos_one(&self) -> i64 {
        1i64 << self.formats.cos_frac
    }

    /// Points of one exhaustive check ([`crate::measure`]), as
    /// [`Config::exhaustive_points`]; exact for every valid configuration.
    pub fn exhaustive_points(&self) -> u128 {
        self.config.exhaustive_points().unwrap_or(u128::MAX)
    }

    /// Smallest and largest signed `cos` codes of RG1.
    pub fn cos_code_range(&self) -> (i64, i64) {
        let half = 1i64 << (self.config.cos_bits - 1);
        (-half, half - 1)
    }

    /// The code nearest to the real `cos` (ties away from zero), or an error if it
    /// lies outside RG1's range.
    pub fn cos_code(&self, cos: f64) -> Result<i64, HwError> {
        let scaled = (cos * self.cos_one() as f64).round();
        let (lo, hi) = self.cos_code_range();
        if !scaled.is_finite() || scaled < lo as f64 || scaled > hi as f64 {
            return Err(HwError::Input(format!(
                "cos = {cos} does not fit the {}-bit Q1.{} input (range {} ..= {})",
                self.config.cos_bits,
                self.formats.cos_frac,
                lo as f64 / self.cos_one() as f64,
                hi as f64 / self.cos_one() as f64
            )));
        }
        Ok(scaled as i64)
    }

    /// The real value of a `cos` code.
    pub fn cos_value(&self, code: i64) -> f64 {
        code as f64 / self.cos_one() as f64
    }

    /// Checks that every field of `input` fits its register.
    pub fn check_input(&self, input: &Input) -> Result<(), HwError> {
        let (lo, hi) = self.cos_code_range();
        if input.cos < lo || input.cos > hi {
            return Err(HwError::Input(format!(
                "cos code {} outside the {}-bit signed range {lo} ..= {hi}",
                input.cos, self.config.cos_bits
            )));
        }
        if u64::from(input.n) >= 1u64 << self.config.n_bits {
            return Err(HwError::Input(format!(
                "n = {} does not fit {} bits (max {})",
                input.n,
                self.config.n_bits,
                (1u64 << self.config.n_bits) - 1
            )));
        }
        for (ks, name) in input.ks.iter().zip(["R", "G", "B"]) {
            if *ks > self.full_scale() {
                return Err(HwError::Input(format!(
                    "k_s·I_{name} = {ks} does not fit {} bits (max {})",
                    self.config.out_bits,
                    self.full_scale()
                )));
            }
        }
        Ok(())
    }

    /// The functional model: what the pipeline outputs for `input`, computed in one
    /// go (no registers, no timing). Agrees bit for bit with [`crate::Pipeline`].
    pub fn eval(&self, input: &Input) -> Result<Output, HwError> {
        self.check_input(input)?;
        let lobe = self.lobe_code(input.cos, input.n);
        Ok(Output {
            rgb: input.ks.map(|ks| self.output_code(lobe, ks)),
        })
    }

    /// ROM1 → Sm1 → MUL → Sm2 → SW → BMUL for one `(cos, n)`: the lobe code, UQ1.f
    /// with `f = formats().lobe_frac`. The lean path behind [`Unit::eval`] and the
    /// exhaustive checks; `cos` and `n` must be in range ([`Unit::check_input`]), an
    /// out-of-range `n` is wrapped to the ROM's address width like a hardware address.
    #[inline]
    pub fn lobe_code(&self, cos: i64, n: u32) -> u64 {
        let f = &self.formats;
        // Sm1: t = 1 - cos, saturated at 0 for codes above 1.0.
        let t = self.cos_one().saturating_sub(cos).max(0) as u64;
        let a = self.rom.words()[(n as usize) & (self.rom.words().len() - 1)];
        // MUL: full product UQ.(coef_frac + t_frac), rounded to mul_frac. (Widening
        // u64 x u64 -> u128 products compile to one multiply instruction.)
        let p = requantize(
            a as u128 * t as u128,
            f.coef_frac + f.t_frac,
            f.mul_frac,
            self.config.mul_round,
        );
        // Sm2 + SW: base = 1 - p, or 0 where negative.
        let one = 1u128 << f.mul_frac;
        if p >= one {
            // SW outputs 0, and 0 stays 0 through every squaring and multiplier.
            return 0;
        }
        let mut s = (one - p) as u64;
        let mut frac = f.mul_frac;
        // BMUL: v squarings, each rounded to its stage's width.
        for (k, &next) in f.square_frac.iter().enumerate() {
            s = self.square_stage(k, s, frac);
            frac = next;
        }
        s
    }

    /// One RGB multiplier: `round(lobe · ks)` to an integer output code.
    #[inline]
    pub fn output_code(&self, lobe: u64, ks: u64) -> u64 {
        requantize(
            lobe as u128 * ks as u128,
            self.formats.lobe_frac,
            0,
            self.config.out_round,
        ) as u64
    }
}
