//! The study functions of `glint.batch` (glint_batch's discovery, per-input job and
//! report writer): the Dask driver in `python/glint/batch.py` sends items and scenes
//! to its workers, which call [`batch_job`], and closes with [`batch_finish`], so its
//! table and report are `glint batch`'s.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use glint_batch::{BatchError, Discover, Item, Row, Spec};
use glint_render::View;

use crate::errors::{self, io_error, render_error};
use crate::json;
use crate::scene::Scene;

/// A batch error as Python sees it: file system failures `OSError`, the rest
/// `ValueError`, with the one line `glint batch` prints.
fn batch_error(py: Python<'_>, err: BatchError) -> PyErr {
    match err {
        BatchError::Io(e) => io_error(py, e),
        BatchError::Render(e) => render_error(py, e),
        other => errors::value_error(&other),
    }
}

/// A value from a Python object through JSON (dicts of a row or an item).
fn from_py<T: serde::de::DeserializeOwned>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<T> {
    let value = json::to_json(obj)?;
    serde_json::from_value(value)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("not a {what}: {e}")))
}

/// The spec of a job: the scene (default `glint.Scene()`), views by name.
fn spec_of(
    py: Python<'_>,
    scene: Option<&Bound<'_, Scene>>,
    views: &[String],
    slices: bool,
    strict: bool,
) -> PyResult<Spec> {
    let scene = scene.map(|s| s.get().inner.clone()).unwrap_or_default();
    let views = views
        .iter()
        .map(|v| v.parse::<View>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| render_error(py, e))?;
    let mut spec = Spec::new(scene, views, slices);
    spec.strict = strict;
    spec.check().map_err(|e| batch_error(py, e))?;
    Ok(spec)
}

/// The inputs of a study, as `glint batch` finds them (files, directories, glob
/// patterns, BIDS datasets): a list of dicts with `id`, `path`, `subject` and
/// `session`. `exclude` is a directory not to walk into (the output directory).
#[pyfunction]
#[pyo3(signature = (inputs, bids_suffix=None, exclude=None))]
pub fn batch_inputs<'py>(
    py: Python<'py>,
    inputs: Vec<PathBuf>,
    bids_suffix: Option<Vec<String>>,
    exclude: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let options = Discover {
        bids_suffixes: bids_suffix.unwrap_or_default(),
        exclude,
    };
    let items = crate::pool::detach(py, || glint_batch::discover(&inputs, &options))?
        .map_err(|e| batch_error(py, e))?;
    let value = serde_json::to_value(&items)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    json::to_py(py, &value)
}

/// One input's job, as `glint batch` runs it: the views of `scene` rendered by one
/// renderer into `out/<id>/` (mosaic, slices when asked, resolved scene, row), each
/// file atomically; skipped when its row says it is up to date (unless `force`).
/// Returns `(row, skipped)`; a bad input gives a failed row, not an exception. The GIL
/// is released throughout, and the work runs on glint's fork-safe threads.
#[pyfunction]
#[pyo3(signature = (item, scene, views, out, slices=false, force=false, strict=false))]
#[allow(clippy::too_many_arguments)]
pub fn batch_job<'py>(
    py: Python<'py>,
    item: &Bound<'py, PyAny>,
    scene: Option<&Bound<'py, Scene>>,
    views: Vec<String>,
    out: PathBuf,
    slices: bool,
    force: bool,
    strict: bool,
) -> PyResult<(Bound<'py, PyAny>, bool)> {
    let item: Item = from_py(item, "batch item (a dict of id, path, subject, session)")?;
    let spec = spec_of(py, scene, &views, slices, strict)?;
    let outcome = crate::pool::detach(py, || glint_batch::run_job(&item, &spec, &out, force))?;
    Ok((row_to_py(py, &outcome.row)?, outcome.skipped))
}

/// The failed row of an input whose job could not run at all (its worker died too
/// often): `error` as its line, the spec key of the job it was.
#[pyfunction]
#[pyo3(signature = (item, scene, views, error, slices=false, strict=false))]
pub fn batch_failed_row<'py>(
    py: Python<'py>,
    item: &Bound<'py, PyAny>,
    scene: Option<&Bound<'py, Scene>>,
    views: Vec<String>,
    error: String,
    slices: bool,
    strict: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let item: Item = from_py(item, "batch item (a dict of id, path, subject, session)")?;
    let spec = spec_of(py, scene, &views, slices, strict)?;
    let key = spec.key().map_err(|e| batch_error(py, e))?;
    let line = error.replace('\n', " ");
    row_to_py(py, &Row::failed(&item, &key, &views, None, line))
}

/// The key of a spec (`glint_batch::Spec::key`: what a rerun compares besides the
/// input's bytes), after checking the scene and the views.
#[pyfunction]
#[pyo3(signature = (scene, views, slices=false, strict=false))]
pub fn batch_spec_key(
    py: Python<'_>,
    scene: Option<&Bound<'_, Scene>>,
    views: Vec<String>,
    slices: bool,
    strict: bool,
) -> PyResult<String> {
    let spec = spec_of(py, scene, &views, slices, strict)?;
    spec.key().map_err(|e| batch_error(py, e))
}

/// Writes `out/results.jsonl` (the rows sorted by id) and `out/index.html`, as
/// `glint batch` does; returns `{"ok": n, "failed": m}`.
#[pyfunction]
pub fn batch_finish<'py>(
    py: Python<'py>,
    out: PathBuf,
    rows: Vec<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let rows = rows
        .iter()
        .map(|r| from_py::<Row>(r, "glint batch row"))
        .collect::<PyResult<Vec<_>>>()?;
    let summary = crate::pool::detach(py, || glint_batch::finish(&out, &rows))?
        .map_err(|e| batch_error(py, e))?;
    let d = PyDict::new(py);
    d.set_item("ok", summary.ok)?;
    d.set_item("failed", summary.failed)?;
    Ok(d)
}

/// A row as a dict of plain values (the JSON of its line in `results.jsonl`).
fn row_to_py<'py>(py: Python<'py>, row: &Row) -> PyResult<Bound<'py, PyAny>> {
    let value = serde_json::to_value(row)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    json::to_py(py, &value)
}
