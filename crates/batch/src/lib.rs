//! glint-batch: a whole study rendered for quality control and figures. The inputs
//! (files, directories, glob patterns, a BIDS dataset) are [discovered](discover) into
//! [`Item`]s; a [`Spec`] says what every input gets (a scene, the views of its mosaic,
//! three orthogonal slices or not); [`run_job`] makes one input's outputs with one warm
//! [`Renderer`](glint_render::Renderer) and returns its [`Row`]; [`run_local`] runs the
//! jobs in parallel on this machine; [`finish`] writes `results.jsonl` and the static
//! `index.html` report. `glint batch` runs these on a thread pool; the Python package
//! (`glint.batch`) runs the same job on a Dask cluster and the same [`finish`], so both
//! write the same table and report.
//!
//! ```
//! use glint_batch::{discover, finish, run_local, Discover, LocalOptions, Spec};
//! use glint_io::{nifti, Endian};
//! use glint_render::{Phantom, Scene, View};
//!
//! // A study of two volumes and a broken file.
//! let study = tempfile::tempdir().unwrap();
//! for name in ["a", "b"] {
//!     let vol = Phantom::SheppLogan.volume(24).unwrap();
//!     nifti::write(&study.path().join(format!("{name}.nii")), &vol, false, Endian::Little).unwrap();
//! }
//! std::fs::write(study.path().join("broken.nii"), b"not a volume").unwrap();
//!
//! let out = tempfile::tempdir().unwrap();
//! let items = discover(&[study.path().into()], &Discover::default()).unwrap();
//! assert_eq!(items.len(), 3);
//! let scene = Scene { size: [32, 32], ..Scene::default() };
//! let spec = Spec::new(scene, vec![View::Left, View::Superior], true);
//! let outcomes = run_local(&items, &spec, out.path(), &LocalOptions::default(), &|_| {}).unwrap();
//! let rows: Vec<_> = outcomes.into_iter().map(|o| o.row).collect();
//! let summary = finish(out.path(), &rows).unwrap();
//! assert_eq!((summary.ok, summary.failed), (2, 1));
//! assert!(out.path().join("a/mosaic.png").is_file());
//! assert!(out.path().join("index.html").is_file());
//!
//! // A second run finds every good input done and renders nothing.
//! let again = run_local(&items, &spec, out.path(), &LocalOptions::default(), &|_| {}).unwrap();
//! assert_eq!(again.iter().filter(|o| o.skipped).count(), 2);
//! ```
//!
//! The output directory holds, per input, a folder named by its [`Item::id`] with
//! `mosaic.png` (the views side by side), `slices.png` (with [`Spec::slices`]: sagittal,
//! coronal and axial cuts through the volume's centre, one intensity window),
//! `scene.json` (the first view's resolved scene: `glint render --scene` renders that
//! tile again) and `row.json` (its [`Row`], written last); then `results.jsonl` (the
//! rows, sorted by id) and `index.html`. Every file is written atomically, so an
//! interrupted run leaves no half-written file, and a rerun skips the inputs whose
//! row says they were rendered from the same bytes ([`Row::checksum`]) with the same
//! spec ([`Spec::key`]).

#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod bids;
mod checksum;
mod discover;
mod job;
mod local;
mod picture;
mod report;
mod row;
mod spec;

use std::path::PathBuf;

use glint_render::RenderError;

pub use checksum::checksum;
pub use discover::{discover, Discover, Item, BIDS_ANAT_SUFFIXES, VOLUME_SUFFIXES};
pub use job::{run_job, Outcome, ROW_FILE};
pub use local::{finish, run_local, LocalOptions, Summary, REPORT_FILE, RESULTS_FILE};
pub use picture::{mosaic, mosaic_exr, slices, Window, MOSAIC_EXR_FILE};
pub use report::report_html;
pub use row::{Outputs, Row, Seconds, Status, VolumeInfo};
pub use spec::{Spec, FORMAT_VERSION};

/// Why a study could not be planned, an input could not be made, or the results not
/// written. An input's error ends in its row ([`Row::error`], the error's
/// [one line](glint_io::one_line)); the others stop the run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BatchError {
    /// Nothing to do: the inputs named no file.
    #[error("no inputs: {0}")]
    NoInputs(String),
    /// A glob pattern is malformed.
    #[error("bad pattern '{pattern}'")]
    Pattern {
        /// The pattern.
        pattern: String,
        /// What is wrong with it.
        source: glob::PatternError,
    },
    /// A glob pattern matched no file.
    #[error("no file matches '{0}'")]
    NoMatch(String),
    /// A file or directory could not be read or written (the error names it).
    #[error(transparent)]
    Io(#[from] glint_io::IoError),
    /// Reading or rendering the input failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The spec cannot be rendered (no views, an unknown view, a scene without a file).
    #[error("{0}")]
    Spec(String),
    /// A row (a `row.json` file, or one handed over by a caller) is not a row.
    #[error("{}: not a glint batch row", path.display())]
    Row {
        /// The file, or the input the row is about.
        path: PathBuf,
        /// What the JSON parser said.
        source: serde_json::Error,
    },
    /// An input's job panicked (a bug: the row says so, the other inputs go on).
    #[error("internal error: {0}")]
    Panic(String),
}

/// A file system error as an [`IoError::Os`](glint_io::IoError::Os) naming `path`, or,
/// when `path` is a symbolic link to nothing, the error that says so
/// ([`glint_io::broken_link`]: a DataLad file whose content was never fetched).
pub(crate) fn os_error(path: impl Into<PathBuf>, source: std::io::Error) -> BatchError {
    let path = path.into();
    if source.kind() == std::io::ErrorKind::NotFound {
        if let Some(e) = glint_io::broken_link(&path) {
            return BatchError::Io(e);
        }
    }
    BatchError::Io(glint_io::IoError::Os { path, source })
}
