//! `glint.hw.Unit`: the bit-accurate model of the specular unit (`glint-hw`) over numpy
//! arrays of input codes.

use std::sync::Arc;

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods as _, PyUntypedArrayMethods as _};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyInt, PyString};

use glint_hw::{Config, Input};

use crate::arrays;
use crate::errors;

/// The specular unit of one configuration (widths, roundings, ROM1 coefficients).
#[pyclass(module = "glint.hw", name = "Unit", frozen)]
pub struct Unit {
    unit: Arc<glint_hw::Unit>,
}

/// Integers of a Python int or an integer numpy array (any contiguous layout), in
/// logical (C) order, with the shape (`[]` for a Python int).
fn int_values(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<i128>, Vec<usize>)> {
    if let Ok(i) = obj.cast::<PyInt>() {
        let x: i128 = i.extract().map_err(|_| {
            PyValueError::new_err(format!("{what} = {i} is out of range for a code"))
        })?;
        return Ok((vec![x], Vec::new()));
    }
    let arr = arrays::as_ndarray(obj, what)?;
    arrays::require_contiguous(arr, what)?;
    macro_rules! try_types {
        ($($t:ty),*) => {
            $(if let Ok(a) = arr.cast::<PyArrayDyn<$t>>() {
                let ro = a.try_readonly().map_err(|e| {
                    PyValueError::new_err(format!("{what} is being written elsewhere: {e}"))
                })?;
                let v = ro.as_array().iter().map(|&x| i128::from(x)).collect();
                return Ok((v, arr.shape().to_vec()));
            })*
        };
    }
    try_types!(i64, i32, i16, i8, u64, u32, u16, u8);
    Err(PyTypeError::new_err(format!(
        "{what} must be integer codes, got {} (real cosines convert with Unit.cos_codes)",
        arrays::dtype_name(arr)
    )))
}

/// The configuration from None (the default), a JSON string or a dict of fields.
fn config_of(py: Python<'_>, config: Option<&Bound<'_, PyAny>>) -> PyResult<Config> {
    let text = match config {
        None => return Ok(Config::default()),
        Some(c) if c.is_instance_of::<PyString>() => c.extract::<String>()?,
        Some(c) if c.is_instance_of::<PyDict>() => py
            .import("json")?
            .call_method1("dumps", (c,))?
            .extract::<String>()?,
        Some(c) => {
            return Err(PyTypeError::new_err(format!(
                "config must be None, a dict or a JSON string, got {}",
                c.get_type().name()?
            )))
        }
    };
    Config::from_json(&text).map_err(|e| errors::value_error(&e))
}

#[pymethods]
impl Unit {
    /// Builds the unit (validates the configuration and fills ROM1). `config`: None for
    /// the default, or a dict / JSON string whose missing fields take the defaults
    /// (`glint hw eval --print-config` shows them).
    #[new]
    #[pyo3(signature = (config=None))]
    fn new(py: Python<'_>, config: Option<&Bound<'_, PyAny>>) -> PyResult<Unit> {
        let config = config_of(py, config)?;
        let unit = crate::pool::detach(py, move || glint_hw::Unit::new(config))?
            .map_err(|e| errors::value_error(&e))?;
        Ok(Unit {
            unit: Arc::new(unit),
        })
    }

