//! `glint hw`: the fixed-point model of the specular unit (ROM contents, width sweeps,
//! stage-by-stage evaluation, exhaustive error check, Verilog, cost, Pareto fronts).

/// `write!` to stdout that returns its error instead of panicking as `print!` does: a
/// closed pipe (`glint hw check | head`) becomes [`StdoutClosed`], which [`run`] turns
/// into a quiet, successful exit; any other write error is reported.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*).map_err($crate::cmd::hw::stdout_error)
    }};
}

/// [`out!`] with a newline, as `println!`.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*).map_err($crate::cmd::hw::stdout_error)
    }};
}

mod pareto;
mod rtl;
mod verdict;

use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context};
use glint_hw::{
    check_exhaustive_size, check_ranges, format_ranges, full_scale, markdown_table, mask_ranges,
    measure, sweep_row, Coefficients, Config, Design, HwError, Input, Reference, Rom, Rounding,
    Target, Unit, MAX_CHECK_POINTS, MAX_SWEEP_POINTS, MAX_V,
};

/// Subcommands of `glint hw`.
#[derive(clap::Subcommand)]
pub enum Command {
    /// Write ROM1 (the coefficient a(n) for every n) in Verilog $readmemh format.
    #[command(
        after_help = "Examples:\n  glint hw rom --v 4 --n-bits 10 --coef-bits 16 -o rom1.hex\n  \
                      glint hw rom --v 4 --n-bits 10 --coef-bits 16 --coef minimax -o rom1_minimax.hex"
    )]
    Rom(RomArgs),
    /// Search the smallest per-stage widths meeting 0.5 and 1 LSB bounds (exhaustive).
    #[command(after_help = "Examples:\n  glint hw sweep --out-bits 8\n  \
                      glint hw sweep --out-bits 10 --v 4 --coef minimax")]
    Sweep(SweepArgs),
    /// Evaluate one input and print every stage's value.
    #[command(
        after_help = "Examples:\n  glint hw eval --cos 0.98 --n 100 --ks-rgb 255,200,180\n  \
                      glint hw eval --config unit.json --cos 0.98 --n 100 --ks-rgb 255,200,180\n  \
                      glint hw eval --print-config > unit.json"
    )]
    Eval(EvalArgs),
    /// Measure a configuration's maximum error exhaustively (every cos code, every n).
    #[command(
        after_help = "Examples:\n  glint hw check\n  glint hw check --out-bits 10\n  \
                      glint hw check --config unit.json"
    )]
    Check(CheckArgs),
    /// Write the Verilog of a unit, its self-checking testbench and test vectors.
    #[command(
        after_help = "Examples:\n  glint hw verilog -o rtl\n  glint hw verilog --config unit.json -o rtl --vectors 100000\n  \
                      glint hw verilog --unit all -o rtl\n\n\
                      Then, in DIR: iverilog -g2005 -o sim glint_kv_tb.v glint_kv.v && vvp -n sim"
    )]
    Verilog(VerilogArgs),
    /// Co-simulate the Verilog against the Rust model with Icarus Verilog, and lint it
    /// with Verilator.
    #[command(
        after_help = "Examples:\n  glint hw cosim\n  glint hw cosim --unit kv --vectors 100000 --keep rtl"
    )]
    Cosim(CosimArgs),
    /// Synthesise the units (yosys, nextpnr-ice40) and print their cost table.
    #[command(
        after_help = "Examples:\n  glint hw synth\n  glint hw synth --config unit.json --keep synth"
    )]
    Synth(SynthArgs),
    /// Explore cost against error for K_v, exact cos^n and Schlick units on three
    /// targets; write pareto.csv and the plots with each family's front.
    #[command(
        after_help = "Examples:\n  nice -n 15 glint hw pareto -o docs/pareto --cache /tmp/pareto-cache --jobs 2\n  \
                      glint hw pareto --quick -o /tmp/quick\n  \
                      glint hw pareto -o /tmp/f --cosim-fronts docs/pareto/pareto.csv --front-vectors 100000"
    )]
    Pareto(pareto::ParetoArgs),
    /// Compute docs/hardware.md's verdict from a pareto.csv (fronts, equal-budget ratios
    /// of K_v against the exact unit, bands); print it, or check or rewrite the doc.
    #[command(
        after_help = "Examples:\n  glint hw verdict --csv docs/pareto/pareto.csv\n  \
                      glint hw verdict --csv docs/pareto/pareto.csv --check docs/hardware.md\n  \
                      glint hw verdict --csv docs/pareto/pareto.csv --write docs/hardware.md"
    )]
    Verdict(verdict::VerdictArgs),
}

