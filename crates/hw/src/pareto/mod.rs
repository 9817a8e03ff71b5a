//! `glint hw pareto`: cost against error for every design of the three families, on
//! three targets, with each family's Pareto front.
//!
//! The exploration ([`explore`]) sizes the candidates ([`space`]), then, in parallel on
//! `jobs` threads, measures each design's errors exhaustively ([`crate::Design::errors`]),
//! lints it with Verilator, co-simulates it with Icarus Verilog against its model
//! (`vectors` vectors) and runs the three cost flows ([`crate::hdl::cost_flows`]). Each
//! finished design is stored in the cache directory under a hash of its JSON and the
//! flow version, so an interrupted run resumes where it stopped. [`write_csv`] and
//! [`plot`] write the results; [`cosim_fronts`] co-simulates the front designs at more
//! vectors. [`verdict`] computes docs/hardware.md's verdict from a `pareto.csv`.

mod csv_io;
mod plot;
pub mod space;
pub mod verdict;

use std::hash::Hasher;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use csv_io::{csv_text, import_csv, read_csv, widths, write_csv, CsvRow, CSV_HEADER};
pub use plot::{plot, Axis, TARGETS};
pub use space::{candidates, shrink, Candidate};

use crate::hdl::{cosim, cost_flows, extra_flows, lint, Costs, ToolError};
use crate::{Design, DesignErrors, HwError};

/// Changes whenever a flow or the error definition changes, so old cache entries are
/// not reused.
pub const FLOW_VERSION: &str = "pareto-2 yosys-gates-rom-bits/ice40-hx8k/ecp5";

/// Seed of every co-simulation's random vectors.
pub const COSIM_SEED: u64 = 30;

/// Why the exploration failed.
#[derive(Debug, thiserror::Error)]
pub enum ParetoError {
    /// A design is invalid.
    #[error(transparent)]
    Hw(#[from] HwError),
    /// A tool failed.
    #[error("{id}: {source}")]
    Tool {
        /// The design.
        id: String,
        /// The failure.
        #[source]
        source: ToolError,
    },
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A plot could not be drawn.
    #[error("plot {file}: {message}")]
    Plot {
        /// The file.
        file: String,
        /// What went wrong.
        message: String,
    },
}

impl ParetoError {
    fn file(path: &Path, e: impl std::fmt::Display) -> ParetoError {
        ParetoError::File {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    }
}

/// What a co-simulation and lint found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Verified {
    /// `verilator --lint-only -Wall` printed nothing.
    pub lint_clean: bool,
    /// Vectors co-simulated.
    pub vectors: u64,
    /// Clocks where the Verilog differed from the model.
    pub mismatches: u64,
}

/// Everything measured for one design (what the cache holds), or, for a design not
/// measured yet, its errors alone (`costs` and `verified` are `None`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    /// Error figures.
    pub errors: DesignErrors,
    /// Cost on the three targets (`None`: not measured).
    pub costs: Option<Costs>,
    /// Bits of tables the design holds.
    pub rom_bits: u64,
    /// Latency, clocks (every design takes one input per clock).
    pub latency: u32,
    /// Lint and co-simulation (`None`: not run).
    pub verified: Option<Verified>,
    /// Seconds the measurement took (wall).
    pub seconds: f64,
    /// When the costs were measured (UTC, RFC 3339), or what is known of it.
    #[serde(default)]
    pub measured_at: String,
    /// The flow version and the tool versions that measured the costs.
    #[serde(default)]
    pub tools: String,
}

impl Measured {
    /// Whether the costs were measured (the cost flows ran).
    pub fn has_costs(&self) -> bool {
        self.costs.is_some()
    }
}

