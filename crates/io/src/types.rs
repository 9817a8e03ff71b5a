//! The data model every reader produces.

// `each_samples!` expands one body for every sample type; its `as f64` is a no-op only
// in the f64 arm.
#![allow(clippy::unnecessary_cast)]

use std::path::PathBuf;

/// Why a file could not be read. Every variant names the file and the problem.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The operating system refused (missing file, permissions, ...).
    // The OS error is the source, not part of the message: `{:#}` (anyhow) prints the
    // chain, which would otherwise repeat it.
    #[error("{path}: I/O error")]
    Os {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The format or a feature of it is not supported.
    #[error("{path}: unsupported: {what}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What is not supported.
        what: String,
    },
    /// The bytes are not a valid file of the format.
    #[error("{path}: {what}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        what: String,
    },
    /// The file ends before the header or the data it announces.
    #[error("{path}: truncated: {what}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// What was missing.
        what: String,
    },
    /// The file does not start with the format's signature.
    #[error("{path}: not a {format} file: {what}")]
    BadMagic {
        /// The file.
        path: PathBuf,
        /// The format that was expected.
        format: &'static str,
        /// What was found instead.
        what: String,
    },
    /// The header announces a different amount of data than the file holds.
    #[error("{path}: size mismatch: {what}")]
    SizeMismatch {
        /// The file.
        path: PathBuf,
        /// The sizes that disagree.
        what: String,
    },
    /// The dimensions overflow or exceed the caller's voxel limit; checked before any
    /// allocation for the samples.
    #[error("{path}: too large: {what}")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The dimensions and the limit.
        what: String,
    },
    /// The voxel-to-world geometry is unusable (NaN or zero spacing, singular affine,
    /// inconsistent slice positions).
    #[error("{path}: bad geometry: {what}")]
    Geometry {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        what: String,
    },
    /// A DICOM directory mixes series, image sizes or pixel formats.
    #[error("{path}: mixed series: {what}")]
    MixedSeries {
        /// The directory.
        path: PathBuf,
        /// The series found.
        what: String,
    },
    /// A mesh face refers to a vertex that does not exist.
    #[error("{path}: bad mesh index: {what}")]
    BadIndex {
        /// The file.
        path: PathBuf,
        /// The face and the vertex count.
        what: String,
    },
    /// The file is a symbolic link into a git-annex object store (a DataLad dataset)
    /// whose content was never fetched ([`crate::broken_link`]).
    #[error("{path}: content not present (git-annex): run `datalad get {path}`")]
    AnnexMissing {
        /// The link.
        path: PathBuf,
    },
    /// The file is a symbolic link whose target does not exist
    /// ([`crate::broken_link`]).
    #[error("{path}: broken symbolic link to {target}")]
    BrokenLink {
        /// The link.
        path: PathBuf,
        /// Where it points (as the link says, relative or absolute).
        target: PathBuf,
    },
    /// An in-memory volume or mesh is inconsistent (not tied to a file).
    #[error("{0}")]
    Inconsistent(String),
}

impl IoError {
    /// The file the error is about, if it is about one.
    pub fn path(&self) -> Option<&std::path::Path> {
        match self {
            IoError::Os { path, .. }
            | IoError::Unsupported { path, .. }
            | IoError::Invalid { path, .. }
            | IoError::Truncated { path, .. }
            | IoError::BadMagic { path, .. }
            | IoError::SizeMismatch { path, .. }
            | IoError::TooLarge { path, .. }
            | IoError::Geometry { path, .. }
            | IoError::MixedSeries { path, .. }
            | IoError::BadIndex { path, .. }
            | IoError::AnnexMissing { path }
            | IoError::BrokenLink { path, .. } => Some(path),
            IoError::Inconsistent(_) => None,
        }
    }
}

/// Voxel samples in the type the file stores them.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    /// Unsigned 8-bit.
    U8(Vec<u8>),
    /// Signed 8-bit.
    I8(Vec<i8>),
    /// Unsigned 16-bit.
    U16(Vec<u16>),
    /// Signed 16-bit.
    I16(Vec<i16>),
    /// Unsigned 32-bit.
    U32(Vec<u32>),
    /// Signed 32-bit.
    I32(Vec<i32>),
    /// 32-bit float.
    F32(Vec<f32>),
    /// 64-bit float.
    F64(Vec<f64>),
}

macro_rules! each_samples {
    ($s:expr, $v:ident => $body:expr) => {
        match $s {
            Samples::U8($v) => $body,
            Samples::I8($v) => $body,
            Samples::U16($v) => $body,
            Samples::I16($v) => $body,
            Samples::U32($v) => $body,
            Samples::I32($v) => $body,
            Samples::F32($v) => $body,
            Samples::F64($v) => $body,
        }
    };
}

