//! DICOM volumes through dicom-rs (`dicom-object`, `dicom-pixeldata`): a directory of
//! single-frame slices or one multi-frame file (classic or enhanced), with native pixel
//! data (implicit or explicit VR, little or big endian, deflated) or compressed pixel
//! data (JPEG baseline, extended and lossless, JPEG 2000, RLE). JPEG-LS is refused:
//! its decoder (CharLS) needs CMake to build.
//!
//! Slices are sorted by their position along the slice normal (row x column direction
//! cosines), the slice step comes from the positions (not SliceThickness), and uneven
//! steps (a missing slice), duplicate positions, different series, orientations or
//! sizes are errors. The affine is built in DICOM's patient LPS space and converted to
//! RAS by negating x and y (DICOM PS3.3 C.7.6.2.1.1). Rescale slope and intercept are
//! kept as the volume's slope and intercept (CT values then are Hounsfield units).
//!
//! Lenient like pydicom (`force=True`), GDCM and DCMTK unless [`ReadOptions::strict`]:
//! files without the 128-byte preamble, or without the file meta group, are read when
//! the data set parses; a multi-frame file without positions is read as a stack in
//! frame order, SpacingBetweenSlices (or 1 mm) apart. Each assumption is a note starting
//! with "geometry assumed:" or naming what was missing.
//!
//! Hostile files: every element length is checked against the bytes left and sequence
//! nesting is bounded before dicom-rs parses the file (see `scan`), and compressed
//! frames are checked against Rows x Columns before decoding (see `pixels`).

mod geometry;
mod header;
mod pixels;
mod scan;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use header::{open_header, Header};

use crate::common::checked_voxels;
use crate::{Format, IoError, ReadOptions, Samples, Volume, VolumeFile};

pub use scan::MAX_NESTING;

/// Tolerance on direction cosines when checking that slices share an orientation.
const ORIENTATION_TOLERANCE: f64 = 1e-4;

/// Relative tolerance when comparing PixelSpacing across the slices of a series.
const SPACING_TOLERANCE: f64 = 1e-3;

/// Longest text quoted from a file in an error message.
const QUOTE_MAX: usize = 200;

fn invalid(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Invalid {
        path: path.into(),
        what: what.into(),
    }
}

/// Text from a file (or an error about it) made fit for a one-line message: control
/// characters escaped, at most [`QUOTE_MAX`] characters.
pub(crate) fn one_line(s: &str) -> String {
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i == QUOTE_MAX {
            out.push_str("...");
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// An error and its sources, joined with ": ".
fn chain(e: &dyn std::error::Error) -> String {
    let mut chain = e.to_string();
    let mut src = e.source();
    while let Some(s) = src {
        chain += &format!(": {s}");
        src = s.source();
    }
    chain
}

fn open_error(path: &Path, e: dicom_object::ReadError) -> IoError {
    let chain = one_line(&chain(&e));
    if chain.contains("DICM") || chain.contains("magic") || chain.contains("preamble") {
        IoError::BadMagic {
            path: path.into(),
            format: "DICOM",
            what: chain,
        }
    } else if chain.to_ascii_lowercase().contains("eof")
        || chain.contains("fill whole buffer")
        || chain.contains("end of file")
    {
        IoError::Truncated {
            path: path.into(),
            what: chain,
        }
    } else if let dicom_object::ReadError::OpenFile { source, .. } = e {
        IoError::Os {
            path: path.into(),
            source,
        }
    } else {
        IoError::Invalid {
            path: path.into(),
            what: chain,
        }
    }
}

/// Reads a DICOM file (single- or multi-frame) or a directory of single-frame slices of
/// one series.
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let mut notes = Vec::new();
    let headers = headers(path, options, &mut notes)?;
    check_series(path, &headers)?;
    let first = &headers[0];
    let plane = geometry::plane(path, first, &mut notes)?;
    let mut frames = geometry::frames(&headers, plane.normal, options.strict, &mut notes)?;
    let dims = [first.cols, first.rows, frames.len()];
    checked_voxels(
        path,
        dims,
        usize::from(first.bits_allocated / 8),
        options.max_voxels,
    )?;
    let slice_vec = geometry::sort_and_step(path, &mut frames, first, plane.normal, &mut notes)?;
    let (affine, spacing) = geometry::affine(path, &plane, slice_vec, frames[0].position)?;
    let (samples, slope, intercept) = assemble(&headers, &frames, options.strict, &mut notes)?;
    let units = first
        .rescale_type
        .clone()
        .or_else(|| (first.modality.as_deref() == Some("CT")).then(|| "HU".to_string()));
    notes.push(format!(
        "{} slice(s) from {} file(s), modality {}",
        frames.len(),
        headers.len(),
        first
            .modality
            .as_deref()
            .map(one_line)
            .unwrap_or("unknown".into())
    ));
    if first.encapsulated {
        notes.push(format!("decoded {}", scan::ts_name(&first.ts)));
    }
    Ok(VolumeFile {
        volume: Volume {
            dims,
            spacing,
            affine,
            samples,
            slope,
            intercept,
            units,
        },
        format: Format::Dicom,
        notes,
        inflate: None,
    })
}

/// The headers of a file, or of every DICOM file in a directory (others skipped).
fn headers(
    path: &Path,
    options: &ReadOptions,
    notes: &mut Vec<String>,
) -> Result<Vec<Header>, IoError> {
    if !path.is_dir() {
        let h = open_header(path, options.max_voxels, options.strict)?;
        notes.extend(h.notes.iter().cloned());
        return Ok(vec![h]);
    }
    let mut entries: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| IoError::Os {
            path: path.into(),
            source: e,
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_file()
                && p.file_name().is_some_and(|n| {
                    let n = n.to_string_lossy();
                    !n.starts_with('.') && !n.eq_ignore_ascii_case("DICOMDIR")
                })
        })
        .collect();
    entries.sort();
    let mut headers = Vec::new();
    let mut skipped = 0;
    for p in &entries {
        match open_header(p, options.max_voxels, options.strict) {
            Ok(h) => headers.push(h),
            // Not DICOM at all (a README, a thumbnail): skip it, but say so.
            Err(IoError::BadMagic { .. }) => skipped += 1,
            Err(e) => return Err(e),
        }
    }
    if skipped > 0 {
        notes.push(format!("skipped {skipped} non-DICOM file(s)"));
    }
    let Some(first) = headers.first() else {
        return Err(invalid(path, "the directory holds no DICOM files"));
    };
    if let Some(n) = first.notes.first() {
        notes.push(format!("{n} (first file)"));
    }
    Ok(headers)
}

