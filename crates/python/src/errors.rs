//! Rust errors to Python exceptions, with the `glint` command's one-line messages.

use std::error::Error;
use std::io::ErrorKind;

use pyo3::exceptions::{
    PyFileExistsError, PyFileNotFoundError, PyIsADirectoryError, PyNotADirectoryError, PyOSError,
    PyPermissionError, PyValueError,
};
use pyo3::prelude::*;

pub use glint_io::one_line;
use glint_render::{RenderError, TurntableError};

/// A `ValueError` with the error's one-line message.
pub fn value_error(err: &dyn Error) -> PyErr {
    PyValueError::new_err(one_line(err))
}

/// A reading error as Python sees it: operating-system failures are `OSError` (the
/// subclass for the cause, e.g. `FileNotFoundError`, with the OS error as
/// `__cause__`); everything else about the file's contents is a `ValueError`.
pub fn io_error(py: Python<'_>, err: glint_io::IoError) -> PyErr {
    let message = one_line(&err);
    match err {
        glint_io::IoError::Os { source, .. } => os_error(py, message, source),
        _ => PyValueError::new_err(message),
    }
}

/// An `OSError` (the subclass for the cause) with `message`, the OS error as its
/// `__cause__`.
pub fn os_error(py: Python<'_>, message: String, source: std::io::Error) -> PyErr {
    let exc = match source.kind() {
        ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        ErrorKind::AlreadyExists => PyFileExistsError::new_err(message),
        ErrorKind::IsADirectory => PyIsADirectoryError::new_err(message),
        ErrorKind::NotADirectory => PyNotADirectoryError::new_err(message),
        _ => PyOSError::new_err(message),
    };
    exc.set_cause(py, Some(PyErr::from(source)));
    exc
}

/// A render error as Python sees it: reading and writing failures as `glint.read`
/// raises them, other OS failures `OSError`, everything else `ValueError`.
pub fn render_error(py: Python<'_>, err: RenderError) -> PyErr {
    match err {
        RenderError::Read(e) | RenderError::Write(e) => io_error(py, e),
        RenderError::Io(e) => {
            let exc = PyOSError::new_err(one_line(&e));
            exc.set_cause(py, Some(PyErr::from(e)));
            exc
        }
        // A scene file the system refused (missing, unreadable): the OSError for it.
        RenderError::SceneFile { path, source } => match *source {
            RenderError::Io(e) => {
                let message = one_line(&RenderError::SceneFile {
                    path,
                    source: Box::new(RenderError::Io(std::io::Error::new(
                        e.kind(),
                        e.to_string(),
                    ))),
                });
                os_error(py, message, e)
            }
            source => value_error(&RenderError::SceneFile {
                path,
                source: Box::new(source),
            }),
        },
        other => value_error(&other),
    }
}

/// A turntable error as Python sees it: a frame's render error as [`render_error`]
/// raises it, a file the system refused (or ffmpeg missing) `OSError`, a bad count,
/// rate or path `ValueError`.
pub fn turntable_error(py: Python<'_>, err: TurntableError) -> PyErr {
    let message = one_line(&err);
    match err {
        TurntableError::Render(e) => render_error(py, e),
        TurntableError::Io { source, .. } => os_error(py, message, source),
        TurntableError::NoFfmpeg { .. } => PyFileNotFoundError::new_err(message),
        TurntableError::Ffmpeg { .. } => PyOSError::new_err(message),
        _ => PyValueError::new_err(message),
    }
}
