//! DICOM Segmentation objects (Segmentation Storage and Label Map Segmentation Storage,
//! PS3.3 A.51 and C.8.20) read as label maps: one label per voxel, the segment's
//! SegmentNumber, 0 for background.
//!
//! Each frame holds one segment (BINARY: 1 bit a pixel, bit-packed across frames;
//! FRACTIONAL: 8 bits, thresholded at half of MaximumFractionalValue) named by its
//! per-frame SegmentIdentificationSequence, or (LABELMAP) every segment at once as pixel
//! values. Frames are placed on one grid by their PlanePositionSequence along the normal
//! of the (shared or per-frame, but one) PlaneOrientationSequence, a slice step apart:
//! SpacingBetweenSlices, else the smallest gap between frame positions, else
//! SliceThickness. Frames that are not on that grid are refused. Where two segments
//! cover one voxel, the higher SegmentNumber is kept (with a note counting such voxels).

use std::path::Path;

use dicom_dictionary_std::{tags, uids};
use dicom_object::mem::InMemElement;
use dicom_object::InMemDicomObject;

use super::geometry::{self, dot, Plane};
use super::header::{int, item, string, Header};
use super::pixels::{self, Frame};
use super::{invalid, one_line, scan, ORIENTATION_TOLERANCE};
use crate::common::checked_voxels;
use crate::{Format, IoError, ReadOptions, Samples, Volume, VolumeFile};

/// Distance (mm) under which two frame positions along the normal are one slice.
const SAME_SLICE_MM: f64 = 1e-3;

/// Largest distance of a frame from its slice, as a fraction of the slice step, and of
/// a frame's in-plane origin from the first frame's, as a fraction of a pixel.
const GRID_TOLERANCE: f64 = 0.05;

/// One segment of a Segmentation's SegmentSequence (PS3.3 C.8.20.2).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Segment {
    /// SegmentNumber: the segment's label in the label map (1 or more).
    pub number: u16,
    /// SegmentLabel (`segment N` when absent).
    pub label: String,
    /// RecommendedDisplayCIELabValue as stored: L*, a*, b* scaled to 0..=65535
    /// (PS3.3 C.10.7.1.1), when given.
    pub cielab: Option<[u16; 3]>,
}

/// How a Segmentation's pixels hold its segments (SegmentationType, PS3.3 C.8.20.2.3).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// One bit a pixel, one segment a frame.
    Binary,
    /// A fraction (stored / MaximumFractionalValue) a pixel, one segment a frame.
    Fractional { max: u32 },
    /// The pixel values are segment numbers.
    LabelMap,
}

/// Whether a SOPClassUID is one of the Segmentation classes this module reads.
pub(super) fn is_segmentation(class: Option<&str>) -> bool {
    matches!(
        class,
        Some(uids::SEGMENTATION_STORAGE) | Some(uids::LABEL_MAP_SEGMENTATION_STORAGE)
    )
}

/// The segments of a DICOM Segmentation file (read without its pixel data), or `None`
/// when the file is DICOM but not a Segmentation.
pub fn read_segments(path: &Path, options: &ReadOptions) -> Result<Option<Vec<Segment>>, IoError> {
    let loaded = scan::load(path, false, options.strict)?;
    let class = string(&loaded.obj, tags::SOP_CLASS_UID);
    if !is_segmentation(class.as_deref()) {
        return Ok(None);
    }
    segments(path, &loaded.obj).map(Some)
}

