//! The configuration of the unit: every stage's width, fixed-point format and rounding,
//! and its validation.

use std::fmt;

use glint_lobe::names::Named;

use serde::de::value::MapAccessDeserializer;
use serde::de::{MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::HwError;

/// Largest `v` accepted: BMUL has `v` squaring stages, so the power is at most
/// `2^10 = 1024` (the same limit as [`glint_lobe::MAX_V`]).
pub const MAX_V: u32 = 10;

/// Largest width of the `n` input (RG2, the ROM1 address): `n <= 2^13 - 1 = 8191`,
/// which stays below the lobe library's [`glint_lobe::MAX_N`] of 10000 and keeps ROM1
/// at most 8192 words.
pub const MAX_N_BITS: u32 = 13;

/// Every register and every adder result of the model is held in a 64-bit integer;
/// products are formed at full (128-bit) width and rounded back, as a hardware
/// multiplier forms its full product before the rounding logic.
pub const MAX_REGISTER_BITS: u32 = 64;

/// Largest `cos_bits`: Sm1 forms `1 - cos` in `cos_bits + 1` bits, which must fit a
/// [`MAX_REGISTER_BITS`] register.
pub const MAX_COS_BITS: u32 = MAX_REGISTER_BITS - 1;

/// The error for `name`, which is none of `T`'s names (the message of
/// [`glint_lobe::names::unknown`], as the other crates' named enums give).
fn unknown<T: Named>(name: &str) -> HwError {
    HwError::Parse(glint_lobe::names::unknown::<T>(name))
}

// The named enums derive their names, parser and lists with strum, as the other crates'
// (see `glint_lobe::names`); serde keeps the JSON spellings of configuration files.

/// How a stage drops fraction bits: `truncate` (also `trunc`, `floor`) or `nearest`
/// (also `round`); case-insensitive.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "lowercase")]
#[strum(
    serialize_all = "lowercase",
    ascii_case_insensitive,
    parse_err_ty = HwError,
    parse_err_fn = unknown::<Rounding>
)]
pub enum Rounding {
    /// Drop the low bits (round toward zero; every rounded value here is >= 0).
    #[strum(to_string = "truncate", serialize = "trunc", serialize = "floor")]
    Truncate,
    /// Round to nearest, ties up: add half an output LSB, then drop the low bits.
    #[strum(to_string = "nearest", serialize = "round")]
    Nearest,
}

impl Rounding {
    /// The name used in configuration files, on the command line and in tables.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl Named for Rounding {
    const WHAT: &'static str = "rounding";
}

/// Which coefficient `a(n)` ROM1 holds: `k` (also `energy`, `energy-fit`) or `minimax`;
/// case-insensitive.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[strum(
    serialize_all = "lowercase",
    ascii_case_insensitive,
    parse_err_ty = HwError,
    parse_err_fn = unknown::<Coefficients>
)]
pub enum Coefficients {
    /// The paper's energy fit `a = (n+1)/(2^v+1)` (K_v).
    #[serde(rename = "k")]
    #[strum(to_string = "k", serialize = "energy", serialize = "energy-fit")]
    EnergyFit,
    /// The `a` minimising the maximum absolute error against `cos^n`
    /// ([`glint_lobe::minimax_coefficient`]); same hardware, other ROM contents.
    #[serde(rename = "minimax")]
    Minimax,
}

impl Coefficients {
    /// The name used in configuration files, on the command line and in tables.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl Named for Coefficients {
    const WHAT: &'static str = "coefficients";
}

/// How the unit forms `a(n)`: `rom`, `const` or `table`. Every source gives the same
/// words as ROM1 (checked when the unit is built, see [`crate::CoefCircuit`]); only the
/// hardware differs.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "lowercase")]
#[strum(
    serialize_all = "lowercase",
    ascii_case_insensitive,
    parse_err_ty = HwError,
    parse_err_fn = unknown::<CoefSource>
)]
pub enum CoefSource {
    /// ROM1: one word per `n` (the paper's Fig. 4).
    Rom,
    /// `a(n) = (n+1)·K` rounded, `K ≈ 1/(2^v+1)`: a shift-and-add constant multiplier,
    /// no ROM (energy-fit coefficients only).
    Const,
    /// `a(n) = T_hi[n_hi] + T_lo[n_lo]` rounded: two small tables and an adder
    /// (energy-fit coefficients only).
    Table,
}

impl CoefSource {
    /// The name used in configuration files, on the command line and in tables.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl Named for CoefSource {
    const WHAT: &'static str = "coefficient source";
}

/// How a BMUL stage squares: `generic`, `symmetric` or `truncated`.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "lowercase")]
#[strum(
    serialize_all = "lowercase",
    ascii_case_insensitive,
    parse_err_ty = HwError,
    parse_err_fn = unknown::<Squarer>
)]
pub enum Squarer {
    /// A generic multiplier with both operands the same register (Fig. 4 as drawn).
    Generic,
    /// A squarer: the partial-product array folded by symmetry (`x_i x_j = x_j x_i`),
    /// about half the partial products. Same result as `Generic`.
    Symmetric,
    /// The symmetric array with the partial-product columns below
    /// `2f_in - f_out - square_guard` dropped and a constant (their mean) added.
    Truncated,
}

