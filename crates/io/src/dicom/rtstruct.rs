//! RT structure sets (RT Structure Set Storage, PS3.3 A.19: the StructureSetROISequence,
//! C.8.8.5, and the ROIContourSequence, C.8.8.6) read as label maps on the grid of the
//! image series they were drawn on.
//!
//! Each ROI's CLOSED_PLANAR contours are rasterised slice by slice (see `raster`): a
//! contour goes to the slice nearest to it when every point is within half the slice
//! spacing of that slice, and a voxel centre is inside when it is inside an odd number
//! of the ROI's contours on that slice (the even-odd rule: a contour inside another is
//! a hole, PS3.3 C.8.8.6.3; CLOSEDPLANAR_XOR contours are combined the same way).
//! Labels are ROINumbers, named by ROIName and coloured by ROIDisplayColor. Where ROIs
//! overlap (an organ inside the body outline, a target inside its margin), the smaller
//! ROI keeps the voxel, so that every ROI stays visible; each ROI's own volume counts
//! all its voxels ([`StructureSet::voxels`]).
//!
//! The image is the one [`ReadOptions::reference`] names (the volume the labels are
//! drawn over), else the series the structure set references (its
//! RTReferencedSeriesSequence), else one of its frame of reference, found beside the
//! structure set. Refused, one line each: an ROI in another frame of reference than
//! the image's, a contour not within half a slice of one slice, malformed ContourData
//! (not numeric, not x/y/z triples, fewer than 3 points, a NumberOfContourPoints that
//! disagrees, values not finite), an unknown ContourGeometricType. POINT, OPEN_PLANAR
//! and OPEN_NONPLANAR contours are skipped with a note: they mark points and lines,
//! which enclose no volume, and structure sets commonly carry them (an isocentre, a
//! marker) beside the organs, so refusing them would refuse most clinical files.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use dicom_dictionary_std::{tags, uids};
use dicom_object::mem::InMemElement;
use dicom_object::InMemDicomObject;

use super::header::{floats, int, string, Header};
use super::raster::{self, OffSlice};
use super::{grid, invalid, one_line, scan, series, Grid};
use crate::affine::{det3, inverse3, linear_part, mul3};
use crate::{Format, IoError, ReadOptions, Samples, Volume, VolumeFile};

/// One ROI of a structure set (StructureSetROISequence and its ROIContourSequence item).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Roi {
    /// ROINumber: the ROI's label in the label map (1 or more).
    pub number: u32,
    /// ROIName (`ROI N` when absent).
    pub name: String,
    /// ROIDisplayColor (sRGB), when given.
    pub color: Option<[u8; 3]>,
    /// ReferencedFrameOfReferenceUID: the coordinate system of its contours.
    pub frame_of_reference: Option<String>,
    /// Closed contours (CLOSED_PLANAR, CLOSEDPLANAR_XOR): the ones rasterised.
    pub contours: usize,
    /// POINT, OPEN_PLANAR and OPEN_NONPLANAR contours, skipped.
    pub skipped: usize,
}

/// An RT structure set rasterised onto the image it was drawn on
/// ([`read_structure_set`]).
#[derive(Clone, Debug)]
pub struct StructureSet {
    /// The ROIs, in StructureSetROISequence order.
    pub rois: Vec<Roi>,
    /// Voxels inside each ROI's contours (one per ROI, in the same order), overlaps with
    /// other ROIs included.
    pub voxels: Vec<u64>,
    /// The label map (labels are ROINumbers; where ROIs overlap, the smaller keeps the
    /// voxel) on the image's grid, with the notes of the reading.
    pub labels: VolumeFile,
    /// The image series (a file or directory) the contours were rasterised onto.
    pub image: PathBuf,
}

impl StructureSet {
    /// The volume of one voxel of the grid, in millilitres.
    pub fn voxel_ml(&self) -> f64 {
        det3(&linear_part(&self.labels.volume.affine)).abs() / 1000.0
    }
}

