//! DICOM volumes through dicom-rs (`dicom-object`): a directory of single-frame slices
//! or one multi-frame file (classic or enhanced), with uncompressed (native) pixel data
//! in implicit or explicit VR, little or big endian.
//!
//! Slices are sorted by their position along the slice normal (row x column direction
//! cosines), the slice step comes from the positions (not SliceThickness), and uneven
//! steps (a missing slice), duplicate positions, different series, orientations or
//! sizes are errors. The affine is built in DICOM's patient LPS space and converted to
//! RAS by negating x and y (DICOM PS3.3 C.7.6.2.1.1). Rescale slope and intercept are
//! kept as the volume's slope and intercept (CT values then are Hounsfield units).
//! Encapsulated (compressed) transfer syntaxes are refused: decoding them needs
//! `dicom-pixeldata` with codec features, a large dependency for a rare case here.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use dicom_core::value::{PrimitiveValue, Value};
use dicom_dictionary_std::tags;
use dicom_object::mem::InMemElement;
use dicom_object::{InMemDicomObject, OpenFileOptions};

use crate::common::{check_affine, checked_voxels, has_dicom_magic};
use crate::{Format, IoError, ReadOptions, Samples, Volume, VolumeFile};

/// Relative tolerance on slice steps: steps differing from the median by more than this
/// fraction are a gap (or an overlap) rather than rounding in the positions.
const STEP_TOLERANCE: f64 = 0.05;

/// Tolerance on direction cosines when checking that slices share an orientation.
const ORIENTATION_TOLERANCE: f64 = 1e-4;

/// Tolerance on the length of, and the angle between, the direction cosines of
/// ImageOrientationPatient.
const UNIT_TOLERANCE: f64 = 1e-3;

/// Relative tolerance when comparing PixelSpacing across the slices of a series.
const SPACING_TOLERANCE: f64 = 1e-3;

fn invalid(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Invalid {
        path: path.into(),
        what: what.into(),
    }
}

/// What one file says about its pixels and geometry (read without the pixel data).
#[derive(Clone, Debug)]
struct Header {
    path: PathBuf,
    rows: usize,
    cols: usize,
    frames: usize,
    bits_allocated: u16,
    bits_stored: u16,
    signed: bool,
    series: Option<String>,
    orientation: Option<[f64; 6]>,
    pixel_spacing: Option<[f64; 2]>,
    /// One position per frame, when known.
    positions: Vec<Option<[f64; 3]>>,
    /// Rescale (slope, intercept) per frame.
    rescale: Vec<(f64, f64)>,
    slice_step: Option<f64>,
    modality: Option<String>,
    rescale_type: Option<String>,
}

