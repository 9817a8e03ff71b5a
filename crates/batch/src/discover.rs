//! The inputs of a study: files, directories (walked for volumes and DICOM series),
//! glob patterns and BIDS datasets, as [`Item`]s with unique, file-system-safe ids.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::{os_error, BatchError};

/// Anatomical suffixes of the BIDS specification ("Magnetic Resonance Imaging:
/// anatomy imaging data", non-parametric structural images, BIDS 1.9), the files of
/// `sub-*/[ses-*/]anat/` a BIDS dataset contributes unless [`Discover::bids_suffixes`]
/// names others (e.g. the parametric `T1map`).
pub const BIDS_ANAT_SUFFIXES: [&str; 9] = [
    "T1w",
    "T2w",
    "PDw",
    "T2starw",
    "FLAIR",
    "inplaneT1",
    "inplaneT2",
    "PDT2",
    "angio",
];

/// File name endings a directory walk takes as volumes (lower case; `.hdr` is the
/// header of a NIfTI or ANALYZE pair, whose `.img` is its data). Directories holding
/// `.dcm` files are DICOM series.
pub const VOLUME_SUFFIXES: [&str; 5] = [".nii", ".nii.gz", ".nrrd", ".nhdr", ".hdr"];

/// How to find the inputs.
#[derive(Clone, Debug, Default)]
pub struct Discover {
    /// The BIDS suffixes to take from `anat/` folders (empty: [`BIDS_ANAT_SUFFIXES`]).
    pub bids_suffixes: Vec<String>,
    /// A directory never to walk into (the output directory, when it lies among the
    /// inputs).
    pub exclude: Option<PathBuf>,
}

/// One input of a study.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Item {
    /// Unique within the study, safe as a file name (letters, digits, `-`, `_`, `.`):
    /// the name of its output folder. A BIDS file's name without its extension
    /// (`sub-01_ses-1_T1w`); a walked file's path below the walked directory with `/`
    /// as `__`; a named file's stem.
    pub id: String,
    /// The file or DICOM directory, absolute.
    pub path: PathBuf,
    /// The BIDS subject label (`01` of `sub-01`), when the path has one.
    #[serde(default)]
    pub subject: Option<String>,
    /// The BIDS session label, when the path has one.
    #[serde(default)]
    pub session: Option<String>,
}

/// The inputs of a study, in the order given (a directory's and a pattern's files
/// sorted by path), each file once. An argument is:
/// - a glob pattern (it holds `*`, `?` or `[`): every path it matches, taken as if
///   named; one that matches nothing is an error;
/// - a BIDS dataset (a directory with `dataset_description.json`): every
///   `sub-*/[ses-*/]anat/*_<suffix>.nii[.gz]` of the suffixes asked for;
/// - another directory: walked for files ending in one of [`VOLUME_SUFFIXES`] and for
///   directories holding `.dcm` files (one DICOM series each), hidden entries skipped,
///   symbolic links followed (loops walked once);
/// - anything else, a file: an input as it is, even if it does not exist (its row then
///   fails, and the others go on).
///
/// A symbolic link whose target is missing is an input too, in a walk and in a BIDS
/// dataset: its row fails with what it is ("content not present (git-annex): run
/// `datalad get PATH`" for a DataLad file never fetched, else "broken symbolic link to
/// TARGET"). Two paths to the same file (links) are one input, the first found.
pub fn discover(inputs: &[PathBuf], options: &Discover) -> Result<Vec<Item>, BatchError> {
    let exclude = match &options.exclude {
        Some(p) => Some(absolute(p)?),
        None => None,
    };
    let suffixes: Vec<String> = if options.bids_suffixes.is_empty() {
        BIDS_ANAT_SUFFIXES.iter().map(|s| s.to_string()).collect()
    } else {
        options.bids_suffixes.clone()
    };
    let mut found = Vec::new();
    for input in inputs {
        let text = input.to_string_lossy();
        if text.contains(['*', '?', '[']) && !input.exists() {
            let paths = glob_paths(&text)?;
            for p in paths {
                found.extend(argument(&p, &suffixes, exclude.as_deref())?);
            }
        } else {
            found.extend(argument(input, &suffixes, exclude.as_deref())?);
        }
    }
    let mut seen = HashSet::new();
    found.retain(|item| {
        let same = std::fs::canonicalize(&item.path).unwrap_or_else(|_| item.path.clone());
        seen.insert(same)
    });
    if found.is_empty() {
        let names: Vec<String> = inputs.iter().map(|p| p.display().to_string()).collect();
        return Err(BatchError::NoInputs(if names.is_empty() {
            "give files, directories, patterns or a BIDS dataset".into()
        } else {
            format!("no volume in {}", names.join(", "))
        }));
    }
    Ok(unique_ids(found))
}