/// Whether a SOPClassUID is RT Structure Set Storage.
pub(super) fn is_structure_set(class: Option<&str>) -> bool {
    class == Some(uids::RT_STRUCTURE_SET_STORAGE)
}

/// One closed contour: its ROI (an index into the ROIs), its place among that ROI's
/// contours (1-based) and its points (LPS mm).
struct Contour {
    roi: usize,
    index: usize,
    points: Vec<[f64; 3]>,
}

/// What a structure set says, before rasterising.
struct Parsed {
    rois: Vec<Roi>,
    contours: Vec<Contour>,
    /// The SeriesInstanceUIDs it references (RTReferencedSeriesSequence).
    series: Vec<String>,
}

/// The ROIs of an RT structure set (numbers, names, colours, contour counts; nothing
/// rasterised), or `None` when the file is DICOM but not a structure set.
pub fn read_rois(path: &Path, options: &ReadOptions) -> Result<Option<Vec<Roi>>, IoError> {
    let loaded = scan::load(path, false, options.strict)?;
    if !is_structure_set(string(&loaded.obj, tags::SOP_CLASS_UID).as_deref()) {
        return Ok(None);
    }
    parse(path, &loaded.obj).map(|p| Some(p.rois))
}

/// An RT structure set rasterised onto its image (see the module documentation), or
/// `None` when the file is DICOM but not a structure set.
pub fn read_structure_set(
    path: &Path,
    options: &ReadOptions,
) -> Result<Option<StructureSet>, IoError> {
    let loaded = scan::load(path, false, options.strict)?;
    if !is_structure_set(string(&loaded.obj, tags::SOP_CLASS_UID).as_deref()) {
        return Ok(None);
    }
    let parsed = parse(path, &loaded.obj)?;
    drop(loaded);
    rasterise(path, parsed, options).map(Some)
}

/// Reads an RT structure set as a label volume.
pub(super) fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    match read_structure_set(path, options)? {
        Some(s) => Ok(s.labels),
        None => Err(invalid(path, "not an RT structure set")),
    }
}

/// The items of a sequence (none when absent).
fn items(obj: &InMemDicomObject, tag: dicom_core::Tag) -> &[InMemDicomObject] {
    obj.get(tag).and_then(InMemElement::items).unwrap_or(&[])
}

/// The ROIs of the StructureSetROISequence: numbers unique and from 1.
fn rois(path: &Path, obj: &InMemDicomObject) -> Result<Vec<Roi>, IoError> {
    let list = items(obj, tags::STRUCTURE_SET_ROI_SEQUENCE);
    if list.is_empty() {
        return Err(invalid(
            path,
            "RT structure set without a StructureSetROISequence (no ROI)",
        ));
    }
    // The frame of reference of ROIs that name none: the structure set's only one.
    let frames: Vec<String> = items(obj, tags::REFERENCED_FRAME_OF_REFERENCE_SEQUENCE)
        .iter()
        .filter_map(|f| string(f, tags::FRAME_OF_REFERENCE_UID))
        .collect();
    let mut out: Vec<Roi> = Vec::with_capacity(list.len());
    for (i, it) in list.iter().enumerate() {
        let number = int(it, tags::ROI_NUMBER)
            .filter(|n| (1..=i64::from(u32::MAX)).contains(n))
            .ok_or_else(|| {
                invalid(
                    path,
                    format!(
                        "StructureSetROISequence item {}: missing or bad ROINumber (labels are numbers from 1)",
                        i + 1
                    ),
                )
            })? as u32;
        if out.iter().any(|r| r.number == number) {
            return Err(invalid(
                path,
                format!("ROINumber {number} appears twice in the StructureSetROISequence"),
            ));
        }
        out.push(Roi {
            number,
            name: string(it, tags::ROI_NAME)
                .map(|s| one_line(&s))
                .unwrap_or_else(|| format!("ROI {number}")),
            color: None,
            frame_of_reference: string(it, tags::REFERENCED_FRAME_OF_REFERENCE_UID)
                .or_else(|| (frames.len() == 1).then(|| frames[0].clone())),
            contours: 0,
            skipped: 0,
        });
    }
    Ok(out)
}