impl Squarer {
    /// The name used in configuration files, on the command line and in tables.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl Named for Squarer {
    const WHAT: &'static str = "squarer";
}

/// Every parameter of the unit. Formats (see `docs/hardware.md`):
///
/// - RG1 `cos`: signed two's complement, `cos_bits` wide, `cos_bits - 2` fraction bits
///   (Q1.f: sign, one integer bit, f fraction bits), so 1.0 is exactly representable.
/// - RG2 `n`: unsigned integer, `n_bits` wide.
/// - ROM1 `a(n)`: unsigned UQi.f, `coef_bits` wide; `i` is the fewest integer bits that
///   hold the largest coefficient, `f = coef_bits - i`.
/// - MUL output `p = a·t`: UQ(i+2).`mul_frac`; Sm2/SW output base: UQ1.`mul_frac`.
/// - BMUL stage `k`: UQ1.`square_frac[k]`.
/// - RGB: `k_s·I` codes and outputs are unsigned `out_bits` integers.
///
/// Missing fields of a configuration file take the default's values; unknown fields,
/// and anything but a JSON object (serde would otherwise read an array as the fields in
/// order), are errors.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
// `remote = "Self"` makes the derives inherent functions (`Config::deserialize`), so
// the trait impls below can wrap them: Deserialize accepts only a map.
#[serde(remote = "Self", default, deny_unknown_fields)]
pub struct Config {
    /// BMUL raises the base to `2^v` with `v` squarings (0..=10; the paper's is 4).
    pub v: u32,
    /// Width of the shininess input `n` and of the ROM1 address (1..=13).
    pub n_bits: u32,
    /// Width of the signed `cos γ` input code (Q1.(cos_bits-2)).
    pub cos_bits: u32,
    /// Which coefficients ROM1 holds.
    pub coefficients: Coefficients,
    /// Width of a ROM1 word.
    pub coef_bits: u32,
    /// How ROM1 contents are rounded from the real coefficients.
    pub coef_round: Rounding,
    /// Fraction bits of the MUL output and of the base (Sm2, SW).
    pub mul_frac: u32,
    /// How MUL rounds the product `a·t`.
    pub mul_round: Rounding,
    /// Fraction bits of each BMUL squaring stage's output, one entry per stage (`v`).
    pub square_frac: Vec<u32>,
    /// How each squaring stage rounds.
    pub square_round: Rounding,
    /// Width of the `k_s·I` inputs and of the R, G, B outputs.
    pub out_bits: u32,
    /// How the RGB multipliers round to the output code.
    pub out_round: Rounding,
    /// How `a(n)` is formed (ROM1, constant multiplier, or two small tables).
    pub coef_source: CoefSource,
    /// How each BMUL stage squares.
    pub squarer: Squarer,
    /// For [`Squarer::Truncated`]: partial-product columns kept below each stage's
    /// output LSB (1..=16; the truncation error is about `(drop/2 + 1)·2^-guard` of
    /// the stage's output LSB, see [`crate::TruncatedSquare`]).
    pub square_guard: u32,
}

impl Default for Config {
    /// The default configuration: the paper's v = 4, n <= 1023, cos as Q1.14, 8-bit
    /// colours, and the smallest widths `glint hw sweep --out-bits 10` finds for a
    /// 10-bit output within 1 LSB of the exact K_4 over every input (measured: 0.9645
    /// LSB at 10 bits, 0.6235 LSB at 8 bits; see `docs/hardware.md` for why).
    fn default() -> Self {
        Config {
            v: 4,
            n_bits: 10,
            cos_bits: 16,
            coefficients: Coefficients::EnergyFit,
            coef_bits: 18,
            coef_round: Rounding::Nearest,
            mul_frac: 15,
            mul_round: Rounding::Nearest,
            square_frac: vec![14, 14, 14, 12],
            square_round: Rounding::Nearest,
            out_bits: 8,
            out_round: Rounding::Nearest,
            coef_source: CoefSource::Rom,
            squarer: Squarer::Generic,
            square_guard: 2,
        }
    }
}

impl Serialize for Config {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        Config::serialize(self, serializer)
    }
}

impl<'de> Deserialize<'de> for Config {
    /// Only a map (a JSON object) is a configuration: the derived code would also read
    /// a sequence positionally, so `[4, 10]` would silently be `v = 4, n_bits = 10`.
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct ObjectOnly;
        impl<'de> Visitor<'de> for ObjectOnly {
            type Value = Config;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a JSON object of configuration fields, e.g. {\"v\": 4}")
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Config, A::Error> {
                Config::deserialize(MapAccessDeserializer::new(map))
            }
        }
        deserializer.deserialize_map(ObjectOnly)
    }
}

