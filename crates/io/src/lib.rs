//! Readers for biomedical volumes (NIfTI, NRRD, MGH, DICOM, raw) and surfaces (STL, OBJ,
//! PLY, GIFTI) into one [`Volume`] and one [`Mesh`] type, with writers for round trips.
//!
//! ```
//! use glint_io::{nifti, Endian, ReadOptions, Samples, Volume};
//!
//! // A 2x2x2 volume of u8 samples with 1 mm voxels at the origin.
//! let vol = Volume::new([2, 2, 2], [1.0; 3], Samples::U8(vec![0, 1, 2, 3, 4, 5, 6, 7])).unwrap();
//! assert_eq!(vol.value(1, 1, 1), 7.0);
//! assert_eq!(vol.range(), (0.0, 7.0));
//!
//! // Write it as gzipped NIfTI and read it back; the format follows the extension.
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("tiny.nii.gz");
//! nifti::write(&path, &vol, true, Endian::Little).unwrap();
//! let back = glint_io::read_volume(&path, &ReadOptions::default()).unwrap();
//! assert_eq!(back.samples, vol.samples);
//! assert_eq!(back.affine, vol.affine);
//! ```
//!
//! A colour volume (DICOM RGB and YBR images) carries its RGB planes in
//! [`Volume::colour`] beside a grey [`Volume::samples`] ([`ReadOptions::grey`]).
//!
//! World coordinates are millimetres in RAS+ (x towards the patient's Right, y Anterior,
//! z Superior), NIfTI's convention; readers of LPS formats (DICOM, NRRD in LPS space)
//! convert. Every reader checks the announced size against [`ReadOptions::max_voxels`]
//! and the file before allocating for samples, and every error names the file
//! ([`IoError`]).
//!
//! | format | module | read | write |
//! | --- | --- | --- | --- |
//! | NIfTI-1, NIfTI-2 `.nii`, `.nii.gz`; `.hdr`/`.img` (also ANALYZE 7.5) | [`nifti`] | yes | `.nii` |
//! | NRRD `.nrrd`, `.nhdr` | [`nrrd`] | raw, gzip, text | raw, gzip |
//! | FreeSurfer MGH `.mgh`, `.mgz` | [`mgh`] | uchar, short, ushort, int, float | no |
//! | DICOM file or directory | [`dicom`] | native, deflate, JPEG (8, 12-bit, lossless), JPEG-LS, JPEG 2000, RLE; grey, 1-bit and colour | no |
//! | OME-Zarr directory (NGFF 0.4, 0.5; Zarr v2, v3) | [`zarr`] | one pyramid level, read whole or streamed a box at a time ([`zarr::Stream`]); blosc, gzip, zstd, sharding | no |
//! | raw samples | [`raw`] | yes | yes |
//! | STL | [`mesh`] | binary, ASCII | binary |
//! | OBJ | [`mesh`] | yes | yes |
//! | PLY | [`mesh`] | ASCII, binary | ASCII, binary |
//! | GIFTI `.gii`, `.gii.gz` (+ per-vertex data: [`read_surface_data`]) | [`gifti`] | ASCII, Base64, GZipBase64, external file | ASCII, Base64, GZipBase64 |

#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod affine;
mod clock;
mod common;
pub mod dicom;
pub mod gifti;
pub mod info;
mod link;
pub mod mesh;
mod message;
pub mod mgh;
pub mod nifti;
pub mod nrrd;
pub mod raw;
mod robust;
mod types;
pub mod zarr;

pub use common::{recycle, write_atomic, Endian, ParseScalarTypeError, ScalarType};
pub use gifti::{read_surface_data, Label, VertexData, VertexValues};
pub use link::broken_link;
pub use message::one_line;
pub use robust::{robust_range, ROBUST_PERCENTILES, ROBUST_SAMPLES};
pub use types::{IoError, Mesh, Rgb, Samples, Volume};

use std::path::Path;

/// The file formats glint reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, strum::IntoStaticStr, strum::Display)]
#[non_exhaustive]
pub enum Format {
    /// NIfTI-1 or NIfTI-2 (`.nii`, `.nii.gz`), or a `.hdr`/`.img` pair (NIfTI or ANALYZE 7.5).
    #[strum(to_string = "NIfTI")]
    Nifti,
    /// NRRD (`.nrrd`, `.nhdr` + data file).
    #[strum(to_string = "NRRD")]
    Nrrd,
    /// FreeSurfer MGH (`.mgh`; `.mgz`, `.mgh.gz` gzip-compressed).
    #[strum(to_string = "MGH")]
    Mgh,
    /// DICOM (a file or a directory of slices).
    #[strum(to_string = "DICOM")]
    Dicom,
    /// Headerless samples described by the caller.
    #[strum(to_string = "raw")]
    Raw,
    /// STL, binary or ASCII.
    #[strum(to_string = "STL")]
    Stl,
    /// Wavefront OBJ.
    #[strum(to_string = "OBJ")]
    Obj,
    /// Stanford PLY, ASCII or binary.
    #[strum(to_string = "PLY")]
    Ply,
    /// GIFTI surface (`.gii`, `.gii.gz`).
    #[strum(to_string = "GIFTI")]
    Gifti,
    /// OME-Zarr multiscale image (a directory: NGFF 0.4 on Zarr v2, 0.5 on Zarr v3).
    #[strum(to_string = "OME-Zarr")]
    Zarr,
}