    /// The configuration as a dict (every field).
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?
            .call_method1("loads", (self.unit.config().to_json(),))
    }

    /// Clock cycles from input to output (`v + 4`).
    #[getter]
    fn latency(&self) -> u32 {
        self.unit.latency()
    }

    /// Full-scale `k_s·I` and output code, `2^out_bits - 1`.
    #[getter]
    fn full_scale(&self) -> u64 {
        self.unit.full_scale()
    }

    /// Smallest and largest signed cos code.
    #[getter]
    fn cos_code_range(&self) -> (i64, i64) {
        self.unit.cos_code_range()
    }

    /// The nearest input codes of real cosines (a float64 array or a float): an int64
    /// array of the same shape.
    fn cos_codes<'py>(
        &self,
        py: Python<'py>,
        cos: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if let Ok(c) = cos.extract::<f64>() {
            if !cos.is_instance_of::<numpy::PyUntypedArray>() {
                let code = self.unit.cos_code(c).map_err(|e| errors::value_error(&e))?;
                return Ok(code.into_pyobject(py)?.into_any());
            }
        }
        let arr = arrays::as_ndarray(cos, "cos")?;
        arrays::require_contiguous(arr, "cos")?;
        let a = arr.cast::<PyArrayDyn<f64>>().map_err(|_| {
            PyTypeError::new_err(format!(
                "cos must be float64, got {}",
                arrays::dtype_name(arr)
            ))
        })?;
        let values: Vec<f64> = a.try_readonly()?.as_array().iter().copied().collect();
        let unit = Arc::clone(&self.unit);
        let codes = crate::pool::detach(py, move || {
            values
                .iter()
                .map(|&c| unit.cos_code(c))
                .collect::<Result<Vec<i64>, _>>()
        })?
        .map_err(|e| errors::value_error(&e))?;
        Ok(PyArray1::from_vec(py, codes)
            .reshape(arr.shape())?
            .into_any())
    }

    /// The R, G, B output codes for every cos code: `cos_codes` (int or integer
    /// array), `n` (int, or an integer array of the same shape) and `ks` (`k_s·I` for
    /// R, G, B as output codes). Returns a uint64 array of shape `cos_codes.shape +
    /// (3,)`. The GIL is released while evaluating.
    fn eval<'py>(
        &self,
        py: Python<'py>,
        cos_codes: &Bound<'py, PyAny>,
        n: &Bound<'py, PyAny>,
        ks: [u64; 3],
    ) -> PyResult<Bound<'py, PyAny>> {
        let (cos, shape) = int_values(cos_codes, "cos_codes")?;
        let (ns, n_shape) = int_values(n, "n")?;
        if !n_shape.is_empty() && n_shape != shape {
            return Err(PyValueError::new_err(format!(
                "n has shape {n_shape:?} but cos_codes has shape {shape:?}; give one n or one per code"
            )));
        }
        let unit = Arc::clone(&self.unit);
        let rgb = crate::pool::detach(py, move || eval_codes(&unit, &cos, &ns, ks))?
            .map_err(PyValueError::new_err)?;
        let mut out_shape = shape;
        out_shape.push(3);
        Ok(PyArray1::from_vec(py, rgb).reshape(out_shape)?.into_any())
    }

    fn __repr__(&self) -> String {
        let c = self.unit.config();
        format!(
            "glint.hw.Unit(v={}, n_bits={}, cos_bits={}, out_bits={}, coefficients={})",
            c.v,
            c.n_bits,
            c.cos_bits,
            c.out_bits,
            c.coefficients.name()
        )
    }

    /// Pickles as its configuration (JSON).
    fn __reduce__<'py>(slf: Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let json = slf.get().unit.config().to_json();
        Ok((slf.get_type().into_any(), (json,)))
    }
}

/// The functional model over flattened codes (`ns` of length 1 applies to all):
/// R, G, B per code, or the first rejected input's one-line message.
fn eval_codes(
    unit: &glint_hw::Unit,
    cos: &[i128],
    ns: &[i128],
    ks: [u64; 3],
) -> Result<Vec<u64>, String> {
    let mut rgb = Vec::with_capacity(cos.len() * 3);
    for (i, &c) in cos.iter().enumerate() {
        let n = if ns.len() == 1 { ns[0] } else { ns[i] };
        let at = |what: String| format!("element {i}: {what}");
        let input = Input {
            cos: i64::try_from(c).map_err(|_| at(format!("cos code {c} out of range")))?,
            n: u32::try_from(n).map_err(|_| at(format!("n = {n} out of range")))?,
            ks,
        };
        let out = unit.eval(&input).map_err(|e| at(errors::one_line(&e)))?;
        rgb.extend_from_slice(&out.rgb);
    }
    Ok(rgb)
}
