//! Cost of a unit: yosys generic synthesis (cell count, CMOS transistor estimate),
//! yosys `synth_ice40` (LUTs, carries, flip-flops, block RAMs, DSPs) and nextpnr-ice40
//! place and route (maximum clock frequency).

use std::fmt::Write as _;
use std::path::Path;

use super::tools::{run, tail};
use super::{write_files, HdlUnit, ToolError};

/// The iCE40 part placed and routed: the HX8K, the largest iCE40 with enough pins for
/// the 56 input and 25 output pins of the units (the UltraPlus UP5K, which has DSPs,
/// has at most 39 I/Os). It has no DSP blocks, so every multiplier is LUT logic.
pub const ICE40_DEVICE: &str = "hx8k";
/// The HX8K package (206 I/Os).
pub const ICE40_PACKAGE: &str = "ct256";
/// Clock constraint given to nextpnr, MHz (the achieved Fmax is reported whatever it is).
const TARGET_MHZ: &str = "100";
/// Placement seed, fixed so that runs are repeatable.
const SEED: &str = "1";

/// Measured cost of one unit.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthReport {
    /// The module.
    pub module: &'static str,
    /// Cells after yosys `synth` (generic gates and flip-flops; memories kept as one
    /// cell each).
    pub cells: u64,
    /// yosys `stat -tech cmos` transistor estimate (logic and flip-flops; ROMs
    /// excluded, see [`HdlUnit::rom_bits`]).
    pub transistors: u64,
    /// iCE40 4-input LUTs.
    pub luts: u64,
    /// iCE40 carry cells.
    pub carries: u64,
    /// iCE40 flip-flops.
    pub ffs: u64,
    /// iCE40 4 kbit block RAMs.
    pub brams: u64,
    /// iCE40 DSP blocks (always 0 on the HX8K).
    pub dsps: u64,
    /// Maximum clock frequency after place and route, MHz.
    pub fmax_mhz: f64,
}

/// Counts of cells whose type starts with `prefix` in a yosys `stat` listing (the last
/// listing in `log` is used).
pub(crate) fn count_cells(log: &str, prefix: &str) -> u64 {
    let last = log.rfind("Number of cells:").map_or(log, |i| &log[i..]);
    last.lines()
        .filter_map(|l| {
            let mut it = l.split_whitespace();
            let name = it.next()?;
            let count = it.next()?.parse::<u64>().ok()?;
            (name.starts_with(prefix) && it.next().is_none()).then_some(count)
        })
        .sum()
}

