//! The `glint` Python package's native module, `glint._glint`: conversions between
//! numpy arrays and the glint crates, and GIL handling. No imaging logic lives here;
//! every function forwards to `glint-io`, `glint-lobe`, `glint-hw`, `glint-render`,
//! `glint-compare`, `glint-batch` or `glint-view` (the notebook viewer's session).
//!
//! Rules every function follows:
//! - inputs are copied into Rust-owned buffers while the GIL is held, then the GIL is
//!   released ([`Python::detach`]) for the work, so another Python thread mutating the
//!   array cannot race it;
//! - errors become Python exceptions whose message is the one line the `glint` command
//!   prints (the error and its sources joined with `: `); file system errors are
//!   `OSError` (or its subclass for the cause, e.g. `FileNotFoundError`), bad values
//!   `ValueError`, wrong types `TypeError`.

#![warn(missing_docs)]

mod arrays;
mod batch;
mod errors;
mod hw;
mod json;
mod lobe;
mod pool;
mod render;
mod scene;
mod view;
mod volume;

use pyo3::prelude::*;

/// The native module. `python/glint/__init__.py` re-exports its contents as `glint`.
#[pymodule]
fn _glint(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<volume::Volume>()?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<render::Renderer>()?;
    m.add_class::<render::Image>()?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(render::compare, m)?)?;
    m.add_function(wrap_pyfunction!(render::turntable, m)?)?;
    m.add_class::<view::ViewSession>()?;
    m.add_function(wrap_pyfunction!(view::view_choices, m)?)?;
    m.add_function(wrap_pyfunction!(view::read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(view::label_table, m)?)?;
    m.add_function(wrap_pyfunction!(volume::read, m)?)?;
    m.add_function(wrap_pyfunction!(lobe::lobe, m)?)?;
    m.add_function(wrap_pyfunction!(lobe::lobe_kinds, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_inputs, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_job, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_failed_row, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_spec_key, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_finish, m)?)?;
    let hw = PyModule::new(m.py(), "hw")?;
    hw.add_class::<hw::Unit>()?;
    m.add_submodule(&hw)?;
    Ok(())
}
