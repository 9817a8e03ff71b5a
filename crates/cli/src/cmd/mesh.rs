//! `glint mesh`: the isosurface of a volume, written as STL, PLY or OBJ.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context};
use glint_io::mesh::{write_obj, write_ply, write_stl, PlyEncoding};
use glint_io::{open_volume, Format, Mesh, ReadOptions};
use glint_render::mesh::{extract, taubin_smooth, Taubin};
use glint_render::vertex_normals;

/// Arguments of `glint mesh`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint mesh mni152_t1_09a.nii.gz --iso 60 -o brain.stl\n  \
    glint mesh ct.nrrd --iso 300 --smooth 20 -o bone.ply\n  \
    glint mesh lh.pial.gii -o lh.pial.ply     # a surface converted, with vertex normals\n\n\
The surface separates values >= ISO (inside) from lower ones; triangles are \
counter-clockwise seen from outside and the normals (PLY, OBJ) point outwards, from the \
volume's gradient (or from the triangles after --smooth).")]
pub struct Args {
    /// The volume (any format glint's io reads), or a surface (.gii, .stl, .obj, .ply)
    /// to convert.
    input: PathBuf,
    /// The iso value, in the volume's physical units (required for a volume).
    #[arg(long, allow_negative_numbers = true)]
    iso: Option<f32>,
    /// Output mesh; the extension picks the format: .stl (binary), .ply (binary), .obj.
    #[arg(short, long)]
    output: PathBuf,
    /// Taubin λ|μ smoothing iterations (0: none).
    #[arg(long, default_value_t = 0)]
    smooth: u32,
    /// Taubin's shrinking factor λ.
    #[arg(long, default_value_t = Taubin::default().lambda)]
    lambda: f32,
    /// Taubin's inflating factor μ (negative, |μ| > λ).
    #[arg(long, default_value_t = Taubin::default().mu, allow_negative_numbers = true)]
    mu: f32,
    /// No summary line, and of the reader's notes only its warnings.
    #[arg(short, long)]
    quiet: bool,
    /// Benchmarking: extract this many times and print ms per extraction to stdout.
    #[arg(long, default_value_t = 1, hide = true)]
    repeat: u32,
}

/// The writer for an output path, from its extension.
/// A mesh writer of glint_io.
type MeshWriter = fn(&Path, &Mesh) -> Result<(), glint_io::IoError>;

fn writer(path: &Path) -> anyhow::Result<MeshWriter> {
    Ok(match Format::guess(path) {
        Some(Format::Stl) => write_stl,
        Some(Format::Ply) => |p, m| write_ply(p, m, PlyEncoding::BinaryLittleEndian),
        Some(Format::Obj) => write_obj,
        _ => bail!(
            "cannot write {}: expected a .stl, .ply or .obj output",
            path.display()
        ),
    })
}

/// Runs `glint mesh`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let write = writer(&args.output)?;
    let taubin = Taubin {
        iterations: args.smooth,
        lambda: args.lambda,
        mu: args.mu,
    };
    taubin.validate()?;
    if args.repeat == 0 || args.repeat > 10_000 {
        bail!("invalid --repeat {}: expected 1..=10000", args.repeat);
    }
    if let Some(dir) = args.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            bail!(
                "cannot write {}: directory {} does not exist",
                args.output.display(),
                dir.display()
            );
        }
    }
    if Format::guess(&args.input).is_some_and(Format::is_mesh) {
        return convert(&args, &taubin, write);
    }
    let Some(iso) = args.iso else {
        bail!("--iso is required to extract a surface from the volume");
    };
    let file = open_volume(&args.input, &ReadOptions::default())
        .with_context(|| format!("cannot read volume {}", args.input.display()))?;
    super::render::print_notes(&args.input, &file.notes, args.quiet);
    let volume = file.volume;
    let (lo, hi) = volume.range();
    if !(lo..=hi).contains(&f64::from(iso)) {
        bail!(
            "--iso {} is outside the volume's range {lo}..{hi}: the surface would be empty",
            iso
        );
    }
    let start = Instant::now();
    let mut mesh = extract(&volume, iso)?;
    for _ in 1..args.repeat {
        mesh = extract(&volume, iso)?;
    }
    let per = start.elapsed().as_secs_f64() * 1e3 / f64::from(args.repeat);
    if args.repeat > 1 {
        println!(
            "glint mesh: {per:.2} ms/extraction ({} runs, {} triangles)",
            args.repeat,
            mesh.triangles.len()
        );
    }
    if mesh.triangles.is_empty() {
        bail!("no surface at --iso {}: no voxel edge crosses it", iso);
    }
    if taubin.iterations > 0 {
        taubin_smooth(&mut mesh, &taubin)?;
    }
    write_and_report(&args, &mesh, write)
}

