//! `glint.Scene`: glint_render::Scene with keyword arguments for its fields and the
//! same JSON as `glint render --scene` / `--dump-scene`.

use pyo3::exceptions::{PyAttributeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use serde_json::Value;

use glint_render::Scene as RScene;

use crate::errors;
use crate::json;

/// Fields the scene JSON omits while they are unset or at their default
/// (`skip_serializing_if`), with what reading one gives then, as JSON: None for an
/// unset `Option`, else the field's default. `__getattr__` and `__dir__` both read
/// this one list; crates/python/tests/test_render.py checks it against the Rust
/// struct's fields, the type stub and the defaults.
const OMITTED: [(&str, &str); 17] = [
    ("iso", "null"),
    ("preset", "null"),
    ("transfer_function", "null"),
    ("window_level", "null"),
    ("derived", "null"),
    ("ssaa", "null"),
    ("opacity_unit", "null"),
    // None: the default lighting (`local`).
    ("lighting", "null"),
    ("crop", "null"),
    ("labels", "null"),
    ("meshes", "[]"),
    ("clip", "[]"),
    ("clip_caps", "false"),
    ("exposure", "0.0"),
    ("tone", "\"linear\""),
    ("filter", "\"trilinear\""),
    ("device", "\"cpu\""),
];

/// A render, described completely (volume, classification, lobe, lights, camera, size).
/// Immutable: `scene.replace(field=value)` returns a changed copy.
#[pyclass(module = "glint", frozen)]
pub struct Scene {
    /// The scene.
    pub(crate) inner: RScene,
}

/// The scene as a JSON object.
fn as_object(scene: &RScene) -> PyResult<serde_json::Map<String, Value>> {
    match serde_json::to_value(scene) {
        Ok(Value::Object(map)) => Ok(map),
        Ok(_) => Err(PyValueError::new_err("a scene serialises to a JSON object")),
        Err(e) => Err(PyValueError::new_err(format!("scene: {e}"))),
    }
}

/// `base` patched with the keyword arguments ([`RScene::patch`], the rule the viewer
/// uses too: `camera`, `lobe` and `material` merged field by field, other fields
/// replaced, None resetting a field to its default); unknown fields and bad values are
/// ValueErrors with the scene parser's message.
pub fn with_fields(base: &RScene, fields: Option<&Bound<'_, PyDict>>) -> PyResult<RScene> {
    let Some(fields) = fields else {
        return Ok(base.clone());
    };
    let mut patch = serde_json::Map::new();
    for (k, v) in fields.iter() {
        let key: String = k.extract()?;
        let mut value = if v.is_none() {
            Value::Null
        } else {
            json::to_json(&v)?
        };
        // A bare path for `input` means a file, as on the command line.
        if key == "input" && value.is_string() {
            value = serde_json::json!({ "path": value });
        }
        patch.insert(key, value);
    }
    base.patch(&patch).map_err(|e| errors::value_error(&e))
}

#[pymethods]
impl Scene {
    /// A scene: the defaults of `glint render` with the given fields replaced. Fields
    /// take the JSON values of the scene file, e.g. `Scene(preset="mr-t2-brain",
    /// size=(256, 256), lobe={"kind": "exact", "n": 40}, camera={"view": "left"})`.
    #[new]
    #[pyo3(signature = (**fields))]
    fn new(fields: Option<&Bound<'_, PyDict>>) -> PyResult<Scene> {
        Ok(Scene {
            inner: with_fields(&RScene::default(), fields)?,
        })
    }

    /// Parses scene JSON (what `glint render --dump-scene` writes).
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Scene> {
        let inner = RScene::from_json(text).map_err(|e| errors::value_error(&e))?;
        Ok(Scene { inner })
    }

    /// The scene as JSON (`glint render --scene` reads it).
    fn to_json(&self) -> PyResult<String> {
        self.inner.to_json().map_err(|e| errors::value_error(&e))
    }

    /// Reads a scene file as `glint render --scene` does: relative paths in it are
    /// relative to the file.
    #[staticmethod]
    fn load(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Scene> {
        let inner = RScene::load(&path).map_err(|e| errors::render_error(py, e))?;
        Ok(Scene { inner })
    }

    /// Writes the scene file atomically as `glint render --dump-scene` does, with
    /// absolute paths, so it renders the same from anywhere.
    fn save(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        self.inner
            .save(&path)
            .map_err(|e| errors::render_error(py, e))
    }

    /// The scene as a dict of plain Python values.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json::to_py(py, &Value::Object(as_object(&self.inner)?))
    }

    /// A copy with the given fields replaced.
    #[pyo3(signature = (**fields))]
    fn replace(&self, fields: Option<&Bound<'_, PyDict>>) -> PyResult<Scene> {
        Ok(Scene {
            inner: with_fields(&self.inner, fields)?,
        })
    }

    /// A field's value as plain Python values (`scene.size`, `scene.lobe["n"]`).
    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        match as_object(&self.inner)?.get(name) {
            Some(v) => json::to_py(py, v),
            None => match OMITTED.iter().find(|(field, _)| *field == name) {
                Some((_, default)) => json::to_py(
                    py,
                    &serde_json::from_str(default).expect("OMITTED holds valid JSON"),
                ),
                None => Err(PyAttributeError::new_err(format!(
                    "'Scene' object has no attribute '{name}'"
                ))),
            },
        }
    }

    fn __dir__(&self) -> PyResult<Vec<String>> {
        let mut names: Vec<String> = as_object(&RScene::default())?.keys().cloned().collect();
        names.extend(OMITTED.iter().map(|(field, _)| field.to_string()));
        names.extend(
            ["from_json", "to_json", "to_dict", "replace", "load", "save"]
                .iter()
                .map(|s| s.to_string()),
        );
        names.sort();
        names.dedup();
        Ok(names)
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<Scene>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    fn __repr__(&self) -> String {
        let compact = serde_json::to_string(&self.inner).unwrap_or_default();
        format!("glint.Scene.from_json({compact:?})")
    }

    /// Pickles as its JSON.
    fn __reduce__<'py>(slf: Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let ctor = slf.get_type().getattr("from_json")?;
        let args = (slf.get().to_json()?,).into_pyobject(py)?;
        PyTuple::new(py, [ctor, args.into_any()])
    }
}
