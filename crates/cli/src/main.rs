//! `glint`: thin glue over the glint crates. Each subcommand lives in `cmd/<name>.rs`
//! with its own `Args` and `run`.

#![forbid(unsafe_code)]

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cmd;

/// mimalloc rather than glibc's malloc: see the dependency's comment in Cargo.toml.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Render 3D biomedical images with cheap, accurate specular lobes, analyse the lobes
/// against Phong's cos^n, and model the hardware unit that computes them.
#[derive(Parser)]
#[command(name = "glint", version, about, long_about = None)]
struct Cli {
    /// Memory the volumes may take, e.g. 8GiB or 600MiB (bricks of derived data are
    /// evicted to stay within it; a volume that cannot fit is refused, naming it)
    /// [default: three quarters of the machine's memory, with each volume's bricks
    /// held to half the size of its samples (at least 128 MiB; every brick of a volume
    /// whose bricks fit in 256 MiB)].
    #[arg(long, global = true, value_name = "SIZE", value_parser = parse_size)]
    memory_limit: Option<u64>,
    #[command(subcommand)]
    command: Command,
}

/// A byte count with an optional unit (`8GiB`, `600 MiB`, `2.5GB`, `1000000`).
fn parse_size(s: &str) -> Result<u64, String> {
    let size: bytesize::ByteSize = s.trim().parse()?;
    match size.as_u64() {
        0 => Err("the memory limit must be above zero".into()),
        n => Ok(n),
    }
}

#[derive(Subcommand)]
enum Command {
    /// Render a volume (or the built-in phantom) to a PNG.
    Render(cmd::render::Args),
    /// Render a scene with exact cos^n and with cheaper lobes; image metrics and a picture.
    Compare(cmd::compare::Args),
    /// The 3D point a pixel of the rendered image shows (world mm, voxel, value,
    /// label), as JSON.
    Pick(cmd::pick::Args),
    /// Extract the isosurface of a volume as an STL, PLY or OBJ mesh.
    Mesh(cmd::mesh::Args),
    /// Evaluate lobes at given angles or cosines.
    Eval(cmd::eval::Args),
    /// Accuracy of the lobes against cos^n: tables, CSVs and plots.
    Analyze(cmd::analyze::Args),
    /// Measure lobe throughput against libm powf.
    #[command(subcommand)]
    Bench(cmd::bench::Command),
    /// Describe a volume or surface file.
    Info(cmd::info::Args),
    /// A whole study: a mosaic of views (and QC slices) per input, a results table and
    /// an HTML report, resumable.
    Batch(cmd::batch::Args),
    /// Interactive viewer in the browser: a local web server rendering frames.
    View(cmd::view::Args),
    /// Transfer functions to and from 3D Slicer (.vp) and ParaView (.json).
    #[command(subcommand)]
    Tf(cmd::tf::Command),
    /// The specular unit: ROM contents, width sweeps, stage-by-stage evaluation.
    #[command(subcommand)]
    Hw(cmd::hw::Command),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => return usage_error(err),
    };
    glint_render::set_memory_limit(cli.memory_limit);
    let result = match cli.command {
        Command::Render(args) => cmd::render::run(args),
        Command::Compare(args) => cmd::compare::run(args),
        Command::Mesh(args) => cmd::mesh::run(args),
        Command::Pick(args) => cmd::pick::run(args),
        Command::Eval(args) => cmd::eval::run(args),
        Command::Analyze(args) => cmd::analyze::run(args),
        Command::Bench(args) => cmd::bench::run(args),
        Command::Info(args) => cmd::info::run(args),
        Command::Hw(args) => cmd::hw::run(args),
        Command::Tf(args) => cmd::tf::run(args),
        Command::View(args) => cmd::view::run(args),
        // Its exit status counts the inputs that failed.
        Command::Batch(args) => match cmd::batch::run(args) {
            Ok(failed) => return ExitCode::from(failed),
            Err(e) => Err(e),
        },
    };
    report(result)
}

/// Help and version go to stdout as clap prints them; a real usage error becomes one
/// line on stderr, like every other error, and exit code 2.
fn usage_error(err: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        err.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        err.exit();
    }
    let text = err.render().to_string();
    let first = text.lines().next().unwrap_or("invalid arguments");
    let first = first.strip_prefix("error: ").unwrap_or(first);
    eprintln!("glint: error: {first} (see --help)");
    ExitCode::from(2)
}

fn report(result: anyhow::Result<()>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // One line for the user: the error and its causes, joined.
            eprintln!("glint: error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