/// The first line of `program flag`'s output, or `program: not found`.
fn version_of(program: &str, flag: &str) -> String {
    match std::process::Command::new(program).arg(flag).output() {
        Ok(o) => {
            let text = format!(
                "{}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            );
            text.lines().next().unwrap_or("").trim().to_string()
        }
        Err(_) => format!("{program}: not found"),
    }
}

/// [`FLOW_VERSION`] and the versions of yosys, nextpnr-ice40, Icarus Verilog and
/// Verilator on this machine, `; `-separated (what a row's `tools` column records).
pub fn tool_versions() -> String {
    [
        FLOW_VERSION.to_string(),
        version_of("yosys", "-V"),
        version_of("nextpnr-ice40", "--version"),
        version_of("iverilog", "-V"),
        version_of("verilator", "--version"),
    ]
    .join("; ")
}

/// The time now, UTC, RFC 3339 to the second.
pub fn now_utc() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    chrono::DateTime::<chrono::Utc>::from_timestamp(secs, 0)
        .map(|t| t.to_rfc3339_opts(chrono::SecondsFormat::Secs, true))
        .unwrap_or_default()
}

/// Which fronts a design is on (within its family and output width).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fronts {
    /// Per target of [`TARGETS`]: error against `cos^n` (n 16-1023) vs cost.
    pub power: [bool; 3],
    /// Per target: error against the own lobe vs cost.
    pub lobe: [bool; 3],
}

impl Fronts {
    /// On any front.
    pub fn any(&self) -> bool {
        self.power.iter().chain(&self.lobe).any(|&b| b)
    }
}

/// One row of `pareto.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The candidate.
    pub candidate: Candidate,
    /// Its measurements.
    pub measured: Measured,
    /// Its fronts.
    pub fronts: Fronts,
}

/// How to run the exploration.
#[derive(Clone, Debug)]
pub struct Options {
    /// The CI subset.
    pub quick: bool,
    /// Designs measured at once (each runs yosys/nextpnr/iverilog one after another).
    pub jobs: usize,
    /// Cache directory (finished designs, and the sized candidate list).
    pub cache: PathBuf,
    /// Co-simulation vectors per design.
    pub vectors: usize,
    /// Measure nothing new: the designs already in the cache get their measured rows,
    /// every other design a row with its errors (computed, exhaustive) and empty costs.
    pub cached_only: bool,
    /// The tools' versions, recorded in each newly measured design ([`tool_versions`]).
    pub tools: String,
    /// iCE40 place-and-route seeds per design (1, 2, ...); a cached design measured with
    /// fewer gets the missing seeds, and the `-nodsp` ECP5 run, added ([`extra_flows`]).
    pub seeds: usize,
}

/// The cache key of a design: FNV-1a of its JSON, the flow version and the vectors.
pub fn key(design: &Design, vectors: usize) -> String {
    let mut h = fnv::FnvHasher::default();
    h.write(design.to_json().as_bytes());
    h.write(FLOW_VERSION.as_bytes());
    h.write(&(vectors as u64).to_le_bytes());
    format!("{:016x}", h.finish())
}

/// Measures one design in `work` (removed afterwards; the result is what is kept).
fn measure_design(
    c: &Candidate,
    vectors: usize,
    seeds: usize,
    work: &Path,
    tools: &str,
) -> Result<Measured, ParetoError> {
    let started = Instant::now();
    let measured_at = now_utc();
    let tool = |source| ParetoError::Tool {
        id: c.id.clone(),
        source,
    };
    let unit = c.design.hdl()?;
    let errors = c.design.errors()?;
    let v = match &c.design {
        Design::Kv(cfg) => cfg.v,
        _ => 4,
    };
    let lint_clean = match lint(unit.as_ref(), &work.join("lint")) {
        Ok(()) => true,
        Err(ToolError::Failed { .. }) => false,
        Err(e) => return Err(tool(e)),
    };
    let r = cosim(unit.as_ref(), vectors, COSIM_SEED, v, &work.join("sim")).map_err(tool)?;
    let mut costs = cost_flows(unit.as_ref(), &work.join("synth")).map_err(tool)?;
    extra_flows(unit.as_ref(), &work.join("synth"), &mut costs, seeds).map_err(tool)?;
    Ok(Measured {
        errors,
        costs: Some(costs),
        rom_bits: unit.rom_bits(),
        latency: unit.latency(),
        verified: Some(Verified {
            lint_clean,
            vectors: r.vectors,
            mismatches: r.mismatches + (r.vectors - r.passed.min(r.vectors)),
        }),
        seconds: started.elapsed().as_secs_f64(),
        measured_at,
        tools: tools.to_string(),
    })
}

