//! Slice geometry: in-plane axes from ImageOrientationPatient, slice positions (given,
//! stacked from one position, or assumed), sorting, even steps, and the RAS affine.

use std::path::Path;

use super::header::Header;
use crate::common::check_affine;
use crate::IoError;

/// Relative tolerance on slice steps: steps differing from the median by more than this
/// fraction are a gap (or an overlap) rather than rounding in the positions.
const STEP_TOLERANCE: f64 = 0.05;

/// Tolerance on the length of, and the angle between, the direction cosines of
/// ImageOrientationPatient.
const UNIT_TOLERANCE: f64 = 1e-3;

/// Slice step assumed when a stack of frames states none (what pydicom-based tools and
/// dcm2niix fall back to as well).
const DEFAULT_STEP_MM: f64 = 1.0;

/// One 2D image of the volume: which file and frame it comes from, and where it is.
pub(super) struct Frame {
    pub file: usize,
    pub frame: usize,
    pub position: [f64; 3],
    pub rescale: (f64, f64),
}

/// The in-plane axes of a series.
pub(super) struct Plane {
    pub row_dir: [f64; 3],
    pub col_dir: [f64; 3],
    pub normal: [f64; 3],
    /// PixelSpacing: (between rows, between columns) in mm.
    pub pixel_spacing: [f64; 2],
}