impl Samples {
    /// Number of samples.
    pub fn len(&self) -> usize {
        each_samples!(self, v => v.len())
    }

    /// Samples the buffer holds without growing.
    pub fn capacity(&self) -> usize {
        each_samples!(self, v => v.capacity())
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The stored sample `i` as f64 (unscaled).
    pub fn get(&self, i: usize) -> f64 {
        each_samples!(self, v => v[i] as f64)
    }

    /// The largest magnitude the type holds (`None` for floats, which hold any).
    pub(crate) fn type_bound(&self) -> Option<f64> {
        Some(match self {
            Samples::U8(_) => 255.0,
            Samples::I8(_) => 128.0,
            Samples::U16(_) => 65535.0,
            Samples::I16(_) => 32768.0,
            Samples::U32(_) => 4_294_967_295.0,
            Samples::I32(_) => 2_147_483_648.0,
            Samples::F32(_) | Samples::F64(_) => return None,
        })
    }

    /// The smallest and largest finite stored sample (unscaled); `None` when none is
    /// finite.
    pub(crate) fn finite_range(&self) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        each_samples!(self, v => for &x in v.iter() {
            let x = x as f64;
            if x.is_finite() {
                lo = lo.min(x);
                hi = hi.max(x);
            }
        });
        (lo <= hi).then_some((lo, hi))
    }

    /// The type's name as NIfTI/NRRD users know it (`uint8`, `int16`, `float32`, ...).
    pub fn type_name(&self) -> &'static str {
        match self {
            Samples::U8(_) => "uint8",
            Samples::I8(_) => "int8",
            Samples::U16(_) => "uint16",
            Samples::I16(_) => "int16",
            Samples::U32(_) => "uint32",
            Samples::I32(_) => "int32",
            Samples::F32(_) => "float32",
            Samples::F64(_) => "float64",
        }
    }
}

/// A 3D scalar volume on a regular grid.
///
/// Sample `(i, j, k)` is at `samples[i + dims[0] * (j + dims[1] * k)]` (x fastest, as
/// NIfTI, NRRD and DICOM store them). Its physical value is
/// `slope * stored + intercept` (NIfTI scl_slope/scl_inter, DICOM rescale).
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    /// Samples along i, j, k.
    pub dims: [usize; 3],
    /// Voxel size in mm along i, j, k (the column norms of the affine's 3x3 part).
    pub spacing: [f64; 3],
    /// Voxel index (i, j, k, 1) to world RAS+ mm, row-major.
    pub affine: [[f64; 4]; 4],
    /// The stored samples.
    pub samples: Samples,
    /// Scale applied to stored samples.
    pub slope: f64,
    /// Offset applied after the scale.
    pub intercept: f64,
    /// Units of the physical values where known (e.g. "HU").
    pub units: Option<String>,
    /// The colour of each voxel, for a colour volume (DICOM RGB and YBR images:
    /// ultrasound, cryosection photographs, secondary captures); `None` for the usual
    /// scalar volume. [`samples`](Self::samples) then holds the grey the caller chose
    /// with [`ReadOptions::grey`](crate::ReadOptions::grey) (the luminance by default),
    /// so every scalar use (transfer functions, isosurfaces, statistics) works on a
    /// colour volume unchanged, and a colour classification takes the colour from here
    /// and the opacity from a transfer function of `samples`.
    pub colour: Option<Rgb>,
}

/// The colour channels of a colour [`Volume`]: red, green and blue as three planar
/// arrays in the layout of [`Volume::samples`] (sample `(i, j, k)` of each at
/// `i + dims[0] * (j + dims[1] * k)`), all of one type: the stored type (`U8`, `U16`
/// or `U32` for DICOM's 8, 16 and 32 bits allocated), unscaled (colour images have no
/// rescale). The full scale of the type is full intensity: 255 for `U8`, 65535 for
/// `U16`; DICOM colour data uses the whole range (PS3.3 C.7.6.3.1.2).
///
/// Whatever the file stored (RGB interleaved or planar, YBR_FULL, YBR_FULL_422, JPEG's
/// YCbCr, JPEG 2000's YBR_ICT/YBR_RCT), the channels are RGB, converted as pydicom
/// converts them (see `docs/formats.md`, "Colour").
#[derive(Clone, Debug, PartialEq)]
pub struct Rgb {
    /// The red channel.
    pub red: Samples,
    /// The green channel.
    pub green: Samples,
    /// The blue channel.
    pub blue: Samples,
}

impl Rgb {
    /// The channels in the order red, green, blue.
    pub fn channels(&self) -> [&Samples; 3] {
        [&self.red, &self.green, &self.blue]
    }