/// The paths a glob pattern matches, sorted.
fn glob_paths(pattern: &str) -> Result<Vec<PathBuf>, BatchError> {
    let paths = glob::glob(pattern).map_err(|source| BatchError::Pattern {
        pattern: pattern.into(),
        source,
    })?;
    let mut out = Vec::new();
    for p in paths {
        match p {
            Ok(p) => out.push(p),
            Err(e) => {
                let path = e.path().to_path_buf();
                return Err(os_error(path, e.into()));
            }
        }
    }
    if out.is_empty() {
        return Err(BatchError::NoMatch(pattern.into()));
    }
    out.sort();
    Ok(out)
}

/// The items of one argument (a path, not a pattern).
fn argument(
    path: &Path,
    suffixes: &[String],
    exclude: Option<&Path>,
) -> Result<Vec<Item>, BatchError> {
    let abs = absolute(path)?;
    if !abs.is_dir() {
        let (subject, session) = bids_labels(&abs);
        return Ok(vec![Item {
            id: stem(&abs),
            path: abs,
            subject,
            session,
        }]);
    }
    if abs.join("dataset_description.json").is_file() {
        return bids(&abs, suffixes, exclude);
    }
    walk(&abs, exclude)
}

/// Every `sub-*/[ses-*/]anat/*_<suffix>.nii[.gz]` of a BIDS dataset, sorted.
fn bids(root: &Path, suffixes: &[String], exclude: Option<&Path>) -> Result<Vec<Item>, BatchError> {
    let mut anat_dirs = Vec::new();
    for sub in sorted_dirs(root, "sub-")? {
        anat_dirs.push(sub.join("anat"));
        for ses in sorted_dirs(&sub, "ses-")? {
            anat_dirs.push(ses.join("anat"));
        }
    }
    let mut items = Vec::new();
    for anat in anat_dirs.iter().filter(|d| d.is_dir()) {
        if exclude.is_some_and(|e| anat.starts_with(e)) {
            continue;
        }
        for file in sorted_entries(anat)? {
            let name = file_name(&file);
            let Some(base) = strip_volume_suffix(&name, &[".nii", ".nii.gz"]) else {
                continue;
            };
            let suffix = base.rsplit('_').next().unwrap_or_default();
            // A link to nothing (a DataLad file never fetched) is an input whose row
            // says so, not a file to drop.
            let present = file.is_file() || glint_io::broken_link(&file).is_some();
            if !present || !suffixes.iter().any(|s| s == suffix) {
                continue;
            }
            let (subject, session) = bids_labels(&file);
            items.push(Item {
                id: safe(base),
                path: file,
                subject,
                session,
            });
        }
    }
    Ok(items)
}

/// Volume files and DICOM series directories below `root`, sorted by path; ids are
/// the paths below `root` with `/` as `__`. Symbolic links are followed (a DataLad
/// dataset's files are links into its annex; a study often links subjects in from
/// elsewhere); a link back to a directory being walked (a loop, which walkdir
/// detects) is not walked again; a link to nothing is taken as a file, so that its
/// row names it ([`glint_io::broken_link`]).
fn walk(root: &Path, exclude: Option<&Path>) -> Result<Vec<Item>, BatchError> {
    let mut items = Vec::new();
    let visible = |path: &Path, depth: usize| {
        let hidden = depth > 0 && file_name(path).starts_with('.');
        !hidden && exclude.is_none_or(|x| path != x)
    };
    let walker = walkdir::WalkDir::new(root)
        .follow_links(true)
        .sort_by_file_name()
        .into_iter()
        .filter_entry(|e| visible(e.path(), e.depth()));
    let mut dicom_dirs = HashSet::new();
    for entry in walker {
        let path = match entry {
            Ok(entry) if entry.file_type().is_file() => entry.into_path(),
            Ok(_) => continue,
            Err(e) if e.loop_ancestor().is_some() => continue,
            Err(e) => match e.path().filter(|p| glint_io::broken_link(p).is_some()) {
                Some(p) if visible(p, e.depth()) => p.to_path_buf(),
                Some(_) => continue,
                None => {
                    let path = e.path().unwrap_or(root).to_path_buf();
                    let io = e
                        .into_io_error()
                        .unwrap_or_else(|| std::io::Error::other("a file system loop"));
                    return Err(os_error(path, io));
                }
            },
        };
        let path = path.as_path();
        let name = file_name(path);
        let lower = name.to_ascii_lowercase();
        let (target, base) = if lower.ends_with(".dcm") {
            let dir = path.parent().unwrap_or(root).to_path_buf();
            if !dicom_dirs.insert(dir.clone()) {
                continue;
            }
            (dir.clone(), dir)
        } else if let Some(base) = strip_volume_suffix(&name, &VOLUME_SUFFIXES) {
            (path.to_path_buf(), path.with_file_name(base))
        } else {
            continue;
        };
        let rel = base.strip_prefix(root).unwrap_or(&base);
        let id = if rel.as_os_str().is_empty() {
            stem(&base)
        } else {
            let parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            safe(&parts.join("__"))
        };
        let (subject, session) = bids_labels(&target);
        items.push(Item {
            id,
            path: target,
            subject,
            session,
        });
    }
    items.sort_by(|a, b| a.path.cmp(&b.path));
    Ok(items)
}