/// One design's measurement: from the cache (topped up with the extra flows it lacks,
/// unless `--cached-only`), or measured now and cached; with how it was had.
fn measure_or_cached(
    c: &Candidate,
    opts: &Options,
) -> Result<(Measured, &'static str), ParetoError> {
    let entry = opts.cache.join(key(&c.design, opts.vectors));
    let file = entry.join("measured.json");
    let cached = std::fs::read_to_string(&file)
        .ok()
        .and_then(|t| serde_json::from_str::<Measured>(&t).ok());
    let (m, how) = match cached {
        Some(m)
            if !opts.cached_only && m.costs.as_ref().is_some_and(|k| k.needs_extra(opts.seeds)) =>
        {
            (top_up(c, m, opts, &entry)?, "cached, extra flows run")
        }
        Some(m) => (m, "cached"),
        None if opts.cached_only => (errors_only(c)?, "not measured"),
        None => {
            let work = entry.join("work");
            let m = measure_design(c, opts.vectors, opts.seeds, &work, &opts.tools)?;
            let text = serde_json::to_string_pretty(&m).map_err(|e| ParetoError::file(&file, e))?;
            glint_io::write_atomic(&file, |w| w.write_all(text.as_bytes()))
                .map_err(|e| ParetoError::file(&file, e))?;
            // The netlists and vectors are large; the result is what is kept.
            let _ = std::fs::remove_dir_all(&work);
            (m, "measured")
        }
    };
    Ok((m, how))
}

/// Runs the extra flows ([`extra_flows`]) a cached design lacks and writes it back; its
/// `tools` gains this run's versions, its `measured_at` the time of the addition.
fn top_up(
    c: &Candidate,
    mut m: Measured,
    opts: &Options,
    entry: &Path,
) -> Result<Measured, ParetoError> {
    let started = Instant::now();
    let tool = |source| ParetoError::Tool {
        id: c.id.clone(),
        source,
    };
    let unit = c.design.hdl()?;
    let work = entry.join("work");
    if let Some(costs) = m.costs.as_mut() {
        extra_flows(unit.as_ref(), &work.join("synth"), costs, opts.seeds).map_err(tool)?;
    }
    let _ = std::fs::remove_dir_all(&work);
    m.seconds += started.elapsed().as_secs_f64();
    m.measured_at = format!("{}; extra flows {}", m.measured_at, now_utc());
    if !m.tools.contains(&opts.tools) {
        m.tools = format!("{}; extra flows: {}", m.tools, opts.tools);
    }
    let file = entry.join("measured.json");
    let text = serde_json::to_string_pretty(&m).map_err(|e| ParetoError::file(&file, e))?;
    glint_io::write_atomic(&file, |w| w.write_all(text.as_bytes()))
        .map_err(|e| ParetoError::file(&file, e))?;
    Ok(m)
}

/// A design's errors, table bits and latency, without the flows (no tools run).
fn errors_only(c: &Candidate) -> Result<Measured, ParetoError> {
    let started = Instant::now();
    let unit = c.design.hdl()?;
    Ok(Measured {
        errors: c.design.errors()?,
        costs: None,
        rom_bits: unit.rom_bits(),
        latency: unit.latency(),
        verified: None,
        seconds: started.elapsed().as_secs_f64(),
        measured_at: String::new(),
        tools: String::new(),
    })
}