    /// The colour of sample `i` as (r, g, b) in 0..1 of the type's full scale.
    ///
    /// # Panics
    /// If `i` is out of range.
    pub fn rgb(&self, i: usize) -> [f32; 3] {
        let scale = |s: &Samples| match s {
            Samples::U8(_) => 1.0 / 255.0,
            Samples::U16(_) => 1.0 / 65535.0,
            Samples::U32(_) => 1.0 / 4294967295.0,
            _ => 1.0,
        };
        self.channels().map(|s| (s.get(i) * scale(s)) as f32)
    }
}

impl Volume {
    /// A volume with a diagonal affine of `spacing`, origin at voxel 0, no scaling.
    pub fn new(dims: [usize; 3], spacing: [f64; 3], samples: Samples) -> Result<Self, IoError> {
        let count = dims
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .ok_or_else(|| IoError::Inconsistent(format!("dims {dims:?} overflow")))?;
        if count == 0 || count != samples.len() {
            return Err(IoError::Inconsistent(format!(
                "dims {dims:?} need {count} samples, got {}",
                samples.len()
            )));
        }
        if spacing.iter().any(|s| !s.is_finite() || *s <= 0.0) {
            return Err(IoError::Inconsistent(format!(
                "invalid spacing {spacing:?}"
            )));
        }
        let mut affine = [[0.0; 4]; 4];
        for a in 0..3 {
            affine[a][a] = spacing[a];
        }
        affine[3][3] = 1.0;
        Ok(Volume {
            dims,
            spacing,
            affine,
            samples,
            slope: 1.0,
            intercept: 0.0,
            units: None,
            colour: None,
        })
    }

    /// Whether the volume holds colour ([`Volume::colour`]).
    pub fn is_colour(&self) -> bool {
        self.colour.is_some()
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether the volume has no voxels (never true for a constructed volume).
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The physical value of voxel `(i, j, k)`.
    ///
    /// # Panics
    /// If the index is out of range.
    pub fn value(&self, i: usize, j: usize, k: usize) -> f64 {
        let idx = i + self.dims[0] * (j + self.dims[1] * k);
        self.slope * self.samples.get(idx) + self.intercept
    }

    /// All physical values as f32, in storage order.
    pub fn to_f32(&self) -> Vec<f32> {
        let (s, b) = (self.slope, self.intercept);
        each_samples!(&self.samples, v => v.iter().map(|&x| (s * x as f64 + b) as f32).collect())
    }

    /// The minimum and maximum physical value (NaN samples ignored).
    pub fn range(&self) -> (f64, f64) {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        each_samples!(&self.samples, v => for &x in v.iter() {
            let x = x as f64;
            if x < lo { lo = x; }
            if x > hi { hi = x; }
        });
        let (a, b) = (
            self.slope * lo + self.intercept,
            self.slope * hi + self.intercept,
        );
        (a.min(b), a.max(b))
    }
}

/// A triangle surface mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in world mm.
    pub positions: Vec<[f32; 3]>,
    /// Triangles as indices into `positions`, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex normals, when the file has them.
    pub normals: Option<Vec<[f32; 3]>>,
    /// One scalar per vertex, when the file has them.
    pub scalars: Option<Vec<f32>>,
}

impl Mesh {
    /// Axis-aligned bounds `(min, max)`, `None` for a mesh without vertices.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(mut lo, mut hi), p| {
                    for a in 0..3 {
                        lo[a] = lo[a].min(p[a]);
                        hi[a] = hi[a].max(p[a]);
                    }
                    (lo, hi)
                }),
        )
    }

    /// Describes the first non-finite vertex position or normal, if any.
    pub(crate) fn non_finite(&self) -> Option<String> {
        let bad = |v: &[[f32; 3]]| v.iter().position(|p| p.iter().any(|x| !x.is_finite()));
        if let Some(k) = bad(&self.positions) {
            return Some(format!(
                "vertex {k} has a non-finite position {:?}",
                self.positions[k]
            ));
        }
        let normals = self.normals.as_deref().unwrap_or_default();
        bad(normals).map(|k| format!("vertex {k} has a non-finite normal {:?}", normals[k]))
    }

    /// Checks that every position and normal is finite and every triangle index is in
    /// range.
    pub fn validate(&self) -> Result<(), IoError> {
        if let Some(what) = self.non_finite() {
            return Err(IoError::Inconsistent(what));
        }
        let n = self.positions.len();
        if let Some(t) = self
            .triangles
            .iter()
            .find(|t| t.iter().any(|&i| i as usize >= n))
        {
            return Err(IoError::Inconsistent(format!(
                "triangle {t:?} indexes past the {n} vertices"
            )));
        }
        Ok(())
    }
}
