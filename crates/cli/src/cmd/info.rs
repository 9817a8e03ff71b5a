//! `glint info`: what a volume or surface file holds (format, dims, spacing, type, range,
//! affine; or vertex and triangle counts and bounds), as text or JSON.

use std::path::PathBuf;

use anyhow::bail;
use glint_io::{Endian, Format, MeshFile, RawParams, ReadOptions, ScalarType, VolumeFile};
use serde_json::{json, Value};

/// Arguments of `glint info`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint info mni152_t1_09a.nii.gz\n  \
    glint info fsaverage5_pial_left.gii.gz --json\n  \
    glint info ct_series/            (a directory of DICOM slices)\n  \
    glint info head.raw --raw-dims 256,256,128 --raw-type u16 --raw-spacing 0.9,0.9,1.5")]
pub struct Args {
    /// The file (.nii, .nii.gz, .nrrd, .nhdr, .dcm, DICOM directory, .stl, .obj, .ply,
    /// .gii, .gii.gz, or raw samples with --raw-dims).
    file: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Refuse volumes with more voxels than this (checked before reading the samples).
    #[arg(long, default_value_t = ReadOptions::default().max_voxels)]
    max_voxels: u64,
    /// Read FILE as headerless samples with these dimensions, e.g. 256,256,128.
    #[arg(long, value_delimiter = ',', num_args = 1)]
    raw_dims: Vec<usize>,
    /// Sample type of a raw file: u8, i8, u16, i16, u32, i32, f32, f64.
    #[arg(long, default_value = "u8", requires = "raw_dims")]
    raw_type: String,
    /// Voxel size of a raw file in mm, e.g. 0.9,0.9,1.5.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1,1,1",
        requires = "raw_dims"
    )]
    raw_spacing: Vec<f64>,
    /// Byte order of a raw file: little or big.
    #[arg(long, default_value = "little", requires = "raw_dims")]
    raw_endian: String,
    /// Bytes to skip at the start of a raw file.
    #[arg(long, default_value_t = 0, requires = "raw_dims")]
    raw_offset: u64,
}

/// Runs `glint info`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut options = ReadOptions {
        max_voxels: args.max_voxels,
        ..ReadOptions::default()
    };
    if !args.raw_dims.is_empty() {
        let dims: [usize; 3] = args
            .raw_dims
            .as_slice()
            .try_into()
            .map_err(|_| anyhow::anyhow!("--raw-dims takes three sizes, e.g. 256,256,128"))?;
        let spacing: [f64; 3] =
            args.raw_spacing.as_slice().try_into().map_err(|_| {
                anyhow::anyhow!("--raw-spacing takes three sizes in mm, e.g. 1,1,1")
            })?;
        let scalar: ScalarType = args.raw_type.parse()?;
        let endian: Endian = args.raw_endian.parse().map_err(anyhow::Error::msg)?;
        options.raw = Some(RawParams {
            dims,
            scalar,
            spacing,
            endian,
            offset: args.raw_offset,
        });
    }
    let is_mesh = options.raw.is_none() && Format::guess(&args.file).is_some_and(Format::is_mesh);
    if options.raw.is_none() && Format::guess(&args.file) == Some(Format::Raw) {
        bail!(
            "{}: a raw file needs --raw-dims (and --raw-type, --raw-spacing)",
            args.file.display()
        );
    }
    if is_mesh {
        let file = glint_io::open_mesh(&args.file)?;
        if args.json {
            println!(
                "{}",
                serde_json::to_string_pretty(&mesh_json(&args, &file))?
            );
        } else {
            print_mesh(&args, &file);
        }
    } else {
        let file = glint_io::open_volume(&args.file, &options)?;
        if args.json {
            println!(
                "{}",
                serde_json::to_string_pretty(&volume_json(&args, &file))?
            );
        } else {
            print_volume(&args, &file);
        }
    }
    Ok(())
}

fn volume_json(args: &Args, f: &VolumeFile) -> Value {
    let v = &f.volume;
    let (lo, hi) = v.range();
    json!({
        "file": args.file.display().to_string(),
        "kind": "volume",
        "format": f.format.name(),
        "dims": v.dims,
        "voxels": v.len(),
        "spacing_mm": v.spacing,
        "type": v.samples.type_name(),
        "slope": v.slope,
        "intercept": v.intercept,
        "range": [finite_or_null(lo), finite_or_null(hi)],
        "units": v.units,
        "affine_voxel_to_ras_mm": v.affine,
        "notes": f.notes,
    })
}

fn finite_or_null(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

fn print_volume(args: &Args, f: &VolumeFile) {
    let v = &f.volume;
    let (lo, hi) = v.range();
    println!("file:     {}", args.file.display());
    println!("format:   {} volume", f.format.name());
    println!(
        "dims:     {} x {} x {} ({} voxels)",
        v.dims[0],
        v.dims[1],
        v.dims[2],
        v.len()
    );
    println!(
        "spacing:  {} x {} x {} mm",
        num(v.spacing[0]),
        num(v.spacing[1]),
        num(v.spacing[2])
    );
    println!("type:     {}", v.samples.type_name());
    if v.slope != 1.0 || v.intercept != 0.0 {
        println!(
            "scaling:  value = {} * stored + {}",
            num(v.slope),
            num(v.intercept)
        );
    }
    let units = v.units.as_deref().unwrap_or("");
    println!("range:    {} .. {} {units}", num(lo), num(hi));
    println!("affine (voxel -> RAS+ mm):");
    for row in &v.affine {
        println!(
            "  {:>12} {:>12} {:>12} {:>12}",
            num(row[0]),
            num(row[1]),
            num(row[2]),
            num(row[3])
        );
    }
    for n in &f.notes {
        println!("note:     {n}");
    }
}

fn mesh_json(args: &Args, f: &MeshFile) -> Value {
    let m = &f.mesh;
    let bounds = m.bounds().map(|(lo, hi)| json!({"min": lo, "max": hi}));
    json!({
        "file": args.file.display().to_string(),
        "kind": "mesh",
        "format": f.format.name(),
        "vertices": m.positions.len(),
        "triangles": m.triangles.len(),
        "normals": m.normals.is_some(),
        "scalars": m.scalars.is_some(),
        "bounds_mm": bounds,
        "coordinate_system": f.coordinate_system,
        "notes": f.notes,
    })
}

fn print_mesh(args: &Args, f: &MeshFile) {
    let m = &f.mesh;
    println!("file:      {}", args.file.display());
    println!("format:    {} surface", f.format.name());
    println!("vertices:  {}", m.positions.len());
    println!("triangles: {}", m.triangles.len());
    println!(
        "normals:   {}",
        if m.normals.is_some() { "yes" } else { "no" }
    );
    if let Some(s) = &m.scalars {
        let (lo, hi) = s
            .iter()
            .filter(|x| x.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        println!("scalars:   {} .. {}", num(lo.into()), num(hi.into()));
    }
    if let Some((lo, hi)) = m.bounds() {
        let fmt = |p: [f32; 3]| {
            format!(
                "({}, {}, {})",
                num(p[0].into()),
                num(p[1].into()),
                num(p[2].into())
            )
        };
        println!("bounds:    {} .. {} mm", fmt(lo), fmt(hi));
    }
    if let Some(cs) = &f.coordinate_system {
        println!("space:     {cs}");
    }
    for n in &f.notes {
        println!("note:      {n}");
    }
}

/// A number with at most 4 decimals and no trailing zeros.
fn num(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn numbers_drop_trailing_zeros() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(-98.0), "-98");
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(-0.0), "0");
        assert_eq!(num(1.23456), "1.2346");
    }
}