/// A surface file written in another format (e.g. GIFTI to PLY for VTK, in
/// scripts/bench/bench-vtk-surface), with vertex normals (the file's, else area-weighted
/// ones from the triangles, as `glint render` shades it), optionally smoothed.
fn convert(args: &Args, taubin: &Taubin, write: MeshWriter) -> anyhow::Result<()> {
    if args.iso.is_some() {
        bail!(
            "--iso applies to volumes; {} is a surface",
            args.input.display()
        );
    }
    let file = glint_io::open_mesh(&args.input)
        .with_context(|| format!("cannot read surface {}", args.input.display()))?;
    super::render::print_notes(&args.input, &file.notes, args.quiet);
    let mut mesh = file.mesh;
    mesh.validate()
        .with_context(|| format!("cannot convert {}", args.input.display()))?;
    if taubin.iterations > 0 {
        taubin_smooth(&mut mesh, taubin)?;
    }
    if mesh.normals.is_none() {
        mesh.normals = Some(vertex_normals(&mesh.positions, &mesh.triangles));
    }
    write_and_report(args, &mesh, write)
}

/// Writes the mesh (atomically, by the writer) and says so unless `--quiet`.
fn write_and_report(args: &Args, mesh: &Mesh, write: MeshWriter) -> anyhow::Result<()> {
    write(&args.output, mesh)?;
    if !args.quiet {
        eprintln!(
            "glint: wrote {} ({} vertices, {} triangles)",
            args.output.display(),
            mesh.positions.len(),
            mesh.triangles.len()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use glint_io::{nifti, Endian, Samples, Volume};

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn run_args(argv: &[&str]) -> anyhow::Result<()> {
        let mut all = vec!["glint", "-q"];
        all.extend_from_slice(argv);
        run(Cli::try_parse_from(all)?.args)
    }

    /// A 16^3 volume with a bright 6^3 cube in the middle.
    fn cube_volume(dir: &Path) -> PathBuf {
        let mut v = vec![0u8; 16 * 16 * 16];
        for k in 5..11 {
            for j in 5..11 {
                for i in 5..11 {
                    v[i + 16 * (j + 16 * k)] = 100;
                }
            }
        }
        let vol = Volume::new([16; 3], [1.0; 3], Samples::U8(v)).unwrap();
        let path = dir.join("cube.nii");
        nifti::write(&path, &vol, false, Endian::Little).unwrap();
        path
    }

    #[test]
    fn writes_each_format_that_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let input = cube_volume(dir.path());
        for ext in ["stl", "ply", "obj"] {
            let out = dir.path().join(format!("cube.{ext}"));
            run_args(&[
                input.to_str().unwrap(),
                "--iso",
                "50",
                "-o",
                out.to_str().unwrap(),
            ])
            .unwrap();
            let mesh = glint_io::read_mesh(&out).unwrap();
            // The iso value halfway between 0 and 100 puts the faces half a voxel
            // outside the bright cube: x in 4.5..10.5.
            let (lo, hi) = mesh.bounds().unwrap();
            for a in 0..3 {
                assert!(
                    (lo[a] - 4.5).abs() < 1e-4 && (hi[a] - 10.5).abs() < 1e-4,
                    "{ext}: {lo:?} {hi:?}"
                );
            }
        }
    }

    #[test]
    fn bad_arguments_fail_without_output() {
        let dir = tempfile::tempdir().unwrap();
        let input = cube_volume(dir.path());
        let input = input.to_str().unwrap();
        let out = dir.path().join("o.stl");
        let out = out.to_str().unwrap();
        let cases: Vec<(Vec<&str>, &str)> = vec![
            (
                vec![input, "--iso", "50", "-o", "x.png"],
                ".stl, .ply or .obj",
            ),
            (
                vec![input, "--iso", "500", "-o", out],
                "outside the volume's range",
            ),
            (
                vec!["/nonexistent.nii", "--iso", "1", "-o", out],
                "cannot read volume",
            ),
            (
                vec![
                    input, "--iso", "50", "--smooth", "3", "--mu", "0.1", "-o", out,
                ],
                "Taubin",
            ),
            (
                vec![input, "--iso", "50", "-o", "/nonexistent/dir/o.stl"],
                "does not exist",
            ),
        ];
        for (argv, needle) in cases {
            let err = format!("{:#}", run_args(&argv).expect_err(&format!("{argv:?}")));
            assert!(err.contains(needle), "{argv:?}: {err}");
            assert!(!Path::new(out).exists());
        }
    }
}
