//! `glint info`: what a volume or surface file holds (format, dims, spacing, type, range,
//! affine; or vertex and triangle counts and bounds), as text or JSON.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::bail;
use glint_io::zarr::Level;
use glint_io::{
    Endian, Format, MeshFile, RawParams, ReadOptions, ScalarType, VertexData, VertexValues,
    VolumeFile,
};
use serde_json::{json, Value};

/// Arguments of `glint info`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint info mni152_t1_09a.nii.gz\n  \
    glint info fsaverage5_pial_left.gii.gz --json\n  \
    glint info ct_series/            (a directory of DICOM slices)\n  \
    glint info aseg.mgz --labels     (labels, names, voxels, ml)\n  \
    glint info mask.nii.gz --labels --label-table totalsegmentator\n  \
    glint info mask.nii.gz --labels --label-table t.csv --all-labels  (absent ones too)\n  \
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
    /// Refuse what is otherwise read with a note: DICOM files without the 128-byte
    /// preamble or the file meta group, multi-frame DICOM without frame positions.
    #[arg(long)]
    strict: bool,
    /// The DICOM series to read from a directory that holds several (its
    /// SeriesInstanceUID, as listed); default: the only or the largest.
    #[arg(long)]
    series: Option<String>,
    /// The level of an OME-Zarr pyramid to read for the range and labels (0 the finest)
    /// [default: the coarsest; every level is listed either way].
    #[arg(long)]
    level: Option<usize>,
    /// List the labels of a label map: value, name, voxel count, volume in ml.
    #[arg(long)]
    labels: bool,
    /// The colour table naming the labels: freesurfer, totalsegmentator, or a file
    /// (FreeSurfer LUT text, Slicer .ctbl/.txt, .json, .csv) [default: freesurfer for
    /// files named *aseg*, *aparc*, *wmparc*, else none].
    #[arg(long, value_name = "TABLE", requires = "labels")]
    label_table: Option<String>,
    /// With --labels: every entry of the colour table, those the map does not hold
    /// listed with 0 voxels and marked absent (default: the labels present only).
    #[arg(long, requires = "labels")]
    all_labels: bool,
}

/// Runs `glint info`.
pub fn run(args: Args) -> anyhow::Result<()> {
    print!("{}", report(&args)?);
    Ok(())
}

/// The text or JSON `glint info` prints.
fn report(args: &Args) -> anyhow::Result<String> {
    let options = read_options(args)?;
    let is_mesh = options.raw.is_none() && Format::guess(&args.file).is_some_and(Format::is_mesh);
    if options.raw.is_none() && Format::guess(&args.file) == Some(Format::Raw) {
        bail!(
            "{}: a raw file needs --raw-dims (and --raw-type, --raw-spacing)",
            args.file.display()
        );
    }
    if is_mesh && args.labels {
        bail!(
            "{}: --labels lists a label volume's labels; this is a mesh",
            args.file.display()
        );
    }
    if is_mesh {
        mesh_report(args)
    } else {
        volume_report(args, &options)
    }
}

