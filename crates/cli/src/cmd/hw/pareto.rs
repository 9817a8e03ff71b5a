//! `glint hw pareto`: the cost/error exploration of the three families (see
//! `glint_hw::pareto` and docs/hardware.md).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use glint_hw::pareto::{self, Options};

/// Arguments of `glint hw pareto`.
#[derive(clap::Args)]
pub struct ParetoArgs {
    /// Output directory: pareto.csv, the plots (PNG and SVG) and front-cosim.csv.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The CI subset: three fixed designs at 8 bits (one a family), no sizing.
    #[arg(long)]
    pub quick: bool,
    /// Designs synthesised at once.
    #[arg(long, default_value_t = 2)]
    pub jobs: usize,
    /// Cache of finished designs (a rerun resumes from it) [default: OUTPUT/cache].
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Co-simulation vectors per design in the exploration.
    #[arg(long, default_value_t = 10_000)]
    pub vectors: usize,
    /// After the exploration, co-simulate every front design with this many vectors
    /// (0: skip) and write front-cosim.csv.
    #[arg(long, default_value_t = 0)]
    pub front_vectors: usize,
    /// Measure nothing new: write the CSV and plots from the designs measured in the
    /// cache; every other design of the space gets a row with its errors (computed)
    /// and empty cost cells.
    #[arg(long)]
    pub cached_only: bool,
    /// Before the run, put this pareto.csv's measured rows into the cache (so a run
    /// resumes from committed results instead of measuring them again).
    #[arg(long)]
    pub import_csv: Option<PathBuf>,
    /// Only co-simulate the front designs of this pareto.csv (with --front-vectors,
    /// default 10^5), no exploration.
    #[arg(long)]
    pub cosim_fronts: Option<PathBuf>,
    /// iCE40 place-and-route seeds per design (the median Fmax is reported); cached
    /// designs measured with fewer get the missing seeds and the ECP5 -nodsp run
    /// [default: 3; 1 with --quick].
    #[arg(long, value_name = "N")]
    pub seeds: Option<usize>,
}

/// Most place-and-route seeds per design.
const MAX_SEEDS: usize = 15;

/// Largest vector count per co-simulation.
const MAX_VECTORS: usize = 100_000_000;

fn log(started: Instant) -> impl Fn(&str) + Sync {
    move |line: &str| eprintln!("[{:>7.1} s] {line}", started.elapsed().as_secs_f64())
}

/// Runs `glint hw pareto`.
pub fn run(args: ParetoArgs) -> anyhow::Result<()> {
    if args.vectors == 0 || args.vectors > MAX_VECTORS || args.front_vectors > MAX_VECTORS {
        bail!("invalid --vectors/--front-vectors: expected 1..={MAX_VECTORS}");
    }
    if args.jobs == 0 || args.jobs > 64 {
        bail!("invalid --jobs {}: expected 1..=64", args.jobs);
    }
    let seeds = args.seeds.unwrap_or(if args.quick { 1 } else { 3 });
    if seeds == 0 || seeds > MAX_SEEDS {
        bail!("invalid --seeds {seeds}: expected 1..={MAX_SEEDS}");
    }
    let started = Instant::now();
    let progress = log(started);
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("creating {}", args.output.display()))?;
    if let Some(csv) = &args.cosim_fronts {
        let rows = pareto::read_csv(csv)?;
        let vectors = if args.front_vectors == 0 {
            100_000
        } else {
            args.front_vectors
        };
        return fronts(&args, &rows, vectors, &progress);
    }
    let cache = args
        .cache
        .clone()
        .unwrap_or_else(|| args.output.join("cache"));
    if let Some(csv) = &args.import_csv {
        std::fs::create_dir_all(&cache).with_context(|| format!("creating {}", cache.display()))?;
        let (new, kept, empty) = pareto::import_csv(csv, &cache)?;
        progress(&format!(
            "{}: {new} measured rows put into {}, {kept} already there, {empty} without costs",
            csv.display(),
            cache.display()
        ));
    }
    let opts = Options {
        quick: args.quick,
        jobs: args.jobs,
        cache,
        vectors: args.vectors,
        cached_only: args.cached_only,
        tools: if args.cached_only {
            String::new()
        } else {
            pareto::tool_versions()
        },
        seeds,
    };
    let rows = pareto::explore(&opts, &progress)?;
    let csv = args.output.join("pareto.csv");
    pareto::write_csv(&csv, &rows)?;
    let files = pareto::plot(&args.output, &rows)?;
    let bad: Vec<&str> = rows
        .iter()
        .filter(|r| {
            r.measured
                .verified
                .is_some_and(|v| !v.lint_clean || v.mismatches > 0)
        })
        .map(|r| r.candidate.id.as_str())
        .collect();
    // The files are written: a closed stdout does not stop the failure check or the
    // front co-simulation below.
    super::unless_closed(print_summary(&rows, &csv, &files, started))?;
    if !bad.is_empty() {
        bail!(
            "co-simulation mismatches or lint warnings: {}",
            bad.join(", ")
        );
    }
    if args.front_vectors > 0 {
        let rows = pareto::read_csv(&csv)?;
        fronts(&args, &rows, args.front_vectors, &progress)?;
    }
    Ok(())
}