/// The SegmentSequence: numbers unique and from 1, labels, colours.
fn segments(path: &Path, obj: &InMemDicomObject) -> Result<Vec<Segment>, IoError> {
    let items = obj
        .get(tags::SEGMENT_SEQUENCE)
        .and_then(InMemElement::items)
        .filter(|i| !i.is_empty())
        .ok_or_else(|| invalid(path, "DICOM SEG without a SegmentSequence"))?;
    let mut out: Vec<Segment> = Vec::with_capacity(items.len());
    for (i, it) in items.iter().enumerate() {
        let number = int(it, tags::SEGMENT_NUMBER)
            .filter(|n| (1..=i64::from(u16::MAX)).contains(n))
            .ok_or_else(|| {
                invalid(
                    path,
                    format!(
                        "SegmentSequence item {}: missing or bad SegmentNumber",
                        i + 1
                    ),
                )
            })? as u16;
        if out.iter().any(|s| s.number == number) {
            return Err(invalid(
                path,
                format!("SegmentNumber {number} appears twice in the SegmentSequence"),
            ));
        }
        let cielab = match it.get(tags::RECOMMENDED_DISPLAY_CIE_LAB_VALUE) {
            None => None,
            Some(e) => {
                let v = e.to_multi_int::<i64>().ok().unwrap_or_default();
                let lab: Option<[u16; 3]> = <[i64; 3]>::try_from(v)
                    .ok()
                    .map(|v| v.map(|x| u16::try_from(x).ok()))
                    .and_then(|[l, a, b]| Some([l?, a?, b?]));
                Some(lab.ok_or_else(|| {
                    invalid(
                        path,
                        format!(
                            "segment {number}: RecommendedDisplayCIELabValue is not three values in 0..=65535"
                        ),
                    )
                })?)
            }
        };
        let label = string(it, tags::SEGMENT_LABEL)
            .map(|s| one_line(&s))
            .unwrap_or_else(|| format!("segment {number}"));
        out.push(Segment {
            number,
            label,
            cielab,
        });
    }
    Ok(out)
}

/// SegmentationType and the bits it needs.
fn kind(path: &Path, obj: &InMemDicomObject, h: &Header) -> Result<Kind, IoError> {
    let ty = string(obj, tags::SEGMENTATION_TYPE).unwrap_or_default();
    let kind = match ty.as_str() {
        "BINARY" => Kind::Binary,
        "FRACTIONAL" => {
            let max = int(obj, tags::MAXIMUM_FRACTIONAL_VALUE)
                .filter(|m| (1..=255).contains(m))
                .ok_or_else(|| {
                    invalid(
                        path,
                        "FRACTIONAL DICOM SEG without a MaximumFractionalValue in 1..=255",
                    )
                })?;
            Kind::Fractional { max: max as u32 }
        }
        "LABELMAP" => Kind::LabelMap,
        other => {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: format!(
                    "SegmentationType {:?}; read: BINARY, FRACTIONAL, LABELMAP",
                    one_line(other)
                ),
            })
        }
    };
    let bits_ok = match kind {
        Kind::Binary => h.bits_allocated == 1,
        Kind::Fractional { .. } => h.bits_allocated == 8,
        Kind::LabelMap => matches!(h.bits_allocated, 8 | 16),
    };
    if !bits_ok || h.samples_per_pixel != 1 {
        return Err(invalid(
            path,
            format!(
                "{ty} DICOM SEG with {} bits allocated and {} samples per pixel (BINARY \
                 has 1 bit, FRACTIONAL 8, LABELMAP 8 or 16; one sample)",
                h.bits_allocated, h.samples_per_pixel
            ),
        ));
    }
    Ok(kind)
}