/// Which Verilog unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum HdlChoice {
    /// The K_v unit of the configuration.
    Kv,
    /// The exact cos^n unit (log2/exp2 tables).
    Pow,
    /// The Schlick unit (pipelined divider).
    Schlick,
    /// All three.
    All,
}

/// Arguments of `glint hw verilog`.
#[derive(clap::Args)]
pub struct VerilogArgs {
    /// Configuration file of the K_v unit (JSON) [default: built-in].
    #[arg(long)]
    config: Option<PathBuf>,
    /// Which unit.
    #[arg(long, value_enum, default_value_t = HdlChoice::Kv)]
    unit: HdlChoice,
    /// Output directory (created if missing).
    #[arg(short, long)]
    output: PathBuf,
    /// Test vectors to write for the testbench (corners first, then random).
    #[arg(long, default_value_t = 10_000)]
    vectors: usize,
    /// Seed of the random vectors.
    #[arg(long, default_value_t = 14)]
    seed: u64,
}

/// Arguments of `glint hw cosim`.
#[derive(clap::Args)]
pub struct CosimArgs {
    /// Configuration file of the K_v unit (JSON) [default: built-in].
    #[arg(long)]
    config: Option<PathBuf>,
    /// Which unit.
    #[arg(long, value_enum, default_value_t = HdlChoice::All)]
    unit: HdlChoice,
    /// Test vectors per unit.
    #[arg(long, default_value_t = 1_000_000)]
    vectors: usize,
    /// Seed of the random vectors.
    #[arg(long, default_value_t = 14)]
    seed: u64,
    /// Keep the design, vectors and simulation in this directory instead of a
    /// temporary one.
    #[arg(long)]
    keep: Option<PathBuf>,
}

/// Arguments of `glint hw synth`.
#[derive(clap::Args)]
pub struct SynthArgs {
    /// Configuration file of the K_v unit (JSON) [default: built-in].
    #[arg(long)]
    config: Option<PathBuf>,
    /// Which unit.
    #[arg(long, value_enum, default_value_t = HdlChoice::All)]
    unit: HdlChoice,
    /// Keep the synthesis files in this directory instead of a temporary one.
    #[arg(long)]
    keep: Option<PathBuf>,
}

/// Arguments of `glint hw rom`.
#[derive(clap::Args)]
pub struct RomArgs {
    /// BMUL squarings; the power is 2^v (0..=10).
    #[arg(long, default_value_t = 4)]
    v: u32,
    /// Width of n, the ROM address (1..=13).
    #[arg(long, default_value_t = 10)]
    n_bits: u32,
    /// Width of a ROM word (integer bits are derived from the largest coefficient).
    #[arg(long, default_value_t = 16)]
    coef_bits: u32,
    /// Coefficients: k (the paper's energy fit, (n+1)/(2^v+1)) or minimax.
    #[arg(long, default_value = "k", value_parser = parse_coef)]
    coef: Coefficients,
    /// Rounding of the words: nearest or truncate.
    #[arg(long, default_value = "nearest", value_parser = parse_round)]
    round: Rounding,
    /// Output file (written atomically).
    #[arg(short, long)]
    output: PathBuf,
}

