//! What one DICOM file says about its pixels and geometry, read without the pixel data.

use std::path::{Path, PathBuf};

use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry, UidDictionary};
use dicom_core::VR;
use dicom_dictionary_std::{tags, StandardDataDictionary, StandardSopClassDictionary};
use dicom_encoding::TransferSyntaxIndex;
use dicom_object::mem::InMemElement;
use dicom_object::InMemDicomObject;
use dicom_transfer_syntax_registry::TransferSyntaxRegistry;

use super::scan::{self, ts_name};
use super::{invalid, one_line};
use crate::common::checked_voxels;
use crate::IoError;

/// The colour photometric interpretations read (PS3.3 C.7.6.3.1.2); YBR_PARTIAL_420
/// and YBR_PARTIAL_422 (MPEG, retired JPEG use) are not.
const COLOUR_PIS: [&str; 5] = ["RGB", "YBR_FULL", "YBR_FULL_422", "YBR_ICT", "YBR_RCT"];

/// What one file says about its pixels and geometry (read without the pixel data).
#[derive(Clone, Debug)]
pub(super) struct Header {
    pub path: PathBuf,
    pub rows: usize,
    pub cols: usize,
    pub frames: usize,
    pub bits_allocated: u16,
    pub bits_stored: u16,
    pub signed: bool,
    /// 1 (grey) or 3 (colour).
    pub samples_per_pixel: u16,
    /// PhotometricInterpretation (MONOCHROME2 when absent).
    pub photometric: String,
    /// PlanarConfiguration 1: a colour frame is all red, then all green, then all blue.
    pub planar: bool,
    /// The transfer syntax UID; `encapsulated` when its pixel data is compressed.
    pub ts: String,
    pub encapsulated: bool,
    pub series: Option<String>,
    /// FrameOfReferenceUID (what an RT structure set's contours refer to).
    pub frame_of_reference: Option<String>,
    pub orientation: Option<[f64; 6]>,
    pub pixel_spacing: Option<[f64; 2]>,
    /// One position per frame, when known.
    pub positions: Vec<Option<[f64; 3]>>,
    /// Rescale (slope, intercept) per frame.
    pub rescale: Vec<(f64, f64)>,
    /// SpacingBetweenSlices, else SliceThickness.
    pub slice_step: Option<f64>,
    /// SpacingBetweenSlices only (what a stack of frames without positions uses).
    pub spacing_between_slices: Option<f64>,
    /// GridFrameOffsetVector (RT Dose, PS3.3 C.8.8.3.2): frame offsets in mm along the
    /// normal from ImagePositionPatient, one per frame.
    pub frame_offsets: Option<Vec<f64>>,
    pub modality: Option<String>,
    pub rescale_type: Option<String>,
    /// SeriesDescription.
    pub description: Option<String>,
    /// DoseGridScaling and DoseUnits of an RT Dose (PS3.3 C.8.8.3).
    pub dose: Option<(f64, Option<String>)>,
    /// SOPClassUID (a Segmentation is read by `seg`).
    pub sop_class: Option<String>,
    /// What was assumed to open the file (no preamble, no meta group).
    pub notes: Vec<String>,
}

/// The dictionary VR of an element stored as UN (some exporters write known attributes
/// as UN in explicit VR; pydicom reads them by their dictionary VR, PS3.5 6.2.2).
fn un_vr(e: &InMemElement) -> Option<VR> {
    (e.vr() == VR::UN)
        .then(|| StandardDataDictionary.by_tag(e.header().tag))
        .flatten()
        .map(|d| d.vr().relaxed())
}

/// The value of a UN element as text, when its dictionary VR is a text VR.
fn un_text(e: &InMemElement) -> Option<String> {
    let bytes = e.to_bytes().ok()?;
    Some(String::from_utf8_lossy(&bytes).into_owned())
}

