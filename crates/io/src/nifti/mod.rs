//! NIfTI-1 and NIfTI-2 volumes (`.nii`, `.nii.gz`), and header/image pairs (`.hdr` +
//! `.img`: NIfTI-1, NIfTI-2 or ANALYZE 7.5).
//!
//! The 348-byte header is parsed here rather than with the `nifti` crate: that crate
//! reads the whole data block into memory sized by the header before any check we could
//! apply (no voxel limit, no growth-with-data), and pulls in nalgebra and ndarray for
//! what is a fixed table of offsets. The layout follows nifti1.h
//! (<https://nifti.nimh.nih.gov/pub/dist/src/niftilib/nifti1.h>), and the qform
//! quaternion formula follows nifti1_io.c `nifti_quatern_to_mat44`. NIfTI-2 follows
//! nifti2.h (<https://nifti.nimh.nih.gov/pub/dist/doc/nifti2.h>): the same fields as
//! 64-bit integers and doubles in a 540-byte header.
//!
//! The module is split by concern: `header` parses the header and derives the
//! dimensions and the affine from it, `write` writes volumes; this file opens the files
//! and reads the samples.

mod header;
mod write;

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::clock::Clock;
use crate::common::{
    can_inflate_to, check_affine, check_scaling, checked_voxels, open_maybe_gz, os_or_invalid,
    read_decoded, read_exact_growing, ScalarType,
};
use crate::{IoError, ReadOptions, Samples, Volume, VolumeFile};

use header::{affine_of, dims_of, parse_header, type_of, unsupported_type_name, Header, Version};

pub use write::{write, write_nifti2};

const HEADER_SIZE: usize = 348;
/// The NIfTI-2 header (nifti2.h); its single-file data starts 4 bytes later.
const HEADER2_SIZE: usize = 540;

/// The image file of a `.hdr` (`.img`, or `.img.gz`, beside it).
fn image_of(path: &Path) -> Result<PathBuf, IoError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem_len = name.to_ascii_lowercase().find(".hdr").unwrap_or(name.len());
    let stem = &name[..stem_len];
    [".img", ".IMG", ".img.gz", ".IMG.GZ"]
        .iter()
        .map(|ext| path.with_file_name(format!("{stem}{ext}")))
        .find(|p| p.is_file())
        .ok_or_else(|| IoError::Invalid {
            path: path.into(),
            what: format!("no image file {stem}.img beside the header"),
        })
}

/// Reads a NIfTI-1 or NIfTI-2 volume (`.nii`, `.nii.gz`), or a header/image pair
/// (`.hdr` + `.img`: NIfTI-1 `ni1`, NIfTI-2 `ni2`, or ANALYZE 7.5), gzip-compressed or
/// not, either byte order. 4D files yield their first volume, with a note.
///
/// The steps, in the order their errors are reported: the header, the sample layout it
/// announces (checked against `options.max_voxels` before anything is allocated), the
/// data offset, the samples, then the geometry and scaling.
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let lower = path.to_string_lossy().to_ascii_lowercase();
    let pair = lower.ends_with(".hdr") || lower.ends_with(".hdr.gz");
    let clock = Clock::default();
    let (mut reader, file_len) = open_maybe_gz(path, &clock)?;
    let (h, header_len) = read_header(path, &mut reader, pair)?;
    let (dims, extra) = dims_of(path, &h)?;
    let ty = sample_type(path, &h)?;
    let count = checked_voxels(path, dims, ty.size(), options.max_voxels)?;
    let offset = data_offset(path, &h, pair, header_len)?;
    let source = if pair {
        let img = image_of(path)?;
        let (r, len) = open_maybe_gz(&img, &clock)?;
        DataSource {
            path: img,
            reader: r,
            len,
            skip: offset,
        }
    } else {
        DataSource {
            path: path.to_path_buf(),
            reader,
            len: file_len,
            skip: offset - header_len as u64,
        }
    };
    let samples = read_samples(source, offset, dims, count, ty, h.endian)?;

    let mut notes = vec![version_note(h.version, pair).to_string()];
    if extra > 1 {
        notes.push(format!("4D+ image: read the first of {extra} volumes"));
    }
    let (affine, source) = affine_of(path, &h)?;
    notes.push(format!("affine from {source}"));
    let spacing = check_affine(path, &affine)?;
    let (slope, intercept) = scaling(&h);
    check_scaling(
        path,
        &samples,
        (slope, intercept),
        ["scl_slope", "scl_inter"],
    )?;
    Ok(VolumeFile {
        volume: Volume {
            dims,
            spacing,
            affine,
            samples,
            slope,
            intercept,
            units: None,
            colour: None,
        },
        format: crate::Format::Nifti,
        notes,
        inflate: clock.spent(),
    })
}

