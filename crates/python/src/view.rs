//! `glint._glint.ViewSession`: glint-view's [`Session`] (the viewer's progressive
//! logic: reduced frames while dragging, a full frame once the input settles, `path`
//! frames refined while the scene holds still) for `glint.Viewer`, the notebook
//! viewer (python/glint/notebook.py), which only carries events and frames.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use numpy::{PyArray1, PyArrayMethods as _};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use glint_render::{
    Depth, Input, LightingModel, ReadOptions, RenderError, Renderer as RRenderer, SceneLobe,
};
use glint_view::protocol::Purpose;
use glint_view::Session;

use crate::errors::{self, render_error};
use crate::scene::Scene;

/// One live view of a volume: the scene, the renderer and the frames owed.
#[pyclass(module = "glint", frozen)]
pub struct ViewSession {
    inner: Mutex<Session>,
    /// Set by `close` (from any thread, without the lock a render
    /// holds): the renderer's cancel flag, so a `path` frame in flight stops.
    closed: Arc<AtomicBool>,
}

impl ViewSession {
    fn lock(&self) -> std::sync::MutexGuard<'_, Session> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }
}

fn purpose_name(p: Purpose) -> &'static str {
    match p {
        Purpose::Interactive => "interactive",
        Purpose::Full => "full",
        Purpose::Save => "save",
    }
}

#[pymethods]
impl ViewSession {
    /// A session of `volume` (a `glint.Volume` or a path; None: the scene's input)
    /// rendered with `scene`; `settle`: seconds of quiet after a drag before the
    /// full frame. The file, the scene's meshes and label map are read now.
    #[new]
    #[pyo3(signature = (volume, scene, settle))]
    fn new(
        py: Python<'_>,
        volume: Option<&Bound<'_, PyAny>>,
        scene: &Bound<'_, Scene>,
        settle: f64,
    ) -> PyResult<ViewSession> {
        let mut scene = scene.get().inner.clone();
        let settle = Duration::try_from_secs_f64(settle).map_err(|_| {
            errors::value_error(&glint_view::ViewError::Message(format!(
                "settle must be a number of seconds >= 0, got {settle}"
            )))
        })?;
        let memory = match volume {
            Some(v) => match v.cast::<crate::volume::Volume>() {
                Ok(v) => {
                    let v = v.get();
                    if let Some((p, _)) = &v.source {
                        scene.input = Input::Path(p.clone());
                    }
                    Some(std::sync::Arc::clone(&v.inner))
                }
                Err(_) => {
                    scene.input = Input::Path(v.extract::<std::path::PathBuf>().map_err(|_| {
                        pyo3::exceptions::PyTypeError::new_err("expected a glint.Volume or a path")
                    })?);
                    None
                }
            },
            None => None,
        };
        let closed = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&closed);
        let session = crate::pool::detach(py, move || {
            let mut renderer = match memory {
                Some(v) => {
                    let mut r = RRenderer::from_source(v, None)?;
                    // Meshes and the label map of the scene, as a file's renderer
                    // reads them.
                    r.resolve(&scene)?;
                    r
                }
                None => RRenderer::open(&scene, &ReadOptions::default())?,
            };
            renderer.set_cancel(Some(flag));
            Session::new(renderer, &scene, settle)
        })?
        .map_err(|e| render_error(py, e))?;
        Ok(ViewSession {
            inner: Mutex::new(session),
            closed,
        })
    }

    /// Ends the session: a `path` frame rendering now (on another thread) stops
    /// within a batch of rows and no frame is owed or rendered after it. Safe from
    /// any thread at any time (the kernel's shutdown, while its main thread renders);
    /// the scene still reads.
    fn close(&self) {
        self.closed.store(true, Ordering::SeqCst);
    }

    /// Whether `close` was called.
    #[getter]
    fn closed(&self) -> bool {
        self.closed.load(Ordering::SeqCst)
    }

    /// The live scene.
    #[getter]
    fn scene(&self) -> Scene {
        Scene {
            inner: self.lock().scene().clone(),
        }
    }

    /// Applies a patch (a dict of scene fields, as `Scene.replace` takes them):
    /// `interactive` for a drag (a reduced frame now, the full one when it settles).
    /// A refused patch raises ValueError and changes nothing.
    #[pyo3(signature = (patch, interactive=false))]
    fn update(&self, patch: &Bound<'_, PyDict>, interactive: bool) -> PyResult<()> {
        let mut map = serde_json::Map::new();
        for (k, v) in patch.iter() {
            let value = if v.is_none() {
                serde_json::Value::Null
            } else {
                crate::json::to_json(&v)?
            };
            map.insert(k.extract::<String>()?, value);
        }
        self.lock()
            .update(&map, interactive, Instant::now())
            .map_err(|e| errors::value_error(&e))
    }

    /// Seconds until a drag's full frame is due (None: no drag under way).
    fn settle_in(&self) -> Option<f64> {
        self.lock()
            .settle_at()
            .map(|at| at.saturating_duration_since(Instant::now()).as_secs_f64())
    }

    /// The frame owed now, if any, rendered (GIL released): a tuple of the sRGB
    /// uint8 array (height, width, 3), its purpose ("interactive", "full") and its
    /// path samples per pixel (0 unless `path`); None when nothing is owed, and
    /// once the session is closed (a frame cancelled by the close included).
    fn next_frame<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<(Bound<'py, PyAny>, &'static str, u32)>> {
        let frame = crate::pool::detach(py, || {
            let mut s = self.lock();
            if self.closed.load(Ordering::SeqCst) {
                return Ok(None);
            }
            let Some(purpose) = s.next(Instant::now()) else {
                return Ok(None);
            };
            let f = match s.render(purpose) {
                Err(RenderError::Cancelled) if self.closed.load(Ordering::SeqCst) => {
                    return Ok(None)
                }
                f => f?,
            };
            let rgb = f.image.encode_srgb(Depth::Eight);
            Ok(Some((
                rgb,
                f.image.width,
                f.image.height,
                purpose,
                f.samples,
            )))
        })?
        .map_err(|e| render_error(py, e))?;
        let Some((rgb, w, h, purpose, samples)) = frame else {
            return Ok(None);
        };
        let array = PyArray1::from_vec(py, rgb).reshape([h as usize, w as usize, 3])?;
        Ok(Some((array.into_any(), purpose_name(purpose), samples)))
    }

    /// Whether the live scene is progressive and still owes refinements, or a drag
    /// owes its full frame.
    fn pending(&self) -> bool {
        if self.closed.load(Ordering::SeqCst) {
            return false;
        }
        let s = self.lock();
        s.settle_at().is_some() || s.owes()
    }

    /// The labels of the scene's label map: a list of dicts (`value`, `name`,
    /// `color`, `voxels`) in value order, empty without one.
    fn labels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let list = self
            .lock()
            .labels()
            .map_or_else(Vec::new, |l| l.entries().to_vec());
        let json = serde_json::to_value(list).map_err(|e| errors::value_error(&e))?;
        crate::json::to_py(py, &json)
    }
}

