//! `glint bench lobes`: throughput of the lobe kernels against libm powf and a copy.

use std::io::Write;
use std::time::Duration;

use anyhow::{bail, Context};
use glint_lobe::measure::{cosines, measure, Workload, SAMPLE_TIME};
use glint_lobe::{KernelPath, Lobe, LobeKind};
use serde_json::json;

/// Subcommands of `glint bench`.
#[derive(clap::Subcommand)]
pub enum Command {
    /// Evaluations per second of every lobe's batch kernel, single thread, against
    /// libm powf (cos^n) and a plain copy of the same bytes.
    Lobes(LobesArgs),
    /// Lobe evaluations per second on the GPU adapter (`--device gpu`'s: any adapter,
    /// lavapipe included): K_v for v = 3..=6 against pow as GPUs compute it,
    /// exp2(n log2 c) (docs/gpu.md).
    GpuLobes(GpuLobesArgs),
}

/// Arguments of `glint bench gpu-lobes`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  glint bench gpu-lobes\n  \
glint bench gpu-lobes --count 4194304 --reps 1024   (a datacenter GPU)")]
pub struct GpuLobesArgs {
    /// Shininess exponent n of cos^n (0..=10000).
    #[arg(long, default_value_t = 100.0)]
    n: f64,
    /// Cosines in the buffer (one invocation each), 64..=16777216.
    #[arg(long, default_value_t = 1 << 20)]
    count: u32,
    /// Lobe evaluations per invocation, 1..=65536.
    #[arg(long, default_value_t = 256)]
    reps: u32,
    /// Timed dispatches per variant (the fastest is reported), after one warm-up.
    #[arg(long, default_value_t = 3)]
    runs: u32,
}

/// Largest array length accepted by `--len`: 16 Mi elements (64 MiB per array; the
/// measurement holds three such arrays).
const MAX_LEN: usize = 1 << 24;

/// Arguments of `glint bench lobes`.
#[derive(clap::Args)]
#[command(
    after_help = "Each workload maps an f32 array of cosines (angles spread over \
0..90 degrees) to an array of results. 4096 elements (16 KiB in + 16 KiB out) stay in \
the L1 cache; 1048576 (4 MiB + 4 MiB) do not, so there the copy is the bound. \
Figures are the fastest of many ~1 ms samples (other processes only slow a sample \
down); expect some noise on a busy machine.\n\nExamples:\n  glint bench lobes\n  \
glint bench lobes --n 1000 --v 5 --len 4096 --json"
)]
pub struct LobesArgs {
    /// Shininess exponent n of cos^n (0..=10000).
    #[arg(long, default_value_t = 100.0, allow_negative_numbers = true)]
    n: f64,
    /// The power fits (k, g, minimax) raise their base to 2^v (0..=10).
    #[arg(long, default_value_t = 4)]
    v: u32,
    /// Array lengths to measure, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [4096usize, 1 << 20])]
    len: Vec<usize>,
    /// Time spent measuring each workload at each length, in milliseconds.
    #[arg(long, default_value_t = 120)]
    budget_ms: u64,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

/// Runs `glint bench`.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Lobes(args) => lobes(args),
        Command::GpuLobes(args) => gpu_lobes(args),
    }
}

#[cfg(feature = "gpu")]
fn gpu_lobes(args: GpuLobesArgs) -> anyhow::Result<()> {
    use glint_render::gpu::{bench_lobes, Choice, Gpu};
    if !(64..=1 << 24).contains(&args.count) || !(1..=65536).contains(&args.reps) {
        bail!(
            "--count {} --reps {}: expected 64..=16777216 and 1..=65536",
            args.count,
            args.reps
        );
    }
    if !(1..=100).contains(&args.runs) {
        bail!("invalid --runs {}: expected 1..=100", args.runs);
    }
    let gpu = Gpu::open(Choice::Any)?;
    let a = gpu.adapter();
    println!(
        "# {} ({}, {}, driver {}); n = {}; {} cosines x {} evaluations; fastest of {}",
        a.name, a.backend, a.device_type, a.driver, args.n, args.count, args.reps, args.runs
    );
    let rates = bench_lobes(&gpu, args.n, args.count, args.reps, args.runs)?;
    let pow = rates.first().map_or(f64::NAN, |r| r.evals_per_s);
    println!(
        "{:<6} {:>14} {:>8} {:>10}",
        "lobe", "evals/s", "vs pow", "mean"
    );
    for r in &rates {
        println!(
            "{:<6} {:>14.4e} {:>7.2}x {:>10.6}",
            r.name,
            r.evals_per_s,
            r.evals_per_s / pow,
            r.mean
        );
    }
    Ok(())
}

#[cfg(not(feature = "gpu"))]
fn gpu_lobes(args: GpuLobesArgs) -> anyhow::Result<()> {
    let _ = (args.n, args.count, args.reps, args.runs);
    bail!("this glint was built without its `gpu` feature: no GPU back end")
}

struct Row {
    name: String,
    len: usize,
    evals_per_sec: f64,
    median_evals_per_sec: f64,
}

