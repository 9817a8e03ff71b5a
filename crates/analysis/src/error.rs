//! The one error type of the analysis.

use std::path::PathBuf;

/// Why an analysis could not be run or its files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// A shininess exponent is NaN, infinite, negative or too large.
    #[error("invalid n = {0}: expected a finite number in 0..={max}", max = glint_lobe::MAX_N)]
    InvalidN(f64),
    /// A `v` is too large.
    #[error("invalid v = {0}: expected 0..={max}", max = glint_lobe::MAX_V)]
    InvalidV(u32),
    /// A list of parameters is empty.
    #[error("the list of {0} is empty: give at least one value")]
    EmptyList(&'static str),
    /// A list of parameters is absurdly long.
    #[error("too many {what}: {count} given, at most {max} allowed")]
    TooMany {
        /// What the list holds.
        what: &'static str,
        /// How many were given.
        count: usize,
        /// The limit.
        max: usize,
    },
    /// The error tolerance is not a positive finite number.
    #[error("invalid tolerance {0}: expected a positive finite number")]
    InvalidTolerance(f64),
    /// The top of a colour scale is not a positive finite number.
    #[error("invalid colour scale maximum {0}: expected a positive finite number")]
    InvalidScale(f64),
    /// The output location cannot be used.
    #[error("cannot write to {path}: {reason}")]
    Output {
        /// The path that was refused.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// A file system operation failed.
    #[error("{what} {path}: {source}")]
    Io {
        /// What was being done ("writing", "renaming", ...).
        what: &'static str,
        /// The path involved.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Drawing a figure failed.
    #[error("drawing {file}: {message}")]
    Plot {
        /// The figure's file name.
        file: String,
        /// The plotting library's message.
        message: String,
    },
    /// An image's pixel buffer does not match its size, or the size is zero or absurd.
    #[error("invalid image: {width}x{height} with {pixels} pixels (expected width*height, both 1..={max})", max = crate::MAX_IMAGE_SIDE)]
    ImageSize {
        /// The stated width.
        width: u32,
        /// The stated height.
        height: u32,
        /// How many pixels the buffer holds.
        pixels: usize,
    },
    /// Two images (or an image and a mask) to compare differ in size.
    #[error("sizes differ: {a_width}x{a_height} against {b_width}x{b_height}")]
    SizeMismatch {
        /// Width of the first.
        a_width: u32,
        /// Height of the first.
        a_height: u32,
        /// Width of the second.
        b_width: u32,
        /// Height of the second.
        b_height: u32,
    },
    /// An image is smaller than the SSIM window.
    #[error("image {width}x{height} is smaller than the {window}x{window} SSIM window")]
    TooSmall {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// The window side.
        window: usize,
    },
    /// Building a lobe failed (should not happen after validation).
    #[error(transparent)]
    Lobe(#[from] glint_lobe::LobeError),
}