/// The segment of each frame (ReferencedSegmentNumber, per-frame or shared), each in
/// `segments`; and every per-frame orientation the same as the header's.
fn frame_segments(
    path: &Path,
    obj: &InMemDicomObject,
    h: &Header,
    segments: &[Segment],
    strict: bool,
    notes: &mut Vec<String>,
) -> Result<Vec<u16>, IoError> {
    let per_frame: &[InMemDicomObject] = obj
        .get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE)
        .and_then(InMemElement::items)
        .unwrap_or(&[]);
    // pydicom's liver_1frame.dcm keeps 3 per-frame groups for its 1 frame: the first
    // NumberOfFrames are used, with a note (refused under --strict).
    if per_frame.len() > h.frames && !strict {
        notes.push(format!(
            "{} per-frame functional groups for NumberOfFrames {}: the first {} used",
            per_frame.len(),
            h.frames,
            h.frames
        ));
    } else if !per_frame.is_empty() && per_frame.len() != h.frames {
        return Err(invalid(
            path,
            format!(
                "{} per-frame functional groups for NumberOfFrames {}",
                per_frame.len(),
                h.frames
            ),
        ));
    }
    let shared = item(obj, tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE);
    let reference = |g: Option<&InMemDicomObject>| {
        g.and_then(|g| item(g, tags::SEGMENT_IDENTIFICATION_SEQUENCE))
            .and_then(|s| int(s, tags::REFERENCED_SEGMENT_NUMBER))
    };
    let mut out = Vec::with_capacity(h.frames);
    for f in 0..h.frames {
        let group = per_frame.get(f);
        if let (Some(o), Some(g)) = (h.orientation, group) {
            let own = item(g, tags::PLANE_ORIENTATION_SEQUENCE)
                .and_then(|p| super::header::floats(p, tags::IMAGE_ORIENTATION_PATIENT));
            if let Some(v) = own {
                let same = v.len() == 6
                    && v.iter()
                        .zip(o)
                        .all(|(a, b)| (a - b).abs() < ORIENTATION_TOLERANCE);
                if !same {
                    return Err(IoError::Geometry {
                        path: path.into(),
                        what: format!("frame {} has another orientation than frame 1", f + 1),
                    });
                }
            }
        }
        let number = reference(group)
            .or_else(|| reference(shared))
            .ok_or_else(|| {
                invalid(
                    path,
                    format!("frame {} has no ReferencedSegmentNumber", f + 1),
                )
            })?;
        let known = segments.iter().any(|s| i64::from(s.number) == number);
        if !known {
            return Err(invalid(
                path,
                format!(
                    "frame {} refers to segment {number}, which the SegmentSequence does not define",
                    f + 1
                ),
            ));
        }
        out.push(number as u16);
    }
    Ok(out)
}

/// Where the frames go: a slice index each, on `slices` slices `step` mm apart along
/// the normal from `origin` (LPS mm).
struct Placement {
    index: Vec<usize>,
    slices: usize,
    origin: [f64; 3],
    step: f64,
}

/// Places every frame on one grid (see the module documentation).
fn place(
    path: &Path,
    h: &Header,
    plane: &Plane,
    max_voxels: u64,
    notes: &mut Vec<String>,
) -> Result<Placement, IoError> {
    let geometry = |what: String| IoError::Geometry {
        path: path.into(),
        what,
    };
    let mut positions = Vec::with_capacity(h.frames);
    for (f, p) in h.positions.iter().enumerate() {
        let p = p
            .filter(|p| p.iter().all(|x| x.is_finite()))
            .ok_or_else(|| {
                geometry(format!(
                    "DICOM SEG frame {} has no usable PlanePositionSequence",
                    f + 1
                ))
            })?;
        positions.push(p);
    }
    let p0 = positions[0];
    let pixel = plane.pixel_spacing[0].min(plane.pixel_spacing[1]);
    let mut along = Vec::with_capacity(positions.len());
    for (f, p) in positions.iter().enumerate() {
        let v = [p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]];
        let (u, w) = (dot(v, plane.row_dir), dot(v, plane.col_dir));
        if u.abs().max(w.abs()) > GRID_TOLERANCE * pixel {
            return Err(geometry(format!(
                "DICOM SEG frame {} is offset in-plane by ({u:.3}, {w:.3}) mm from frame 1: \
                 frames on different grids are not read",
                f + 1
            )));
        }
        along.push(dot(*p, plane.normal));
    }
    let mut sorted = along.clone();
    sorted.sort_by(f64::total_cmp);
    let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
    let min_gap = sorted
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|g| *g > SAME_SLICE_MM)
        .min_by(f64::total_cmp);
    let usable = |s: &Option<f64>| s.filter(|s| s.is_finite() && *s > SAME_SLICE_MM);
    let step = match (
        usable(&h.spacing_between_slices),
        min_gap,
        usable(&h.slice_step),
    ) {
        (Some(s), _, _) => s,
        (None, Some(g), _) => g,
        (None, None, Some(t)) => t,
        (None, None, None) => {
            notes.push("geometry assumed: one slice and no slice thickness, 1 mm".into());
            1.0
        }
    };
    let span = (hi - lo) / step;
    if !(span.is_finite() && span < max_voxels as f64) {
        return Err(IoError::TooLarge {
            path: path.into(),
            what: format!(
                "frames span {:.3} mm at a slice step of {step} mm: too many slices",
                hi - lo
            ),
        });
    }
    let slices = span.round() as usize + 1;
    let mut index = Vec::with_capacity(along.len());
    for (f, d) in along.iter().enumerate() {
        let k = (d - lo) / step;
        if (k - k.round()).abs() > GRID_TOLERANCE {
            return Err(geometry(format!(
                "DICOM SEG frame {} lies between slices ({:.3} mm from the first, slice step {step} mm)",
                f + 1,
                d - lo
            )));
        }
        index.push(k.round() as usize);
    }
    let shift = lo - along[0];
    let origin = std::array::from_fn(|r| p0[r] + shift * plane.normal[r]);
    Ok(Placement {
        index,
        slices,
        origin,
        step,
    })
}

