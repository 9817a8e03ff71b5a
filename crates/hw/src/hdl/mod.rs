//! Verilog of the specular units, co-simulation against the Rust models with Icarus
//! Verilog, lint with Verilator, and synthesis with yosys and nextpnr-ice40.
//!
//! Three units share one interface, so one testbench and one vector format serve all:
//!
//! | port | width | meaning |
//! |---|---|---|
//! | `clk`, `rst` | 1 | clock; synchronous reset (clears every valid bit) |
//! | `in_valid` | 1 | an input is presented this clock |
//! | `cos_in` | `cos_bits` | `cos γ`, signed Q1.(cos_bits-2) |
//! | `n_in` | `n_bits` | shininess, unsigned |
//! | `ks_r_in`, `ks_g_in`, `ks_b_in` | `out_bits` | `k_s·I` per channel |
//! | `out_valid` | 1 | R, G, B hold a result |
//! | `r_out`, `g_out`, `b_out` | `out_bits` | the specular colour codes |
//!
//! - [`KvUnit`]: the paper's K_v pipeline from a [`crate::Config`] (ROM1 from its
//!   `$readmemh` file);
//! - [`PowerUnit`]: an exact `cos^n` unit (log2 table, multiplier, exp2 table, the
//!   approach of published specular hardware), within 1 LSB of `cos^n`;
//! - [`SchlickUnit`]: Schlick's `c/(n - n·c + c)` with a pipelined restoring divider.
//!
//! Every unit accepts one input per clock and has a fixed latency. The testbench reads
//! one line per clock (the input, and the output the Rust model expects after that
//! clock edge) and compares `out_valid` on every clock and R, G, B whenever it is high.

mod arrays;
mod flows;
mod kv;
mod power;
mod schlick;
mod stimulus;
mod synth;
mod tools;
mod vlog;

use std::path::{Path, PathBuf};

pub use flows::{cost_flows, extra_flows, median, Costs, Ecp5Cells, GATE_SET, NAND2_TRANSISTORS};
pub use kv::KvUnit;
pub use power::{PowParams, PowerUnit, MAX_POW_INDEX};
pub use schlick::{SchlickParams, SchlickUnit};
pub use stimulus::{expected_stream, stimulus, write_vectors, Stimulus};
pub use synth::{cost_table, synth, CostRow, SynthReport, ICE40_DEVICE, ICE40_PACKAGE};
pub use tools::{cosim, lint, testbench, CosimReport};

use crate::{Input, Output};

/// The widths of the shared interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ports {
    /// Width of the signed `cos` code (Q1.(cos_bits-2)).
    pub cos_bits: u32,
    /// Width of `n`.
    pub n_bits: u32,
    /// Width of each `k_s·I` input and R, G, B output.
    pub out_bits: u32,
}

/// One text file of a design.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HdlFile {
    /// File name (no directory).
    pub name: String,
    /// Contents.
    pub text: String,
}

/// A pipelined unit with a Verilog description and a bit-accurate Rust model.
pub trait HdlUnit: Sync {
    /// The Verilog module name (also the stem of its file names).
    fn module(&self) -> &'static str;
    /// A one-line description for tables.
    fn describe(&self) -> String;
    /// The interface widths.
    fn ports(&self) -> Ports;
    /// Clock edges from the edge that loads an input to the edge that loads its result.
    fn latency(&self) -> u32;
    /// The functional model: the outputs for one input (which fits its ports).
    fn eval(&self, input: &Input) -> Output;
    /// Bits of ROM (lookup tables) the unit holds.
    fn rom_bits(&self) -> u64;
    /// The synthesisable Verilog: the module, then any `$readmemh` files it loads
    /// (read from the working directory of the simulator or synthesiser).
    fn files(&self) -> Vec<HdlFile>;
    /// The cycle model: the output registers after each clock edge for the given
    /// input stream (`None` = `in_valid` low). The default is a delay line of
    /// [`HdlUnit::latency`] registers around [`HdlUnit::eval`], which is what a
    /// pipeline with a valid bit per stage computes.
    fn cycle_model(&self, stream: &[Option<Input>]) -> Vec<Option<Output>> {
        let l = self.latency() as usize;
        (0..stream.len())
            .map(|k| {
                k.checked_sub(l)
                    .and_then(|i| stream[i])
                    .map(|inp| self.eval(&inp))
            })
            .collect()
    }
    /// The unit's exhaustive error against `cos^n`: every `cos` code in `[0, 1]`, every
    /// `n`, `k_s·I` at full scale; the maximum of `|output - F·c^n|` in output LSBs.
    fn max_error_vs_power(&self) -> f64 {
        stimulus::max_error_vs_power(self)
    }
}

/// Why writing, simulating or synthesising a design failed.
#[derive(Debug, thiserror::Error)]
pub enum ToolError {
    /// A file could not be written or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// An external program is not installed.
    #[error(
        "{tool} is not installed (Debian package {package}; scripts/install-deps installs it)"
    )]
    Missing {
        /// The program.
        tool: &'static str,
        /// Its Debian package.
        package: &'static str,
    },
    /// An external program failed.
    #[error("{tool} failed ({status}): {tail}")]
    Failed {
        /// The program.
        tool: &'static str,
        /// Its exit status.
        status: String,
        /// The last lines of its output.
        tail: String,
    },
    /// A program's output did not contain what was expected.
    #[error("could not read {what} from the output of {tool}: {tail}")]
    Parse {
        /// The program.
        tool: &'static str,
        /// What was looked for.
        what: &'static str,
        /// The last lines of its output.
        tail: String,
    },
    /// A file could not be written (atomically).
    #[error(transparent)]
    Write(#[from] glint_io::IoError),
    /// The unit cannot be built for this configuration.
    #[error(transparent)]
    Config(#[from] crate::HwError),
}

impl ToolError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> ToolError {
        ToolError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Writes `files` into `dir` (created if missing), each atomically.
pub fn write_files(dir: &Path, files: &[HdlFile]) -> Result<(), ToolError> {
    std::fs::create_dir_all(dir).map_err(|e| ToolError::io(dir, e))?;
    for f in files {
        glint_io::write_atomic(&dir.join(&f.name), |w| w.write_all(f.text.as_bytes()))?;
    }
    Ok(())
}

/// `2^bits - 1`.
pub(crate) fn mask(bits: u32) -> u64 {
    u64::MAX
        .checked_shr(64u32.saturating_sub(bits))
        .unwrap_or(0)
}
