//! Directories as exports come: the image series in a folder, and the objects beside
//! them that are not read (RT structure sets and plans, structured reports, DICOMDIR,
//! files that are not DICOM), listed with the reason.
//!
//! A radiotherapy or PACS export puts a CT series beside an RT structure set, a plan, a
//! dose grid or a second series; glint reads one image series (the only one, the one
//! [`ReadOptions::series`] names, or the one with the most slices) and says in a note
//! what it skipped and why. A file of the series read that cannot be read is still an
//! error (a missing slice would otherwise go unnoticed).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::header::{open_header, Header, Refused};
use super::{invalid, one_line};
use crate::{IoError, ReadOptions};

/// Most skipped objects named one by one in a note; the rest are counted.
const NOTE_MAX_NAMED: usize = 8;

/// The series key of files without a SeriesInstanceUID.
const NO_UID: &str = "(no SeriesInstanceUID)";

/// One image series of a DICOM file or directory ([`list`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// SeriesInstanceUID (`(no SeriesInstanceUID)` when the files have none).
    pub uid: String,
    /// Modality (CT, MR, RTDOSE, US, ...).
    pub modality: Option<String>,
    /// SeriesDescription.
    pub description: Option<String>,
    /// Files of the series.
    pub files: usize,
    /// Frames in all its files: the slices of the volume it makes.
    pub slices: usize,
    /// Columns and rows of its images (of the first file; a series that mixes sizes is
    /// refused when read).
    pub columns: usize,
    /// See [`Series::columns`].
    pub rows: usize,
    /// Its PhotometricInterpretation (MONOCHROME2, RGB, YBR_FULL_422, ...).
    pub photometric: String,
}

/// A file of a DICOM directory that is not read as part of an image series.
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    /// The file.
    pub path: PathBuf,
    /// Why it is not read (one line).
    pub reason: String,
    /// Its SOP class name (e.g. "RT Structure Set Storage"), when it parsed.
    pub class: Option<String>,
    /// Its Modality, when it parsed.
    pub modality: Option<String>,
    /// Its SeriesInstanceUID, when it parsed.
    pub series: Option<String>,
}

/// What a DICOM file or directory holds ([`list`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Listing {
    /// The image series, most slices first.
    pub series: Vec<Series>,
    /// Every file not read as an image, in path order.
    pub skipped: Vec<Skipped>,
}

/// The headers of the files that open as images, and the others.
struct Scan {
    headers: Vec<Header>,
    refused: Vec<(PathBuf, Box<Refused>)>,
    not_dicom: Vec<PathBuf>,
}

/// The files of a directory worth opening: regular (or symbolic links to regular
/// files), not hidden, not DICOMDIR. A link whose target is missing is one too: opening
/// it fails with [`crate::broken_link`]'s error, which reading the directory reports
/// (a slice whose content was never fetched must not go unnoticed).
fn entries(path: &Path) -> Result<Vec<PathBuf>, IoError> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| crate::link::os_error(path, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            (p.is_file() || crate::broken_link(p).is_some())
                && p.file_name().is_some_and(|n| {
                    let n = n.to_string_lossy();
                    !n.starts_with('.') && !n.eq_ignore_ascii_case("DICOMDIR")
                })
        })
        .collect();
    entries.sort();
    Ok(entries)
}

fn scan(path: &Path, options: &ReadOptions) -> Result<Scan, IoError> {
    let mut s = Scan {
        headers: Vec::new(),
        refused: Vec::new(),
        not_dicom: Vec::new(),
    };
    for p in entries(path)? {
        match open_header(&p, options.max_voxels, options.strict) {
            Ok(h) => s.headers.push(h),
            // Not DICOM at all (a README, a thumbnail).
            Err(r) if matches!(r.error, IoError::BadMagic { .. }) => s.not_dicom.push(p),
            Err(r) => s.refused.push((p, r)),
        }
    }
    Ok(s)
}

/// The image series of the headers, most slices first (then by UID).
fn group(headers: &[Header]) -> Vec<(Series, Vec<usize>)> {
    let mut by_uid: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (i, h) in headers.iter().enumerate() {
        let uid = h.series.clone().unwrap_or_else(|| NO_UID.into());
        by_uid.entry(uid).or_default().push(i);
    }
    let mut out: Vec<(Series, Vec<usize>)> = by_uid
        .into_iter()
        .map(|(uid, members)| {
            let first = &headers[members[0]];
            let series = Series {
                uid,
                modality: first.modality.clone(),
                description: first.description.clone(),
                files: members.len(),
                slices: members.iter().map(|&i| headers[i].frames).sum(),
                columns: first.cols,
                rows: first.rows,
                photometric: first.photometric.clone(),
            };
            (series, members)
        })
        .collect();
    out.sort_by(|a, b| b.0.slices.cmp(&a.0.slices).then(a.0.uid.cmp(&b.0.uid)));
    out
}

fn skipped_of(path: PathBuf, r: Refused) -> Skipped {
    let reason = match &r.error {
        IoError::Unsupported { what, .. } | IoError::Invalid { what, .. } => what.clone(),
        e => e.to_string(),
    };
    Skipped {
        path,
        reason: one_line(&reason),
        class: r.class,
        modality: r.modality,
        series: r.series,
    }
}