/// Arguments of `glint hw sweep`.
#[derive(clap::Args)]
pub struct SweepArgs {
    /// Output code width (k_s·I inputs and R, G, B outputs).
    #[arg(long, default_value_t = 8)]
    out_bits: u32,
    /// Values of v to sweep, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [3u32, 4, 5])]
    v: Vec<u32>,
    /// Bounds in output LSBs, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [0.5f64, 1.0])]
    bound: Vec<f64>,
    /// Coefficients in ROM1: k or minimax.
    #[arg(long, default_value = "k", value_parser = parse_coef)]
    coef: Coefficients,
    /// Width of n (1..=13).
    #[arg(long, default_value_t = 10)]
    n_bits: u32,
    /// Width of the signed cos code (Q1.(cos_bits-2)); every code in [-1, 1] is checked.
    #[arg(long, default_value_t = 16)]
    cos_bits: u32,
    /// Rounding of every stage: nearest or truncate.
    #[arg(long, default_value = "nearest", value_parser = parse_round)]
    round: Rounding,
    /// Skip the rows against cos^n (only the exact lobe).
    #[arg(long)]
    lobe_only: bool,
}

/// Arguments of `glint hw eval`.
#[derive(clap::Args)]
pub struct EvalArgs {
    /// Configuration file (JSON; missing fields take the defaults) [default: built-in].
    #[arg(long)]
    config: Option<PathBuf>,
    /// cos γ as a real number (rounded to the input code).
    #[arg(long, allow_negative_numbers = true, conflicts_with = "cos_code", required_unless_present_any = ["cos_code", "print_config"])]
    cos: Option<f64>,
    /// cos γ as the signed input code instead.
    #[arg(long, allow_negative_numbers = true)]
    cos_code: Option<i64>,
    /// Shininess exponent n.
    #[arg(long, default_value_t = 100)]
    n: u32,
    /// k_s·I for R, G, B as output-width codes.
    #[arg(long, value_delimiter = ',', num_args = 1, default_values_t = [255u64, 200, 180])]
    ks_rgb: Vec<u64>,
    /// Print the configuration (JSON) and exit; a starting point for --config files.
    #[arg(long)]
    print_config: bool,
}

/// Arguments of `glint hw check`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// Configuration file (JSON) [default: built-in].
    #[arg(long)]
    config: Option<PathBuf>,
    /// Override the configuration's output width.
    #[arg(long)]
    out_bits: Option<u32>,
}

fn parse_coef(s: &str) -> Result<Coefficients, String> {
    s.trim()
        .parse()
        .map_err(|e: glint_hw::HwError| e.to_string())
}

fn parse_round(s: &str) -> Result<Rounding, String> {
    s.trim()
        .parse()
        .map_err(|e: glint_hw::HwError| e.to_string())
}

/// Standard output was closed by its reader (`glint hw check | head`): the rest of the
/// output is not wanted, so the command stops and exits as a success, as `head` expects.
#[derive(Debug)]
pub(crate) struct StdoutClosed;

impl std::fmt::Display for StdoutClosed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("standard output closed")
    }
}

impl std::error::Error for StdoutClosed {}

/// `result` of printing, with a closed stdout ([`StdoutClosed`]) taken as success: for
/// the summaries of long runs, whose work and files matter more than their output.
pub(crate) fn unless_closed(result: anyhow::Result<()>) -> anyhow::Result<()> {
    match result {
        Err(e) if e.is::<StdoutClosed>() => Ok(()),
        other => other,
    }
}

/// The error of a failed write to stdout: [`StdoutClosed`] for a closed pipe.
pub(crate) fn stdout_error(e: std::io::Error) -> anyhow::Error {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        StdoutClosed.into()
    } else {
        anyhow::Error::new(e).context("writing to stdout")
    }
}

/// Runs `glint hw`.
pub fn run(command: Command) -> anyhow::Result<()> {
    unless_closed(dispatch(command))
}