fn lobes(args: LobesArgs) -> anyhow::Result<()> {
    if args.len.is_empty() {
        bail!("--len needs at least one array length");
    }
    for &len in &args.len {
        if !(1..=MAX_LEN).contains(&len) {
            bail!("invalid --len {len}: expected 1..={MAX_LEN}");
        }
    }
    if !(1..=60_000).contains(&args.budget_ms) {
        bail!("invalid --budget-ms {}: expected 1..=60000", args.budget_ms);
    }
    let lobe =
        |kind| Lobe::<f32>::new(kind, args.n, args.v).with_context(|| format!("lobe '{kind}'"));
    let mut workloads: Vec<(String, Workload)> = vec![
        ("copy".into(), Workload::Copy),
        ("libm-powf".into(), Workload::LibmPowf { n: args.n as f32 }),
        (
            "k-scalar-eval".into(),
            Workload::LobeScalar(lobe(LobeKind::EnergyFit)?),
        ),
    ];
    for &kind in LobeKind::ALL {
        workloads.push((kind.name().into(), Workload::Lobe(lobe(kind)?)));
    }
    let budget = Duration::from_millis(args.budget_ms);
    let mut rows = Vec::new();
    for &len in &args.len {
        let cos = cosines(len);
        for (name, workload) in &workloads {
            let rate = measure(workload, &cos, budget);
            rows.push(Row {
                name: name.clone(),
                len,
                evals_per_sec: rate.evals_per_sec,
                median_evals_per_sec: rate.median_evals_per_sec,
            });
        }
    }
    let mut stdout = std::io::stdout().lock();
    let written = if args.json {
        print_json(&mut stdout, &args, &rows)
    } else {
        print_table(&mut stdout, &args, &rows)
    };
    match written {
        // A closed pipe (`glint bench lobes | head`) is not an error.
        Err(err) if err.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => other.context("writing to stdout"),
    }
}

/// The reference rates (libm powf, copy) at `len`.
fn references(rows: &[Row], len: usize) -> (f64, f64) {
    let get = |name: &str| {
        rows.iter()
            .find(|r| r.len == len && r.name == name)
            .map_or(f64::NAN, |r| r.evals_per_sec)
    };
    (get("libm-powf"), get("copy"))
}

fn cpu_model() -> Option<String> {
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("model name"))?;
    Some(line.split_once(':')?.1.trim().to_string())
}

fn print_table(w: &mut impl Write, args: &LobesArgs, rows: &[Row]) -> std::io::Result<()> {
    writeln!(
        w,
        "# n = {}, v = {}; SIMD path {} ({} f32 lanes); single thread; fastest of {:?} samples",
        args.n,
        args.v,
        KernelPath::best(),
        KernelPath::best().lanes(),
        SAMPLE_TIME
    )?;
    if let Some(cpu) = cpu_model() {
        writeln!(w, "# cpu: {cpu}")?;
    }
    writeln!(
        w,
        "{:<14} {:>9} {:>11} {:>9} {:>9} {:>8}",
        "workload", "len", "evals/s", "ns/eval", "x powf", "x copy"
    )?;
    for row in rows {
        let (powf, copy) = references(rows, row.len);
        writeln!(
            w,
            "{:<14} {:>9} {:>11.3e} {:>9.3} {:>9.2} {:>8.3}",
            row.name,
            row.len,
            row.evals_per_sec,
            1e9 / row.evals_per_sec,
            row.evals_per_sec / powf,
            row.evals_per_sec / copy
        )?;
    }
    Ok(())
}

fn print_json(w: &mut impl Write, args: &LobesArgs, rows: &[Row]) -> std::io::Result<()> {
    let results: Vec<_> = rows
        .iter()
        .map(|row| {
            let (powf, copy) = references(rows, row.len);
            json!({
                "workload": row.name,
                "len": row.len,
                "evals_per_sec": row.evals_per_sec,
                "median_evals_per_sec": row.median_evals_per_sec,
                "ratio_to_libm_powf": row.evals_per_sec / powf,
                "ratio_to_copy": row.evals_per_sec / copy,
            })
        })
        .collect();
    let doc = json!({
        "n": args.n,
        "v": args.v,
        "simd_path": KernelPath::best().name(),
        "cpu": cpu_model(),
        "threads": 1,
        "sample_time_ms": SAMPLE_TIME.as_secs_f64() * 1e3,
        "budget_ms": args.budget_ms,
        "results": results,
    });
    serde_json::to_writer_pretty(&mut *w, &doc)?;
    writeln!(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(len: Vec<usize>, n: f64, budget_ms: u64) -> LobesArgs {
        LobesArgs {
            n,
            v: 4,
            len,
            budget_ms,
            json: true,
        }
    }

    #[test]
    fn bad_arguments_are_errors() {
        let msg = |a| format!("{:#}", lobes(a).unwrap_err());
        assert!(msg(args(vec![0], 100.0, 10)).contains("invalid --len 0"));
        assert!(msg(args(vec![MAX_LEN + 1], 100.0, 10)).contains("invalid --len"));
        assert!(msg(args(vec![], 100.0, 10)).contains("at least one"));
        assert!(msg(args(vec![16], 100.0, 0)).contains("invalid --budget-ms 0"));
        assert!(msg(args(vec![16], -1.0, 10)).contains("invalid shininess"));
    }

    #[test]
    fn ratios_are_against_the_same_length() {
        let row = |name: &str, len, rate| Row {
            name: name.into(),
            len,
            evals_per_sec: rate,
            median_evals_per_sec: rate,
        };
        let rows = [
            row("copy", 16, 8.0),
            row("libm-powf", 16, 2.0),
            row("copy", 32, 4.0),
            row("libm-powf", 32, 1.0),
        ];
        assert_eq!(references(&rows, 16), (2.0, 8.0));
        assert_eq!(references(&rows, 32), (1.0, 4.0));
        assert!(references(&rows, 64).0.is_nan());
    }
}