/// ROIDisplayColor: three values in 0..=255.
fn color(path: &Path, roi: &Roi, it: &InMemDicomObject) -> Result<Option<[u8; 3]>, IoError> {
    let Some(e) = it.get(tags::ROI_DISPLAY_COLOR) else {
        return Ok(None);
    };
    let v = e.to_multi_int::<i64>().ok().unwrap_or_default();
    <[i64; 3]>::try_from(v)
        .ok()
        .map(|v| v.map(|x| u8::try_from(x).ok()))
        .and_then(|[r, g, b]| Some([r?, g?, b?]))
        .map(Some)
        .ok_or_else(|| {
            invalid(
                path,
                format!(
                    "ROI {} '{}': ROIDisplayColor is not three values in 0..=255",
                    roi.number, roi.name
                ),
            )
        })
}

/// The points of one contour (LPS mm), checked: numbers, x/y/z triples, at least 3
/// points, as many as NumberOfContourPoints says, finite. The values were parsed from
/// an element whose length was checked against the file (`scan`): nothing is sized by
/// NumberOfContourPoints.
fn points(path: &Path, what: &str, c: &InMemDicomObject) -> Result<Vec<[f64; 3]>, IoError> {
    let bad = |why: String| invalid(path, format!("{what}: {why}"));
    if c.get(tags::CONTOUR_DATA).is_none() {
        return Err(bad("no ContourData".into()));
    }
    let data = floats(c, tags::CONTOUR_DATA)
        .ok_or_else(|| bad("ContourData is not a list of numbers".into()))?;
    if data.len() % 3 != 0 {
        return Err(bad(format!(
            "ContourData holds {} numbers, not x/y/z triples",
            data.len()
        )));
    }
    let n = data.len() / 3;
    if let Some(declared) = int(c, tags::NUMBER_OF_CONTOUR_POINTS) {
        if declared != n as i64 {
            return Err(bad(format!(
                "NumberOfContourPoints is {declared}, ContourData holds {n} points"
            )));
        }
    }
    if n < 3 {
        return Err(bad(format!(
            "a closed contour of {n} point(s) encloses nothing"
        )));
    }
    if data.iter().any(|x| !x.is_finite()) {
        return Err(bad("ContourData holds a value that is not finite".into()));
    }
    Ok(data.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
}

/// The ROIs, their colours and closed contours, and the series referenced.
fn parse(path: &Path, obj: &InMemDicomObject) -> Result<Parsed, IoError> {
    let mut rois = rois(path, obj)?;
    let mut contours = Vec::new();
    for (i, it) in items(obj, tags::ROI_CONTOUR_SEQUENCE).iter().enumerate() {
        let number = int(it, tags::REFERENCED_ROI_NUMBER);
        let r = rois
            .iter()
            .position(|r| Some(i64::from(r.number)) == number)
            .ok_or_else(|| {
                invalid(
                    path,
                    format!(
                        "ROIContourSequence item {} refers to ROI {}, which the StructureSetROISequence does not define",
                        i + 1,
                        number.map_or("(none)".into(), |n| n.to_string())
                    ),
                )
            })?;
        if rois[r].color.is_none() {
            rois[r].color = color(path, &rois[r], it)?;
        }
        for c in items(it, tags::CONTOUR_SEQUENCE) {
            let roi = &mut rois[r];
            let index = roi.contours + roi.skipped + 1;
            let what = format!("ROI {} '{}' contour {index}", roi.number, roi.name);
            let kind = string(c, tags::CONTOUR_GEOMETRIC_TYPE).unwrap_or_default();
            match kind.to_ascii_uppercase().as_str() {
                "CLOSED_PLANAR" | "CLOSEDPLANAR_XOR" => {}
                "POINT" | "OPEN_PLANAR" | "OPEN_NONPLANAR" => {
                    roi.skipped += 1;
                    continue;
                }
                other => {
                    return Err(IoError::Unsupported {
                        path: path.into(),
                        what: format!(
                            "{what}: ContourGeometricType {:?}; read: CLOSED_PLANAR, CLOSEDPLANAR_XOR (POINT, OPEN_PLANAR, OPEN_NONPLANAR skipped)",
                            one_line(other)
                        ),
                    })
                }
            }
            let points = points(path, &what, c)?;
            roi.contours += 1;
            contours.push(Contour {
                roi: r,
                index,
                points,
            });
        }
    }
    let mut series = Vec::new();
    for f in items(obj, tags::REFERENCED_FRAME_OF_REFERENCE_SEQUENCE) {
        for st in items(f, tags::RT_REFERENCED_STUDY_SEQUENCE) {
            for se in items(st, tags::RT_REFERENCED_SERIES_SEQUENCE) {
                series.extend(string(se, tags::SERIES_INSTANCE_UID));
            }
        }
    }
    Ok(Parsed {
        rois,
        contours,
        series,
    })
}

/// The image series the contours go onto (see the module documentation): its place and
/// headers.
fn image(
    path: &Path,
    parsed: &Parsed,
    options: &ReadOptions,
    notes: &mut Vec<String>,
) -> Result<(PathBuf, Vec<Header>), IoError> {
    let given = options.reference.clone();
    let place = given.clone().unwrap_or_else(|| match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    });
    let plain = ReadOptions {
        series: None,
        reference: None,
        ..options.clone()
    };
    let headers = series::images(&place, &plain).map_err(|e| match e {
        IoError::BadMagic { .. } => invalid(
            path,
            format!(
                "an RT structure set is drawn on a DICOM image; {} is not DICOM",
                place.display()
            ),
        ),
        e => e,
    })?;
    let mut groups: BTreeMap<String, Vec<Header>> = BTreeMap::new();
    for h in headers {
        groups
            .entry(h.series.clone().unwrap_or_default())
            .or_default()
            .push(h);
    }
    let wanted: Vec<&str> = parsed
        .rois
        .iter()
        .filter_map(|r| r.frame_of_reference.as_deref())
        .collect();
    let referenced = groups
        .iter()
        .find(|(uid, _)| parsed.series.contains(uid))
        .map(|(uid, _)| uid.clone());
    let chosen = referenced.or_else(|| {
        groups
            .iter()
            .filter(|(_, hs)| {
                hs[0]
                    .frame_of_reference
                    .as_deref()
                    .is_some_and(|f| wanted.contains(&f))
            })
            .max_by_key(|(_, hs)| hs.iter().map(|h| h.frames).sum::<usize>())
            .map(|(uid, _)| uid.clone())
    });
    let ours = wanted.first().map_or("(none)".into(), |f| one_line(f));
    let Some(uid) = chosen else {
        let theirs: Vec<String> = groups
            .values()
            .filter_map(|hs| hs[0].frame_of_reference.as_deref().map(one_line))
            .collect();
        return Err(match given {
            Some(_) if !theirs.is_empty() => IoError::Geometry {
                path: path.into(),
                what: format!(
                    "the structure set's frame of reference {ours} is not the image's ({}, {}): its contours are in another patient coordinate system",
                    theirs.join(", "),
                    place.display()
                ),
            },
            _ => invalid(
                path,
                format!(
                    "no image series of its frame of reference {ours} in {}: name the image it was drawn on (e.g. glint render CT_DIR --labels {})",
                    place.display(),
                    path.display()
                ),
            ),
        });
    };
    if !parsed.series.is_empty() && !parsed.series.contains(&uid) {
        notes.push(format!(
            "rasterised onto series {} of the same frame of reference (the structure set references {})",
            one_line(&uid),
            parsed.series.iter().map(|s| one_line(s)).collect::<Vec<_>>().join(", ")
        ));
    }
    let headers = groups.remove(&uid).unwrap_or_default();
    Ok((place, headers))
}