/// The summary of an exploration: designs, fronts, files, and designs per family.
fn print_summary(
    rows: &[pareto::Row],
    csv: &std::path::Path,
    files: &[String],
    started: Instant,
) -> anyhow::Result<()> {
    outln!(
        "# glint hw pareto: {} designs, {} on a front; wrote {} and {} in {:.0} s",
        rows.len(),
        rows.iter().filter(|r| r.fronts.any()).count(),
        csv.display(),
        files.join(", "),
        started.elapsed().as_secs_f64()
    )?;
    let mut fams: Vec<(String, u32, usize)> = Vec::new();
    for r in rows {
        let k = (
            r.candidate.design.family().to_string(),
            r.candidate.design.out_bits(),
        );
        match fams.iter_mut().find(|f| f.0 == k.0 && f.1 == k.1) {
            Some(f) => f.2 += 1,
            None => fams.push((k.0, k.1, 1)),
        }
    }
    for (f, o, n) in fams {
        outln!("{f} {o}-bit: {n} designs")?;
    }
    Ok(())
}

fn fronts(
    args: &ParetoArgs,
    rows: &[pareto::CsvRow],
    vectors: usize,
    progress: &(dyn Fn(&str) + Sync),
) -> anyhow::Result<()> {
    let front: Vec<(String, glint_hw::Design)> = rows
        .iter()
        .filter(|r| r.on_front)
        .map(|r| (r.id.clone(), r.design.clone()))
        .collect();
    if front.is_empty() {
        bail!("no design of the CSV is on a front");
    }
    let work = tempfile::tempdir().context("creating a temporary directory")?;
    let started = Instant::now();
    let results = pareto::cosim_fronts(&front, vectors, args.jobs, work.path(), progress)?;
    let mut text = String::from("id,vectors,mismatches,lint_clean,seconds\n");
    for r in &results {
        text += &format!(
            "{},{},{},{},{:.0}\n",
            r.id,
            r.verified.vectors,
            r.verified.mismatches,
            u8::from(r.verified.lint_clean),
            r.seconds
        );
    }
    let out = args.output.join("front-cosim.csv");
    glint_io::write_atomic(&out, |w| w.write_all(text.as_bytes()))?;
    let bad: Vec<&str> = results
        .iter()
        .filter(|r| {
            r.verified.mismatches > 0
                || !r.verified.lint_clean
                || (r.verified.vectors as usize) < vectors
        })
        .map(|r| r.id.as_str())
        .collect();
    let printed = outln!(
        "# {} front designs co-simulated with {vectors} vectors each in {:.0} s: {} failed; wrote {}",
        results.len(),
        started.elapsed().as_secs_f64(),
        bad.len(),
        out.display()
    );
    if !bad.is_empty() {
        bail!("front co-simulation failed for {}", bad.join(", "));
    }
    super::unless_closed(printed)
}