/// The directories of `dir` whose names start with `prefix`, sorted.
fn sorted_dirs(dir: &Path, prefix: &str) -> Result<Vec<PathBuf>, BatchError> {
    Ok(sorted_entries(dir)?
        .into_iter()
        .filter(|p| p.is_dir() && file_name(p).starts_with(prefix))
        .collect())
}

/// The entries of a directory, sorted.
fn sorted_entries(dir: &Path) -> Result<Vec<PathBuf>, BatchError> {
    let read = std::fs::read_dir(dir).map_err(|e| os_error(dir, e))?;
    let mut paths = Vec::new();
    for entry in read {
        paths.push(entry.map_err(|e| os_error(dir, e))?.path());
    }
    paths.sort();
    Ok(paths)
}

/// The file name, lossily as text.
fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// `name` without the longest of `suffixes` it ends with (case-insensitive), or
/// `None` when it ends with none of them.
fn strip_volume_suffix<'a>(name: &'a str, suffixes: &[&str]) -> Option<&'a str> {
    let lower = name.to_ascii_lowercase();
    suffixes
        .iter()
        .filter(|s| lower.ends_with(*s) && name.len() > s.len())
        .max_by_key(|s| s.len())
        .map(|s| &name[..name.len() - s.len()])
}

/// A file's name without a volume extension, made safe.
fn stem(path: &Path) -> String {
    let name = file_name(path);
    let base = strip_volume_suffix(&name, &VOLUME_SUFFIXES).unwrap_or(&name);
    safe(base)
}

/// `sub-` and `ses-` labels of the path's components (BIDS entities).
fn bids_labels(path: &Path) -> (Option<String>, Option<String>) {
    let label = |prefix: &str| {
        path.components().rev().find_map(|c| {
            let part = c.as_os_str().to_string_lossy();
            let rest = part.strip_prefix(prefix)?;
            let label: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric())
                .collect();
            (!label.is_empty()).then_some(label)
        })
    };
    (label("sub-"), label("ses-"))
}

/// `s` with every character other than ASCII letters, digits, `-`, `_` and `.` as `_`
/// (and a leading `.` too), never empty.
fn safe(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if out.starts_with('.') {
        out.replace_range(..1, "_");
    }
    if out.is_empty() {
        out.push_str("input");
    }
    out
}

/// Ids made unique: the second and later items of one id get `-2`, `-3`, ...; ids
/// that would name the study's own files get a `_` in front.
fn unique_ids(mut items: Vec<Item>) -> Vec<Item> {
    let mut used: HashMap<String, usize> = HashMap::new();
    let taken: HashSet<String> = items.iter().map(|i| i.id.clone()).collect();
    for item in &mut items {
        if [crate::RESULTS_FILE, crate::REPORT_FILE].contains(&item.id.as_str()) {
            item.id.insert(0, '_');
        }
        let n = used.entry(item.id.clone()).or_insert(0);
        *n += 1;
        if *n > 1 {
            let mut k = *n;
            let mut candidate = format!("{}-{k}", item.id);
            while taken.contains(&candidate) {
                k += 1;
                candidate = format!("{}-{k}", item.id);
            }
            item.id = candidate;
        }
    }
    items
}

