//! `glint.Volume` and `glint.read`: a volume file or a numpy array as a glint volume.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::npyffi::NPY_ORDER;
use numpy::{PyArray1, PyArray2, PyArrayMethods as _};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use glint_io::ReadOptions;

use crate::arrays;
use crate::errors;

/// A 3-D scalar volume: samples indexed `[i, j, k]`, voxel-to-world affine (RAS+ mm),
/// spacing, value scaling and what the reader noted. Immutable; shared by reference
/// with the renderer.
#[pyclass(module = "glint", frozen)]
pub struct Volume {
    /// The volume (never mutated, so views into its samples stay valid).
    pub(crate) inner: Arc<glint_io::Volume>,
    /// The file and voxel limit it was read with, for pickling by path.
    pub(crate) source: Option<(PathBuf, Option<u64>)>,
    format: Option<&'static str>,
    notes: Vec<String>,
}

impl Volume {
    /// A volume that came from memory, not from a file.
    pub(crate) fn in_memory(volume: glint_io::Volume) -> Volume {
        Volume {
            inner: Arc::new(volume),
            source: None,
            format: None,
            notes: Vec::new(),
        }
    }
}

/// Reads a volume file (NIfTI, NRRD, DICOM file or directory), the format chosen from
/// the path as `glint info` does. The GIL is released while reading.
#[pyfunction]
#[pyo3(signature = (path, max_voxels=None))]
pub fn read(py: Python<'_>, path: PathBuf, max_voxels: Option<u64>) -> PyResult<Volume> {
    let mut options = ReadOptions::default();
    if let Some(m) = max_voxels {
        options.max_voxels = m;
    }
    let p = path.clone();
    let file = crate::pool::detach(py, move || glint_io::open_volume(&p, &options))?
        .map_err(|e| errors::io_error(py, e))?;
    Ok(Volume {
        inner: Arc::new(file.volume),
        source: Some((path, max_voxels)),
        format: Some(file.format.name()),
        notes: file.notes,
    })
}

/// Largest relative difference between a given spacing and the affine's column norms
/// that still counts as agreeing: float32 headers carry ~7 significant digits.
const SPACING_RTOL: f64 = 1e-5;