pub(super) fn floats(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<Vec<f64>> {
    let e = obj.get(tag)?;
    match un_vr(e) {
        Some(VR::DS) => un_text(e)?
            .trim_end_matches(['\0', ' '])
            .split('\\')
            .map(|x| x.trim().parse().ok())
            .collect(),
        Some(_) => None,
        None => e.to_multi_float64().ok(),
    }
}

fn float(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<f64> {
    floats(obj, tag).and_then(|v| v.first().copied())
}

pub(super) fn string(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<String> {
    let e = obj.get(tag)?;
    let s = match un_vr(e) {
        Some(_) => un_text(e)?,
        None => e.to_str().ok()?.into_owned(),
    };
    Some(s.trim().trim_end_matches('\0').to_string()).filter(|s| !s.is_empty())
}

pub(super) fn int(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<i64> {
    let e = obj.get(tag)?;
    match un_vr(e) {
        // UN values are little endian: UN only occurs in explicit VR little endian
        // files (big endian files get theirs converted by dicom-rs).
        Some(VR::US) => {
            let b = e.to_bytes().ok()?;
            Some(i64::from(u16::from_le_bytes(b.get(..2)?.try_into().ok()?)))
        }
        Some(VR::IS) => un_text(e)?
            .trim_end_matches(['\0', ' '])
            .trim()
            .parse()
            .ok(),
        Some(_) => None,
        None => e.to_int::<i64>().ok(),
    }
}

/// The first item of a sequence.
pub(super) fn item(obj: &InMemDicomObject, tag: dicom_core::Tag) -> Option<&InMemDicomObject> {
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

/// A multi-valued decimal attribute with exactly `N` values, if present.
fn fixed<const N: usize>(
    path: &Path,
    obj: Option<&InMemDicomObject>,
    tag: dicom_core::Tag,
    name: &str,
) -> Result<Option<[f64; N]>, IoError> {
    obj.and_then(|o| floats(o, tag))
        .map(|v| {
            <[f64; N]>::try_from(v)
                .map_err(|v| invalid(path, format!("{name} has {} values, expected {N}", v.len())))
        })
        .transpose()
}

/// The image size and sample format a file declares.
pub(super) struct ImageFormat {
    pub rows: usize,
    pub cols: usize,
    pub frames: usize,
    pub bits_allocated: u16,
    pub bits_stored: u16,
    pub signed: bool,
    pub samples_per_pixel: u16,
    pub photometric: String,
    pub planar: bool,
}

impl ImageFormat {
    /// Bytes of native (uncompressed) pixel data: bit-packed across frames for 1 bit
    /// allocated (PS3.5 8.1.1), two samples a pixel for YBR_FULL_422 (PS3.3 C.7.6.3.1.2).
    pub fn native_bytes(&self) -> Option<u64> {
        let pixels = (self.rows as u64)
            .checked_mul(self.cols as u64)?
            .checked_mul(self.frames as u64)?;
        if self.bits_allocated == 1 {
            return Some(pixels.div_ceil(8));
        }
        let per_pixel = match (self.samples_per_pixel, self.photometric.as_str()) {
            (1, _) => 1,
            (_, "YBR_FULL_422") => 2,
            _ => 3,
        };
        pixels
            .checked_mul(per_pixel)?
            .checked_mul(u64::from(self.bits_allocated / 8))
    }
}

/// Image size and sample format, checked against the voxel limit before anything is
/// sized by them: grey (1 sample per pixel, 1, 8, 16 or 32 bits allocated) or colour
/// (3 samples per pixel in one of [`COLOUR_PIS`]).
fn image_size(
    path: &Path,
    obj: &InMemDicomObject,
    max_voxels: u64,
) -> Result<ImageFormat, IoError> {
    let need = |tag, name: &str| {
        int(obj, tag).ok_or_else(|| invalid(path, format!("missing or bad {name}")))
    };
    let rows = need(tags::ROWS, "Rows")?;
    let cols = need(tags::COLUMNS, "Columns")?;
    let bits_allocated = need(tags::BITS_ALLOCATED, "BitsAllocated")?;
    let bits_stored = int(obj, tags::BITS_STORED).unwrap_or(bits_allocated);
    let signed = int(obj, tags::PIXEL_REPRESENTATION).unwrap_or(0) == 1;
    let spp = int(obj, tags::SAMPLES_PER_PIXEL).unwrap_or(1);
    let photometric = string(obj, tags::PHOTOMETRIC_INTERPRETATION)
        .unwrap_or_else(|| "MONOCHROME2".into())
        .to_ascii_uppercase();
    let frames = match string(obj, tags::NUMBER_OF_FRAMES) {
        None => 1,
        Some(_) => need(tags::NUMBER_OF_FRAMES, "NumberOfFrames")?,
    };
    if rows < 1 || cols < 1 || frames < 1 || rows > 65535 || cols > 65535 {
        return Err(invalid(
            path,
            format!("bad image size: {rows} rows, {cols} columns, {frames} frames"),
        ));
    }
    // Bound the frame count before anything is sized by it. For compressed pixel data
    // this bounds the decoded size (Rows x Columns x Frames) before decoding.
    checked_voxels(
        path,
        [cols as usize, rows as usize, frames as usize],
        1,
        max_voxels,
    )?;
    let unsupported = |what: String| IoError::Unsupported {
        path: path.into(),
        what,
    };
    match spp {
        1 => {}
        3 if COLOUR_PIS.contains(&photometric.as_str()) => {}
        3 => {
            return Err(unsupported(format!(
                "colour photometric interpretation {}; read: {}",
                one_line(&photometric),
                COLOUR_PIS.join(", ")
            )))
        }
        _ => {
            return Err(unsupported(format!(
                "{spp} samples per pixel ({}); grey (1) and colour (3) are read",
                one_line(&photometric)
            )))
        }
    }
    let bits_ok = match spp {
        1 => matches!(bits_allocated, 1 | 8 | 16 | 32),
        _ => matches!(bits_allocated, 8 | 16 | 32),
    };
    if !bits_ok || bits_stored < 1 || bits_stored > bits_allocated {
        return Err(unsupported(format!(
            "{bits_allocated} bits allocated, {bits_stored} stored{}",
            if spp == 3 { " (colour)" } else { "" }
        )));
    }
    if spp == 3 && bits_allocated > 8 && photometric.starts_with("YBR_FULL") {
        // pydicom's YBR conversion, the reference, is defined for 8 bits only.
        return Err(unsupported(format!(
            "{photometric} with {bits_allocated} bits allocated: YBR is converted to RGB for \
             8-bit samples only"
        )));
    }
    Ok(ImageFormat {
        rows: rows as usize,
        cols: cols as usize,
        frames: frames as usize,
        bits_allocated: bits_allocated as u16,
        bits_stored: bits_stored as u16,
        signed,
        samples_per_pixel: spp as u16,
        photometric,
        planar: spp == 3 && int(obj, tags::PLANAR_CONFIGURATION) == Some(1),
    })
}

/// Refuses a transfer syntax whose pixel data this build cannot decode, naming it;
/// returns whether the pixel data is encapsulated (compressed).
fn check_transfer_syntax(path: &Path, ts: &str) -> Result<bool, IoError> {
    let unsupported = |what: String| IoError::Unsupported {
        path: path.into(),
        what,
    };
    let Some(syntax) = TransferSyntaxRegistry.get(ts) else {
        return Err(unsupported(format!(
            "unknown transfer syntax {}",
            one_line(ts)
        )));
    };
    // JPEG-LS has no decoder in the registry (CharLS needed CMake); `jpegls` decodes it.
    if !syntax.can_decode_all() && !super::jpegls::is_jpeg_ls(ts) {
        return Err(unsupported(format!(
            "transfer syntax {} has no pixel data decoder in this build; convert to an \
             uncompressed syntax, e.g. with gdcmconv --raw",
            ts_name(ts)
        )));
    }
    Ok(syntax.is_encapsulated_pixel_data())
}

/// Per-frame positions (when known) and rescales (slope, intercept).
type FrameTable = (Vec<Option<[f64; 3]>>, Vec<(f64, f64)>);

/// Per-frame positions and rescales: from the per-frame functional groups of an enhanced
/// multi-frame object, else the one top-level (or shared) position for frame 0.
fn frame_table(path: &Path, obj: &InMemDicomObject, frames: usize) -> Result<FrameTable, IoError> {
    let rescale_of = |o: &InMemDicomObject| {
        (
            float(o, tags::RESCALE_SLOPE).unwrap_or(1.0),
            float(o, tags::RESCALE_INTERCEPT).unwrap_or(0.0),
        )
    };
    let pos3 = |o: Option<&InMemDicomObject>| {
        fixed::<3>(
            path,
            o,
            tags::IMAGE_POSITION_PATIENT,
            "ImagePositionPatient",
        )
    };
    let shared_rescale = find(
        obj,
        tags::PIXEL_VALUE_TRANSFORMATION_SEQUENCE,
        tags::RESCALE_SLOPE,
    )
    .map(rescale_of)
    .unwrap_or((1.0, 0.0));
    let per_frame = obj
        .get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE)
        .and_then(InMemElement::items);
    match per_frame {
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
                positions.push(pos3(item(it, tags::PLANE_POSITION_SEQUENCE))?);
                rescale.push(
                    item(it, tags::PIXEL_VALUE_TRANSFORMATION_SEQUENCE)
                        .filter(|p| p.get(tags::RESCALE_SLOPE).is_some())
                        .map(rescale_of)
                        .unwrap_or(shared_rescale),
                );
            }
            Ok((positions, rescale))
        }
        _ => {
            let top = pos3(find(
                obj,
                tags::PLANE_POSITION_SEQUENCE,
                tags::IMAGE_POSITION_PATIENT,
            ))?;
            let mut positions = vec![None; frames];
            positions[0] = top;
            let r = if obj.get(tags::RESCALE_SLOPE).is_some() {
                rescale_of(obj)
            } else {
                shared_rescale
            };
            Ok((positions, vec![r; frames]))
        }
    }
}

fn header_of(
    path: &Path,
    obj: &InMemDicomObject,
    ts: &str,
    data_len: u64,
    max_voxels: u64,
) -> Result<Header, IoError> {
    let format = image_size(path, obj, max_voxels)?;
    let ImageFormat {
        rows,
        cols,
        frames,
        bits_allocated,
        ..
    } = format;
    let encapsulated = check_transfer_syntax(path, ts)?;
    if encapsulated && bits_allocated == 1 {
        return Err(IoError::Unsupported {
            path: path.into(),
            what: format!(
                "1-bit pixel data in the compressed transfer syntax {}",
                ts_name(ts)
            ),
        });
    }
    // The pixels of every frame must fit in the data set before anything (per-frame
    // positions, rescales, the pixel buffer) is sized by the frame count: native pixels
    // take their full size; compressed ones are bounded by the voxel limit above, and
    // each frame takes at least one 8-byte fragment header (PS3.5 A.4).
    let need = if encapsulated {
        8u64.checked_mul(frames as u64)
    } else {
        format.native_bytes()
    };
    if need.is_none_or(|need| need > data_len) {
        let what = if encapsulated {
            format!("{frames} compressed frames need more than the data set's {data_len} bytes")
        } else {
            format!(
                "{rows} rows x {cols} columns x {frames} frames of {bits_allocated}-bit \
                 pixels need more bytes than the file's {data_len}"
            )
        };
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what,
        });
    }
    let orientation = fixed::<6>(
        path,
        find(
            obj,
            tags::PLANE_ORIENTATION_SEQUENCE,
            tags::IMAGE_ORIENTATION_PATIENT,
        ),
        tags::IMAGE_ORIENTATION_PATIENT,
        "ImageOrientationPatient",
    )?;
    let pixel_spacing = fixed::<2>(
        path,
        find(obj, tags::PIXEL_MEASURES_SEQUENCE, tags::PIXEL_SPACING),
        tags::PIXEL_SPACING,
        "PixelSpacing",
    )?;
    let spacing_between_slices = find(
        obj,
        tags::PIXEL_MEASURES_SEQUENCE,
        tags::SPACING_BETWEEN_SLICES,
    )
    .and_then(|o| float(o, tags::SPACING_BETWEEN_SLICES));
    let slice_step = spacing_between_slices.or_else(|| {
        find(obj, tags::PIXEL_MEASURES_SEQUENCE, tags::SLICE_THICKNESS)
            .and_then(|o| float(o, tags::SLICE_THICKNESS))
    });
    let (positions, rescale) = frame_table(path, obj, frames)?;
    let dose = float(obj, tags::DOSE_GRID_SCALING).map(|s| (s, string(obj, tags::DOSE_UNITS)));
    Ok(Header {
        path: path.into(),
        rows,
        cols,
        frames,
        bits_allocated,
        bits_stored: format.bits_stored,
        signed: format.signed,
        samples_per_pixel: format.samples_per_pixel,
        photometric: format.photometric,
        planar: format.planar,
        ts: ts.to_string(),
        encapsulated,
        series: string(obj, tags::SERIES_INSTANCE_UID),
        frame_of_reference: string(obj, tags::FRAME_OF_REFERENCE_UID),
        orientation,
        pixel_spacing,
        positions,
        rescale,
        slice_step,
        spacing_between_slices,
        frame_offsets: floats(obj, tags::GRID_FRAME_OFFSET_VECTOR).filter(|v| v.len() == frames),
        modality: string(obj, tags::MODALITY),
        rescale_type: string(obj, tags::RESCALE_TYPE),
        description: string(obj, tags::SERIES_DESCRIPTION),
        dose,
        sop_class: string(obj, tags::SOP_CLASS_UID),
        notes: Vec::new(),
    })
}