impl Format {
    /// The format's usual name.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// Whether the format holds surfaces (else volumes).
    pub fn is_mesh(self) -> bool {
        matches!(
            self,
            Format::Stl | Format::Obj | Format::Ply | Format::Gifti
        )
    }

    /// Guesses the format from a path: a directory is DICOM; otherwise the extension
    /// (case-insensitive, `.gz` looked through). `None` if unknown.
    pub fn guess(path: &Path) -> Option<Format> {
        if zarr::is_store(path) {
            return Some(Format::Zarr);
        }
        if path.is_dir() {
            return Some(Format::Dicom);
        }
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        let name = name.strip_suffix(".gz").unwrap_or(&name);
        let ext = name.rsplit_once('.').map(|(_, e)| e).unwrap_or("");
        Some(match ext {
            "nii" | "hdr" => Format::Nifti,
            "nrrd" | "nhdr" => Format::Nrrd,
            "mgh" | "mgz" => Format::Mgh,
            "dcm" | "dicom" | "ima" => Format::Dicom,
            "raw" | "bin" | "img" => Format::Raw,
            "stl" => Format::Stl,
            "obj" => Format::Obj,
            "ply" => Format::Ply,
            "gii" => Format::Gifti,
            _ => return None,
        })
    }
}

/// How to interpret a headerless file of samples.
#[derive(Clone, Debug, PartialEq)]
pub struct RawParams {
    /// Samples along i, j, k (i fastest in the file).
    pub dims: [usize; 3],
    /// The stored type.
    pub scalar: ScalarType,
    /// Voxel size in mm.
    pub spacing: [f64; 3],
    /// Byte order of multi-byte samples.
    pub endian: Endian,
    /// Bytes to skip before the samples.
    pub offset: u64,
}

/// Limits and hints for readers.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    /// Refuse volumes with more voxels than this before allocating for them.
    pub max_voxels: u64,
    /// Read the file as raw samples with these parameters, whatever its extension.
    pub raw: Option<RawParams>,
    /// Refuse what lenient readers accept with a note: DICOM files without the 128-byte
    /// preamble or the file meta group, multi-frame DICOM without frame positions,
    /// DICOM PixelSpacing of zero, OME-Zarr levels with missing chunks.
    pub strict: bool,
    /// What a colour volume's [`Volume::samples`] hold: its luminance (the default) or
    /// one of its channels. The colour itself is in [`Volume::colour`] either way,
    /// unless [`ReadOptions::colour`] is off.
    pub grey: Grey,
    /// Keep a colour volume's colour in [`Volume::colour`] (the default: renderers
    /// then draw it in colour); `false` drops it after reading, leaving the grey
    /// samples alone, which render as a grey volume (`glint render --channel`).
    pub colour: bool,
    /// The DICOM series to read from a directory that holds several, by its
    /// SeriesInstanceUID; `None` reads the only image series, or the largest (with a
    /// note naming the others).
    pub series: Option<String>,
    /// The level of an OME-Zarr pyramid to read (default: the finest).
    pub level: zarr::Level,
    /// The image (a DICOM file or directory) an RT structure set's contours are
    /// rasterised onto: the volume they are drawn over. `None`: the series the structure
    /// set references, found in its own directory (see [`dicom::read_structure_set`]).
    pub reference: Option<std::path::PathBuf>,
}

/// The grey a colour volume's [`Volume::samples`] hold ([`ReadOptions::grey`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Grey {
    /// The luma `0.299 R + 0.587 G + 0.114 B` (ITU-R BT.601, the Y of DICOM's YBR_FULL,
    /// PS3.3 C.7.6.3.1.2), rounded to the channels' type.
    #[default]
    Luminance,
    /// The red channel.
    Red,
    /// The green channel.
    Green,
    /// The blue channel.
    Blue,
}

impl Grey {
    /// Every choice, in the order of [`Grey::name`]s users type.
    pub const ALL: [Grey; 4] = [Grey::Luminance, Grey::Red, Grey::Green, Grey::Blue];

    /// The name on the command line: `luminance`, `red`, `green`, `blue`.
    pub fn name(self) -> &'static str {
        match self {
            Grey::Luminance => "luminance",
            Grey::Red => "red",
            Grey::Green => "green",
            Grey::Blue => "blue",
        }
    }
}