impl Config {
    /// Parses a JSON configuration: a JSON object whose missing fields take the
    /// default's values. Not validated; see [`Config::validate`].
    pub fn from_json(text: &str) -> Result<Config, HwError> {
        serde_json::from_str(text).map_err(|e| HwError::Parse(e.to_string()))
    }

    /// The configuration as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a Config always serialises")
    }

    /// Fraction bits of the `cos` input code.
    pub fn cos_frac(&self) -> u32 {
        self.cos_bits.saturating_sub(2)
    }

    /// Points of one exhaustive check ([`crate::measure`]): every `cos` code in
    /// `[-1, 1]` times every `n`, `(2^(cos_bits - 1) + 1) · 2^n_bits`, so callers can
    /// bound the work before building anything. Exact in `u128` (a valid configuration
    /// has at most `(2^62 + 1) · 2^13`); `None` if `cos_bits < 2` or it would not fit.
    pub fn exhaustive_points(&self) -> Option<u128> {
        if self.cos_bits < 2 {
            return None;
        }
        // 1 << k is exact for k < 128, which checked_shl guarantees.
        let codes = 1u128.checked_shl(self.cos_bits - 1)? + 1;
        codes.checked_mul(1u128.checked_shl(self.n_bits)?)
    }

    /// Checks everything that does not depend on the ROM contents: no zero widths,
    /// `v` and `n_bits` in range, one `square_frac` entry per squaring, and every
    /// register within [`MAX_REGISTER_BITS`]. Every field is bounded before any
    /// arithmetic uses it, and widths are added in `u64`, so no value of a `u32` field
    /// can wrap past a check.
    pub fn validate(&self) -> Result<(), HwError> {
        if self.v > MAX_V {
            return Err(HwError::InvalidV(self.v));
        }
        let widths: [(&'static str, u32); 5] = [
            ("n_bits", self.n_bits),
            ("cos_bits", self.cos_bits),
            ("coef_bits", self.coef_bits),
            ("mul_frac", self.mul_frac),
            ("out_bits", self.out_bits),
        ];
        for (field, w) in widths {
            if w == 0 {
                return Err(HwError::ZeroWidth { field });
            }
        }
        if self.n_bits > MAX_N_BITS {
            return Err(HwError::InvalidNBits(self.n_bits));
        }
        if self.cos_bits < 2 {
            return Err(HwError::TooNarrow {
                field: "cos_bits",
                bits: self.cos_bits,
                reason: "the signed Q1.f cos code needs a sign and an integer bit",
            });
        }
        if self.square_frac.len() != self.v as usize {
            return Err(HwError::SquareCount {
                v: self.v,
                got: self.square_frac.len(),
            });
        }
        if self.square_frac.contains(&0) {
            return Err(HwError::ZeroWidth {
                field: "square_frac",
            });
        }
        // Sm1 forms 1 - cos in one more bit than the signed input.
        check_register(
            "Sm1 = cos_bits + 1 (so cos_bits <= 63)",
            u64::from(self.cos_bits) + 1,
        )?;
        check_register("ROM1 word = coef_bits", self.coef_bits.into())?;
        // The base register is UQ1.mul_frac; MUL/Sm2 add integer bits, checked once
        // the ROM's integer width is known (Unit::new).
        check_register(
            "SW base = mul_frac + 1 (so mul_frac <= 63)",
            u64::from(self.mul_frac) + 1,
        )?;
        for &f in &self.square_frac {
            check_register(
                "BMUL stage = square_frac + 1 (so square_frac <= 63)",
                u64::from(f) + 1,
            )?;
        }
        check_register("RGB output = out_bits", self.out_bits.into())?;
        if self.coef_source != CoefSource::Rom && self.coefficients != Coefficients::EnergyFit {
            return Err(HwError::Parse(format!(
                "coef_source = {} computes the energy fit (n+1)/(2^v+1); minimax coefficients need coef_source = rom",
                self.coef_source.name()
            )));
        }
        if self.squarer == Squarer::Truncated && !(1..=16).contains(&self.square_guard) {
            return Err(HwError::TooNarrow {
                field: "square_guard",
                bits: self.square_guard,
                reason: "a truncated squarer keeps 1..=16 columns below its output LSB",
            });
        }
        // A truncated squarer's result is exact only to units of its last fraction bit;
        // an output finer than that has no meaning, and there its model's trace and
        // evaluation were found to disagree (config_errors' proptest, issue 30).
        let last = self.square_frac.last().copied().unwrap_or(0);
        if self.squarer == Squarer::Truncated && self.out_bits > last {
            return Err(HwError::Parse(format!(
                "out_bits = {} is finer than the truncated squarer's last square_frac = {last}: use at most {last} output bits or another squarer",
                self.out_bits
            )));
        }
        Ok(())
    }
}

/// Rejects a register wider than the model's 64-bit integers. `bits` is a `u64` so that
/// callers add widths without wrapping.
pub(crate) fn check_register(register: &'static str, bits: u64) -> Result<(), HwError> {
    if bits > u64::from(MAX_REGISTER_BITS) {
        Err(HwError::TooWide { register, bits })
    } else {
        Ok(())
    }
}
