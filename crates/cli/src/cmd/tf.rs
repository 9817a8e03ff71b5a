//! `glint tf export`: a preset or a transfer-function file written as a 3D Slicer
//! volume property file (`.vp`) or a ParaView colour map (`.json`).

use std::path::PathBuf;

use anyhow::{bail, Context};
use glint_render::{preset, TfFormat, TransferFunctionFile};

/// Transfer functions to and from other programs.
#[derive(clap::Subcommand)]
pub enum Command {
    /// Write a preset (or convert a transfer-function file) as a 3D Slicer volume
    /// property file (.vp: the function and the material) or a ParaView colour map
    /// (.json: the function), told by the output's extension.
    #[command(after_help = "Examples:\n  \
    glint tf export --preset ct-bone -o ct-bone.vp      # Slicer: Volume rendering > Import\n  \
    glint tf export --preset ct-bone -o ct-bone.json    # ParaView: Choose preset > Import\n  \
    glint tf export --from slicer.vp -o paraview.json   # convert\n  \
    glint render head.nii.gz --tf ct-bone.vp -o head.png")]
    Export(ExportArgs),
}

/// `glint tf export`'s options.
#[derive(clap::Args)]
pub struct ExportArgs {
    /// The preset to write (`glint render --help` lists them).
    #[arg(long, required_unless_present = "from", conflicts_with = "from")]
    preset: Option<String>,
    /// A transfer-function file to convert (glint JSON, ParaView .json or Slicer .vp).
    #[arg(long, value_name = "FILE")]
    from: Option<PathBuf>,
    /// An MR preset's values are relative to the volume's maximum: scale them to this
    /// maximum [default: as stored, the last point at 1].
    #[arg(long, value_name = "VALUE", requires = "preset")]
    volume_max: Option<f64>,
    /// The colour map's name in a ParaView file [default: the preset's or the input
    /// file's name].
    #[arg(long)]
    name: Option<String>,
    /// Output file: .vp (3D Slicer) or .json (ParaView).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
}

/// Runs `glint tf`.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Export(args) => export(args),
    }
}

fn export(args: ExportArgs) -> anyhow::Result<()> {
    let format = TfFormat::for_output(&args.output)?;
    let (file, default_name) = match (&args.preset, &args.from) {
        (Some(name), _) => {
            let p = preset(name)?;
            let max = args.volume_max.unwrap_or(0.0);
            if !max.is_finite() || max < 0.0 {
                bail!("--volume-max {max}: expected a positive value");
            }
            let material = p.material();
            let file = TransferFunctionFile {
                tf: p.transfer_function(max)?,
                material: glint_render::MaterialOverrides {
                    ambient: Some(material.ambient),
                    diffuse: Some(material.diffuse),
                    specular: Some(material.specular),
                    shade: Some(material.shade),
                },
                power: Some(p.specular_power()),
                notes: Vec::new(),
            };
            (file, p.name.to_string())
        }
        (None, Some(path)) => {
            let file = TransferFunctionFile::read(path)?;
            let stem = path
                .file_stem()
                .map_or("glint".into(), |s| s.to_string_lossy().into_owned());
            (file, stem)
        }
        (None, None) => bail!("give --preset NAME or --from FILE"),
    };
    let text = match format {
        TfFormat::SlicerVp => file.to_vp(),
        TfFormat::ParaView | TfFormat::Glint => {
            file.to_paraview(args.name.as_deref().unwrap_or(&default_name))
        }
    };
    glint_io::write_atomic(&args.output, |w| w.write_all(text.as_bytes()))
        .with_context(|| format!("writing {}", args.output.display()))?;
    Ok(())
}