impl std::str::FromStr for Grey {
    type Err = String;
    /// Parses a [`Grey::name`] (also `r`, `g`, `b`, `luma`), case-insensitive.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.trim().to_ascii_lowercase().as_str() {
            "luminance" | "luma" | "y" => Grey::Luminance,
            "red" | "r" => Grey::Red,
            "green" | "g" => Grey::Green,
            "blue" | "b" => Grey::Blue,
            _ => {
                return Err(format!(
                    "unknown channel '{s}' (expected luminance, red, green or blue)"
                ))
            }
        })
    }
}

impl Default for ReadOptions {
    fn default() -> Self {
        // 2^31 voxels: a 1290^3 volume, 8 GiB as f32; far above clinical CT (512^2 x ~2000).
        ReadOptions {
            max_voxels: 1 << 31,
            raw: None,
            strict: false,
            grey: Grey::Luminance,
            colour: true,
            series: None,
            level: zarr::Level::Finest,
            reference: None,
        }
    }
}

/// A volume with what is known about the file it came from.
#[derive(Clone, Debug)]
pub struct VolumeFile {
    /// The volume.
    pub volume: Volume,
    /// The format read.
    pub format: Format,
    /// Facts about the reading worth telling the user (where the affine came from,
    /// dropped dimensions, ...).
    pub notes: Vec<String>,
    /// Time spent inflating gzip data (with reading the compressed bytes), for
    /// compressed NIfTI and gzip-encoded NRRD; `None` when nothing was inflated or it
    /// was not measured.
    pub inflate: Option<std::time::Duration>,
}

/// A mesh with what is known about the file it came from.
#[derive(Clone, Debug)]
pub struct MeshFile {
    /// The mesh.
    pub mesh: Mesh,
    /// The format read.
    pub format: Format,
    /// The space the positions are in, where the file says (GIFTI's DataSpace and
    /// TransformedSpace, e.g. `NIFTI_XFORM_TALAIRACH`).
    pub coordinate_system: Option<String>,
    /// Facts about the reading worth telling the user.
    pub notes: Vec<String>,
}

/// Reads a volume, choosing the format from the path (extension, or a directory of
/// DICOM slices).
pub fn read_volume(path: &Path, options: &ReadOptions) -> Result<Volume, IoError> {
    open_volume(path, options).map(|f| f.volume)
}

/// Reads a volume like [`read_volume`], with the format and notes.
pub fn open_volume(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let mut file = open_any_volume(path, options)?;
    if !options.colour {
        file.volume.colour = None;
    }
    Ok(file)
}

/// [`open_volume`] before [`ReadOptions::colour`] is applied.
fn open_any_volume(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    if let Err(e) = std::fs::metadata(path) {
        return Err(link::os_error(path, e));
    }
    if let Some(params) = &options.raw {
        return raw::read(path, params, options);
    }
    match Format::guess(path) {
        Some(Format::Nifti) => nifti::read(path, options),
        Some(Format::Nrrd) => nrrd::read(path, options),
        Some(Format::Mgh) => mgh::read(path, options),
        Some(Format::Dicom) => dicom::read(path, options),
        Some(Format::Zarr) => zarr::read(path, options),
        Some(Format::Raw) => unsupported(
            path,
            "a raw file needs its dimensions, type and spacing (ReadOptions::raw)",
        ),
        Some(f) if f.is_mesh() => unsupported(path, "this is a surface format, not a volume"),
        Some(f) => unsupported(
            path,
            &format!("{} volumes are not implemented yet", f.name()),
        ),
        None if common::has_dicom_magic(path) => dicom::read(path, options),
        None => unsupported(
            path,
            "unknown volume extension (expected .nii, .nii.gz, .nrrd, .nhdr, .mgh, .mgz, .dcm, \
             a DICOM directory, or raw parameters)",
        ),
    }
}

/// Reads a surface mesh, choosing the format from the extension.
pub fn read_mesh(path: &Path) -> Result<Mesh, IoError> {
    open_mesh(path).map(|f| f.mesh)
}

/// Reads a mesh like [`read_mesh`], with the format and coordinate system.
pub fn open_mesh(path: &Path) -> Result<MeshFile, IoError> {
    match std::fs::metadata(path) {
        Err(e) => return Err(link::os_error(path, e)),
        Ok(m) if m.is_dir() => return unsupported(path, "a directory is not a surface file"),
        Ok(_) => {}
    }
    match Format::guess(path) {
        Some(Format::Stl) => mesh::read_stl(path),
        Some(Format::Obj) => mesh::read_obj(path),
        Some(Format::Ply) => mesh::read_ply(path),
        Some(Format::Gifti) => gifti::read(path),
        Some(_) => unsupported(path, "this is a volume format, not a surface"),
        None => unsupported(
            path,
            "unknown surface extension (expected .stl, .obj, .ply, .gii or .gii.gz)",
        ),
    }
}

fn unsupported<T>(path: &Path, what: &str) -> Result<T, IoError> {
    Err(IoError::Unsupported {
        path: path.to_path_buf(),
        what: what.into(),
    })
}
