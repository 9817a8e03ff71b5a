//! A bit-accurate, cycle-accurate fixed-point model of the specular unit of Pavlov,
//! Romanyuk and Dumenko (the paper's Fig. 4): RG1/RG2 → ROM1 → Sm1 → MUL → Sm2 → SW →
//! BMUL (`v` squarings) → RGB multipliers, computing `k_s·I · K_v(n, cos γ)`.
//!
//! ```
//! use glint_hw::{Config, Input, Pipeline, Unit};
//!
//! // The default configuration: v = 4, n <= 1023, cos as Q1.14, 8-bit colours.
//! let unit = Unit::new(Config::default()).unwrap();
//! let input = Input { cos: unit.cos_code(0.98).unwrap(), n: 100, ks: [255, 200, 180] };
//!
//! // Functional model: K_4(100, 0.98) = (1 - 101/17 · 0.02)^16 ≈ 0.1280.
//! let out = unit.eval(&input).unwrap();
//! let exact = (1.0f64 - 101.0 / 17.0 * (1.0 - unit.cos_value(input.cos))).powi(16);
//! assert!((out.rgb[0] as f64 - 255.0 * exact).abs() <= 0.5);
//!
//! // Cycle model: the same codes, `latency()` clock edges later.
//! let mut pipe = Pipeline::new(&unit);
//! let mut got = pipe.clock(Some(input)).unwrap();
//! for _ in 0..unit.latency() {
//!     assert_eq!(got, None);
//!     got = pipe.clock(None).unwrap();
//! }
//! assert_eq!(got, Some(out));
//!
//! // Bad configurations are rejected with a typed error.
//! assert!(Unit::new(Config { v: 11, ..Config::default() }).is_err());
//! ```
//!
//! Every width, format and rounding is a [`Config`] field; the model computes with
//! integers only (registers in `u64`, products at full width in `u128`). [`Rom`] holds
//! the ROM1 contents (energy-fit or minimax coefficients) and writes them for
//! `$readmemh`; [`measure`] and [`within`] check a unit exhaustively against the exact
//! lobe and `cos^n`; [`sweep_row`] searches the smallest widths for an error bound.
//! Formats and the default configuration are explained in `docs/hardware.md`.

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod accuracy;
mod arith;
mod check;
mod config;
#[cfg(feature = "tools")]
mod design;
mod fixed;
#[cfg(feature = "tools")]
pub mod hdl;
#[cfg(feature = "tools")]
pub mod pareto;
mod pipeline;
mod report;
mod rom;
mod sweep;
mod table;
mod unit;

pub use accuracy::{measure, within, ErrorsAtN, Measurement, Reference, Worst, BOUND_SLACK_LSB};
pub use arith::{csd_digits, CoefCircuit, TruncatedSquare, MAX_TRUNCATED_COLUMNS};
pub use check::{
    check_exhaustive_size, check_ranges, full_scale, MAX_CHECK_POINTS, MAX_SWEEP_POINTS,
};
pub use config::{
    CoefSource, Coefficients, Config, Rounding, Squarer, MAX_COS_BITS, MAX_N_BITS,
    MAX_REGISTER_BITS, MAX_V,
};
#[cfg(feature = "tools")]
pub use design::{Design, DesignErrors, DESIGN_COS_BITS, DESIGN_N_BITS, N_RANGES};
pub use fixed::requantize;
pub use pipeline::{BaseReg, MulReg, Pipeline, Registers, RomSm1Reg, SquareReg, Trace};
pub use report::{TraceRow, TraceTable};
pub use rom::{coefficient_int_bits, real_coefficients, Rom};
pub use sweep::{
    format_ranges, markdown_table, mask_ranges, sweep_row, SweepRow, Target, Widths, START_FRAC,
};
pub use table::CosTableError;
pub use unit::{Formats, Input, Output, Unit};

/// Why a configuration or an input was rejected.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum HwError {
    /// A width parameter is 0.
    #[error("invalid configuration: {field} = 0; every width must be at least 1 bit")]
    ZeroWidth {
        /// The offending field.
        field: &'static str,
    },
    /// `v` is above [`MAX_V`].
    #[error("invalid configuration: v = {0}; expected 0..={MAX_V} (BMUL has v squaring stages, power 2^v <= 1024)")]
    InvalidV(u32),
    /// `n_bits` is above [`MAX_N_BITS`].
    #[error("invalid configuration: n_bits = {0}; expected 1..={MAX_N_BITS} (n <= 8191, ROM1 <= 8192 words)")]
    InvalidNBits(u32),
    /// `square_frac` does not have one entry per squaring stage.
    #[error("invalid configuration: square_frac has {got} entries but v = {v} needs exactly {v} (one per BMUL squaring stage)")]
    SquareCount {
        /// `v`.
        v: u32,
        /// Entries given.
        got: usize,
    },
    /// A width is too small for what the stage must hold.
    #[error("invalid configuration: {field} = {bits} is too narrow: {reason}")]
    TooNarrow {
        /// The offending field.
        field: &'static str,
        /// Its value.
        bits: u32,
        /// Why.
        reason: &'static str,
    },
    /// A register would not fit the model's 64-bit integers.
    #[error("invalid configuration: {register} would be {bits} bits wide; the model holds every register in a 64-bit integer (max {MAX_REGISTER_BITS})")]
    TooWide {
        /// Which register.
        register: &'static str,
        /// Its width (a `u64`: the sum of widths it is formed from never wraps).
        bits: u64,
    },
    /// A configuration file or name could not be parsed.
    #[error("invalid configuration: {0}")]
    Parse(String),
    /// A comparison unit (see [`hdl`]) is not designed for these interface widths.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// The model disagrees with itself (a bug, reported rather than hidden).
    #[error("internal error: {0}")]
    Internal(String),
    /// An input does not fit its register.
    #[error("invalid input: {0}")]
    Input(String),
}
