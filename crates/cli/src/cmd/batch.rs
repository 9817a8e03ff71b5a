//! `glint batch`: a whole study on this machine. Parses flags into a
//! [`glint_batch::Spec`] and calls the library (discover, run_local, finish); shows a
//! progress bar.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use glint_batch::bids::{GeneratedBy, Selection};
use glint_batch::{Discover, LocalOptions, Outcome, Spec, Status};
use glint_render::{SceneLobe, View};

use super::choice::choice;
use super::scene_flags::SceneFlags;

/// The views of a mosaic when neither --views nor --view says.
const DEFAULT_VIEWS: [View; 3] = [View::Left, View::Anterior, View::Superior];

/// Highest exit status that counts failed inputs (more failures also exit with it).
const MAX_FAILED_STATUS: usize = 100;

/// Arguments of `glint batch`.
#[derive(clap::Args)]
#[command(
    mut_arg("input", |a| a
        .required(true)
        .help("Volumes: files, directories (walked for .nii, .nii.gz, .nrrd, .nhdr, .hdr \
files and for folders of .dcm files), glob patterns (quoted: 'data/*.nii.gz') or a \
BIDS dataset (a directory with dataset_description.json: its sub-*/[ses-*/]anat/ \
images)")),
    mut_arg("view", |a| a
        .conflicts_with("views")
        .help("A mosaic of this one view (see --views)")),
    after_help = "Examples:\n  \
    glint batch scans/ -o qc/ --preset mr-t2-brain --size 256x256 --slices\n  \
    glint batch /data/bids -o qc/ --bids-suffix T1w,T2w --views left,superior\n  \
    glint batch /data/bids -o /data/bids/derivatives/glint --participant-label 01,02 --suffix T1w\n  \
    glint batch 'site*/sub-*.nii.gz' --scene brain.json -o figures/ --jobs 2\n\n\
Writes OUT/<id>/mosaic.png (the views side by side), OUT/<id>/slices.png (--slices:\n\
sagittal, coronal and axial cuts through the centre, one intensity window),\n\
OUT/<id>/scene.json (the first view's resolved scene), OUT/<id>/row.json, then\n\
OUT/results.jsonl (a row per input: checksum, outputs, seconds, reader notes or the\n\
error) and OUT/index.html (open it from the disk). Every file is written atomically.\n\
A rerun skips inputs made from the same bytes with the same scene and views (--force\n\
redoes them) and retries the failed ones. With a BIDS dataset among the inputs, OUT is\n\
a BIDS derivatives dataset: OUT/dataset_description.json (DatasetType derivative,\n\
GeneratedBy glint, its version and this command). Symbolic links are followed; a link\n\
to nothing (a DataLad file not fetched) is a failed row that says so.\n\n\
Exit status: 0 when every input was made; otherwise the number of inputs that failed\n\
(at most 100), after the table and report are written. An error that stops the whole\n\
run (no input found, a bad scene or flag, an output directory that cannot be made)\n\
prints one line and exits 1 (2 for a usage error), before any input is made."
)]
pub struct Args {
    // Boxed: the options are many, and main's subcommand enum should stay small.
    #[command(flatten)]
    opts: Box<Options>,
}

/// The options of `glint batch` (boxed inside [`Args`]).
#[derive(clap::Args)]
struct Options {
    #[command(flatten)]
    scene: SceneFlags,
    /// Output directory (made if missing).
    #[arg(short, long, value_name = "DIR")]
    output: PathBuf,
    /// The views of each mosaic, left to right [default: left,anterior,superior].
    #[arg(long, value_delimiter = ',', value_parser = choice::<View>(View::NAMES.iter().copied()))]
    views: Vec<View>,
    /// Also write three orthogonal slices per input, for quality control.
    #[arg(long)]
    slices: bool,
    /// Also write the mosaic's linear radiance beside each mosaic.png, as mosaic.exr:
    /// 32-bit float OpenEXR (RGBA, before the sRGB encoding and clip; as `glint
    /// render -o x.exr`).
    #[arg(long)]
    exr: bool,
    /// BIDS datasets: the anat/ suffixes to take [default: T1w, T2w, PDw, T2starw,
    /// FLAIR, inplaneT1, inplaneT2, PDT2, angio].
    #[arg(
        long,
        visible_alias = "suffix",
        value_delimiter = ',',
        value_name = "SUFFIX"
    )]
    bids_suffix: Vec<String>,
    /// BIDS: only these participants (labels with or without sub-, e.g. 01,02); a
    /// label no input has is an error.
    #[arg(long, value_delimiter = ',', value_name = "LABEL")]
    participant_label: Vec<String>,
    /// BIDS: only these sessions (labels with or without ses-, e.g. pre).
    #[arg(long, value_delimiter = ',', value_name = "LABEL")]
    session_label: Vec<String>,
    /// Inputs made at once [default: one per core].
    #[arg(short, long, default_value_t = 0, hide_default_value = true)]
    jobs: usize,
    /// Make every input again, even those whose outputs are up to date.
    #[arg(long)]
    force: bool,
    /// Specular lobe (see glint render --help) [default: k].
    #[arg(long, value_parser = choice::<SceneLobe>(SceneLobe::ALL.map(|k| k.name())))]
    lobe: Option<SceneLobe>,
    /// No progress bar and no line per failed input.
    #[arg(short, long)]
    quiet: bool,
}

