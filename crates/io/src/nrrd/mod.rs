//! NRRD volumes (`.nrrd` attached, `.nhdr` detached header), 3D Slicer's native format.
//!
//! The header is parsed here: the crates.io `nrrd` crates are unmaintained stubs or
//! lack detached headers, gzip and space directions, and the header is a short list of
//! `key: value` lines. Follows the NRRD0005 spec at
//! <https://teem.sourceforge.net/nrrd/format.html>. Supported: dimension 2 or 3, the
//! eight sample types, `raw`, `gzip` and `text` encodings, `byte skip` (including -1 for
//! raw data), `line skip`, `space` (RAS/LPS/LAS, converted to RAS), `space directions`,
//! `space origin`, or `spacings` without a space. The time spent inflating gzip data is
//! reported as [`VolumeFile::inflate`](crate::VolumeFile::inflate).
//!
//! The module is split by concern: `header` reads and validates the header's fields,
//! `data` opens the data file and decodes the samples, `geometry` builds the affine,
//! `write` writes volumes.

mod data;
mod geometry;
mod header;
mod write;

use std::path::Path;

use crate::clock::Clock;
use crate::common::check_affine;
use crate::{Format, IoError, ReadOptions, Volume, VolumeFile};

use data::{decode, open_data};
use geometry::geometry;
use header::{read_fields, Layout};

pub use write::{write, write_detached};

/// Longest header accepted: real headers are a few hundred bytes.
const MAX_HEADER_BYTES: u64 = 1 << 20;

/// NRRD data encodings for [`write()`] and [`write_detached`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// Samples as bytes.
    Raw,
    /// Samples as bytes, gzip-compressed.
    Gzip,
}

fn invalid(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Invalid {
        path: path.into(),
        what: what.into(),
    }
}

/// Reads a NRRD volume (attached or detached header).
///
/// The steps, in the order their errors are reported: the header's fields, the sample
/// layout they announce (checked against `options.max_voxels` before anything is
/// allocated), the data file, the samples, then the geometry.
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let fields = read_fields(path)?;
    let layout = Layout::parse(path, &fields, options)?;
    let (dpath, data) = open_data(path, &fields, layout.line_skip)?;
    let clock = Clock::default();
    let samples = decode(path, &dpath, data, &layout, &clock)?;
    let (affine, notes) = geometry(path, &fields, layout.dimension)?;
    let spacing = check_affine(path, &affine)?;
    Ok(VolumeFile {
        volume: Volume {
            dims: layout.dims,
            spacing,
            affine,
            samples,
            slope: 1.0,
            intercept: 0.0,
            units: None,
            colour: None,
        },
        format: Format::Nrrd,
        notes,
        inflate: clock.spent(),
    })
}

/// At most 40 characters of `s`, for quoting header text in a message.
fn truncate(s: &str) -> String {
    s.chars().take(40).collect()
}