fn dispatch(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Rom(args) => rom(args),
        Command::Sweep(args) => sweep(args),
        Command::Eval(args) => eval(args),
        Command::Check(args) => check(args),
        Command::Verilog(args) => rtl::verilog(args),
        Command::Cosim(args) => rtl::cosim(args),
        Command::Synth(args) => rtl::synth(args),
        Command::Pareto(args) => pareto::run(args),
        Command::Verdict(args) => verdict::run(args),
    }
}

/// Largest configuration file read: a real one is well under 1 KiB, and reading is
/// bounded so that `--config /dev/zero` or a huge file fails instead of filling memory.
const MAX_CONFIG_BYTES: u64 = 1 << 20;

/// The configuration in `path` (bounded read, typed parse), or the default.
pub(crate) fn load_config(path: Option<&Path>) -> anyhow::Result<Config> {
    match path {
        None => Ok(Config::default()),
        Some(p) => {
            let text = read_bounded(p)?;
            Config::from_json(&text).with_context(|| format!("in {}", p.display()))
        }
    }
}

/// A configuration file's text, read up to [`MAX_CONFIG_BYTES`].
fn read_bounded(p: &Path) -> anyhow::Result<String> {
    let reading = || format!("reading configuration {}", p.display());
    let mut text = String::new();
    std::fs::File::open(p)
        .with_context(reading)?
        .take(MAX_CONFIG_BYTES + 1)
        .read_to_string(&mut text)
        .with_context(reading)?;
    if text.len() as u64 > MAX_CONFIG_BYTES {
        bail!(
            "configuration {} is larger than {MAX_CONFIG_BYTES} bytes; it is not a glint hw configuration",
            p.display()
        );
    }
    Ok(text)
}

/// The design in `path` (a K_v configuration, or any family with `"family"`), or the
/// default K_v unit; bounded read as [`load_config`].
fn load_design(path: Option<&Path>) -> anyhow::Result<Design> {
    match path {
        None => Ok(Design::Kv(Config::default())),
        Some(p) => {
            let text = read_bounded(p)?;
            Design::from_json(&text).with_context(|| format!("in {}", p.display()))
        }
    }
}

/// Runs `f`, naming the configuration file in its error if there is one.
fn in_file<T>(path: Option<&Path>, f: impl FnOnce() -> Result<T, HwError>) -> anyhow::Result<T> {
    match path {
        None => Ok(f()?),
        Some(p) => f().with_context(|| format!("in {}", p.display())),
    }
}

/// Builds the unit, naming the configuration file in the error if there is one.
fn build_unit(config: Config, path: Option<&Path>) -> anyhow::Result<Unit> {
    in_file(path, || Unit::new(config))
}

fn rom(args: RomArgs) -> anyhow::Result<()> {
    let rom = Rom::new(args.coef, args.v, args.n_bits, args.coef_bits, args.round)?;
    glint_io::write_atomic(&args.output, |w| w.write_all(rom.to_readmemh().as_bytes()))?;
    eprintln!(
        "wrote {} words of {} bits (UQ{}.{}, {} coefficients, v = {}) to {}",
        rom.words().len(),
        rom.word_bits(),
        rom.int_bits(),
        rom.frac_bits(),
        rom.coefficients(),
        rom.v(),
        args.output.display()
    );
    Ok(())
}