pub(super) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The in-plane axes of the first header (the series shares them).
pub(super) fn plane(
    path: &Path,
    first: &Header,
    strict: bool,
    notes: &mut Vec<String>,
) -> Result<Plane, IoError> {
    let orientation = first.orientation.unwrap_or_else(|| {
        notes.push("geometry assumed: no ImageOrientationPatient, axial".into());
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
    let pixel_spacing = match first.pixel_spacing {
        // Secondary captures and some CR/DX write 0\0 for "unknown" (pydicom reads it
        // as given); taken as missing, like no PixelSpacing at all.
        Some([0.0, 0.0]) if strict => {
            return Err(IoError::Geometry {
                path: path.into(),
                what: "PixelSpacing is 0\\0 (--strict)".into(),
            })
        }
        Some([0.0, 0.0]) => {
            notes.push("geometry assumed: PixelSpacing 0\\0, 1 mm pixels".into());
            [1.0, 1.0]
        }
        Some(s) => s,
        None => {
            notes.push("geometry assumed: no PixelSpacing, 1 mm pixels".into());
            [1.0, 1.0]
        }
    };
    if pixel_spacing.iter().any(|s| !s.is_finite() || *s <= 0.0) {
        return Err(IoError::Geometry {
            path: path.into(),
            what: format!("PixelSpacing {pixel_spacing:?} is not usable"),
        });
    }
    Ok(Plane {
        row_dir,
        col_dir,
        normal,
        pixel_spacing,
    })
}

/// The position of frame `k` of `h` (see [`frames`]).
fn position(
    h: &Header,
    k: usize,
    single: bool,
    normal: [f64; 3],
    strict: bool,
    notes: &mut Vec<String>,
) -> Result<[f64; 3], IoError> {
    let refuse = |what: &str| IoError::Geometry {
        path: h.path.clone(),
        what: what.into(),
    };
    let positive = |s: Option<f64>| s.filter(|s| s.is_finite() && *s > 0.0);
    let stack =
        |origin: [f64; 3], s: f64| std::array::from_fn(|a| origin[a] + k as f64 * s * normal[a]);
    Ok(match (h.positions[k], h.positions[0]) {
        (Some(p), _) => p,
        (None, Some(p0)) if h.frame_offsets.is_some() => {
            // RT Dose: offsets along the normal, relative to the position when the first
            // is 0 (the only form glint reads; PS3.3 C.8.8.3.2).
            let off = h.frame_offsets.as_deref().unwrap_or_default();
            if off[0] != 0.0 {
                return Err(refuse(
                    "GridFrameOffsetVector does not start at 0 (absolute offsets)",
                ));
            }
            std::array::from_fn(|a| p0[a] + off[k] * normal[a])
        }
        (None, Some(p0)) if h.frames > 1 => {
            // Classic multi-frame: frames stacked along the normal from the one given
            // position, by SpacingBetweenSlices (or SliceThickness).
            let s = match positive(h.slice_step) {
                Some(s) => s,
                None if strict => {
                    return Err(refuse(
                        "multi-frame without per-frame positions or slice spacing",
                    ))
                }
                None => {
                    if k == 1 {
                        notes.push(format!(
                            "geometry assumed: no slice spacing, frames {DEFAULT_STEP_MM} mm apart"
                        ));
                    }
                    DEFAULT_STEP_MM
                }
            };
            if k == 1 {
                notes.push(format!("frame positions from a slice spacing of {s} mm"));
            }
            stack(p0, s)
        }
        (None, None) if single && h.frames > 1 && h.positions.iter().all(Option::is_none) => {
            if strict {
                return Err(refuse(
                    "multi-frame without ImagePositionPatient: cannot place the frames (--strict)",
                ));
            }
            let (s, from) = match positive(h.spacing_between_slices) {
                Some(s) => (s, "SpacingBetweenSlices"),
                None => (DEFAULT_STEP_MM, "no SpacingBetweenSlices"),
            };
            if k == 0 {
                notes.push(format!(
                    "geometry assumed: no ImagePositionPatient, {} frames in file order {s} mm \
                     apart ({from}) from the origin",
                    h.frames
                ));
            }
            stack([0.0; 3], s)
        }
        _ if single && h.frames == 1 => [0.0; 3],
        _ => return Err(refuse("no ImagePositionPatient: cannot order the slices")),
    })
}

/// Every frame of every file with its position, in file and frame order.
pub(super) fn frames(
    headers: &[Header],
    normal: [f64; 3],
    strict: bool,
    notes: &mut Vec<String>,
) -> Result<Vec<Frame>, IoError> {
    let single = headers.len() == 1;
    let mut frames = Vec::new();
    for (fi, h) in headers.iter().enumerate() {
        for k in 0..h.frames {
            let position = position(h, k, single, normal, strict, notes)?;
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
    Ok(frames)
}

/// Sorts the frames along the normal and returns the step between them (a vector):
/// duplicate positions and uneven steps are errors; a single slice takes its thickness.
pub(super) fn sort_and_step(
    path: &Path,
    frames: &mut [Frame],
    first: &Header,
    normal: [f64; 3],
    notes: &mut Vec<String>,
) -> Result<[f64; 3], IoError> {
    let along = |p: &[f64; 3]| dot(*p, normal);
    frames.sort_by(|a, b| along(&a.position).total_cmp(&along(&b.position)));
    let n = frames.len();
    if n == 1 {
        let s = first
            .slice_step
            .filter(|s| s.is_finite() && *s > 0.0)
            .unwrap_or_else(|| {
                notes.push("a single slice without thickness: 1 mm assumed".into());
                DEFAULT_STEP_MM
            });
        return Ok(normal.map(|x| x * s));
    }
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
    Ok(std::array::from_fn(|k| (b[k] - a[k]) / (n - 1) as f64))
}

/// The voxel-to-RAS affine: built in DICOM's LPS space, then x and y negated (PS3.3
/// C.7.6.2.1.1); returns it with its spacing.
pub(super) fn affine(
    path: &Path,
    plane: &Plane,
    slice_vec: [f64; 3],
    origin: [f64; 3],
) -> Result<([[f64; 4]; 4], [f64; 3]), IoError> {
    let mut affine = [[0.0; 4]; 4];
    for r in 0..3 {
        let flip = if r < 2 { -1.0 } else { 1.0 };
        affine[r][0] = flip * plane.row_dir[r] * plane.pixel_spacing[1];
        affine[r][1] = flip * plane.col_dir[r] * plane.pixel_spacing[0];
        affine[r][2] = flip * slice_vec[r];
        affine[r][3] = flip * origin[r];
    }
    affine[3][3] = 1.0;
    let spacing = check_affine(path, &affine)?;
    Ok((affine, spacing))
}
