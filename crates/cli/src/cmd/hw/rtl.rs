//! `glint hw verilog`, `cosim` and `synth`: the Verilog units, their co-simulation
//! against the Rust models and their cost.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context};
use glint_hw::hdl::{self, HdlUnit, KvUnit, PowerUnit, SchlickUnit};

use super::{build_unit, load_config, unless_closed, CosimArgs, HdlChoice, SynthArgs, VerilogArgs};

/// Largest number of test vectors a command writes (~40 bytes a line: 4 GB of text).
const MAX_VECTORS: usize = 100_000_000;

/// The chosen units: the K_v unit of the configuration, and the comparison units at
/// its interface widths.
fn hdl_units(
    choice: HdlChoice,
    config: Option<&Path>,
) -> anyhow::Result<(Vec<Box<dyn HdlUnit>>, u32)> {
    let cfg = load_config(config)?;
    let kv = KvUnit::new(build_unit(cfg, config)?);
    let ports = kv.ports();
    let v = kv.unit().config().v;
    let mut units: Vec<Box<dyn HdlUnit>> = Vec::new();
    if matches!(choice, HdlChoice::Kv | HdlChoice::All) {
        units.push(Box::new(kv));
    }
    if matches!(choice, HdlChoice::Pow | HdlChoice::All) {
        units.push(Box::new(PowerUnit::new(ports)?));
    }
    if matches!(choice, HdlChoice::Schlick | HdlChoice::All) {
        units.push(Box::new(SchlickUnit::new(ports)?));
    }
    Ok((units, v))
}

fn check_vectors(n: usize) -> anyhow::Result<()> {
    if n == 0 || n > MAX_VECTORS {
        bail!("invalid --vectors {n}: expected 1..={MAX_VECTORS}");
    }
    Ok(())
}

/// A working directory: `keep` (created), or a temporary one removed on drop.
fn work_dir(keep: Option<&Path>) -> anyhow::Result<(PathBuf, Option<tempfile::TempDir>)> {
    match keep {
        Some(d) => {
            std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
            Ok((d.to_path_buf(), None))
        }
        None => {
            let t = tempfile::tempdir().context("creating a temporary directory")?;
            Ok((t.path().to_path_buf(), Some(t)))
        }
    }
}

pub(super) fn verilog(args: VerilogArgs) -> anyhow::Result<()> {
    check_vectors(args.vectors)?;
    let (units, v) = hdl_units(args.unit, args.config.as_deref())?;
    for u in &units {
        let mut files = u.files();
        files.push(hdl::testbench(u.as_ref()));
        hdl::write_files(&args.output, &files)?;
        let stim = hdl::stimulus(u.ports(), v, args.vectors, args.seed);
        let name = format!("{}_vectors.txt", u.module());
        let clocks = hdl::write_vectors(u.as_ref(), &stim, &args.output.join(&name))?;
        let names: Vec<String> = files.iter().map(|f| f.name.clone()).collect();
        eprintln!(
            "{}: wrote {} and {name} ({} vectors, {clocks} clocks) to {}",
            u.module(),
            names.join(", "),
            stim.vectors(),
            args.output.display()
        );
    }
    Ok(())
}

pub(super) fn cosim(args: CosimArgs) -> anyhow::Result<()> {
    check_vectors(args.vectors)?;
    let (units, v) = hdl_units(args.unit, args.config.as_deref())?;
    let (dir, _tmp) = work_dir(args.keep.as_deref())?;
    let mut failed = Vec::new();
    for u in &units {
        let r = hdl::cosim(u.as_ref(), args.vectors, args.seed, v, &dir)?;
        // A closed stdout does not stop the checks: a failure still fails the command.
        unless_closed(outln!(
            "{}: {} of {} vectors passed, {} mismatches, {} clocks (latency {}, valid checked on every clock); model {:.1} s, iverilog {:.1} s",
            r.module,
            r.passed,
            r.vectors,
            r.mismatches,
            r.clocks,
            u.latency(),
            r.model_secs,
            r.sim_secs
        ))?;
        for line in &r.first_mismatches {
            unless_closed(outln!("  {line}"))?;
        }
        if !r.ok() {
            failed.push(r.module);
        }
        match hdl::lint(u.as_ref(), &dir) {
            Ok(()) => unless_closed(outln!("{}: verilator --lint-only -Wall: clean", u.module()))?,
            Err(e) => {
                unless_closed(outln!("{}: {e}", u.module()))?;
                failed.push(u.module());
            }
        }
    }
    if !failed.is_empty() {
        bail!("co-simulation or lint failed for {}", failed.join(", "));
    }
    Ok(())
}

pub(super) fn synth(args: SynthArgs) -> anyhow::Result<()> {
    let (units, _) = hdl_units(args.unit, args.config.as_deref())?;
    let (dir, _tmp) = work_dir(args.keep.as_deref())?;
    let mut rows = Vec::new();
    for u in &units {
        let started = Instant::now();
        let synth = hdl::synth(u.as_ref(), &dir)?;
        eprintln!(
            "{}: synthesised, placed and routed in {:.0} s",
            u.module(),
            started.elapsed().as_secs_f64()
        );
        rows.push(hdl::CostRow {
            unit: format!("{} ({})", u.module(), u.describe()),
            synth,
            rom_bits: u.rom_bits(),
            latency: u.latency(),
            error_vs_power: u.max_error_vs_power(),
        });
    }
    outln!(
        "# glint hw synth: yosys synth + stat -tech cmos (generic), synth_ice40 + nextpnr-ice40 --{} --package {} (no DSPs on this part: multipliers are LUTs); one result per clock",
        hdl::ICE40_DEVICE,
        hdl::ICE40_PACKAGE
    )?;
    outln!("# max err vs cos^n: exhaustive over every cos code in [0,1] x every n, k_s·I at full scale, from the Rust models")?;
    out!("{}", hdl::cost_table(&rows))?;
    Ok(())
}
