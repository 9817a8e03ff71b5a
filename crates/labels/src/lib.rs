//! glint-labels: label maps (segmentations) as people have them. A label volume
//! (FreeSurfer's `aseg.mgz`, TotalSegmentator's multilabel NIfTI, any integer volume
//! glint-io reads) becomes a [`LabelGrid`]; a [`LabelTable`] names and colours its
//! values (FreeSurfer's `FreeSurferColorLUT.txt` and TotalSegmentator's class list are
//! built in; FreeSurfer LUT text, 3D Slicer `.ctbl`/`.txt`, JSON and CSV tables are
//! read; a DICOM Segmentation carries its own, [`LabelTable::embedded`]);
//! [`LabelGrid::summary`] counts voxels and millilitres per label; and
//! [`label_surfaces`] extracts one smoothed, closed surface per label in world mm.
//!
//! ```
//! use glint_io::{Samples, Volume};
//! use glint_labels::{label_surfaces, LabelGrid, LabelTable};
//!
//! // Two 4x4x4 blocks side by side, labels 17 and 53 (FreeSurfer's left and right
//! // hippocampus), in a 12x8x8 grid of 2 mm voxels.
//! let (nx, ny, nz) = (12, 8, 8);
//! let values: Vec<u8> = (0..nx * ny * nz)
//!     .map(|i| {
//!         let (x, y, z) = (i % nx, i / nx % ny, i / (nx * ny));
//!         let inside = (2..6).contains(&y) && (2..6).contains(&z);
//!         match x {
//!             2..=5 if inside => 17,
//!             6..=9 if inside => 53,
//!             _ => 0,
//!         }
//!     })
//!     .collect();
//! let volume = Volume::new([nx, ny, nz], [2.0; 3], Samples::U8(values)).unwrap();
//! let grid = LabelGrid::from_volume(&volume).unwrap();
//! let summary = grid.summary();
//! assert_eq!(summary[&17].voxels, 64);
//! assert_eq!(grid.voxel_ml(), 0.008); // 2 x 2 x 2 mm = 8 mm^3
//!
//! let table = LabelTable::freesurfer();
//! assert_eq!(table.name_of(17), "Left-Hippocampus");
//! assert_eq!(table.lookup("right-hippocampus").unwrap(), 53);
//!
//! let surfaces = label_surfaces(&grid, &[17, 53], 1.0).unwrap();
//! assert_eq!(surfaces.len(), 2);
//! assert!(surfaces.iter().all(|(_, mesh)| !mesh.triangles.is_empty()));
//! ```

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod builtin;
mod grid;
mod segmentation;
mod surface;
mod table;

pub use builtin::{FREESURFER_LUT, TOTALSEGMENTATOR_CLASSES};
pub use grid::{world_box, LabelExtent, LabelGrid};
pub use segmentation::cielab_to_srgb;
pub use surface::{
    default_label_smoothing, label_surfaces, label_surfaces_keeping_thin, MAX_SMOOTHING, MIN_KEPT,
};
pub use table::{
    generated_color, named_color, LabelEntry, LabelTable, BUILTIN_TABLES, MAX_TABLE_BYTES, OPAQUE,
};

use std::path::PathBuf;

/// Why a label map or a colour table could not be used. Every message is one line
/// that names the file or the value at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LabelError {
    /// The label volume could not be read.
    #[error(transparent)]
    Io(#[from] glint_io::IoError),
    /// A colour table file could not be read.
    #[error("{path}: I/O error")]
    Os {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A colour table's text is malformed.
    #[error("{path}: line {line}: {what}")]
    Table {
        /// The file (or `<built-in name>`).
        path: PathBuf,
        /// 1-based line number (0 for a JSON table's whole text).
        line: usize,
        /// What is wrong.
        what: String,
    },
    /// The volume does not hold labels (non-integer, negative or colour values).
    #[error("not a label volume: {0}")]
    NotLabels(String),
    /// A label named by the user is not in the table, or a number is malformed.
    #[error("unknown label {name:?}: {hint}")]
    UnknownLabel {
        /// What the user gave.
        name: String,
        /// What would be accepted (near names, or how to name a label).
        hint: String,
    },
    /// A parameter is out of range (smoothing).
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// A surface could not be extracted.
    #[error(transparent)]
    Mesh(#[from] glint_mesh::MeshError),
}
