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
//!
//! Two more, run by [`extra_flows`] (also on designs measured before they existed):
//! iCE40 place and route with more seeds (the median Fmax is the figure a single seed's
//! luck cannot move), and ECP5 with `synth_ecp5 -nodsp` (the multipliers as logic: the
//! control that says what the hard multipliers are worth to each design).

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
    /// iCE40: Fmax (MHz) of every place-and-route seed run, seed 1 ([`Costs::ice40_fmax`])
    /// first; empty for a design measured before seeds were added.
    #[serde(default)]
    pub ice40_fmax_seeds: Vec<f64>,
    /// ECP5 without DSPs (`synth_ecp5 -nodsp`); `None`: not run.
    #[serde(default)]
    pub ecp5_nodsp: Option<Ecp5Cells>,
}

/// ECP5 cell counts of one `synth_ecp5` run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ecp5Cells {
    /// LUT4s.
    pub luts: u64,
    /// CCU2C carry cells.
    pub ccu2: u64,
    /// Flip-flops.
    pub ffs: u64,
    /// 18×18 multipliers (0 with `-nodsp`).
    pub mult18: u64,
    /// 18 kbit block RAMs.
    pub brams: u64,
    /// 16×4 distributed RAMs.
    pub lutram: u64,
}

impl Ecp5Cells {
    /// LUT4 equivalents: LUT4 + 2 per CCU2C + 2 per distributed RAM.
    pub fn lut_equiv(&self) -> u64 {
        self.luts + 2 * self.ccu2 + 2 * self.lutram
    }

    fn of_stat(text: &str) -> Ecp5Cells {
        Ecp5Cells {
            luts: count_cells(text, "LUT4"),
            ccu2: count_cells(text, "CCU2C"),
            ffs: count_cells(text, "TRELLIS_FF"),
            mult18: count_cells(text, "MULT18X18D"),
            brams: count_cells(text, "DP16KD") + count_cells(text, "PDPW16KD"),
            lutram: count_cells(text, "TRELLIS_DPR16X4"),
        }
    }
}

/// The median of `xs` (the mean of the middle two for an even count; `None` if empty).
pub fn median(xs: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    Some(if v.len() % 2 == 1 {
        v[m]
    } else {
        (v[m - 1] + v[m]) / 2.0
    })
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

    /// The median iCE40 Fmax over the seeds run ([`Costs::ice40_fmax`] if only seed 1).
    pub fn ice40_fmax_median(&self) -> f64 {
        median(&self.ice40_fmax_seeds).unwrap_or(self.ice40_fmax)
    }

    /// Place-and-route seeds run on iCE40 (1 for a design measured before seeds).
    pub fn ice40_seeds(&self) -> usize {
        self.ice40_fmax_seeds.len().max(1)
    }

    /// Whether [`extra_flows`] with `seeds` has something left to run.
    pub fn needs_extra(&self, seeds: usize) -> bool {
        self.ecp5_nodsp.is_none() || self.ice40_seeds() < seeds
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
    let ice40_fmax = ice40_pnr(dir, m, 1)?;

    let ecp5 = format!("read_verilog {v}; synth_ecp5 -top {m}; tee -o {m}_ecp5.txt stat");
    run("yosys", "yosys", dir, &["-q", "-p", &ecp5])?;
    let e = read(dir, &format!("{m}_ecp5.txt"))?;
    Ok(Costs {
        ice40_fmax_seeds: vec![ice40_fmax],
        ecp5_nodsp: None,
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

/// Places and routes `{m}_ice40.json` (in `dir`) on the iCE40 with `seed`: the Fmax, MHz.
fn ice40_pnr(dir: &Path, m: &str, seed: u32) -> Result<f64, ToolError> {
    let json = format!("{m}_ice40.json");
    let report = format!("{m}_pnr_{seed}.json");
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
            &seed.to_string(),
            "--report",
            &report,
            "-q",
        ],
    )?;
    let pnr = read(dir, &report)?;
    fmax_from_report(&pnr).ok_or_else(|| ToolError::Parse {
        tool: "nextpnr-ice40",
        what: "fmax",
        tail: tail(&pnr),
    })
}

/// Runs what `costs` lacks of the extra flows on `unit` in `dir`: iCE40 place and route
/// with seeds up to `seeds` (seed 1's Fmax is [`Costs::ice40_fmax`]) and ECP5 with
/// `synth_ecp5 -nodsp`. Returns whether anything ran.
pub fn extra_flows<U: HdlUnit + ?Sized>(
    unit: &U,
    dir: &Path,
    costs: &mut Costs,
    seeds: usize,
) -> Result<bool, ToolError> {
    if !costs.needs_extra(seeds) {
        return Ok(false);
    }
    write_files(dir, &unit.files())?;
    let m = unit.module();
    let v = format!("{m}.v");
    if costs.ice40_fmax_seeds.is_empty() {
        costs.ice40_fmax_seeds.push(costs.ice40_fmax);
    }
    if costs.ice40_fmax_seeds.len() < seeds {
        let json = format!("{m}_ice40.json");
        if !dir.join(&json).exists() {
            let ice = format!("read_verilog {v}; synth_ice40 -top {m} -json {json}");
            run("yosys", "yosys", dir, &["-q", "-p", &ice])?;
        }
        for seed in costs.ice40_fmax_seeds.len() + 1..=seeds {
            let f = ice40_pnr(dir, m, seed as u32)?;
            costs.ice40_fmax_seeds.push(f);
        }
    }
    if costs.ecp5_nodsp.is_none() {
        let nodsp =
            format!("read_verilog {v}; synth_ecp5 -nodsp -top {m}; tee -o {m}_ecp5_nodsp.txt stat");
        run("yosys", "yosys", dir, &["-q", "-p", &nodsp])?;
        costs.ecp5_nodsp = Some(Ecp5Cells::of_stat(&read(
            dir,
            &format!("{m}_ecp5_nodsp.txt"),
        )?));
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_of_seeds() {
        assert_eq!(median(&[]), None);
        assert_eq!(median(&[50.0]), Some(50.0));
        assert_eq!(median(&[53.0, 49.0, 51.0]), Some(51.0));
        assert_eq!(median(&[53.0, 49.0, 51.0, 60.0]), Some(52.0));
        assert_eq!(median(&[f64::NAN, 40.0]), Some(40.0));
    }
}