/// A file opened as DICOM but not read as an image, with what it says about itself.
pub(super) struct Refused {
    /// Why it is not read.
    pub error: IoError,
    /// Its SeriesInstanceUID, Modality and SOP class name, when the data set parsed.
    pub series: Option<String>,
    pub modality: Option<String>,
    pub class: Option<String>,
    /// Its SOPClassUID, when the data set parsed (an RT structure set is read by
    /// `rtstruct`).
    pub class_uid: Option<String>,
    /// Whether it parsed and has no PixelData (an RT structure set, a report, ...).
    pub not_image: bool,
}

impl From<IoError> for Box<Refused> {
    fn from(error: IoError) -> Box<Refused> {
        Box::new(Refused {
            error,
            series: None,
            modality: None,
            class: None,
            class_uid: None,
            not_image: false,
        })
    }
}

/// The name of a data set's SOPClassUID (its UID when the dictionary has no name).
fn class_name(obj: &InMemDicomObject) -> Option<String> {
    let class = obj
        .get(tags::SOP_CLASS_UID)
        .and_then(|e| e.to_str().ok())
        .map(|s| s.trim_end_matches(['\0', ' ']).to_string());
    class
        .as_deref()
        .and_then(|uid| StandardSopClassDictionary.by_uid(uid))
        .map(|u| u.name.to_string())
        .or(class)
        .map(|n| one_line(&n))
}

