//! The one error type of the renderer crates (glint-core, glint-volume, glint-raster and
//! the glint-render facade).

use std::path::PathBuf;

/// The source of an error from a crate this one does not depend on (the hardware
/// unit's, glint-hw, whose lobe the glint-render facade builds).
pub type BoxedError = Box<dyn std::error::Error + Send + Sync>;

/// Why a render could not be set up or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The volume cannot be rendered (too small, too large, singular affine, ...).
    #[error("volume cannot be rendered: {0}")]
    Volume(String),
    /// The render was stopped before it finished, on the caller's request (a viewer
    /// whose user moved while a progressive frame was refining).
    #[error("render cancelled")]
    Cancelled,
    /// A render parameter is out of range (size, step, zoom, light, ...).
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// A picked image point lies off the image (a pick, `Renderer::pick`, or any
    /// other query of one pixel): coordinates in pixels from the image's top-left
    /// corner.
    #[error("pick at ({x}, {y}) is off the {width}x{height} image: expected x in [0, {width}) and y in [0, {height}), pixels from the top-left corner")]
    OffImage {
        /// The point's x, pixels from the left edge.
        x: f64,
        /// The point's y, pixels from the top edge.
        y: f64,
        /// Image width in pixels.
        width: u32,
        /// Image height in pixels.
        height: u32,
    },
    /// A transfer function is malformed (unsorted points, values out of range, ...).
    #[error("invalid transfer function: {0}")]
    TransferFunction(String),
    /// An environment map could not be read or used (a missing, truncated or
    /// malformed `.hdr` or `.exr` file, an absurd size, NaN or negative texels, an
    /// unknown built-in name).
    #[error("environment map {map}: {what}")]
    EnvironmentMap {
        /// The file or built-in name.
        map: String,
        /// What went wrong.
        what: String,
    },
    /// A transfer-function JSON file could not be read or parsed.
    #[error("{path}: {what}")]
    TransferFunctionFile {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        what: String,
    },
    /// No preset has this name.
    #[error("unknown preset '{name}': expected one of {known}")]
    UnknownPreset {
        /// The name asked for.
        name: String,
        /// The known names, comma-separated.
        known: String,
    },
    /// The lobe parameters were rejected by glint-lobe.
    #[error(transparent)]
    Lobe(#[from] glint_lobe::LobeError),
    /// The hardware unit of a `hw` lobe (`lobe.hw`) is not a valid configuration.
    #[error("invalid hardware unit configuration (lobe.hw)")]
    HwConfig(#[source] BoxedError),
    /// The shininess does not fit the hardware unit's integer `n` input.
    #[error("shininess n = {n} cannot be given to the hardware unit")]
    HwN {
        /// The scene's shininess.
        n: f64,
        /// The unit's refusal (names the input's range).
        #[source]
        source: BoxedError,
    },
    /// A `hw` lobe's `lobe.v` differs from its unit's `v` (`lobe.hw.v`).
    #[error("lobe.v = {lobe} contradicts the hardware unit's v = {unit} (lobe.hw.v): a hw lobe squares as often as its unit does; give the same v or leave lobe.v out")]
    HwV {
        /// `lobe.v`.
        lobe: u32,
        /// The unit's `v`.
        unit: u32,
    },
    /// The unit's output could not be tabulated over its cosine codes.
    #[error("the hardware unit cannot be tabulated")]
    HwTable(#[source] BoxedError),
    /// A mesh cannot be rendered or meshed (non-finite coordinates, bad indices,
    /// scalars that do not match the vertices, no triangles).
    #[error("mesh cannot be rendered")]
    Mesh(#[source] glint_io::IoError),
    /// A label map or its colour table cannot be used (glint-labels' error is the
    /// source).
    #[error("label map {}", path.display())]
    Labels {
        /// The label volume.
        path: PathBuf,
        /// What was wrong.
        source: BoxedError,
    },
    /// Reading the input volume failed.
    #[error(transparent)]
    Read(#[from] glint_io::IoError),
    /// A scene is malformed (bad JSON, unknown field, unsupported version).
    #[error("{0}")]
    Scene(String),
    /// A scene file could not be used (the file; what was wrong is the source, which
    /// error chains print after it).
    #[error("{}", path.display())]
    SceneFile {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        source: Box<RenderError>,
    },
    /// The operating system refused (the caller names the file).
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// Encoding the image as PNG failed.
    #[error("cannot encode the PNG")]
    Encode(#[source] png::EncodingError),
    /// Encoding the image as OpenEXR failed.
    #[error("cannot encode the OpenEXR image: {0}")]
    EncodeExr(String),
    /// Writing the image failed (the io error names the file).
    #[error(transparent)]
    Write(glint_io::IoError),
}

/// The error for `name`, which is none of the named enum `T`'s names (its parser's
/// error): `invalid parameter: unknown view 'up': expected one of ...`.
pub fn unknown_name<T: glint_lobe::names::Named>(name: &str) -> RenderError {
    RenderError::Parameter(glint_lobe::names::unknown::<T>(name))
}