/// Every ROI in the frame of reference of the image.
fn check_frames(
    path: &Path,
    rois: &[Roi],
    image: &Header,
    notes: &mut Vec<String>,
) -> Result<(), IoError> {
    let Some(theirs) = image.frame_of_reference.as_deref() else {
        notes.push("the image has no FrameOfReferenceUID: assumed the structure set's".into());
        return Ok(());
    };
    for r in rois.iter().filter(|r| r.contours > 0) {
        match r.frame_of_reference.as_deref() {
            Some(f) if f != theirs => {
                return Err(IoError::Geometry {
                    path: path.into(),
                    what: format!(
                        "ROI {} '{}' is in frame of reference {}, the image in {}: its contours are in another patient coordinate system",
                        r.number,
                        r.name,
                        one_line(f),
                        one_line(theirs)
                    ),
                })
            }
            Some(_) => {}
            None => notes.push(format!(
                "ROI {} '{}' names no frame of reference: assumed the image's",
                r.number, r.name
            )),
        }
    }
    Ok(())
}

/// The voxels of one ROI: `(slice, row, first column, last column)` runs.
type Runs = Vec<(usize, usize, usize, usize)>;

/// The one-line refusal of a contour that is not on one slice of the image.
fn off_slice(path: &Path, roi: &Roi, c: &Contour, e: OffSlice, g: &Grid) -> IoError {
    let step = g.spacing[2];
    let what = match e {
        OffSlice::Spread { lo, hi } => format!(
            "ROI {} '{}' contour {} is not in one slice plane of the image: its points lie from slice {lo:.2} to {hi:.2} (each must be within half the slice spacing, {:.3} mm, of one slice)",
            roi.number, roi.name, c.index, step / 2.0
        ),
        OffSlice::Outside { at } => format!(
            "ROI {} '{}' contour {} lies at slice {at:.2}, more than half the slice spacing ({:.3} mm) outside the image's slices 0..{}: it was not drawn on this image",
            roi.number,
            roi.name,
            c.index,
            step / 2.0,
            g.dims[2] - 1
        ),
    };
    IoError::Geometry {
        path: path.into(),
        what,
    }
}