fn floats(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<Vec<f64>> {
    obj.get(tag).and_then(|e| e.to_multi_float64().ok())
}

fn float(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<f64> {
    obj.get(tag).and_then(|e| e.to_float64().ok())
}

fn string(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<String> {
    obj.get(tag)
        .and_then(|e| e.to_str().ok())
        .map(|s| s.trim().trim_end_matches('\0').to_string())
        .filter(|s| !s.is_empty())
}

fn int(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<i64> {
    obj.get(tag).and_then(|e| e.to_int::<i64>().ok())
}

/// The first item of a sequence.
fn item(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<&InMemDicomObject> {
    obj.get(tag)
        .and_then(InMemElement::items)
        .and_then(|i| i.first())
}

/// Looks an attribute up at the top level, then in the shared functional groups, then in
/// the first per-frame group (enhanced multi-frame objects, PS3.3 C.7.6.16).
fn find(
    obj: &InMemDicomObject,
    group: dicom_core::Tag,
    tag: dicom_core::Tag,
) -> Option<&InMemDicomObject> {
    if obj.get(tag).is_some() {
        return Some(obj);
    }
    for fg in [
        tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE,
        tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE,
    ] {
        if let Some(g) = item(obj, fg).and_then(|f| item(f, group)) {
            if g.get(tag).is_some() {
                return Some(g);
            }
        }
    }
    None
}

fn header_of(path: &Path, obj: &InMemDicomObject, max_voxels: u64) -> Result<Header, IoError> {
    let need = |tag, name: &str| {
        int(obj, tag).ok_or_else(|| invalid(path, format!("missing or bad {name}")))
    };
    let rows = need(tags::ROWS, "Rows")?;
    let cols = need(tags::COLUMNS, "Columns")?;
    let bits_allocated = need(tags::BITS_ALLOCATED, "BitsAllocated")?;
    let bits_stored = int(obj, tags::BITS_STORED).unwrap_or(bits_allocated);
    let signed = int(obj, tags::PIXEL_REPRESENTATION).unwrap_or(0) == 1;
    let spp = int(obj, tags::SAMPLES_PER_PIXEL).unwrap_or(1);
    let frames = int(obj, tags::NUMBER_OF_FRAMES).unwrap_or(1);
    if rows < 1 || cols < 1 || frames < 1 || rows > 65535 || cols > 65535 {
        return Err(invalid(
            path,
            format!("bad image size: {rows} rows, {cols} columns, {frames} frames"),
        ));
    }
    // Bound the frame count before anything is sized by it.
    checked_voxels(
        path,
        [cols as usize, rows as usize, frames as usize],
        1,
        max_voxels,
    )?;
    if spp != 1 {
        return Err(IoError::Unsupported {
            path: path.into(),
            what: format!(
                "{spp} samples per pixel ({}); only grayscale volumes are read",
                string(obj, tags::PHOTOMETRIC_INTERPRETATION).unwrap_or_default()
            ),
        });
    }
    if !matches!(bits_allocated, 8 | 16 | 32) || bits_stored < 1 || bits_stored > bits_allocated {
        return Err(IoError::Unsupported {
            path: path.into(),
            what: format!("{bits_allocated} bits allocated, {bits_stored} stored"),
        });
    }
    // The pixels of every frame must fit in the file before anything (per-frame
    // positions, rescales, the pixel buffer) is sized by the frame count.
    let need = (rows as u64)
        .checked_mul(cols as u64)
        .and_then(|x| x.checked_mul(frames as u64))
        .and_then(|x| x.checked_mul(bits_allocated as u64 / 8));
    let len = file_len(path)?;
    if need.is_none_or(|need| need > len) {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!(
                "{rows} rows x {cols} columns x {frames} frames of {bits_allocated}-bit pixels \
                 need more bytes than the file's {len}"
            ),
        });
    }
    let orientation = find(
        obj,
        tags::PLANE_ORIENTATION_SEQUENCE,
        tags::IMAGE_ORIENTATION_PATIENT,
    )
    .and_then(|o| floats(o, tags::IMAGE_ORIENTATION_PATIENT))
    .map(|v| {
        <[f64; 6]>::try_from(v).map_err(|v| {
            invalid(
                path,
                format!("ImageOrientationPatient has {} values, expected 6", v.len()),
            )
        })
    })
    .transpose()?;
    let pixel_spacing = find(obj, tags::PIXEL_MEASURES_SEQUENCE, tags::PIXEL_SPACING)
        .and_then(|o| floats(o, tags::PIXEL_SPACING))
        .map(|v| {
            <[f64; 2]>::try_from(v).map_err(|v| {
                invalid(
                    path,
                    format!("PixelSpacing has {} values, expected 2", v.len()),
                )
            })
        })
        .transpose()?;
    let slice_step = find(
        obj,
        tags::PIXEL_MEASURES_SEQUENCE,
        tags::SPACING_BETWEEN_SLICES,
    )
    .and_then(|o| float(o, tags::SPACING_BETWEEN_SLICES))
    .or_else(|| {
        find(obj, tags::PIXEL_MEASURES_SEQUENCE, tags::SLICE_THICKNESS)
            .and_then(|o| float(o, tags::SLICE_THICKNESS))
    });
    let frames = frames as usize;
    let rescale_of = |o: &InMemDicomObject| {
        (
            float(o, tags::RESCALE_SLOPE).unwrap_or(1.0),
            float(o, tags::RESCALE_INTERCEPT).unwrap_or(0.0),
        )
    };
    let pos3 = |o: &InMemDicomObject| -> Result<Option<[f64; 3]>, IoError> {
        floats(o, tags::IMAGE_POSITION_PATIENT)
            .map(|v| {
                <[f64; 3]>::try_from(v).map_err(|v| {
                    invalid(
                        path,
                        format!("ImagePositionPatient has {} values, expected 3", v.len()),
                    )
                })
            })
            .transpose()
    };
    let per_frame = obj
        .get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE)
        .and_then(InMemElement::items);
    let shared_rescale = find(
        obj,
        tags::PIXEL_VALUE_TRANSFORMATION_SEQUENCE,
        tags::RESCALE_SLOPE,
    )
    .map(rescale_of)
    .unwrap_or((1.0, 0.0));
    let (positions, rescale) = match per_frame {
        Some(items) if frames > 1 => {
            if items.len() != frames {
                return Err(invalid(
                    path,
                    format!("{} per-frame groups for {frames} frames", items.len()),
                ));
            }
            let mut positions = Vec::with_capacity(frames);
            let mut rescale = Vec::with_capacity(frames);
            for it in items {
                positions.push(match item(it, tags::PLANE_POSITION_SEQUENCE) {
                    Some(p) => pos3(p)?,
                    None => None,
                });
                rescale.push(
                    item(it, tags::PIXEL_VALUE_TRANSFORMATION_SEQUENCE)
                        .filter(|p| p.get(tags::RESCALE_SLOPE).is_some())
                        .map(rescale_of)
                        .unwrap_or(shared_rescale),
                );
            }
            (positions, rescale)
        }
        _ => {
            let top = if obj.get(tags::IMAGE_POSITION_PATIENT).is_some() {
                pos3(obj)?
            } else {
                match find(
                    obj,
                    tags::PLANE_POSITION_SEQUENCE,
                    tags::IMAGE_POSITION_PATIENT,
                ) {
                    Some(p) => pos3(p)?,
                    None => None,
                }
            };
            let mut positions = vec![None; frames];
            positions[0] = top;
            let r = if obj.get(tags::RESCALE_SLOPE).is_some() {
                rescale_of(obj)
            } else {
                shared_rescale
            };
            (positions, vec![r; frames])
        }
    };
    Ok(Header {
        path: path.into(),
        rows: rows as usize,
        cols: cols as usize,
        frames,
        bits_allocated: bits_allocated as u16,
        bits_stored: bits_stored as u16,
        signed,
        series: string(obj, tags::SERIES_INSTANCE_UID),
        orientation,
        pixel_spacing,
        positions,
        rescale,
        slice_step,
        modality: string(obj, tags::MODALITY),
        rescale_type: string(obj, tags::RESCALE_TYPE),
    })
}

fn open_header(path: &Path, max_voxels: u64) -> Result<Header, IoError> {
    // Files without the PS3.10 preamble and "DICM" marker (bare data sets from old
    // systems) are not read.
    if !has_dicom_magic(path) {
        return Err(IoError::BadMagic {
            path: path.into(),
            format: "DICOM",
            what: "no \"DICM\" marker after the 128-byte preamble".into(),
        });
    }
    check_declared_lengths(path)?;
    let obj = OpenFileOptions::new()
        .read_until(tags::PIXEL_DATA)
        .open_file(path)
        .map_err(|e| open_error(path, e))?;
    header_of(path, &obj, max_voxels)
}

fn file_len(path: &Path) -> Result<u64, IoError> {
    std::fs::metadata(path)
        .map(|m| m.len())
        .map_err(|e| IoError::Os {
            path: path.into(),
            source: e,
        })
}

/// VRs whose explicit-VR header has two reserved bytes and a 32-bit length (PS3.5 7.1.2).
const LONG_VRS: [&[u8; 2]; 13] = [
    b"OB", b"OD", b"OF", b"OL", b"OV", b"OW", b"SQ", b"SV", b"UC", b"UN", b"UR", b"UT", b"UV",
];

/// Walks the element headers of a DICOM file (meta group, data set, nested sequence
/// items, encapsulated pixel fragments) and refuses any element whose declared length
/// exceeds the bytes left in the file.
///
/// dicom-rs allocates a value buffer of the declared length before reading it, so a
/// 400-byte file declaring a 4 GB element costs 4 GB of memory before "truncated" is
/// reported. dicom-parser offers no length limit, hence this hand-written header walk
/// (headers only, no values). Where the walk cannot follow the encoding (deflated
/// transfer syntax, an undefined-length UN element, an unknown VR) it stops and leaves
/// the rest to dicom-rs: it only ever rejects a length it parsed unambiguously.
fn check_declared_lengths(path: &Path) -> Result<(), IoError> {
    use std::io::{BufReader, Read, Seek, SeekFrom};
    let file = crate::common::open(path)?;
    let len = file_len(path)?;
    let mut r = BufReader::new(file);
    let io = |e: std::io::Error| crate::common::os_or_invalid(path, e);
    r.seek(SeekFrom::Start(132)).map_err(io)?;
    let mut pos: u64 = 132;
    let too_long = |tag: (u16, u16), declared: u64, left: u64| IoError::Truncated {
        path: path.into(),
        what: format!(
            "element ({:04X},{:04X}) declares {declared} bytes, only {left} are left in the file",
            tag.0, tag.1
        ),
    };
    let mut ts = String::new();
    let (mut explicit, mut big) = (true, false);
    let mut in_meta = true;
    let mut buf = [0u8; 12];
    loop {
        if pos + 8 > len {
            return Ok(());
        }
        r.read_exact(&mut buf[..8]).map_err(io)?;
        pos += 8;
        if in_meta && u16::from_le_bytes([buf[0], buf[1]]) != 0x0002 {
            in_meta = false;
            match ts.as_str() {
                "1.2.840.10008.1.2" => explicit = false,
                "1.2.840.10008.1.2.2" => big = true,
                // Deflated: the data set is a zlib stream, no headers to walk.
                "1.2.840.10008.1.2.1.99" => return Ok(()),
                _ => {}
            }
        }
        let (ex, be) = if in_meta {
            (true, false)
        } else {
            (explicit, big)
        };
        let u16_at = |b: &[u8], i: usize| {
            if be {
                u16::from_be_bytes([b[i], b[i + 1]])
            } else {
                u16::from_le_bytes([b[i], b[i + 1]])
            }
        };
        let u32_at = |b: &[u8], i: usize| {
            if be {
                u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
            } else {
                u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
            }
        };
        let tag = (u16_at(&buf, 0), u16_at(&buf, 2));
        let mut sequence = false;
        let declared = if tag.0 == 0xFFFE || !ex {
            // Items and delimiters never carry a VR; implicit VR: 32-bit length.
            if tag.0 != 0xFFFE {
                use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry, VirtualVr};
                sequence = dicom_dictionary_std::StandardDataDictionary
                    .by_tag(dicom_core::Tag(tag.0, tag.1))
                    .is_some_and(|e| matches!(e.vr(), VirtualVr::Exact(dicom_core::VR::SQ)));
            }
            u32_at(&buf, 4)
        } else {
            let vr = [buf[4], buf[5]];
            if !vr.iter().all(u8::is_ascii_uppercase) {
                return Ok(());
            }
            if LONG_VRS.contains(&&vr) {
                if pos + 4 > len {
                    return Ok(());
                }
                r.read_exact(&mut buf[8..12]).map_err(io)?;
                pos += 4;
                let l = u32_at(&buf, 8);
                if &vr == b"UN" && l == u32::MAX {
                    // An implicit-VR sequence inside explicit VR (PS3.5 6.2.2): stop.
                    return Ok(());
                }
                sequence = &vr == b"SQ";
                l
            } else {
                u32::from(u16_at(&buf, 6))
            }
        };
        if declared == u32::MAX {
            if tag == (0x7FE0, 0x0010) {
                // Encapsulated pixel data: fragments until the sequence delimiter.
                loop {
                    if pos + 8 > len {
                        return Ok(());
                    }
                    r.read_exact(&mut buf[..8]).map_err(io)?;
                    pos += 8;
                    let (g, e, l) = (u16_at(&buf, 0), u16_at(&buf, 2), u32_at(&buf, 4));
                    if (g, e) == (0xFFFE, 0xE0DD) {
                        break;
                    }
                    if u64::from(l) > len - pos {
                        return Err(too_long((g, e), l.into(), len - pos));
                    }
                    r.seek_relative(i64::from(l)).map_err(io)?;
                    pos += u64::from(l);
                }
            }
            // Otherwise an undefined-length sequence or item: walk into it.
            continue;
        }
        let declared = u64::from(declared);
        if declared > len - pos {
            return Err(too_long(tag, declared, len - pos));
        }
        if tag.0 == 0xFFFE || sequence {
            // Walk into items and sequences so nested lengths are checked too.
            continue;
        }
        if tag == (0x0002, 0x0010) && declared <= 64 {
            let mut v = vec![0u8; declared as usize];
            r.read_exact(&mut v).map_err(io)?;
            ts = String::from_utf8_lossy(&v)
                .trim_end_matches(['\0', ' '])
                .to_string();
        } else {
            r.seek_relative(declared as i64).map_err(io)?;
        }
        pos += declared;
    }
}

fn open_error(path: &Path, e: dicom_object::ReadError) -> IoError {
    let msg = e.to_string();
    let mut chain = msg.clone();
    let mut src = std::error::Error::source(&e);
    while let Some(s) = src {
        chain += &format!(": {s}");
        src = s.source();
    }
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

/// One 2D image of the volume: which file and frame it comes from, and where it is.
struct Frame {
    file: usize,
    frame: usize,
    position: [f64; 3],
    rescale: (f64, f64),
}

/// Reads a DICOM file (single- or multi-frame) or a directory of single-frame slices of
/// one series.
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let mut notes = Vec::new();
    let headers: Vec<Header> = if path.is_dir() {
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
            match open_header(p, options.max_voxels) {
                Ok(h) => headers.push(h),
                // Not DICOM at all (a README, a thumbnail): skip it, but say so.
                Err(IoError::BadMagic { .. }) => skipped += 1,
                Err(e) => return Err(e),
            }
        }
        if skipped > 0 {
            notes.push(format!("skipped {skipped} non-DICOM file(s)"));
        }
        if headers.is_empty() {
            return Err(invalid(path, "the directory holds no DICOM files"));
        }
        headers
    } else {
        vec![open_header(path, options.max_voxels)?]
    };

    // One series, one image size, one pixel format.
    let mut series: BTreeMap<String, usize> = BTreeMap::new();
    for h in &headers {
        *series
            .entry(h.series.clone().unwrap_or_else(|| "(none)".into()))
            .or_default() += 1;
    }
    if series.len() > 1 {
        return Err(IoError::MixedSeries {
            path: path.into(),
            what: format!(
                "{} series: {}; point glint at one series",
                series.len(),
                series
                    .iter()
                    .map(|(k, n)| format!("{k} ({n} files)"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        });
    }
    let first = headers[0].clone();
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

    // Geometry: in-plane axes from the orientation, slice axis from the positions.
    let orientation = first.orientation.unwrap_or_else(|| {
        notes.push("no ImageOrientationPatient: axial assumed".into());
        [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
    });
    let row_dir = [orientation[0], orientation[1], orientation[2]];
    let col_dir = [orientation[3], orientation[4], orientation[5]];
    // Direction cosines are unit vectors at right angles (PS3.3 C.7.6.2.1.1); anything
    // else would silently scale or shear the geometry.
    let (nr, nc) = (dot(row_dir, row_dir).sqrt(), dot(col_dir, col_dir).sqrt());
    if !(nr.is_finite() && nc.is_finite())
        || (nr - 1.0).abs() > UNIT_TOLERANCE
        || (nc - 1.0).abs() > UNIT_TOLERANCE
        || dot(row_dir, col_dir).abs() > UNIT_TOLERANCE
    {
        return Err(IoError::Geometry {
            path: path.into(),
            what: format!(
                "ImageOrientationPatient {orientation:?} is not two orthogonal unit vectors \
                 (lengths {nr:.4} and {nc:.4}, dot product {:.4})",
                dot(row_dir, col_dir)
            ),
        });
    }
    let row_dir = row_dir.map(|x| x / nr);
    let col_dir = col_dir.map(|x| x / nc);
    let normal = cross(row_dir, col_dir);
    let nn = dot(normal, normal).sqrt();
    let normal = normal.map(|x| x / nn);
    let pixel_spacing = first.pixel_spacing.unwrap_or_else(|| {
        notes.push("no PixelSpacing: 1 mm pixels assumed".into());
        [1.0, 1.0]
    });
    if pixel_spacing.iter().any(|s| !s.is_finite() || *s <= 0.0)
        || orientation.iter().any(|x| !x.is_finite())
    {
        return Err(IoError::Geometry {
            path: path.into(),
            what: format!("PixelSpacing {pixel_spacing:?} or ImageOrientationPatient {orientation:?} is not usable"),
        });
    }

    let mut frames = Vec::new();
    for (fi, h) in headers.iter().enumerate() {
        let step = h.slice_step.filter(|s| s.is_finite() && *s > 0.0);
        for k in 0..h.frames {
            let position = match (h.positions[k], h.positions[0]) {
                (Some(p), _) => p,
                (None, Some(p0)) if h.frames > 1 => {
                    // Classic multi-frame: frames stacked along the normal from the one
                    // given position, by SpacingBetweenSlices (or SliceThickness).
                    let s = step.ok_or_else(|| IoError::Geometry {
                        path: h.path.clone(),
                        what: "multi-frame without per-frame positions or slice spacing".into(),
                    })?;
                    if k == 1 {
                        notes.push(format!("frame positions from a slice spacing of {s} mm"));
                    }
                    std::array::from_fn(|a| p0[a] + k as f64 * s * normal[a])
                }
                _ if headers.len() == 1 && h.frames == 1 => [0.0; 3],
                _ => {
                    return Err(IoError::Geometry {
                        path: h.path.clone(),
                        what: "no ImagePositionPatient: cannot order the slices".into(),
                    })
                }
            };
            if position.iter().any(|x| !x.is_finite()) {
                return Err(IoError::Geometry {
                    path: h.path.clone(),
                    what: format!("ImagePositionPatient {position:?} is not finite"),
                });
            }
            frames.push(Frame {
                file: fi,
                frame: k,
                position,
                rescale: h.rescale[k],
            });
        }
    }
    let dims = [first.cols, first.rows, frames.len()];
    let bytes_per = usize::from(first.bits_allocated / 8);
    checked_voxels(path, dims, bytes_per, options.max_voxels)?;
    // Each file must be at least as large as the pixels it announces, checked before
    // dicom-object reads (and allocates for) them.
    for h in &headers {
        let need = (h.rows * h.cols * h.frames * bytes_per) as u64;
        let len = std::fs::metadata(&h.path)
            .map_err(|e| IoError::Os {
                path: h.path.clone(),
                source: e,
            })?
            .len();
        if len < need {
            return Err(IoError::SizeMismatch {
                path: h.path.clone(),
                what: format!(
                    "{} rows x {} columns x {} frames of {}-bit pixels need {need} bytes, the file has {len}",
                    h.rows, h.cols, h.frames, h.bits_allocated
                ),
            });
        }
    }

    let along = |p: &[f64; 3]| dot(*p, normal);
    frames.sort_by(|a, b| along(&a.position).total_cmp(&along(&b.position)));
    let n = frames.len();
    let slice_vec = if n > 1 {
        let steps: Vec<f64> = frames
            .windows(2)
            .map(|w| along(&w[1].position) - along(&w[0].position))
            .collect();
        let mut sorted = steps.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        if let Some(i) = steps
            .iter()
            .position(|&s| s <= 1e-6 * median.abs().max(1.0))
        {
            return Err(IoError::Geometry {
                path: path.into(),
                what: format!(
                    "two slices at the same position {:?} along the normal (duplicates, or several acquisitions)",
                    frames[i].position
                ),
            });
        }
        if let Some(i) = steps
            .iter()
            .position(|&s| (s - median).abs() > STEP_TOLERANCE * median)
        {
            return Err(IoError::Geometry {
                path: path.into(),
                what: format!(
                    "uneven slice spacing: a step of {:.4} mm between positions {:.4} and {:.4} where \
                     the median step is {median:.4} mm (a missing slice?)",
                    steps[i],
                    along(&frames[i].position),
                    along(&frames[i + 1].position)
                ),
            });
        }
        let (a, b) = (frames[0].position, frames[n - 1].position);
        std::array::from_fn(|k| (b[k] - a[k]) / (n - 1) as f64)
    } else {
        let s = first
            .slice_step
            .filter(|s| s.is_finite() && *s > 0.0)
            .unwrap_or_else(|| {
                notes.push("a single slice without thickness: 1 mm assumed".into());
                1.0
            });
        normal.map(|x| x * s)
    };

    // LPS affine, then to RAS by negating the x and y rows.
    let origin = frames[0].position;
    let mut affine = [[0.0; 4]; 4];
    for r in 0..3 {
        let flip = if r < 2 { -1.0 } else { 1.0 };
        affine[r][0] = flip * row_dir[r] * pixel_spacing[1];
        affine[r][1] = flip * col_dir[r] * pixel_spacing[0];
        affine[r][2] = flip * slice_vec[r];
        affine[r][3] = flip * origin[r];
    }
    affine[3][3] = 1.0;
    let spacing = check_affine(path, &affine)?;

    // Pixels: read each file once and place its frames in sorted order.
    let frame_len = first.rows * first.cols;
    let mut per_file: Vec<Option<Vec<Samples>>> = (0..headers.len()).map(|_| None).collect();
    let mut order: Vec<(usize, usize)> = Vec::with_capacity(n);
    for f in &frames {
        order.push((f.file, f.frame));
    }
    for (fi, h) in headers.iter().enumerate() {
        per_file[fi] = Some(read_pixels(h, frame_len)?);
    }
    let rescales: Vec<(f64, f64)> = frames.iter().map(|f| f.rescale).collect();
    let uniform = rescales.iter().all(|r| *r == rescales[0]);
    let mut parts: Vec<Samples> = Vec::with_capacity(n);
    for &(fi, k) in &order {
        let frames_of = per_file[fi].as_mut().expect("read above");
        parts.push(std::mem::replace(
            &mut frames_of[k],
            Samples::U8(Vec::new()),
        ));
    }
    let (samples, slope, intercept) = if uniform {
        (concat(parts), rescales[0].0, rescales[0].1)
    } else {
        // Per-slice rescale (common in PET): apply it, store float32.
        notes.push("per-slice rescale slopes differ: values rescaled to float32".into());
        let mut out = Vec::with_capacity(n * frame_len);
        for (p, (s, b)) in parts.iter().zip(&rescales) {
            out.extend((0..p.len()).map(|i| (s * p.get(i) + b) as f32));
        }
        (Samples::F32(out), 1.0, 0.0)
    };
    let units = first
        .rescale_type
        .clone()
        .or_else(|| (first.modality.as_deref() == Some("CT")).then(|| "HU".to_string()));
    notes.push(format!(
        "{} slice(s) from {} file(s), modality {}",
        n,
        headers.len(),
        first.modality.as_deref().unwrap_or("unknown")
    ));
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
    })
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
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

/// Reads a file's pixel data and splits it into frames of `frame_len` samples.
fn read_pixels(h: &Header, frame_len: usize) -> Result<Vec<Samples>, IoError> {
    let path = h.path.as_path();
    let obj = dicom_object::open_file(path).map_err(|e| open_error(path, e))?;
    let big_endian = obj.meta().transfer_syntax().trim_end_matches('\0') == "1.2.840.10008.1.2.2";
    let elem = obj
        .element(tags::PIXEL_DATA)
        .map_err(|_| invalid(path, "no PixelData"))?;
    let total = frame_len * h.frames;
    let bits = h.bits_allocated;
    // The stored words as u32, whatever VR the file used.
    let words: Vec<u32> = match elem.value() {
        Value::PixelSequence(_) => {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: format!(
                    "compressed pixel data (transfer syntax {}); convert to an uncompressed \
                     syntax, e.g. with dcmdjpeg or gdcmconv --raw",
                    obj.meta().transfer_syntax().trim_end_matches('\0')
                ),
            })
        }
        Value::Primitive(PrimitiveValue::U8(bytes)) => {
            let per = usize::from(bits / 8);
            bytes
                .chunks_exact(per)
                .take(total)
                .map(|c| match (per, big_endian) {
                    (1, _) => u32::from(c[0]),
                    (2, false) => u32::from(u16::from_le_bytes([c[0], c[1]])),
                    (2, true) => u32::from(u16::from_be_bytes([c[0], c[1]])),
                    (_, false) => u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                    (_, true) => u32::from_be_bytes([c[0], c[1], c[2], c[3]]),
                })
                .collect()
        }
        Value::Primitive(PrimitiveValue::U16(w)) => match bits {
            16 => w.iter().take(total).map(|&x| u32::from(x)).collect(),
            // 8-bit pixels packed two to a little-endian word.
            8 => w
                .iter()
                .flat_map(|x| x.to_le_bytes())
                .take(total)
                .map(u32::from)
                .collect(),
            _ => w
                .chunks_exact(2)
                .take(total)
                .map(|c| {
                    let (lo, hi) = if big_endian {
                        (c[1], c[0])
                    } else {
                        (c[0], c[1])
                    };
                    u32::from(lo) | (u32::from(hi) << 16)
                })
                .collect(),
        },
        Value::Primitive(PrimitiveValue::U32(w)) => w.iter().take(total).copied().collect(),
        _ => return Err(invalid(path, "PixelData has an unexpected value type")),
    };
    if words.len() < total {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!(
                "{} rows x {} columns x {} frames of {bits}-bit pixels need {total} samples, \
                 PixelData holds {}",
                h.rows,
                h.cols,
                h.frames,
                words.len()
            ),
        });
    }
    // Keep the stored bits; sign-extend them for signed pixels (PS3.5 8.1.1).
    let stored = u32::from(h.bits_stored);
    let mask = if stored >= 32 {
        u32::MAX
    } else {
        (1u32 << stored) - 1
    };
    let signed = |x: u32| -> i32 {
        let shift = 32 - stored;
        (((x & mask) << shift) as i32) >> shift
    };
    let frames = words
        .chunks_exact(frame_len)
        .map(|f| match (bits, h.signed) {
            (8, false) => Samples::U8(f.iter().map(|&x| (x & mask) as u8).collect()),
            (8, true) => Samples::I8(f.iter().map(|&x| signed(x) as i8).collect()),
            (16, false) => Samples::U16(f.iter().map(|&x| (x & mask) as u16).collect()),
            (16, true) => Samples::I16(f.iter().map(|&x| signed(x) as i16).collect()),
            (_, false) => Samples::U32(f.iter().map(|&x| x & mask).collect()),
            (_, true) => Samples::I32(f.iter().map(|&x| signed(x)).collect()),
        })
        .collect();
    Ok(frames)
}
