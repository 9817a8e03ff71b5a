//! The three cost flows of `glint hw pareto`, each from the same Verilog:
//!
//! - **gates**: yosys `synth -flatten` up to the fine-grained steps, with memories
//!   kept as memories (a 1024-word ROM mapped to logic keeps ABC busy for ten minutes
//!   and more at 30-bit words), sync-reset flip-flops legalised to plain D flip-flops
//!   plus logic, `abc -g` onto a fixed set of simple gates (AND, NAND, OR, NOR, XOR,
//!   XNOR, ANDNOT, ORNOT, MUX), then `stat -tech cmos`. yosys counts 4 transistors
//!   for a NAND2 (and NOR2), 2 for an inverter, 6 for AND/OR/ANDNOT/ORNOT, 12 for
//!   XOR/XNOR/MUX and 16 for a D flip-flop (the figures of yosys' `kernel/cost.h`,
//!   checked against its totals), so NAND2 equivalents are transistors / 4. ROM bits
//!   are counted, not dropped: one transistor per bit, as in a mask-programmed NOR
//!   ROM (its address decoder and sense amplifiers are not counted);
//! - **iCE40 HX8K**: `synth_ice40` and `nextpnr-ice40` (LUTs, carries, FFs, BRAMs, Fmax);
//! - **ECP5** (hard 18×18 multipliers): `synth_ecp5` cell counts, no place and route
//!   (nextpnr-ecp5 is not packaged in Debian 12, whose tools this project installs).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::synth::{count_cells, fmax_from_report, number_after};
use super::tools::{run, tail};
use super::{write_files, HdlUnit, ToolError, ICE40_DEVICE, ICE40_PACKAGE};

/// Gates the generic flow maps to.
pub const GATE_SET: &str = "AND,NAND,OR,NOR,XOR,XNOR,ANDNOT,ORNOT,MUX";

/// Transistors of a NAND2 in yosys' CMOS cost model.
pub const NAND2_TRANSISTORS: f64 = 4.0;

/// The measured cost of one design on every target.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Costs {
    /// Gate-level: cells after `abc -g` (flip-flops included; a ROM is one cell).
    pub gate_cells: u64,
    /// Gate-level: `stat -tech cmos` transistors of the logic and flip-flops, plus one
    /// per ROM bit.
    pub transistors: u64,
    /// iCE40: 4-input LUTs.
    pub ice40_luts: u64,
    /// iCE40: carry cells.
    pub ice40_carries: u64,
    /// iCE40: flip-flops.
    pub ice40_ffs: u64,
    /// iCE40: 4 kbit block RAMs.
    pub ice40_brams: u64,
    /// iCE40: Fmax after place and route, MHz.
    pub ice40_fmax: f64,
    /// ECP5: LUT4s.
    pub ecp5_luts: u64,
    /// ECP5: CCU2C carry cells (two LUT4s and a carry each).
    pub ecp5_ccu2: u64,
    /// ECP5: flip-flops.
    pub ecp5_ffs: u64,
    /// ECP5: 18×18 multipliers.
    pub ecp5_mult18: u64,
    /// ECP5: 18 kbit block RAMs.
    pub ecp5_brams: u64,
    /// ECP5: 16×4 distributed RAMs (LUT RAM).
    pub ecp5_lutram: u64,
}

impl Costs {
    /// NAND2 equivalents: transistors / 4.
    pub fn nand2(&self) -> f64 {
        self.transistors as f64 / NAND2_TRANSISTORS
    }

    /// iCE40 area per result: LUTs × clock period (ns); one result per clock.
    pub fn ice40_lut_ns(&self) -> f64 {
        self.ice40_luts as f64 * 1000.0 / self.ice40_fmax
    }

    /// ECP5 logic in LUT4s: LUT4 + 2 per CCU2C + 2 per distributed RAM.
    pub fn ecp5_lut_equiv(&self) -> u64 {
        self.ecp5_luts + 2 * self.ecp5_ccu2 + 2 * self.ecp5_lutram
    }
}