/// Rasterises the closed contours of every ROI onto the image's grid.
fn rasterise(path: &Path, parsed: Parsed, options: &ReadOptions) -> Result<StructureSet, IoError> {
    let mut notes = Vec::new();
    let (place, headers) = image(path, &parsed, options, &mut notes)?;
    check_frames(path, &parsed.rois, &headers[0], &mut notes)?;
    let top = parsed.rois.iter().map(|r| r.number).max().unwrap_or(1);
    let bytes = match top {
        0..=255 => 1,
        256..=65535 => 2,
        _ => 4,
    };
    let mut image_notes = Vec::new();
    let g = grid(&place, &headers, bytes, options, &mut image_notes)?;
    notes.extend(image_notes.into_iter().map(|n| format!("image: {n}")));
    let linear = linear_part(&g.affine);
    let inv = inverse3(&linear).ok_or_else(|| IoError::Geometry {
        path: place.clone(),
        what: "the image's affine is singular".into(),
    })?;
    let t = [g.affine[0][3], g.affine[1][3], g.affine[2][3]];
    // Contour points are LPS mm; the affine maps voxels to RAS (x and y negated).
    let to_index = |p: [f64; 3]| mul3(&inv, [-p[0] - t[0], -p[1] - t[1], p[2] - t[2]]);
    let rois = parsed.rois;
    let mut slices: Vec<BTreeMap<usize, Vec<Vec<[f64; 2]>>>> = vec![BTreeMap::new(); rois.len()];
    for c in &parsed.contours {
        let ijk: Vec<[f64; 3]> = c.points.iter().map(|&p| to_index(p)).collect();
        let ks: Vec<f64> = ijk.iter().map(|p| p[2]).collect();
        let k = raster::slice_of(&ks, g.dims[2])
            .map_err(|e| off_slice(path, &rois[c.roi], c, e, &g))?;
        slices[c.roi]
            .entry(k)
            .or_default()
            .push(ijk.iter().map(|p| [p[0], p[1]]).collect());
    }
    let mut runs: Vec<Runs> = Vec::with_capacity(rois.len());
    for per in &slices {
        let mut own = Runs::new();
        for (&k, polygons) in per {
            own.extend(
                raster::fill(polygons, g.dims[0], g.dims[1])
                    .into_iter()
                    .map(|(j, a, b)| (k, j, a, b)),
            );
        }
        runs.push(own);
    }
    drop(slices);
    let voxels: Vec<u64> = runs
        .iter()
        .map(|r| r.iter().map(|&(_, _, a, b)| (b - a + 1) as u64).sum())
        .collect();
    let (labels, overlaps) = paint(&rois, &runs, &voxels, g.dims);
    drop(runs);
    let contours: usize = rois.iter().map(|r| r.contours).sum();
    notes.push(format!(
        "RT structure set: {} ROI(s), {contours} closed contour(s) rasterised onto {} ({}x{}x{}): voxel centres inside by the even-odd rule, each contour on the slice within half the slice spacing; labels are ROINumbers",
        rois.len(),
        place.display(),
        g.dims[0],
        g.dims[1],
        g.dims[2]
    ));
    let skipped: usize = rois.iter().map(|r| r.skipped).sum();
    if skipped > 0 {
        notes.push(format!(
            "skipped {skipped} POINT/OPEN_PLANAR/OPEN_NONPLANAR contour(s): points and lines enclose no volume"
        ));
    }
    for (r, v) in rois.iter().zip(&voxels) {
        if r.contours == 0 {
            notes.push(format!(
                "ROI {} '{}' has no closed contour: 0 ml",
                r.number, r.name
            ));
        } else if *v == 0 {
            notes.push(format!(
                "ROI {} '{}': its contours enclose no voxel centre: 0 ml",
                r.number, r.name
            ));
        }
    }
    if overlaps > 0 {
        notes.push(format!(
            "{overlaps} voxel(s) in more than one ROI: the smallest ROI keeps them (each ROI's volume counts them)"
        ));
    }
    let samples = match bytes {
        1 => Samples::U8(labels.into_iter().map(|v| v as u8).collect()),
        2 => Samples::U16(labels.into_iter().map(|v| v as u16).collect()),
        _ => Samples::U32(labels),
    };
    Ok(StructureSet {
        rois,
        voxels,
        labels: VolumeFile {
            volume: Volume {
                dims: g.dims,
                spacing: g.spacing,
                affine: g.affine,
                samples,
                slope: 1.0,
                intercept: 0.0,
                units: None,
                colour: None,
            },
            format: Format::Dicom,
            notes,
            inflate: None,
        },
        image: place,
    })
}

/// The label map: every ROI's runs painted, the largest ROI first, so that the
/// smaller keeps a voxel they share; and the number of voxels in more than one ROI.
fn paint(rois: &[Roi], runs: &[Runs], voxels: &[u64], dims: [usize; 3]) -> (Vec<u32>, u64) {
    let mut labels = vec![0u32; dims[0] * dims[1] * dims[2]];
    let mut shared: Option<Vec<bool>> = None;
    let mut overlaps = 0u64;
    let mut order: Vec<usize> = (0..rois.len()).collect();
    order.sort_by_key(|&r| (std::cmp::Reverse(voxels[r]), rois[r].number));
    for r in order {
        for &(k, j, a, b) in &runs[r] {
            let row = (k * dims[1] + j) * dims[0];
            for i in row + a..=row + b {
                if labels[i] != 0 {
                    let seen = shared.get_or_insert_with(|| vec![false; labels.len()]);
                    if !seen[i] {
                        seen[i] = true;
                        overlaps += 1;
                    }
                }
                labels[i] = rois[r].number;
            }
        }
    }
    (labels, overlaps)
}