/// Runs `glint batch`; returns the exit status (the number of failed inputs, at most
/// [`MAX_FAILED_STATUS`]).
pub fn run(args: Args) -> anyhow::Result<u8> {
    let mut args = *args.opts;
    // The positional inputs are the study's, not the scene's volume.
    let inputs = std::mem::take(&mut args.scene.input);
    let items = glint_batch::discover(
        &inputs,
        &Discover {
            bids_suffixes: args.bids_suffix.clone(),
            exclude: Some(args.output.clone()),
        },
    )?;
    let selection = Selection {
        participants: args.participant_label.clone(),
        sessions: args.session_label.clone(),
    };
    let items = glint_batch::bids::select(items, &selection)?;
    let spec = spec(&args)?;
    let bar = progress_bar(&args, items.len());
    let progress = |o: &Outcome| {
        if let Some(e) = o.row.error.as_deref().filter(|_| !args.quiet) {
            let line = format!("glint batch: {}: {e}", o.row.id);
            match &bar {
                Some(b) => b.println(line),
                None => eprintln!("{line}"),
            }
        }
        if let Some(b) = &bar {
            b.inc(1);
        }
    };
    let options = LocalOptions {
        jobs: args.jobs,
        force: args.force,
        ..LocalOptions::default()
    };
    let outcomes = glint_batch::run_local(&items, &spec, &args.output, &options, &progress)?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let skipped = outcomes.iter().filter(|o| o.skipped).count();
    let rows: Vec<_> = outcomes.into_iter().map(|o| o.row).collect();
    let summary = glint_batch::finish(&args.output, &rows)?;
    // Renders of BIDS datasets make a BIDS derivatives dataset, as BIDS apps write.
    let datasets: Vec<&Path> = inputs
        .iter()
        .map(PathBuf::as_path)
        .filter(|p| glint_batch::bids::is_dataset(p))
        .collect();
    if !datasets.is_empty() {
        let by = GeneratedBy {
            name: "glint".into(),
            version: env!("CARGO_PKG_VERSION").into(),
            command: command_line(),
        };
        glint_batch::bids::write_description(&args.output, &by, &datasets)?;
    }
    if !args.quiet {
        eprintln!(
            "glint batch: {} inputs: {} made ({skipped} up to date), {} failed; report {}",
            rows.len(),
            summary.ok,
            summary.failed,
            args.output.join(glint_batch::REPORT_FILE).display()
        );
    }
    debug_assert_eq!(
        summary.failed,
        rows.iter().filter(|r| r.status == Status::Failed).count()
    );
    Ok(summary.failed.min(MAX_FAILED_STATUS) as u8)
}

/// The command line that runs, each argument with whitespace or quotes in single
/// quotes (as a shell would take it back).
fn command_line() -> String {
    std::env::args()
        .map(|a| {
            if a.is_empty() || a.contains(|c: char| c.is_whitespace() || "'\"\\$`".contains(c)) {
                format!("'{}'", a.replace('\'', "'\\''"))
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The spec of the flags (the inputs taken out): the scene (a scene file and flags,
/// the lobe), the views.
fn spec(args: &Options) -> anyhow::Result<Spec> {
    let mut scene = args.scene.scene()?;
    if let Some(kind) = args.lobe {
        args.scene.set_lobe(&mut scene, kind);
    }
    let views = match (&args.views[..], args.scene.view) {
        ([], Some(view)) => vec![view],
        ([], None) => DEFAULT_VIEWS.to_vec(),
        (views, _) => views.to_vec(),
    };
    let mut spec = Spec::new(scene, views, args.slices);
    spec.strict = args.scene.strict;
    spec.exr = args.exr;
    spec.check()?;
    Ok(spec)
}

fn progress_bar(args: &Options, n: usize) -> Option<indicatif::ProgressBar> {
    if args.quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(n as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {pos}/{len} inputs [{bar:40}] {elapsed_precise}, ETA {eta}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    Some(bar)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn parse(argv: &[&str]) -> Result<Options, clap::Error> {
        let mut full = vec!["glint"];
        full.extend_from_slice(argv);
        Cli::try_parse_from(full).map(|c| {
            let mut o = *c.args.opts;
            o.scene.input.clear();
            o
        })
    }

    #[test]
    fn views_come_from_views_or_view_or_the_default() {
        let o = parse(&["a.nii", "-o", "out"]).unwrap();
        assert_eq!(spec(&o).unwrap().views, DEFAULT_VIEWS);
        let o = parse(&["a.nii", "-o", "out", "--views", "right,inferior"]).unwrap();
        assert_eq!(spec(&o).unwrap().views, [View::Right, View::Inferior]);
        let o = parse(&["a.nii", "-o", "out", "--view", "posterior"]).unwrap();
        assert_eq!(spec(&o).unwrap().views, [View::Posterior]);
        assert!(parse(&["a.nii", "-o", "o", "--view", "left", "--views", "left"]).is_err());
        assert!(parse(&["a.nii", "-o", "o", "--views", "sideways"]).is_err());
        // The inputs are required, and they are not the scene's volume.
        assert!(parse(&["-o", "out"]).is_err());
        let o = parse(&["a.nii", "b.nii", "-o", "out", "--size", "64x48"]).unwrap();
        let s = spec(&o).unwrap();
        assert_eq!(s.scene.size, [64, 48]);
        assert_eq!(s.scene.input, glint_render::Scene::default().input);
    }
}