/// The sized candidates, from the cache if a previous run sized them.
fn cached_candidates(
    opts: &Options,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Candidate>, ParetoError> {
    // The file names the design space's version: a space with other designs (here
    // space 3: K_v and the exact unit sized at the same cos^n budgets) is sized anew,
    // while the measured designs it shares with an older space stay cached.
    let file = opts.cache.join(if opts.quick {
        "candidates-quick.json"
    } else {
        "candidates-3.json"
    });
    if let Ok(text) = std::fs::read_to_string(&file) {
        if let Ok(c) = serde_json::from_str::<Vec<Candidate>>(&text) {
            progress(&format!("{} candidates from {}", c.len(), file.display()));
            return Ok(c);
        }
    }
    let started = Instant::now();
    // Each sizing step is kept as it finishes, so a stopped run resumes its sizing too.
    let steps = opts.cache.join("sizing-3");
    let c = candidates(opts.quick, Some(&steps), progress)?;
    progress(&format!(
        "sized {} candidates in {:.0} s",
        c.len(),
        started.elapsed().as_secs_f64()
    ));
    let text = serde_json::to_string_pretty(&c).map_err(|e| ParetoError::file(&file, e))?;
    glint_io::write_atomic(&file, |w| w.write_all(text.as_bytes()))
        .map_err(|e| ParetoError::file(&file, e))?;
    Ok(c)
}

/// Runs the exploration: sizes the candidates, measures each (in parallel, cached) and
/// marks the fronts. `progress` gets one line per finished step.
pub fn explore(opts: &Options, progress: &(dyn Fn(&str) + Sync)) -> Result<Vec<Row>, ParetoError> {
    std::fs::create_dir_all(&opts.cache).map_err(|e| ParetoError::file(&opts.cache, e))?;
    let mut cands = cached_candidates(opts, progress)?;
    // The comparison units first (fewer, and each family needs its points), then K_v.
    cands.sort_by_key(|c| u8::from(matches!(c.design, Design::Kv(_))));
    if opts.cached_only {
        let measured = cands
            .iter()
            .filter(|c| {
                opts.cache
                    .join(key(&c.design, opts.vectors))
                    .join("measured.json")
                    .exists()
            })
            .count();
        progress(&format!(
            "--cached-only: {measured} of {} designs measured so far; the others get their errors and empty costs",
            cands.len()
        ));
    }
    let total = cands.len();
    let done = AtomicUsize::new(0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.jobs.max(1))
        .build()
        .map_err(|e| ParetoError::file(&opts.cache, e))?;
    let started = Instant::now();
    // New designs first, then cached ones that lack the extra flows: a run stopped
    // early has measured what the CSV misses most. The rows keep the candidates' order.
    let mut order: Vec<usize> = (0..total).collect();
    order.sort_by_key(|&i| {
        opts.cache
            .join(key(&cands[i].design, opts.vectors))
            .join("measured.json")
            .exists()
    });
    let mut measured: Vec<(usize, Result<Measured, ParetoError>)> = pool.install(|| {
        order
            .par_iter()
            .with_max_len(1)
            .map(|&i| {
                let c = &cands[i];
                let (m, how) = match measure_or_cached(c, opts) {
                    Ok(x) => x,
                    Err(e) => return (i, Err(e)),
                };
                let k = done.fetch_add(1, Ordering::SeqCst) + 1;
                let costs = match (&m.costs, &m.verified) {
                    (Some(c), Some(v)) => format!(
                        "{:.0} NAND2, {} iCE40 LUTs @ {:.1} MHz, ECP5 {} LUT-eq + {} MULT18; cosim {} vectors, {} mismatches",
                        c.nand2(),
                        c.ice40_luts,
                        c.ice40_fmax,
                        c.ecp5_lut_equiv(),
                        c.ecp5_mult18,
                        v.vectors,
                        v.mismatches
                    ),
                    _ => "costs not measured".to_string(),
                };
                progress(&format!(
                    "[{k}/{total}, {:.0} s] {}: {how} ({:.0} s): lobe {:.3}, cos^n(16+) {:.3} LSB; {costs}",
                    started.elapsed().as_secs_f64(),
                    c.id,
                    m.seconds,
                    m.errors.lobe,
                    m.errors.power_16_up(),
                ));
                (i, Ok(m))
            })
            .collect()
    });
    measured.sort_by_key(|(i, _)| *i);
    let measured = measured.into_iter().map(|(_, m)| m);
    let mut rows = Vec::with_capacity(total);
    for (c, m) in cands.into_iter().zip(measured) {
        rows.push(Row {
            candidate: c,
            measured: m?,
            fronts: Fronts::default(),
        });
    }
    mark_fronts(&mut rows);
    Ok(rows)
}

/// Marks each row's fronts: within its family and output width, no other design is at
/// most as costly and at most as wrong, and strictly better in one. Designs whose
/// costs are not measured are on no front and dominate none.
pub fn mark_fronts(rows: &mut [Row]) {
    let n = rows.len();
    for (t, axis) in TARGETS.iter().enumerate() {
        for by_lobe in [false, true] {
            let point = |r: &Row| {
                let e = if by_lobe {
                    r.measured.errors.lobe
                } else {
                    r.measured.errors.power_16_up()
                };
                r.measured.costs.as_ref().map(|c| (axis.cost(c), e))
            };
            let flags: Vec<bool> = (0..n)
                .map(|i| {
                    let Some((ci, ei)) = point(&rows[i]) else {
                        return false;
                    };
                    let group =
                        |r: &Row| (r.candidate.design.family(), r.candidate.design.out_bits());
                    !(0..n).any(|j| {
                        if j == i || group(&rows[j]) != group(&rows[i]) {
                            return false;
                        }
                        let Some((cj, ej)) = point(&rows[j]) else {
                            return false;
                        };
                        cj <= ci && ej <= ei && (cj < ci || ej < ei)
                    })
                })
                .collect();
            for (r, f) in rows.iter_mut().zip(flags) {
                if by_lobe {
                    r.fronts.lobe[t] = f;
                } else {
                    r.fronts.power[t] = f;
                }
            }
        }
    }
}

/// One front design's long co-simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct FrontCosim {
    /// The design's id.
    pub id: String,
    /// Lint and co-simulation.
    pub verified: Verified,
    /// Seconds.
    pub seconds: f64,
}