/// Lists the image series of a DICOM directory (or the one file) and every file not
/// read as an image, with the reason. Reads headers only, not pixel data.
pub fn list(path: &Path, options: &ReadOptions) -> Result<Listing, IoError> {
    if !path.is_dir() {
        return Ok(
            match open_header(path, options.max_voxels, options.strict) {
                Ok(h) => Listing {
                    series: group(std::slice::from_ref(&h))
                        .into_iter()
                        .map(|g| g.0)
                        .collect(),
                    skipped: Vec::new(),
                },
                Err(r) => Listing {
                    series: Vec::new(),
                    skipped: vec![skipped_of(path.into(), *r)],
                },
            },
        );
    }
    let s = scan(path, options)?;
    let mut skipped: Vec<Skipped> = s
        .refused
        .into_iter()
        .map(|(p, r)| skipped_of(p, *r))
        .chain(s.not_dicom.into_iter().map(|p| Skipped {
            path: p,
            reason: "not a DICOM file".into(),
            class: None,
            modality: None,
            series: None,
        }))
        .collect();
    skipped.sort_by(|a, b| a.path.cmp(&b.path));
    Ok(Listing {
        series: group(&s.headers).into_iter().map(|g| g.0).collect(),
        skipped,
    })
}

/// A series for a note: UID, modality, description, slices.
fn describe(s: &Series) -> String {
    let mut d = format!(
        "{} ({}",
        one_line(&s.uid),
        s.modality.as_deref().map_or("no modality".into(), one_line)
    );
    if let Some(desc) = &s.description {
        d += &format!(", '{}'", one_line(desc));
    }
    d + &format!(", {} slice(s))", s.slices)
}

/// The file name of a skipped object and why, for a note.
fn describe_skipped(path: &Path, r: &Refused) -> String {
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let why = match &r.error {
        _ if r.not_image => {
            format!(
                "not an image: {}",
                r.class.as_deref().unwrap_or("no SOPClassUID")
            )
        }
        IoError::Unsupported { what, .. } | IoError::Invalid { what, .. } => what.clone(),
        e => e.to_string(),
    };
    one_line(&format!("{name} ({why})"))
}

/// The headers of the series to read from a directory: the one `options.series` names,
/// the only one, or the one with the most slices. Notes name every series and object
/// skipped. A file that fails to open in the chosen series (or whose series could not be
/// read) is an error.
pub(super) fn select(
    path: &Path,
    options: &ReadOptions,
    notes: &mut Vec<String>,
) -> Result<Vec<Header>, IoError> {
    let s = scan(path, options)?;
    let groups = group(&s.headers);
    let chosen = match &options.series {
        Some(uid) => groups.iter().position(|g| &g.0.uid == uid).ok_or_else(|| {
            invalid(
                path,
                format!(
                    "no series {} here; the image series are: {}",
                    one_line(uid),
                    groups
                        .iter()
                        .map(|g| describe(&g.0))
                        .collect::<Vec<_>>()
                        .join("; ")
                ),
            )
        })?,
        None if groups.is_empty() => {
            // Nothing to read: the first refusal that is about an image says why;
            // otherwise there were only non-images.
            if let Some((_, r)) = s.refused.into_iter().find(|(_, r)| !r.not_image) {
                return Err(r.error);
            }
            return Err(invalid(path, "the directory holds no DICOM image"));
        }
        None => 0,
    };
    let uid = groups[chosen].0.uid.clone();
    let mut skipped = Vec::new();
    for (p, r) in s.refused {
        let ours = r.series.as_deref().unwrap_or(NO_UID) == uid;
        if (ours || r.series.is_none()) && !r.not_image {
            return Err(r.error);
        }
        skipped.push(describe_skipped(&p, &r));
    }
    if groups.len() > 1 {
        let others: Vec<String> = groups
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != chosen)
            .map(|(_, g)| describe(&g.0))
            .collect();
        notes.push(format!(
            "{} image series here: read {}{}; skipped {} (choose with --series UID)",
            groups.len(),
            describe(&groups[chosen].0),
            if options.series.is_some() {
                ""
            } else {
                ", the largest"
            },
            others.join("; ")
        ));
    }
    if !skipped.is_empty() {
        let n = skipped.len();
        let mut named: Vec<String> = skipped.into_iter().take(NOTE_MAX_NAMED).collect();
        if n > NOTE_MAX_NAMED {
            named.push(format!("and {} more", n - NOTE_MAX_NAMED));
        }
        notes.push(format!("skipped {n} object(s): {}", named.join("; ")));
    }
    if !s.not_dicom.is_empty() {
        notes.push(format!("skipped {} non-DICOM file(s)", s.not_dicom.len()));
    }
    let members = &groups[chosen].1;
    let mut headers: Vec<Option<Header>> = s.headers.into_iter().map(Some).collect();
    let chosen: Vec<Header> = members.iter().filter_map(|&i| headers[i].take()).collect();
    if let Some(n) = chosen[0].notes.first() {
        notes.push(format!("{n} (first file)"));
    }
    Ok(chosen)
}

/// The headers of the files of a directory that open as images (the others are left
/// out), or of the one file: where an RT structure set looks for the series it was
/// drawn on.
pub(super) fn images(path: &Path, options: &ReadOptions) -> Result<Vec<Header>, IoError> {
    if !path.is_dir() {
        return open_header(path, options.max_voxels, options.strict)
            .map(|h| vec![h])
            .map_err(|r| r.error);
    }
    Ok(scan(path, options)?.headers)
}
