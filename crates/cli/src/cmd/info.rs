//! `glint info`: what a volume or surface file holds (format, dims, spacing, type, range,
//! affine; or vertex and triangle counts and bounds), as text or JSON.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::bail;
use glint_io::info::FileInfo;
use glint_io::zarr::Level;
use glint_io::{Endian, Format, RawParams, ReadOptions, ScalarType};

/// Arguments of `glint info`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    glint info mni152_t1_09a.nii.gz\n  \
    glint info fsaverage5_pial_left.gii.gz --json\n  \
    glint info ct_series/            (a directory of DICOM slices)\n  \
    glint info aseg.mgz --labels     (labels, names, voxels, ml)\n  \
    glint info mask.nii.gz --labels --label-table totalsegmentator\n  \
    glint info mask.nii.gz --labels --label-table t.csv --all-labels  (absent ones too)\n  \
    glint info head.raw --raw-dims 256,256,128 --raw-type u16 --raw-spacing 0.9,0.9,1.5\n  \
    glint info --devices             (the GPU adapters, for --device gpu|auto)")]
pub struct Args {
    /// The file (.nii, .nii.gz, .nrrd, .nhdr, .dcm, DICOM directory, .stl, .obj, .ply,
    /// .gii, .gii.gz, or raw samples with --raw-dims).
    #[arg(required_unless_present = "devices")]
    file: Option<PathBuf>,
    /// List the GPU adapters instead (name, backend, device type, driver, largest 3D
    /// texture side, compute), for `--device gpu|auto` (docs/gpu.md).
    #[arg(long, conflicts_with = "file")]
    devices: bool,
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

impl Args {
    /// The file (clap requires it unless --devices, which `run` answers first).
    fn file(&self) -> &std::path::Path {
        self.file
            .as_deref()
            .expect("clap requires FILE without --devices")
    }
}

/// Runs `glint info`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if args.devices {
        print!("{}", super::devices::report(args.json)?);
        return Ok(());
    }
    print!("{}", report(&args)?);
    Ok(())
}

/// The text or JSON `glint info` prints.
fn report(args: &Args) -> anyhow::Result<String> {
    let options = read_options(args)?;
    let is_mesh = options.raw.is_none() && Format::guess(args.file()).is_some_and(Format::is_mesh);
    if options.raw.is_none() && Format::guess(args.file()) == Some(Format::Raw) {
        bail!(
            "{}: a raw file needs --raw-dims (and --raw-type, --raw-spacing)",
            args.file().display()
        );
    }
    if is_mesh && args.labels {
        bail!(
            "{}: --labels lists a label volume's labels; this is a mesh",
            args.file().display()
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
    let (file, overlays) = if Format::guess(args.file()) == Some(Format::Gifti) {
        glint_io::gifti::read_with_data(args.file())?
    } else {
        (Some(glint_io::open_mesh(args.file())?), Vec::new())
    };
    let info = FileInfo::mesh(args.file(), file.as_ref(), &overlays);
    if args.json {
        out = serde_json::to_string_pretty(&info.to_json())? + "\n";
    } else {
        write!(out, "{info}")?;
    }
    Ok(out)
}

/// The report of a volume (with a DICOM directory's listing and, asked for, its labels).
fn volume_report(args: &Args, options: &ReadOptions) -> anyhow::Result<String> {
    let mut out = String::new();
    let reading =
        super::spinner::Spinner::start(format!("reading {}", args.file().display()), false);
    let file = glint_io::open_volume(args.file(), options)?;
    drop(reading);
    // Assumed geometry is worth a warning even when the output goes to a script.
    for n in file
        .notes
        .iter()
        .filter(|n| n.starts_with("geometry assumed") || n.contains("chunks missing"))
    {
        eprintln!("glint: {}: {n}", args.file().display());
    }
    // A DICOM directory: every series and every object not read, too.
    let listing = match args.file().is_dir() && file.format == Format::Dicom {
        true => Some(glint_io::dicom::list(args.file(), options)?),
        false => None,
    };
    let info = FileInfo::volume(args.file(), &file, listing.as_ref());
    let labels = super::info_labels::Listing {
        table: args.label_table.as_deref(),
        all: args.all_labels,
    };
    if args.json {
        let mut v = info.to_json();
        if args.labels {
            super::info_labels::add_json(&mut v, args.file(), &file.volume, &labels)?;
        }
        out = serde_json::to_string_pretty(&v)? + "\n";
    } else {
        write!(out, "{info}")?;
        if args.labels {
            super::info_labels::print(&mut out, args.file(), &file.volume, &labels)?;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::{report, Args};
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
    fn devices_are_listed_as_text_and_json_and_a_file_or_devices_is_required() {
        let cli = Cli::try_parse_from(["info", "--devices"]).unwrap();
        assert!(cli.args.devices && cli.args.file.is_none());
        let text = super::super::devices::report(false).unwrap();
        let list: Value =
            serde_json::from_str(&super::super::devices::report(true).unwrap()).unwrap();
        let list = list.as_array().unwrap();
        // One line per adapter, or one line saying there is none.
        assert_eq!(text.lines().count(), list.len().max(1), "{text}");
        for a in list {
            assert!(a["name"].is_string() && a["max_texture_3d"].is_u64(), "{a}");
        }
        assert!(Cli::try_parse_from(["info"]).is_err());
        assert!(Cli::try_parse_from(["info", "v.nii", "--devices"]).is_err());
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
}
