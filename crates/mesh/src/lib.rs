//! glint-mesh: triangle meshes from volumes. Isosurfaces by marching cubes over the
//! passes of flying edges ([`extract`], [`extract_grid`]), area-weighted vertex
//! normals ([`vertex_normals`]) and Taubin smoothing ([`taubin_smooth`]). Reads and
//! writes nothing itself (glint-io does) and draws nothing (glint-raster does), so it
//! carries no image or font dependencies.
//!
//! ```
//! use glint_io::{Samples, Volume};
//!
//! // A ball of radius 5 voxels in a 16^3 grid: its isosurface at 0.5 is closed.
//! let n = 16;
//! let values: Vec<f32> = (0..n * n * n)
//!     .map(|i| {
//!         let p = [i % n, i / n % n, i / (n * n)].map(|x| x as f32 - 7.5);
//!         if p.iter().map(|x| x * x).sum::<f32>() < 25.0 { 1.0 } else { 0.0 }
//!     })
//!     .collect();
//! let volume = Volume::new([n; 3], [1.0; 3], Samples::F32(values)).unwrap();
//! let mut mesh = glint_mesh::extract(&volume, 0.5).unwrap();
//! assert!(mesh.triangles.len() > 100);
//! glint_mesh::taubin_smooth(&mut mesh, &glint_mesh::Taubin::default()).unwrap();
//! assert_eq!(mesh.normals.as_ref().map(Vec::len), Some(mesh.positions.len()));
//! ```

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod isosurface;
mod normals;

pub use isosurface::{extract, extract_grid, taubin_smooth, Taubin};
pub use normals::vertex_normals;

use glint_io::IoError;

/// Largest voxel count extracted from (2^28, the bound of glint-volume's field too):
/// the passes keep a few bytes per voxel and edge, and vertex indices are 32-bit.
pub const MAX_VOXELS: usize = 1 << 28;

/// Why a mesh could not be extracted or smoothed. The messages are those of the
/// renderer's errors for the same faults (glint-core's `RenderError`), which the
/// glint-render facade maps these to.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The volume cannot be meshed (too small, too large, singular affine, ...).
    #[error("volume cannot be rendered: {0}")]
    Volume(String),
    /// A parameter is out of range (iso value, smoothing factors).
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// The mesh is malformed (bad indices, non-finite coordinates).
    #[error("mesh cannot be rendered")]
    Mesh(#[source] IoError),
}
