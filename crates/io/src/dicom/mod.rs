//! DICOM volumes through dicom-rs (`dicom-object`, `dicom-pixeldata`): a directory of
//! single-frame slices or one multi-frame file (classic or enhanced), with native pixel
//! data (implicit or explicit VR, little or big endian, deflated; 1 to 32 bits, grey or
//! colour) or compressed pixel data (JPEG baseline, extended 8 and 12-bit and lossless,
//! JPEG-LS, JPEG 2000, RLE). Colour images (RGB, YBR_FULL, YBR_FULL_422, YBR_ICT,
//! YBR_RCT) become colour volumes ([`Volume::colour`]). A directory may hold several
//! series and non-image objects: one image series is read ([`list`], `series`). A
//! Segmentation (DICOM SEG) file is read as a label map ([`read_segments`] gives its
//! segments' names and colours; see `seg`).
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

mod checks;
mod colour;
mod geometry;
mod header;
mod jpeg;
mod jpegls;
mod pixels;
mod raster;
mod rtstruct;
mod scan;
mod seg;
mod series;

use std::collections::BTreeMap;
use std::path::Path;

use header::{open_header, Header};
use pixels::Frame;

use crate::common::checked_voxels;
use crate::{Format, IoError, ReadOptions, Rgb, Samples, Volume, VolumeFile};

pub use rtstruct::{read_rois, read_structure_set, Roi, StructureSet};
pub use scan::MAX_NESTING;
pub use seg::{read_segments, Segment};
pub use series::{list, Listing, Series, Skipped};

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
        crate::link::os_error(path, source)
    } else {
        IoError::Invalid {
            path: path.into(),
            what: chain,
        }
    }
}

/// Reads a DICOM file (single- or multi-frame) or the image series of a directory (the
/// only one, the one [`ReadOptions::series`] names, or the largest; see [`list`]).
///
/// A colour image (3 samples per pixel) gives a colour volume: RGB in
/// [`Volume::colour`], and in [`Volume::samples`] the grey [`ReadOptions::grey`] asks
/// for. An RT Dose grid is scaled by its DoseGridScaling (slope), in its DoseUnits.
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let mut notes = Vec::new();
    let headers = if path.is_dir() {
        series::select(path, options, &mut notes)?
    } else {
        let h = match open_header(path, options.max_voxels, options.strict) {
            Ok(h) => h,
            Err(r) if rtstruct::is_structure_set(r.class_uid.as_deref()) => {
                return rtstruct::read(path, options);
            }
            Err(r) => return Err(r.error),
        };
        if let Some(uid) = options
            .series
            .as_ref()
            .filter(|u| h.series.as_ref() != Some(u))
        {
            return Err(invalid(
                path,
                format!(
                    "the file is series {}, not {}",
                    one_line(h.series.as_deref().unwrap_or("(none)")),
                    one_line(uid)
                ),
            ));
        }
        notes.extend(h.notes.iter().cloned());
        if seg::is_segmentation(h.sop_class.as_deref()) {
            return seg::read(path, h, options, notes);
        }
        vec![h]
    };
    let first = &headers[0];
    let bytes =
        usize::from(first.bits_allocated.div_ceil(8)) * usize::from(first.samples_per_pixel);
    let Grid {
        frames,
        dims,
        affine,
        spacing,
    } = grid(path, &headers, bytes, options, &mut notes)?;
    let (samples, colour, mut slope, intercept) = assemble(&headers, &frames, options, &mut notes)?;
    let mut units = first
        .rescale_type
        .clone()
        .or_else(|| (first.modality.as_deref() == Some("CT")).then(|| "HU".to_string()));
    if let Some((scaling, dose_units)) = &first.dose {
        // PS3.3 C.8.8.3.4.2: dose = DoseGridScaling x stored value.
        slope *= scaling;
        units = dose_units.clone().or(units);
        notes.push(format!(
            "RT Dose: stored values x DoseGridScaling {scaling}"
        ));
    }
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
            colour,
        },
        format: Format::Dicom,
        notes,
        inflate: None,
    })
}