/// The read options `args` ask for (raw geometry included).
fn read_options(args: &Args) -> anyhow::Result<ReadOptions> {
    let mut options = ReadOptions {
        max_voxels: args.max_voxels,
        strict: args.strict,
        series: args.series.clone(),
        level: args.level.map_or(Level::Coarsest, Level::Index),
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
    Ok(options)
}

/// The report of a mesh or a GIFTI of per-vertex data.
fn mesh_report(args: &Args) -> anyhow::Result<String> {
    let mut out = String::new();
    // A GIFTI file is read once for its surface and its overlays; one of per-vertex data
    // only (sulcal depth, a parcellation) has no surface, just the overlays.
    let (file, overlays) = if Format::guess(&args.file) == Some(Format::Gifti) {
        glint_io::gifti::read_with_data(&args.file)?
    } else {
        (Some(glint_io::open_mesh(&args.file)?), Vec::new())
    };
    if args.json {
        let mut v = match &file {
            Some(f) => mesh_json(args, f),
            None => json!({
                "file": args.file.display().to_string(),
                "kind": "vertex data",
                "format": "GIFTI",
            }),
        };
        v["overlays"] = overlays.iter().map(overlay_json).collect();
        out = serde_json::to_string_pretty(&v)? + "\n";
    } else {
        match &file {
            Some(f) => print_mesh(&mut out, args, f)?,
            None => {
                writeln!(out, "file:      {}", args.file.display())?;
                writeln!(out, "format:    GIFTI per-vertex data (no surface)")?;
            }
        }
        for o in &overlays {
            writeln!(out, "overlay:   {}", overlay_line(o))?;
        }
    }
    Ok(out)
}

/// The report of a volume (with a DICOM directory's listing and, asked for, its labels).
fn volume_report(args: &Args, options: &ReadOptions) -> anyhow::Result<String> {
    let mut out = String::new();
    let reading = super::spinner::Spinner::start(format!("reading {}", args.file.display()), false);
    let file = glint_io::open_volume(&args.file, options)?;
    drop(reading);
    // Assumed geometry is worth a warning even when the output goes to a script.
    for n in file
        .notes
        .iter()
        .filter(|n| n.starts_with("geometry assumed") || n.contains("chunks missing"))
    {
        eprintln!("glint: {}: {n}", args.file.display());
    }
    // A DICOM directory: every series and every object not read, too.
    let listing = match args.file.is_dir() && file.format == Format::Dicom {
        true => Some(glint_io::dicom::list(&args.file, options)?),
        false => None,
    };
    if args.json {
        let mut v = volume_json(args, &file);
        if let Some(l) = &listing {
            listing_json(&mut v, l);
        }
        if args.labels {
            super::info_labels::add_json(
                &mut v,
                &args.file,
                &file.volume,
                &super::info_labels::Listing {
                    table: args.label_table.as_deref(),
                    all: args.all_labels,
                },
            )?;
        }
        out = serde_json::to_string_pretty(&v)? + "\n";
    } else {
        print_volume(&mut out, args, &file)?;
        if let Some(l) = &listing {
            print_listing(&mut out, l)?;
        }
        if args.labels {
            super::info_labels::print(
                &mut out,
                &args.file,
                &file.volume,
                &super::info_labels::Listing {
                    table: args.label_table.as_deref(),
                    all: args.all_labels,
                },
            )?;
        }
    }
    Ok(out)
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
        "colour": v.is_colour(),
        "affine_voxel_to_ras_mm": v.affine,
        "notes": f.notes,
    })
}

/// The series and skipped objects of a DICOM directory, into `glint info --json`.
fn listing_json(v: &mut Value, l: &glint_io::dicom::Listing) {
    v["series"] = l
        .series
        .iter()
        .map(|s| {
            json!({
                "uid": s.uid, "modality": s.modality, "description": s.description,
                "files": s.files, "slices": s.slices, "dims": [s.columns, s.rows, s.slices],
                "photometric": s.photometric,
            })
        })
        .collect();
    v["skipped"] = l
        .skipped
        .iter()
        .map(|k| {
            json!({
                "file": k.path.display().to_string(), "reason": k.reason,
                "class": k.class, "modality": k.modality, "series": k.series,
            })
        })
        .collect();
}

/// One line per series and per skipped object of a DICOM directory.
fn print_listing(out: &mut String, l: &glint_io::dicom::Listing) -> std::fmt::Result {
    for s in &l.series {
        let m = s.modality.as_deref().unwrap_or("?");
        let d = s
            .description
            .as_deref()
            .map(|d| format!(" '{d}'"))
            .unwrap_or_default();
        let (c, r, n) = (s.columns, s.rows, s.slices);
        writeln!(
            out,
            "series:   {} {m}{d}: {c} x {r} x {n} ({} files)",
            s.uid, s.files
        )?;
    }
    for k in &l.skipped {
        writeln!(out, "skipped:  {}: {}", k.path.display(), k.reason)?;
    }
    Ok(())
}