/// The names the viewer's panel offers: a dict of `presets`, `lobes` and
/// `lighting` models.
#[pyfunction]
pub fn view_choices<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let presets: Vec<&str> = glint_render::PRESETS.iter().map(|p| p.name).collect();
    d.set_item("presets", presets)?;
    d.set_item("lobes", SceneLobe::ALL.map(|k| k.name()).to_vec())?;
    d.set_item("lighting", LightingModel::ALL.map(|m| m.name()).to_vec())?;
    Ok(d)
}

/// Reads a surface mesh (GIFTI, STL, OBJ, PLY; as `glint render --mesh` does): a
/// tuple of vertex positions (float32 (n, 3), world mm), triangles (uint32 (m, 3))
/// and per-vertex scalars (float32 (n,), or None). The napari plugin's surface reader.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn read_mesh<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
) -> PyResult<(
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Option<Bound<'py, PyAny>>,
)> {
    let mesh = crate::pool::detach(py, || glint_io::read_mesh(&path))?
        .map_err(|e| errors::io_error(py, e))?;
    let n = mesh.positions.len();
    let m = mesh.triangles.len();
    let positions: Vec<f32> = mesh.positions.into_iter().flatten().collect();
    let triangles: Vec<u32> = mesh.triangles.into_iter().flatten().collect();
    let positions = PyArray1::from_vec(py, positions)
        .reshape([n, 3])?
        .into_any();
    let triangles = PyArray1::from_vec(py, triangles)
        .reshape([m, 3])?
        .into_any();
    let scalars = mesh.scalars.map(|s| PyArray1::from_vec(py, s).into_any());
    Ok((positions, triangles, scalars))
}

/// The labels of a label map (NIfTI, MGZ, DICOM SEG, ...), as `glint view`'s legend
/// lists them: dicts of `value`, `name`, `color` (`#rrggbb`), `voxels` and `shown`,
/// in value order. The napari plugin's label names and colours.
#[pyfunction]
pub fn label_table<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let spec = glint_render::LabelSpec::new(path);
    let list = crate::pool::detach(py, || glint_view::LabelList::read(&spec, None))?
        .map_err(|e| render_error(py, e))?;
    let json = serde_json::to_value(list.entries()).map_err(|e| errors::value_error(&e))?;
    crate::json::to_py(py, &json)
}