/// Whether `d` is among the slowest to simulate: K_v units with generated squarer
/// arrays (dozens of 64-bit partial-product rows a stage, which Icarus evaluates 3-10
/// times slower than a unit with generic multipliers: `docs/pareto/front-cosim-1e5.csv`).
/// [`cosim_fronts`] starts these first, so the last design to finish is a short one
/// and the `jobs` threads end together.
fn slow_to_simulate(d: &Design) -> bool {
    matches!(d, Design::Kv(c) if c.squarer != crate::Squarer::Generic)
}

/// Co-simulates every row on a front with `vectors` vectors and lints it, `jobs` at a
/// time (the slowest first: K_v units with generated squarer arrays), in temporary
/// directories under `work`. The results are in the order of `rows`.
pub fn cosim_fronts(
    rows: &[(String, Design)],
    vectors: usize,
    jobs: usize,
    work: &Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<FrontCosim>, ParetoError> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .map_err(|e| ParetoError::file(work, e))?;
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_by_key(|&i| !slow_to_simulate(&rows[i].1));
    let mut done: Vec<(usize, FrontCosim)> = pool.install(|| {
        order
            .par_iter()
            .with_max_len(1)
            .map(|&i| {
                let (id, d) = &rows[i];
                let started = Instant::now();
                let tool = |source| ParetoError::Tool {
                    id: id.clone(),
                    source,
                };
                let unit = d.hdl()?;
                let dir = work.join(id);
                let lint_clean = match lint(unit.as_ref(), &dir) {
                    Ok(()) => true,
                    Err(ToolError::Failed { .. }) => false,
                    Err(e) => return Err(tool(e)),
                };
                let v = match d {
                    Design::Kv(c) => c.v,
                    _ => 4,
                };
                let r = cosim(unit.as_ref(), vectors, COSIM_SEED + 1, v, &dir).map_err(tool)?;
                let _ = std::fs::remove_dir_all(&dir);
                let f = FrontCosim {
                    id: id.clone(),
                    verified: Verified {
                        lint_clean,
                        vectors: r.vectors,
                        mismatches: r.mismatches + (r.vectors - r.passed.min(r.vectors)),
                    },
                    seconds: started.elapsed().as_secs_f64(),
                };
                progress(&format!(
                    "{id}: {} vectors, {} mismatches, lint {}, {:.0} s",
                    f.verified.vectors,
                    f.verified.mismatches,
                    if lint_clean { "clean" } else { "WARNINGS" },
                    f.seconds
                ));
                Ok((i, f))
            })
            .collect::<Result<Vec<_>, ParetoError>>()
    })?;
    done.sort_by_key(|&(i, _)| i);
    Ok(done.into_iter().map(|(_, f)| f).collect())
}