fn finite_or_null(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

fn print_volume(out: &mut String, args: &Args, f: &VolumeFile) -> std::fmt::Result {
    let v = &f.volume;
    let (lo, hi) = v.range();
    writeln!(out, "file:     {}", args.file.display())?;
    writeln!(out, "format:   {} volume", f.format.name())?;
    writeln!(
        out,
        "dims:     {} x {} x {} ({} voxels)",
        v.dims[0],
        v.dims[1],
        v.dims[2],
        v.len()
    )?;
    writeln!(
        out,
        "spacing:  {} x {} x {} mm",
        num(v.spacing[0]),
        num(v.spacing[1]),
        num(v.spacing[2])
    )?;
    writeln!(out, "type:     {}", v.samples.type_name())?;
    if v.is_colour() {
        writeln!(
            out,
            "colour:   RGB (the range below is of the grey samples)"
        )?;
    }
    if v.slope != 1.0 || v.intercept != 0.0 {
        writeln!(
            out,
            "scaling:  value = {} * stored + {}",
            num(v.slope),
            num(v.intercept)
        )?;
    }
    let units = v
        .units
        .as_deref()
        .map(|u| format!(" {u}"))
        .unwrap_or_default();
    writeln!(out, "range:    {} .. {}{units}", num(lo), num(hi))?;
    writeln!(out, "affine (voxel -> RAS+ mm):")?;
    for row in &v.affine {
        writeln!(
            out,
            "  {:>12} {:>12} {:>12} {:>12}",
            num(row[0]),
            num(row[1]),
            num(row[2]),
            num(row[3])
        )?;
    }
    for n in &f.notes {
        writeln!(out, "note:     {n}")?;
    }
    Ok(())
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

fn print_mesh(out: &mut String, args: &Args, f: &MeshFile) -> std::fmt::Result {
    let m = &f.mesh;
    writeln!(out, "file:      {}", args.file.display())?;
    writeln!(out, "format:    {} surface", f.format.name())?;
    writeln!(out, "vertices:  {}", m.positions.len())?;
    writeln!(out, "triangles: {}", m.triangles.len())?;
    writeln!(
        out,
        "normals:   {}",
        if m.normals.is_some() { "yes" } else { "no" }
    )?;
    if let Some(s) = &m.scalars {
        let (lo, hi) = s
            .iter()
            .filter(|x| x.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        writeln!(out, "scalars:   {} .. {}", num(lo.into()), num(hi.into()))?;
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
        writeln!(out, "bounds:    {} .. {} mm", fmt(lo), fmt(hi))?;
    }
    if let Some(cs) = &f.coordinate_system {
        writeln!(out, "space:     {cs}")?;
    }
    for n in &f.notes {
        writeln!(out, "note:      {n}")?;
    }
    Ok(())
}

/// The finite range of some values, `None` if there are none.
fn finite_range(v: &[f32]) -> Option<(f32, f32)> {
    v.iter()
        .filter(|x| x.is_finite())
        .fold(None, |r, &x| match r {
            None => Some((x, x)),
            Some((a, b)) => Some((a.min(x), b.max(x))),
        })
}

/// The distinct label keys in use.
fn keys_used(keys: &[i32]) -> usize {
    keys.iter().collect::<std::collections::BTreeSet<_>>().len()
}

/// One line about a per-vertex array: name, intent, count and range or labels.
fn overlay_line(o: &VertexData) -> String {
    match &o.values {
        VertexValues::Scalars(v) => {
            let range = finite_range(v)
                .map(|(lo, hi)| format!(", {} .. {}", num(lo.into()), num(hi.into())))
                .unwrap_or_default();
            format!("{} ({}): {} values{range}", o.name, o.intent, v.len())
        }
        VertexValues::Labels { keys, table } => format!(
            "{} ({}): {} values, {} labels used of {} in the table",
            o.name,
            o.intent,
            keys.len(),
            keys_used(keys),
            table.len()
        ),
    }
}

fn overlay_json(o: &VertexData) -> Value {
    match &o.values {
        VertexValues::Scalars(v) => json!({
            "name": o.name,
            "intent": o.intent,
            "values": v.len(),
            "range": finite_range(v).map(|(lo, hi)| json!([lo, hi])),
        }),
        VertexValues::Labels { keys, table } => json!({
            "name": o.name,
            "intent": o.intent,
            "values": keys.len(),
            "labels_used": keys_used(keys),
            "label_table": table.iter().map(|l| json!({"key": l.key, "name": l.name, "rgba": l.rgba})).collect::<Vec<_>>(),
        }),
    }
}

/// A number with at most 4 decimals and no trailing zeros.
fn num(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x != 0.0 && x.abs() < 5e-5 {
        // Too small for four decimals: four significant digits instead of "0".
        let s = format!("{x:.3e}");
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        return format!("{mantissa}e{exp}");
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
    use super::{listing_json, num, print_listing, report, Args};
    use clap::Parser;
    use glint_io::{Endian, Mesh, Samples, Volume};
    use serde_json::Value;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn run(argv: &[&str]) -> anyhow::Result<String> {
        let cli = Cli::try_parse_from(std::iter::once("info").chain(argv.iter().copied()))?;
        report(&cli.args)
    }

    fn json(argv: &[&str]) -> Value {
        let mut a = argv.to_vec();
        a.push("--json");
        serde_json::from_str(&run(&a).unwrap()).unwrap()
    }

    #[test]
    fn numbers_drop_trailing_zeros() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(-98.0), "-98");
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(-0.0), "0");
        assert_eq!(num(1.23456), "1.2346");
        // Review defect 9: tiny values keep their significant digits instead of "0".
        assert_eq!(num(1e-300), "1e-300");
        assert_eq!(num(-2.5e-6), "-2.5e-6");
        assert_eq!(num(1.23456e-5), "1.235e-5");
    }

    #[test]
    fn nifti_text_and_json() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v.nii.gz");
        let mut vol = Volume::new([4, 3, 2], [1.0; 3], Samples::I16((0..24).collect())).unwrap();
        vol.affine[0] = [0.0, 0.0, -2.5, 10.0];
        vol.affine[2] = [1.0, 0.0, 0.0, -4.0];
        vol.slope = 2.0;
        glint_io::nifti::write(&p, &vol, true, Endian::Little).unwrap();
        let path = p.to_str().unwrap();
        let text = run(&[path]).unwrap();
        assert!(text.contains("format:   NIfTI volume"), "{text}");
        assert!(text.contains("dims:     4 x 3 x 2 (24 voxels)"), "{text}");
        // Column norms of the affine: (0,0,1) -> 1, (0,1,0) -> 1, (-2.5,0,0) -> 2.5.
        assert!(text.contains("spacing:  1 x 1 x 2.5 mm"), "{text}");
        // Stored 0..23 scaled by 2.
        assert!(text.contains("range:    0 .. 46\n"), "{text}");
        let v = json(&[path]);
        assert_eq!(v["dims"], serde_json::json!([4, 3, 2]));
        assert_eq!(v["type"], "int16");
        assert_eq!(
            v["affine_voxel_to_ras_mm"][0],
            serde_json::json!([0.0, 0.0, -2.5, 10.0])
        );
        assert_eq!(
            v["affine_voxel_to_ras_mm"][2],
            serde_json::json!([1.0, 0.0, 0.0, -4.0])
        );
    }

    #[test]
    fn raw_flags() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v.raw");
        std::fs::write(&p, [0u8, 1, 0, 2, 0xFF, 0xFF]).unwrap();
        let path = p.to_str().unwrap();
        let v = json(&[
            path,
            "--raw-dims",
            "3,1,1",
            "--raw-type",
            "u16",
            "--raw-endian",
            "big",
            "--raw-spacing",
            "0.5,1,1",
        ]);
        assert_eq!(v["type"], "uint16");
        assert_eq!(v["range"], serde_json::json!([1.0, 65535.0]));
        assert_eq!(v["spacing_mm"], serde_json::json!([0.5, 1.0, 1.0]));
        let err = run(&[path]).unwrap_err().to_string();
        assert!(err.contains("--raw-dims"), "{err}");
        let err = run(&[path, "--raw-dims", "3,1"]).unwrap_err().to_string();
        assert!(err.contains("three sizes"), "{err}");
        let err = run(&[path, "--raw-dims", "3,1,1", "--raw-type", "c64"])
            .unwrap_err()
            .to_string();
        assert!(err.contains("unknown sample type"), "{err}");
    }

    #[test]
    fn max_voxels_limit() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v.raw");
        std::fs::write(&p, [0u8; 27]).unwrap();
        let err = run(&[
            p.to_str().unwrap(),
            "--raw-dims",
            "3,3,3",
            "--max-voxels",
            "26",
        ])
        .unwrap_err();
        assert!(err.to_string().contains("too large"), "{err}");
    }

    /// An OME-Zarr store (a directory, not of DICOM): every level listed, the coarsest
    /// read by default and marked, no DICOM "skipped" line for its metadata files;
    /// `--level` reads another.
    #[test]
    fn a_zarr_store_lists_its_levels_without_dicom_lines() {
        let store = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../io/tests/data/zarr/v05-zstd.zarr"
        );
        let text = run(&[store]).unwrap();
        assert!(!text.contains("skipped"), "{text}");
        assert!(!text.contains("DICOM"), "{text}");
        assert_eq!(text.matches("level ").count(), 5, "{text}");
        assert!(text.contains("level 4 '4': 4x3x10 uint16"), "{text}");
        assert!(text.contains("(read)"), "{text}");
        let v = json(&[store]);
        assert_eq!(v["dims"], serde_json::json!([4, 3, 10]));
        assert!(v.get("skipped").is_none(), "{v}");
        let v = json(&[store, "--level", "0"]);
        assert_eq!(v["dims"], serde_json::json!([64, 48, 10]));
    }

    #[test]
    fn mesh_json() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.ply");
        let mesh = Mesh {
            positions: vec![[0.0, 0.0, 0.0], [2.0, 0.0, -1.0], [0.0, 3.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            ..Mesh::default()
        };
        glint_io::mesh::write_ply(&p, &mesh, glint_io::mesh::PlyEncoding::BinaryLittleEndian)
            .unwrap();
        let v = json(&[p.to_str().unwrap()]);
        assert_eq!(v["vertices"], 3);
        assert_eq!(v["triangles"], 1);
        assert_eq!(v["bounds_mm"]["min"], serde_json::json!([0.0, 0.0, -1.0]));
        assert_eq!(v["bounds_mm"]["max"], serde_json::json!([2.0, 3.0, 0.0]));
        let text = run(&[p.to_str().unwrap()]).unwrap();
        assert!(
            text.contains("bounds:    (0, 0, -1) .. (2, 3, 0) mm"),
            "{text}"
        );
    }

    /// A bare DICOM data set (no preamble, no meta group) in explicit VR little endian,
    /// written element by element (PS3.5 7.1.2): Modality, Rows 1, Columns 2, 8 bits,
    /// PixelData 5, 7.
    fn bare_dicom() -> Vec<u8> {
        let mut b = Vec::new();
        let mut el = |g: u16, e: u16, vr: &[u8; 2], v: &[u8]| {
            b.extend(g.to_le_bytes());
            b.extend(e.to_le_bytes());
            b.extend(vr);
            if vr == b"OB" {
                b.extend([0, 0]);
                b.extend((v.len() as u32).to_le_bytes());
            } else {
                b.extend((v.len() as u16).to_le_bytes());
            }
            b.extend(v);
        };
        el(0x0008, 0x0060, b"CS", b"OT");
        el(0x0028, 0x0010, b"US", &1u16.to_le_bytes());
        el(0x0028, 0x0011, b"US", &2u16.to_le_bytes());
        el(0x0028, 0x0100, b"US", &8u16.to_le_bytes());
        el(0x7FE0, 0x0010, b"OB", &[5, 7]);
        b
    }

    #[test]
    fn strict_refuses_a_bare_dicom_data_set() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bare.dcm");
        std::fs::write(&p, bare_dicom()).unwrap();
        let path = p.to_str().unwrap();
        let text = run(&[path]).unwrap();
        assert!(text.contains("dims:     2 x 1 x 1"), "{text}");
        assert!(text.contains("range:    5 .. 7"), "{text}");
        assert!(
            text.contains("note:     no preamble and no file meta group"),
            "{text}"
        );
        let err = run(&[path, "--strict"]).unwrap_err().to_string();
        assert!(err.contains("--strict"), "{err}");
    }

    /// Issue 17: `glint info` lists a GIFTI's per-vertex arrays, also for a file that
    /// has no surface (fsaverage5 sulcal depth; range from nibabel 5.4.2 via
    /// scripts/fixtures/gifti-reference.py: -1.4937248 .. 1.8069096).
    #[test]
    fn gifti_overlays_listed() {
        let Some(p) = glint_testkit::sample("fsaverage5_sulc_left.gii.gz") else {
            return;
        };
        let text = run(&[p.to_str().unwrap()]).unwrap();
        assert!(
            text.contains("format:    GIFTI per-vertex data (no surface)"),
            "{text}"
        );
        assert!(
            text.contains("(NIFTI_INTENT_SHAPE): 10242 values, -1.4937 .. 1.8069\n"),
            "{text}"
        );
        let v = json(&[p.to_str().unwrap()]);
        assert_eq!(v["overlays"][0]["values"], 10242);
        assert_eq!(v["overlays"][0]["intent"], "NIFTI_INTENT_SHAPE");
    }

    #[test]
    fn bad_file_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("broken.nii");
        std::fs::write(&p, b"not a nifti file at all").unwrap();
        let err = run(&[p.to_str().unwrap()]).unwrap_err().to_string();
        assert!(
            err.contains("broken.nii") && err.contains("truncated"),
            "{err}"
        );
    }

    /// A DICOM directory's listing: one line per series and per skipped object, and
    /// the same in JSON.
    #[test]
    fn dicom_listing_lines_and_json() {
        use glint_io::dicom::{Listing, Series, Skipped};
        let l = Listing {
            series: vec![Series {
                uid: "1.2.3".into(),
                modality: Some("CT".into()),
                description: Some("chest".into()),
                files: 64,
                slices: 64,
                columns: 512,
                rows: 512,
                photometric: "MONOCHROME2".into(),
            }],
            skipped: vec![Skipped {
                path: "x/rs.dcm".into(),
                reason: "no PixelData: not an image (RT Structure Set Storage)".into(),
                class: Some("RT Structure Set Storage".into()),
                modality: Some("RTSTRUCT".into()),
                series: Some("1.2.4".into()),
            }],
        };
        let mut out = String::new();
        print_listing(&mut out, &l).unwrap();
        assert_eq!(
            out,
            "series:   1.2.3 CT 'chest': 512 x 512 x 64 (64 files)\n\
             skipped:  x/rs.dcm: no PixelData: not an image (RT Structure Set Storage)\n"
        );
        let mut v = serde_json::json!({});
        listing_json(&mut v, &l);
        assert_eq!(v["series"][0]["dims"], serde_json::json!([512, 512, 64]));
        assert_eq!(v["skipped"][0]["class"], "RT Structure Set Storage");
    }
}