/// `path` made absolute against the current directory.
fn absolute(path: &Path) -> Result<PathBuf, BatchError> {
    std::path::absolute(path).map_err(|e| os_error(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(path: &Path) {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, b"x").unwrap();
    }

    fn ids(items: &[Item]) -> Vec<&str> {
        items.iter().map(|i| i.id.as_str()).collect()
    }

    #[test]
    fn a_bids_dataset_gives_its_anatomical_images() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        touch(&root.join("dataset_description.json"));
        touch(&root.join("sub-01/anat/sub-01_T1w.nii.gz"));
        touch(&root.join("sub-01/anat/sub-01_T1w.json"));
        touch(&root.join("sub-01/anat/sub-01_T2w.nii"));
        touch(&root.join("sub-01/func/sub-01_task-rest_bold.nii.gz"));
        touch(&root.join("sub-02/ses-pre/anat/sub-02_ses-pre_T1w.nii.gz"));
        touch(&root.join("sub-02/ses-pre/anat/sub-02_ses-pre_T1map.nii.gz"));
        touch(&root.join("derivatives/sub-01/anat/sub-01_T1w.nii.gz"));
        let items = discover(&[root.to_path_buf()], &Discover::default()).unwrap();
        assert_eq!(
            ids(&items),
            ["sub-01_T1w", "sub-01_T2w", "sub-02_ses-pre_T1w"]
        );
        assert_eq!(items[2].subject.as_deref(), Some("02"));
        assert_eq!(items[2].session.as_deref(), Some("pre"));
        assert_eq!(items[0].session, None);
        assert!(items.iter().all(|i| i.path.is_absolute()));
        // --bids-suffix picks others.
        let only = Discover {
            bids_suffixes: vec!["T1map".into()],
            ..Discover::default()
        };
        let items = discover(&[root.to_path_buf()], &only).unwrap();
        assert_eq!(ids(&items), ["sub-02_ses-pre_T1map"]);
    }

    #[test]
    fn a_directory_is_walked_for_volumes_and_dicom_series() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        touch(&root.join("a.nii.gz"));
        touch(&root.join("b.NRRD"));
        touch(&root.join("notes.txt"));
        touch(&root.join("pair.hdr"));
        touch(&root.join("pair.img"));
        touch(&root.join("site2/a.nii.gz"));
        touch(&root.join("series/1.dcm"));
        touch(&root.join("series/2.dcm"));
        touch(&root.join(".hidden/c.nii"));
        touch(&root.join("out/d.nii"));
        let options = Discover {
            exclude: Some(root.join("out")),
            ..Discover::default()
        };
        let items = discover(&[root.to_path_buf()], &options).unwrap();
        assert_eq!(ids(&items), ["a", "b", "pair", "series", "site2__a"]);
        assert_eq!(items[3].path, root.join("series"));
    }

    #[test]
    fn patterns_files_and_duplicates() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        touch(&root.join("x/scan.nii"));
        touch(&root.join("y/scan.nii"));
        touch(&root.join("y/other.nii"));
        let pattern = root.join("*/scan.nii");
        let missing = root.join("gone.nii.gz");
        let items = discover(
            &[pattern, root.join("x/scan.nii"), missing.clone()],
            &Discover::default(),
        )
        .unwrap();
        // The same file twice is one input; equal stems get -2.
        assert_eq!(ids(&items), ["scan", "scan-2", "gone"]);
        assert_eq!(items[2].path, missing);
        let err = discover(&[root.join("*.nrrd")], &Discover::default()).unwrap_err();
        assert!(matches!(err, BatchError::NoMatch(_)), "{err}");
        let err = discover(&[root.join("[")], &Discover::default()).unwrap_err();
        assert!(matches!(err, BatchError::Pattern { .. }), "{err}");
        let empty = root.join("empty");
        std::fs::create_dir(&empty).unwrap();
        let err = discover(&[empty], &Discover::default()).unwrap_err();
        assert!(matches!(err, BatchError::NoInputs(_)), "{err}");
    }

    #[test]
    fn ids_are_safe_file_names() {
        assert_eq!(safe("a b/c"), "a_b_c");
        assert_eq!(safe(".hidden"), "_hidden");
        assert_eq!(safe(""), "input");
        let items = unique_ids(vec![
            Item {
                id: "index.html".into(),
                path: "/a".into(),
                subject: None,
                session: None,
            },
            Item {
                id: "s".into(),
                path: "/b".into(),
                subject: None,
                session: None,
            },
            Item {
                id: "s".into(),
                path: "/c".into(),
                subject: None,
                session: None,
            },
            Item {
                id: "s-2".into(),
                path: "/d".into(),
                subject: None,
                session: None,
            },
        ]);
        assert_eq!(ids(&items), ["_index.html", "s", "s-3", "s-2"]);
    }
}