/// Checks a user affine as the readers check file affines ([`glint_io::affine::check`]):
/// finite, last row `[0, 0, 0, 1]`, not singular. Returns the spacing (column norms).
fn check_affine(a: &[[f64; 4]; 4]) -> PyResult<[f64; 3]> {
    glint_io::affine::check(a).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A voxel-to-world affine, row-major.
type Affine = [[f64; 4]; 4];

/// The spacing and affine from what the caller gave.
fn geometry(
    spacing: Option<[f64; 3]>,
    affine: Option<Affine>,
) -> PyResult<([f64; 3], Option<Affine>)> {
    let Some(a) = affine else {
        return Ok((spacing.unwrap_or([1.0; 3]), None));
    };
    let from_affine = check_affine(&a)?;
    if let Some(s) = spacing {
        let agree = s
            .iter()
            .zip(&from_affine)
            .all(|(x, y)| (x - y).abs() <= SPACING_RTOL * y.abs());
        if !agree {
            return Err(PyValueError::new_err(format!(
                "spacing {s:?} disagrees with the affine's column norms {from_affine:?}; give one of them"
            )));
        }
    }
    Ok((from_affine, Some(a)))
}

/// An f64 copy of the physical values (`slope * stored + intercept`), x fastest.
fn physical_f64(v: &glint_io::Volume) -> Vec<f64> {
    (0..v.samples.len())
        .map(|i| v.slope * v.samples.get(i) + v.intercept)
        .collect()
}

#[pymethods]
impl Volume {
    /// A volume from a 3-D numpy array indexed `[i, j, k]` (copied).
    #[staticmethod]
    #[pyo3(signature = (array, spacing=None, affine=None, slope=1.0, intercept=0.0, units=None))]
    fn from_array(
        array: &Bound<'_, PyAny>,
        spacing: Option<[f64; 3]>,
        affine: Option<[[f64; 4]; 4]>,
        slope: f64,
        intercept: f64,
        units: Option<String>,
    ) -> PyResult<Volume> {
        let (dims, samples) = arrays::samples_from_array(array)?;
        let (spacing, affine) = geometry(spacing, affine)?;
        if !slope.is_finite() || slope == 0.0 || !intercept.is_finite() {
            return Err(PyValueError::new_err(format!(
                "slope {slope} and intercept {intercept} must be finite, slope non-zero"
            )));
        }
        let mut v =
            glint_io::Volume::new(dims, spacing, samples).map_err(|e| errors::value_error(&e))?;
        if let Some(a) = affine {
            v.affine = a;
        }
        v.slope = slope;
        v.intercept = intercept;
        v.units = units;
        Ok(Volume::in_memory(v))
    }

    /// Samples along i, j, k.
    #[getter]
    fn shape(&self) -> (usize, usize, usize) {
        let d = self.inner.dims;
        (d[0], d[1], d[2])
    }

    /// The stored sample type (numpy name).
    #[getter]
    fn dtype(&self) -> &'static str {
        self.inner.samples.type_name()
    }

    /// The stored samples, a read-only numpy view `[i, j, k]` (no copy).
    #[getter]
    fn samples<'py>(slf: Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let inner = Arc::clone(&slf.get().inner);
        // SAFETY: `inner` lives in `slf` (frozen: never replaced) behind an Arc whose
        // volume is never mutated, and `slf` is the view's owner.
        unsafe { arrays::borrow_samples(inner.dims, &inner.samples, slf.into_any()) }
    }

    /// Physical values `slope * stored + intercept` as a new float64 array `[i, j, k]`:
    /// what nibabel's `img.get_fdata()` returns for the same file.
    fn fdata<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let inner = Arc::clone(&self.inner);
        let values = crate::pool::detach(py, move || physical_f64(&inner))?;
        let d = self.inner.dims;
        Ok(PyArray1::from_vec(py, values)
            .reshape_with_order(d, NPY_ORDER::NPY_FORTRANORDER)?
            .into_any())
    }

    /// Voxel size in mm along i, j, k.
    #[getter]
    fn spacing(&self) -> (f64, f64, f64) {
        let s = self.inner.spacing;
        (s[0], s[1], s[2])
    }

    /// Voxel index `(i, j, k, 1)` to world RAS+ mm, a new 4x4 float64 array.
    #[getter]
    fn affine<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows: Vec<Vec<f64>> = self.inner.affine.iter().map(|r| r.to_vec()).collect();
        PyArray2::from_vec2(py, &rows).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// Scale applied to stored samples.
    #[getter]
    fn slope(&self) -> f64 {
        self.inner.slope
    }

    /// Offset applied after the scale.
    #[getter]
    fn intercept(&self) -> f64 {
        self.inner.intercept
    }

    /// Units of the physical values where known (e.g. "HU").
    #[getter]
    fn units(&self) -> Option<String> {
        self.inner.units.clone()
    }

    /// What the reader noted (where the affine came from, dropped dimensions, ...).
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }

    /// The file format read (`NIfTI-1`, `NRRD`, `DICOM`), None for arrays.
    #[getter]
    fn format(&self) -> Option<&'static str> {
        self.format
    }

    /// The file read, None for arrays.
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.source.as_ref().map(|(p, _)| p.clone())
    }

    /// Smallest and largest physical value (NaN ignored).
    fn range(&self) -> (f64, f64) {
        self.inner.range()
    }

    fn __repr__(&self) -> String {
        let v = &self.inner;
        let origin = match &self.source {
            Some((p, _)) => format!("{:?}", p.display().to_string()),
            None => "array".into(),
        };
        format!(
            "glint.Volume({origin}, shape={:?}, dtype={}, spacing={:?})",
            v.dims,
            v.samples.type_name(),
            v.spacing
        )
    }

    /// Pickling: a volume read from a file pickles as its path (read again where it is
    /// unpickled: cheap to send to process pools, Dask or Ray workers); an array-backed
    /// volume pickles by value.
    fn __reduce__<'py>(slf: Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let this = slf.get();
        let glint = py.import("glint")?;
        if let Some((path, max_voxels)) = &this.source {
            let args = (path.clone(), *max_voxels).into_pyobject(py)?;
            return PyTuple::new(py, [glint.getattr("read")?, args.into_any()]);
        }
        let v = &this.inner;
        let affine = this.affine(py)?;
        let samples = Volume::samples(slf.clone())?;
        let args = (
            samples,
            None::<[f64; 3]>,
            affine,
            v.slope,
            v.intercept,
            v.units.clone(),
        )
            .into_pyobject(py)?;
        let ctor = glint.getattr("Volume")?.getattr("from_array")?;
        PyTuple::new(py, [ctor, args.into_any()])
    }
}