/// One series, one image size and pixel format, one orientation and pixel spacing.
fn check_series(path: &Path, headers: &[Header]) -> Result<(), IoError> {
    let mut series: BTreeMap<String, usize> = BTreeMap::new();
    for h in headers {
        *series
            .entry(h.series.clone().unwrap_or_else(|| "(none)".into()))
            .or_default() += 1;
    }
    if series.len() > 1 {
        return Err(IoError::MixedSeries {
            path: path.into(),
            what: one_line(&format!(
                "{} series: {}; point glint at one series",
                series.len(),
                series
                    .iter()
                    .map(|(k, n)| format!("{k} ({n} files)"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        });
    }
    let first = &headers[0];
    for h in &headers[1..] {
        if (h.rows, h.cols, h.bits_allocated, h.signed)
            != (first.rows, first.cols, first.bits_allocated, first.signed)
        {
            return Err(IoError::MixedSeries {
                path: path.into(),
                what: format!(
                    "{} is {}x{} {}-bit, {} is {}x{} {}-bit",
                    first.path.display(),
                    first.cols,
                    first.rows,
                    first.bits_allocated,
                    h.path.display(),
                    h.cols,
                    h.rows,
                    h.bits_allocated
                ),
            });
        }
        let same_orientation = match (h.orientation, first.orientation) {
            (Some(a), Some(b)) => a
                .iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() < ORIENTATION_TOLERANCE),
            (None, None) => true,
            _ => false,
        };
        let same_spacing = match (h.pixel_spacing, first.pixel_spacing) {
            (Some(a), Some(b)) => a
                .iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= SPACING_TOLERANCE * x.abs().max(y.abs())),
            (None, None) => true,
            _ => false,
        };
        if !same_spacing {
            return Err(IoError::MixedSeries {
                path: path.into(),
                what: format!(
                    "{} has PixelSpacing {:?}, {} has {:?}",
                    first.path.display(),
                    first.pixel_spacing,
                    h.path.display(),
                    h.pixel_spacing
                ),
            });
        }
        if !same_orientation {
            return Err(IoError::Geometry {
                path: path.into(),
                what: format!(
                    "{} and {} have different orientations",
                    first.path.display(),
                    h.path.display()
                ),
            });
        }
    }
    Ok(())
}

/// Reads every file's pixels once and places the frames in sorted order; per-slice
/// rescales that differ are applied (float32), else kept as slope and intercept.
fn assemble(
    headers: &[Header],
    frames: &[geometry::Frame],
    strict: bool,
    notes: &mut Vec<String>,
) -> Result<(Samples, f64, f64), IoError> {
    let first = &headers[0];
    let frame_len = first.rows * first.cols;
    let mut per_file = Vec::with_capacity(headers.len());
    for h in headers {
        per_file.push(pixels::read_pixels(h, frame_len, strict)?);
    }
    let parts: Vec<Samples> = frames
        .iter()
        .map(|f| std::mem::replace(&mut per_file[f.file][f.frame], Samples::U8(Vec::new())))
        .collect();
    let rescales: Vec<(f64, f64)> = frames.iter().map(|f| f.rescale).collect();
    if rescales.iter().all(|r| *r == rescales[0]) {
        return Ok((concat(parts), rescales[0].0, rescales[0].1));
    }
    // Per-slice rescale (common in PET): apply it, store float32.
    notes.push("per-slice rescale slopes differ: values rescaled to float32".into());
    let mut out = Vec::with_capacity(frames.len() * frame_len);
    for (p, (s, b)) in parts.iter().zip(&rescales) {
        out.extend((0..p.len()).map(|i| (s * p.get(i) + b) as f32));
    }
    Ok((Samples::F32(out), 1.0, 0.0))
}

fn concat(parts: Vec<Samples>) -> Samples {
    macro_rules! cat {
        ($v:ident) => {
            Samples::$v(
                parts
                    .into_iter()
                    .flat_map(|p| match p {
                        Samples::$v(v) => v,
                        _ => unreachable!("every frame of a series has the same type"),
                    })
                    .collect(),
            )
        };
    }
    match parts.first() {
        Some(Samples::U8(_)) | None => cat!(U8),
        Some(Samples::I8(_)) => cat!(I8),
        Some(Samples::U16(_)) => cat!(U16),
        Some(Samples::I16(_)) => cat!(I16),
        Some(Samples::U32(_)) => cat!(U32),
        Some(Samples::I32(_)) => cat!(I32),
        Some(Samples::F32(_)) => cat!(F32),
        Some(Samples::F64(_)) => cat!(F64),
    }
}