/// Where a series' voxels are: its frames in slice order, the grid's size and its
/// voxel-to-RAS affine and spacing.
struct Grid {
    frames: Vec<geometry::Frame>,
    dims: [usize; 3],
    affine: [[f64; 4]; 4],
    spacing: [f64; 3],
}

/// The grid of a series (its headers, read without pixels), checked as one series and
/// against the voxel limit at `bytes` a voxel.
fn grid(
    path: &Path,
    headers: &[Header],
    bytes: usize,
    options: &ReadOptions,
    notes: &mut Vec<String>,
) -> Result<Grid, IoError> {
    check_series(path, headers)?;
    let first = &headers[0];
    let plane = geometry::plane(path, first, options.strict, notes)?;
    let mut frames = geometry::frames(headers, plane.normal, options.strict, notes)?;
    let dims = [first.cols, first.rows, frames.len()];
    checked_voxels(path, dims, bytes, options.max_voxels)?;
    let slice_vec = geometry::sort_and_step(path, &mut frames, first, plane.normal, notes)?;
    let (affine, spacing) = geometry::affine(path, &plane, slice_vec, frames[0].position)?;
    Ok(Grid {
        frames,
        dims,
        affine,
        spacing,
    })
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
        if (
            h.rows,
            h.cols,
            h.bits_allocated,
            h.signed,
            h.samples_per_pixel,
        ) != (
            first.rows,
            first.cols,
            first.bits_allocated,
            first.signed,
            first.samples_per_pixel,
        ) {
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

/// The samples, colour, slope and intercept of a volume.
type Assembled = (Samples, Option<Rgb>, f64, f64);

/// Reads every file's pixels once and places the frames in sorted order; per-slice
/// rescales that differ are applied (float32), else kept as slope and intercept. A
/// colour series gives its RGB planes and the grey `options.grey` asks for.
fn assemble(
    headers: &[Header],
    frames: &[geometry::Frame],
    options: &ReadOptions,
    notes: &mut Vec<String>,
) -> Result<Assembled, IoError> {
    let first = &headers[0];
    let frame_len = first.rows * first.cols;
    let mut per_file = Vec::with_capacity(headers.len());
    for h in headers {
        per_file.push(pixels::read_pixels(h, frame_len, options.strict)?);
    }
    let mut take = |f: &geometry::Frame| {
        std::mem::replace(
            &mut per_file[f.file][f.frame],
            Frame::Grey(Samples::U8(Vec::new())),
        )
    };
    if first.samples_per_pixel == 3 {
        let mut planes: [Vec<Samples>; 3] = Default::default();
        for f in frames {
            if let Frame::Rgb(rgb) = take(f) {
                for (plane, s) in planes.iter_mut().zip(rgb) {
                    plane.push(s);
                }
            }
        }
        let rgb = planes.map(concat);
        let grey = colour::grey(&rgb, options.grey);
        notes.push(format!(
            "colour ({}) read as RGB; grey samples: {}",
            one_line(&first.photometric),
            options.grey.name()
        ));
        let [red, green, blue] = rgb;
        return Ok((grey, Some(Rgb { red, green, blue }), 1.0, 0.0));
    }
    let mut parts = Vec::with_capacity(frames.len());
    for f in frames {
        if let Frame::Grey(s) = take(f) {
            parts.push(s);
        }
    }
    let rescales: Vec<(f64, f64)> = frames.iter().map(|f| f.rescale).collect();
    if rescales.iter().all(|r| *r == rescales[0]) {
        return Ok((concat(parts), None, rescales[0].0, rescales[0].1));
    }
    // Per-slice rescale (common in PET): apply it, store float32.
    notes.push("per-slice rescale slopes differ: values rescaled to float32".into());
    let mut out = Vec::with_capacity(frames.len() * frame_len);
    for (p, (s, b)) in parts.iter().zip(&rescales) {
        out.extend((0..p.len()).map(|i| (s * p.get(i) + b) as f32));
    }
    Ok((Samples::F32(out), None, 1.0, 0.0))
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