/// Reads and parses the header (348 bytes, or 540 for NIfTI-2); returns it with its
/// length.
fn read_header(
    path: &Path,
    reader: &mut Box<dyn Read>,
    pair: bool,
) -> Result<(Header, usize), IoError> {
    let head = read_exact_growing(path, &mut *reader, HEADER_SIZE, "NIfTI header")?;
    let h = parse_header(
        path,
        &head,
        || {
            read_exact_growing(
                path,
                &mut *reader,
                HEADER2_SIZE - HEADER_SIZE,
                "NIfTI-2 header",
            )
        },
        pair,
    )?;
    let len = if h.version == Version::Two {
        HEADER2_SIZE
    } else {
        HEADER_SIZE
    };
    Ok((h, len))
}

/// The stored sample type, or an error naming the datatype refused.
fn sample_type(path: &Path, h: &Header) -> Result<ScalarType, IoError> {
    type_of(h.datatype).ok_or_else(|| IoError::Unsupported {
        path: path.into(),
        what: format!(
            "datatype {} ({}); supported: uint8, int8, uint16, int16, uint32, int32, \
             float32, float64",
            h.datatype,
            unsupported_type_name(h.datatype)
        ),
    })
}

/// `vox_offset` as a byte offset: a pair's image usually starts at 0, a single file's
/// data after the header.
fn data_offset(path: &Path, h: &Header, pair: bool, header_len: usize) -> Result<u64, IoError> {
    let min_offset = if pair { 0.0 } else { header_len as f64 };
    if !h.vox_offset.is_finite() || h.vox_offset < min_offset || h.vox_offset > 1e12 {
        return Err(IoError::Invalid {
            path: path.into(),
            what: format!(
                "vox_offset {} is not a byte offset past the header",
                h.vox_offset
            ),
        });
    }
    Ok(h.vox_offset as u64)
}

/// Where the samples are read from: the image file of a pair, or the rest of a single
/// file after its header.
struct DataSource {
    path: PathBuf,
    reader: Box<dyn Read>,
    /// The file's length, when known (uncompressed).
    len: Option<u64>,
    /// Bytes to skip in `reader` before the samples.
    skip: u64,
}

/// Reads `count` samples of `ty` at byte `offset` of the data file: its size is checked
/// first when known; the samples are allocated at once when the file (compressed or
/// not) can hold them, else grow with the data actually read.
fn read_samples(
    src: DataSource,
    offset: u64,
    dims: [usize; 3],
    count: usize,
    ty: ScalarType,
    endian: crate::Endian,
) -> Result<Samples, IoError> {
    let DataSource {
        path,
        mut reader,
        len,
        skip,
    } = src;
    let nbytes = count * ty.size();
    // For an uncompressed file the size is known up front.
    if let Some(len) = len {
        if len < offset + nbytes as u64 {
            return Err(IoError::SizeMismatch {
                path,
                what: format!(
                    "the header announces {nbytes} bytes of {ty} data at offset {offset} \
                     ({}x{}x{}), but the file has {len} bytes",
                    dims[0], dims[1], dims[2]
                ),
            });
        }
    }
    let skipped = std::io::copy(&mut (&mut reader).take(skip), &mut std::io::sink())
        .map_err(|e| os_or_invalid(&path, e))?;
    if skipped < skip {
        return Err(IoError::Truncated {
            path,
            what: format!("the file ends before the data offset {offset}"),
        });
    }
    let checked = len.is_some() || can_inflate_to(&path, offset + nbytes as u64);
    read_decoded(&path, reader, count, ty, endian, "voxel data", checked)
}

/// The first note: which header the file has.
fn version_note(version: Version, pair: bool) -> &'static str {
    match version {
        Version::One if pair => "NIfTI-1 header/image pair",
        Version::One => "NIfTI-1",
        Version::Two if pair => "NIfTI-2 header/image pair",
        Version::Two => "NIfTI-2",
        Version::Analyze => "ANALYZE 7.5 (no orientation: axes taken as RAS)",
    }
}

/// The scaling of stored values. nifti1.h: "If the scl_slope field is nonzero, then
/// each voxel value in the dataset should be scaled as y = scl_slope * x + scl_inter".
fn scaling(h: &Header) -> (f64, f64) {
    let (mut slope, mut intercept) = (h.slope, h.intercept);
    if slope == 0.0 || !slope.is_finite() {
        slope = 1.0;
        intercept = 0.0;
    }
    if !intercept.is_finite() {
        intercept = 0.0;
    }
    (slope, intercept)
}
