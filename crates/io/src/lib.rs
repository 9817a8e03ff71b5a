//! Readers for biomedical volumes (NIfTI, NRRD, DICOM, raw) and surfaces (STL, OBJ,
//! PLY, GIFTI) into one [`Volume`] and one [`Mesh`] type.
//!
//! ```
//! use glint_io::{Samples, Volume};
//!
//! // A 2x2x2 volume of u8 samples with 1 mm voxels at the origin.
//! let vol = Volume::new([2, 2, 2], [1.0; 3], Samples::U8(vec![0, 1, 2, 3, 4, 5, 6, 7])).unwrap();
//! assert_eq!(vol.value(1, 1, 1), 7.0);
//! assert_eq!(vol.range(), (0.0, 7.0));
//! ```
//!
//! World coordinates are millimetres in RAS+ (x towards the patient's Right, y Anterior,
//! z Superior), NIfTI's convention; readers of LPS formats (DICOM) convert.

#![warn(missing_docs)]

mod types;

pub use types::{IoError, Mesh, Samples, Volume};

use std::path::Path;

/// Limits and hints for readers.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    /// Refuse volumes with more voxels than this before allocating for them.
    pub max_voxels: u64,
}

impl Default for ReadOptions {
    fn default() -> Self {
        // 2^31 voxels: a 1290^3 volume, 8 GiB as f32; far above clinical CT (512^2 x ~2000).
        ReadOptions {
            max_voxels: 1 << 31,
        }
    }
}

/// Reads a volume, choosing the format from the path (extension, or a directory of
/// DICOM slices).
pub fn read_volume(path: &Path, options: &ReadOptions) -> Result<Volume, IoError> {
    let _ = options;
    Err(IoError::Unsupported {
        path: path.to_path_buf(),
        what: "volume formats are not implemented yet".into(),
    })
}

/// Reads a surface mesh, choosing the format from the extension.
pub fn read_mesh(path: &Path) -> Result<Mesh, IoError> {
    Err(IoError::Unsupported {
        path: path.to_path_buf(),
        what: "mesh formats are not implemented yet".into(),
    })
}