fn sweep(args: SweepArgs) -> anyhow::Result<()> {
    for &b in &args.bound {
        if !(b.is_finite() && b > 0.0) {
            bail!("invalid --bound {b}: a bound is a positive number of output LSBs");
        }
    }
    let started = Instant::now();
    let mut rows = Vec::new();
    let refs: &[Reference] = if args.lobe_only {
        &[Reference::Lobe]
    } else {
        &[Reference::Lobe, Reference::Power]
    };
    for &v in &args.v {
        // Before `square_frac: vec![..; v]` below: no allocation sized by unchecked input.
        if v > MAX_V {
            return Err(HwError::InvalidV(v).into());
        }
        let base = Config {
            v,
            n_bits: args.n_bits,
            cos_bits: args.cos_bits,
            coefficients: args.coef,
            coef_round: args.round,
            mul_round: args.round,
            square_frac: vec![1; v as usize],
            square_round: args.round,
            out_bits: args.out_bits,
            out_round: args.round,
            ..Config::default()
        };
        base.validate()?;
        // Before the ROM is built (minimax coefficients take seconds) or anything runs.
        check_exhaustive_size(&base, MAX_SWEEP_POINTS)?;
        Unit::new(Config {
            coef_bits: 64,
            ..base.clone()
        })?;
        for &reference in refs {
            for &bound in &args.bound {
                let row = sweep_row(&base, Target { reference, bound }, &mut |line| {
                    eprintln!("[{:>6.1} s] {line}", started.elapsed().as_secs_f64())
                })?;
                rows.push(row);
            }
        }
    }
    let points = rows.first().map_or(0, |r| r.points_per_check);
    outln!(
        "# glint hw sweep: out_bits = {}, coefficients = {}, n_bits = {}, cos Q1.{} ({} bits), rounding {}",
        args.out_bits,
        args.coef,
        args.n_bits,
        args.cos_bits.saturating_sub(2),
        args.cos_bits,
        args.round
    )?;
    outln!(
        "# error = |code - F·L(c,n)| in LSBs, F = k_s·I full scale = {}; exhaustive: every cos code in [-1,1] (lobe) or [0,1] (cos^n) x every n = {} points per check",
        full_scale(args.out_bits),
        points
    )?;
    outln!(
        "# 'n where asked': for cos^n, the n where an ideal unit (exact lobe, correctly rounded) meets the bound"
    )?;
    out!("{}", markdown_table(&rows))?;
    eprintln!("total {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

fn eval(args: EvalArgs) -> anyhow::Result<()> {
    let config = load_config(args.config.as_deref())?;
    let unit = build_unit(config, args.config.as_deref())?;
    if args.print_config {
        outln!("{}", unit.config().to_json())?;
        return Ok(());
    }
    if args.ks_rgb.len() != 3 {
        bail!(
            "--ks-rgb takes three codes R,G,B, got {}",
            args.ks_rgb.len()
        );
    }
    let cos = match (args.cos, args.cos_code) {
        (_, Some(code)) => code,
        (Some(c), None) => unit.cos_code(c)?,
        (None, None) => bail!("give --cos or --cos-code"),
    };
    let input = Input {
        cos,
        n: args.n,
        ks: [args.ks_rgb[0], args.ks_rgb[1], args.ks_rgb[2]],
    };
    let table = unit.trace_table(&input)?;
    let cfg = unit.config();
    outln!(
        "# glint hw eval: v = {}, coefficients = {}, latency = {} clocks, one input per clock",
        cfg.v,
        cfg.coefficients,
        unit.latency()
    )?;
    outln!(
        "{:<12} {:<18} {:>22} {:>18}  value",
        "stage",
        "format",
        "code",
        "hex"
    )?;
    for r in &table.rows {
        outln!(
            "{:<12} {:<18} {:>22} {:>18}  {}",
            r.stage,
            r.format,
            r.code,
            r.hex,
            r.value
        )?;
    }
    let rgb = table.output.rgb;
    outln!("# output R,G,B = {},{},{}", rgb[0], rgb[1], rgb[2])?;
    Ok(())
}

/// Prints the figures `glint hw pareto` gives for `design` (same function, same format).
fn print_design_errors(design: &Design) -> anyhow::Result<()> {
    let e = design.errors()?;
    let ranges: Vec<String> = glint_hw::N_RANGES
        .iter()
        .zip(e.power)
        .map(|(&(a, b), x)| format!("n {a}-{b} {x:.4}"))
        .collect();
    outln!(
        "pareto figures ({}): lobe {:.4} | cos^n {} | all n {:.4}",
        design.family(),
        e.lobe,
        ranges.join(" | "),
        e.power_all
    )?;
    Ok(())
}

fn check(args: CheckArgs) -> anyhow::Result<()> {
    let design = load_design(args.config.as_deref())?;
    let mut config = match design {
        Design::Kv(c) => c,
        other => {
            let other = match args.out_bits {
                Some(o) => other.with_out_bits(o),
                None => other,
            };
            in_file(args.config.as_deref(), || other.hdl().map(|_| ()))?;
            outln!("# glint hw check: {}", other.to_json())?;
            return print_design_errors(&other);
        }
    };
    if let Some(b) = args.out_bits {
        config.out_bits = b;
    }
    // Validate and bound the work before the ROM is built or anything runs.
    in_file(args.config.as_deref(), || config.validate())?;
    check_exhaustive_size(&config, MAX_CHECK_POINTS)?;
    let unit = build_unit(config, args.config.as_deref())?;
    let started = Instant::now();
    let m = measure(&unit);
    let secs = started.elapsed().as_secs_f64();
    let cfg = unit.config();
    let last = (1u32 << cfg.n_bits) - 1;
    outln!(
        "# glint hw check: {} points (every cos code in [-1,1] x every n 0..={last}), k_s·I = {} (full scale), {:.1} s",
        m.points,
        unit.full_scale(),
        secs
    )?;
    outln!("# configuration: {}", serde_json_line(cfg))?;
    let w = m.worst_lobe(0..=last);
    outln!(
        "max error vs exact lobe ({}): {:.4} LSB at n = {}, cos = {:.9}",
        if cfg.coefficients == Coefficients::EnergyFit {
            "K_v"
        } else {
            "minimax power lobe"
        },
        w.error,
        w.n,
        unit.cos_value(w.cos)
    )?;
    outln!(
        "{:<12} {:>14} {:>22} {:>22}",
        "n range",
        "vs lobe",
        "vs cos^n (unit)",
        "vs cos^n (ideal)"
    )?;
    for (a, b) in check_ranges(last) {
        outln!(
            "{:<12} {:>14.4} {:>22.4} {:>22.4}",
            format!("{a}-{b}"),
            m.worst_lobe(a..=b).error,
            m.worst_power(a..=b).error,
            m.worst_ideal_power(a..=b).error
        )?;
    }
    let excess = m
        .per_n
        .iter()
        .map(|e| e.power - e.ideal_power)
        .fold(f64::MIN, f64::max);
    outln!("max over n of (unit - ideal) error vs cos^n: {excess:.4} LSB")?;
    print_design_errors(&Design::Kv(cfg.clone()))?;
    for bound in [0.5, 1.0] {
        let ok: Vec<bool> = m
            .per_n
            .iter()
            .map(|e| e.power <= bound + glint_hw::BOUND_SLACK_LSB)
            .collect();
        let ranges = mask_ranges(&ok);
        outln!(
            "n where the unit is within {bound} LSB of cos^n: {}",
            format_ranges(&ranges)
        )?;
    }
    Ok(())
}

fn serde_json_line(cfg: &Config) -> String {
    serde_json::to_string(cfg).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rom_file_is_readmemh_and_bad_runs_leave_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("rom1.hex");
        let args = |v: u32| RomArgs {
            v,
            n_bits: 10,
            coef_bits: 16,
            coef: Coefficients::EnergyFit,
            round: Rounding::Nearest,
            output: out.clone(),
        };
        run(Command::Rom(args(4))).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        let words: Vec<&str> = text.lines().filter(|l| !l.starts_with("//")).collect();
        // 1024 words; a(16) = 17/17 = 1.0 = 0x400 in UQ6.10.
        assert_eq!(words.len(), 1024);
        assert_eq!(words[16], "0400");
        std::fs::remove_file(&out).unwrap();
        let err = run(Command::Rom(args(11))).unwrap_err();
        assert!(format!("{err:#}").contains("v = 11"));
        assert!(!out.exists());
        // Only the temporary files' directory entries could remain; there are none.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn eval_args(config: PathBuf) -> EvalArgs {
        EvalArgs {
            config: Some(config),
            cos: Some(0.98),
            cos_code: None,
            n: 100,
            ks_rgb: vec![255, 200, 180],
            print_config: false,
        }
    }

    /// One line naming the file, without a panic.
    fn one_line_error(r: anyhow::Result<()>, file: &Path, want: &str) {
        let msg = format!("{:#}", r.unwrap_err());
        assert!(msg.contains(&file.display().to_string()), "{msg}");
        assert!(msg.contains(want), "{msg}");
        assert!(!msg.contains('\n'), "{msg}");
    }

    #[test]
    fn hostile_configuration_files_fail_with_one_line() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // The review's repros: a u32::MAX width (wrapped past validation, then a
        // formatting panic in eval and a hang in check), a check too large to run, and
        // a JSON array read as positional fields.
        let huge = write(d, "huge.json", r#"{"cos_bits": 4294967295}"#);
        one_line_error(
            run(Command::Eval(eval_args(huge.clone()))),
            &huge,
            "4294967296 bits",
        );
        let mut print = eval_args(huge.clone());
        print.print_config = true;
        one_line_error(run(Command::Eval(print)), &huge, "cos_bits <= 63");
        let check = |p: &Path| {
            run(Command::Check(CheckArgs {
                config: Some(p.to_path_buf()),
                out_bits: None,
            }))
        };
        one_line_error(check(&huge), &huge, "64-bit");
        let big = write(d, "big.json", r#"{"cos_bits": 60, "n_bits": 13}"#);
        let msg = format!("{:#}", check(&big).unwrap_err());
        assert!(msg.contains("more than the 4294967296"), "{msg}");
        let array = write(d, "array.json", "[4, 10]");
        one_line_error(
            run(Command::Eval(eval_args(array.clone()))),
            &array,
            "JSON object",
        );
        one_line_error(check(&array), &array, "JSON object");
        // Every other width at u32::MAX is refused too.
        for field in ["v", "n_bits", "coef_bits", "mul_frac", "out_bits"] {
            let p = write(d, "f.json", &format!(r#"{{"{field}": 4294967295}}"#));
            one_line_error(check(&p), &p, field);
        }
        let p = write(d, "sq.json", r#"{"square_frac": [14, 14, 14, 4294967295]}"#);
        one_line_error(check(&p), &p, "square_frac");
        // A file far larger than any configuration is refused without reading it all.
        let p = write(
            d,
            "large.json",
            &" ".repeat((MAX_CONFIG_BYTES + 10) as usize),
        );
        one_line_error(check(&p), &p, "larger than");
    }

    fn sweep_args(v: Vec<u32>, cos_bits: u32, n_bits: u32) -> SweepArgs {
        SweepArgs {
            out_bits: 8,
            v,
            bound: vec![1.0],
            coef: Coefficients::EnergyFit,
            n_bits,
            cos_bits,
            round: Rounding::Nearest,
            lobe_only: true,
        }
    }

    #[test]
    fn sweep_refuses_absurd_sizes_before_working() {
        // The review's repro: wrapped to 8192 points and ran for ever.
        let e = run(Command::Sweep(sweep_args(vec![4], 60, 13))).unwrap_err();
        assert!(
            format!("{e:#}").contains("more than the 268435456"),
            "{e:#}"
        );
        let e = run(Command::Sweep(sweep_args(vec![4], u32::MAX, 10))).unwrap_err();
        assert!(format!("{e:#}").contains("cos_bits <= 63"), "{e:#}");
        // v = u32::MAX would size a 16 GiB square_frac list before validation.
        let e = run(Command::Sweep(sweep_args(vec![u32::MAX], 16, 10))).unwrap_err();
        assert!(format!("{e:#}").contains("v = 4294967295"), "{e:#}");
    }
}