/// Opens a file and reads its header (everything before the pixel data); a file that
/// parses but is not read as an image comes back with its series, modality and class.
pub(super) fn open_header(
    path: &Path,
    max_voxels: u64,
    strict: bool,
) -> Result<Header, Box<Refused>> {
    let loaded = scan::load(path, false, strict)?;
    let ts = loaded
        .obj
        .meta()
        .transfer_syntax()
        .trim_end_matches(['\0', ' '])
        .to_string();
    let obj = &loaded.obj;
    let refused = |error: IoError| Refused {
        error,
        series: string(obj, tags::SERIES_INSTANCE_UID),
        modality: string(obj, tags::MODALITY),
        class: class_name(obj),
        class_uid: string(obj, tags::SOP_CLASS_UID),
        not_image: false,
    };
    if !loaded.has_pixels {
        let name = class_name(obj).unwrap_or_else(|| "no SOPClassUID".into());
        return Err(Box::new(Refused {
            not_image: true,
            ..refused(IoError::Unsupported {
                path: path.into(),
                what: format!("no PixelData: not an image ({name})"),
            })
        }));
    }
    let mut h =
        header_of(path, obj, &ts, loaded.data_len, max_voxels).map_err(|e| Box::new(refused(e)))?;
    h.notes = loaded.notes;
    Ok(h)
}