fn read(dir: &Path, name: &str) -> Result<String, ToolError> {
    std::fs::read_to_string(dir.join(name)).map_err(|e| ToolError::io(&dir.join(name), e))
}

/// Runs the three flows on `unit` in `dir` (the design's files are written there).
pub fn cost_flows<U: HdlUnit + ?Sized>(unit: &U, dir: &Path) -> Result<Costs, ToolError> {
    write_files(dir, &unit.files())?;
    let m = unit.module();
    let v = format!("{m}.v");
    let parse = |what: &'static str, x: Option<u64>, text: &str| {
        x.ok_or_else(|| ToolError::Parse {
            tool: "yosys",
            what,
            tail: tail(text),
        })
    };

    let gates = format!(
        "read_verilog {v}; synth -flatten -top {m} -run :fine; opt -fast -full; techmap; \
         opt -fast; dfflegalize -cell $_DFF_P_ 01; abc -g {GATE_SET}; opt_clean; \
         tee -o {m}_gates.txt stat -tech cmos"
    );
    run("yosys", "yosys", dir, &["-q", "-p", &gates])?;
    let text = read(dir, &format!("{m}_gates.txt"))?;
    if text.contains("$_SDFF") || text.contains("$_DFFE") {
        return Err(ToolError::Parse {
            tool: "yosys",
            what: "a netlist of simple gates and D flip-flops (a complex flip-flop was left)",
            tail: tail(&text),
        });
    }
    let gate_cells = parse(
        "the cell count",
        number_after(&text, "Number of cells:"),
        &text,
    )?;
    // Logic and flip-flops from yosys, plus one transistor per ROM bit.
    let transistors = parse(
        "the transistor estimate",
        number_after(&text, "Estimated number of transistors:"),
        &text,
    )? + unit.rom_bits();

    let json = format!("{m}_ice40.json");
    let ice =
        format!("read_verilog {v}; synth_ice40 -top {m} -json {json}; tee -o {m}_ice40.txt stat");
    run("yosys", "yosys", dir, &["-q", "-p", &ice])?;
    let ice_text = read(dir, &format!("{m}_ice40.txt"))?;
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
            "--timing-allow-fail",
            "--freq",
            "100",
            "--seed",
            "1",
            "--report",
            &report,
            "-q",
        ],
    )?;
    let pnr = read(dir, &report)?;
    let ice40_fmax = fmax_from_report(&pnr).ok_or_else(|| ToolError::Parse {
        tool: "nextpnr-ice40",
        what: "fmax",
        tail: tail(&pnr),
    })?;

    let ecp5 = format!("read_verilog {v}; synth_ecp5 -top {m}; tee -o {m}_ecp5.txt stat");
    run("yosys", "yosys", dir, &["-q", "-p", &ecp5])?;
    let e = read(dir, &format!("{m}_ecp5.txt"))?;
    Ok(Costs {
        gate_cells,
        transistors,
        ice40_luts: count_cells(&ice_text, "SB_LUT4"),
        ice40_carries: count_cells(&ice_text, "SB_CARRY"),
        ice40_ffs: count_cells(&ice_text, "SB_DFF"),
        ice40_brams: count_cells(&ice_text, "SB_RAM40_4K"),
        ice40_fmax,
        ecp5_luts: count_cells(&e, "LUT4"),
        ecp5_ccu2: count_cells(&e, "CCU2C"),
        ecp5_ffs: count_cells(&e, "TRELLIS_FF"),
        ecp5_mult18: count_cells(&e, "MULT18X18D"),
        ecp5_brams: count_cells(&e, "DP16KD") + count_cells(&e, "PDPW16KD"),
        ecp5_lutram: count_cells(&e, "TRELLIS_DPR16X4"),
    })
}