/// Reads a Segmentation (its header `h` already read) as a label volume.
pub(super) fn read(
    path: &Path,
    h: Header,
    options: &ReadOptions,
    mut notes: Vec<String>,
) -> Result<VolumeFile, IoError> {
    let loaded = scan::load(path, false, options.strict)?;
    let obj = &loaded.obj;
    let segments = segments(path, obj)?;
    let kind = kind(path, obj, &h)?;
    let numbers = match kind {
        Kind::LabelMap => vec![0; h.frames],
        _ => frame_segments(path, obj, &h, &segments, options.strict, &mut notes)?,
    };
    drop(loaded);
    if h.orientation.is_none() {
        return Err(IoError::Geometry {
            path: path.into(),
            what: "DICOM SEG without a PlaneOrientationSequence".into(),
        });
    }
    let plane = geometry::plane(path, &h, options.strict, &mut notes)?;
    let placed = place(path, &h, &plane, options.max_voxels, &mut notes)?;
    let dims = [h.cols, h.rows, placed.slices];
    let total = checked_voxels(path, dims, 2, options.max_voxels)?;
    let slice_vec = plane.normal.map(|x| x * placed.step);
    let (affine, spacing) = geometry::affine(path, &plane, slice_vec, placed.origin)?;
    let frame_len = h.rows * h.cols;
    let frames = pixels::read_pixels(&h, frame_len, options.strict)?;
    // Frames in SegmentNumber order (stable): a higher number overwrites a lower one.
    let mut order: Vec<usize> = (0..frames.len().min(h.frames)).collect();
    order.sort_by_key(|&f| numbers[f]);
    let mut labels = vec![0u16; total];
    let mut overlaps = 0u64;
    for f in order {
        let Frame::Grey(s) = &frames[f] else {
            return Err(invalid(path, "DICOM SEG with colour frames"));
        };
        let base = placed.index[f] * frame_len;
        for (p, cell) in labels[base..base + frame_len].iter_mut().enumerate() {
            let v = s.get(p);
            let label = match kind {
                Kind::Binary if v != 0.0 => numbers[f],
                Kind::Fractional { max } if 2.0 * v >= f64::from(max) => numbers[f],
                Kind::LabelMap => v as u16,
                _ => 0,
            };
            if label != 0 {
                overlaps += u64::from(*cell != 0 && *cell != label);
                *cell = label;
            }
        }
    }
    notes.push(format!(
        "DICOM SEG ({}): {} segment(s), {} frame(s) on {} slice(s); labels are SegmentNumbers",
        match kind {
            Kind::Binary => "BINARY".to_string(),
            Kind::Fractional { max } => format!("FRACTIONAL, thresholded at 0.5 of {max}"),
            Kind::LabelMap => "LABELMAP".to_string(),
        },
        segments.len(),
        h.frames,
        placed.slices
    ));
    if overlaps > 0 {
        notes.push(format!(
            "{overlaps} voxel(s) in more than one segment: the higher SegmentNumber kept"
        ));
    }
    let samples = if labels.iter().all(|&v| v <= 255) {
        Samples::U8(labels.into_iter().map(|v| v as u8).collect())
    } else {
        Samples::U16(labels)
    };
    Ok(VolumeFile {
        volume: Volume {
            dims,
            spacing,
            affine,
            samples,
            slope: 1.0,
            intercept: 0.0,
            units: None,
            colour: None,
        },
        format: Format::Dicom,
        notes,
        inflate: None,
    })
}