/// The number after `key` on the last line of `log` containing it.
pub(crate) fn number_after(log: &str, key: &str) -> Option<u64> {
    let line = log.lines().rev().find(|l| l.contains(key))?;
    line[line.find(key)? + key.len()..]
        .trim()
        .trim_end_matches('+')
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// The smallest achieved frequency over the clocks of a nextpnr `--report` JSON file.
pub(crate) fn fmax_from_report(json: &str) -> Option<f64> {
    let v: serde_json::Value = serde_json::from_str(json).ok()?;
    v.get("fmax")?
        .as_object()?
        .values()
        .filter_map(|c| c.get("achieved")?.as_f64())
        .reduce(f64::min)
}

/// Synthesises `unit` in `dir` and places and routes it on the iCE40 HX8K.
pub fn synth<U: HdlUnit + ?Sized>(unit: &U, dir: &Path) -> Result<SynthReport, ToolError> {
    write_files(dir, &unit.files())?;
    let m = unit.module();
    let v = format!("{m}.v");
    // Generic: the coarse `synth` steps, then gates without `memory_map`, so that a ROM
    // stays one memory cell instead of becoming a mux tree of constants.
    let generic = format!(
        "read_verilog {v}; synth -flatten -top {m} -run :fine; opt -fast -full; techmap; \
         opt -fast; abc -fast; opt -fast; stat -tech cmos"
    );
    let log = run(
        "yosys",
        "yosys",
        dir,
        &[
            "-q",
            "-p",
            &format!("{generic}; tee -o {m}_generic.txt stat -tech cmos"),
        ],
    )?;
    let text = std::fs::read_to_string(dir.join(format!("{m}_generic.txt")))
        .map_err(|e| ToolError::io(&dir.join(format!("{m}_generic.txt")), e))?;
    let parse = |what: &'static str, x: Option<u64>| {
        x.ok_or_else(|| ToolError::Parse {
            tool: "yosys",
            what,
            tail: tail(&format!("{log}{text}")),
        })
    };
    let cells = parse("the cell count", number_after(&text, "Number of cells:"))?;
    let transistors = parse(
        "the transistor estimate",
        number_after(&text, "Estimated number of transistors:"),
    )?;
    let json = format!("{m}_ice40.json");
    let ice =
        format!("read_verilog {v}; synth_ice40 -top {m} -json {json}; tee -o {m}_ice40.txt stat");
    run("yosys", "yosys", dir, &["-q", "-p", &ice])?;
    let text = std::fs::read_to_string(dir.join(format!("{m}_ice40.txt")))
        .map_err(|e| ToolError::io(&dir.join(format!("{m}_ice40.txt")), e))?;
    let report = format!("{m}_pnr.json");
    run(
        "nextpnr-ice40",
        "nextpnr-ice40",
        dir,
        &[
            &format!("--{ICE40_DEVICE}"),
            "--package",
            ICE40_PACKAGE,
            "--json",
            &json,
            "--pcf-allow-unconstrained",
            // Report the achieved Fmax even when it is below the target.
            "--timing-allow-fail",
            "--freq",
            TARGET_MHZ,
            "--seed",
            SEED,
            "--report",
            &report,
            "-q",
        ],
    )?;
    let pnr = std::fs::read_to_string(dir.join(&report))
        .map_err(|e| ToolError::io(&dir.join(&report), e))?;
    let fmax_mhz = fmax_from_report(&pnr).ok_or_else(|| ToolError::Parse {
        tool: "nextpnr-ice40",
        what: "fmax",
        tail: tail(&pnr),
    })?;
    Ok(SynthReport {
        module: m,
        cells,
        transistors,
        luts: count_cells(&text, "SB_LUT4"),
        carries: count_cells(&text, "SB_CARRY"),
        ffs: count_cells(&text, "SB_DFF"),
        brams: count_cells(&text, "SB_RAM40_4K"),
        dsps: count_cells(&text, "SB_MAC16"),
        fmax_mhz,
    })
}

/// One row of the cost table.
#[derive(Clone, Debug, PartialEq)]
pub struct CostRow {
    /// What the unit is.
    pub unit: String,
    /// Its synthesis results.
    pub synth: SynthReport,
    /// ROM bits it holds.
    pub rom_bits: u64,
    /// Latency, clocks.
    pub latency: u32,
    /// Exhaustive max error against `cos^n`, output LSBs.
    pub error_vs_power: f64,
}

/// The cost table in Markdown. Every unit takes one input per clock, so the area
/// per result is area / Fmax (here LUTs × ns per clock).
pub fn cost_table(rows: &[CostRow]) -> String {
    let mut s = String::from(
        "| unit | cells | transistors | ROM bits | LUTs | carries | DSPs | FFs | BRAMs | Fmax MHz | LUT·ns per result | latency | max err vs cos^n (LSB) |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let y = &r.synth;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} | {:.0} | {} | {:.3} |",
            r.unit,
            y.cells,
            y.transistors,
            r.rom_bits,
            y.luts,
            y.carries,
            y.dsps,
            y.ffs,
            y.brams,
            y.fmax_mhz,
            y.luts as f64 * 1000.0 / y.fmax_mhz,
            r.latency,
            r.error_vs_power
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_yosys_and_nextpnr_output() {
        // Shapes of yosys 0.23 `stat` and nextpnr 0.4 `--report` output, by hand.
        let stat = "   Number of wires:                 10\n   Number of cells:                 7\n\
                    \x20    SB_CARRY                        2\n     SB_DFF                          1\n\
                    \x20    SB_DFFE                         3\n     SB_LUT4                         1\n\n\
                    \x20  Estimated number of transistors:       1234+\n";
        assert_eq!(count_cells(stat, "SB_DFF"), 4);
        assert_eq!(count_cells(stat, "SB_LUT4"), 1);
        assert_eq!(count_cells(stat, "SB_MAC16"), 0);
        assert_eq!(number_after(stat, "Number of cells:"), Some(7));
        assert_eq!(
            number_after(stat, "Estimated number of transistors:"),
            Some(1234)
        );
        let report = r#"{"fmax": {"clk$SB_IO_IN_$glb_clk": {"achieved": 61.5, "constraint": 100.0},
                          "other": {"achieved": 80.0, "constraint": 12.0}}, "utilization": {}}"#;
        assert_eq!(fmax_from_report(report), Some(61.5));
        assert_eq!(fmax_from_report("{}"), None);
    }
}
