//! `glint.lobe`: any lobe of `glint-lobe` over a numpy array, on the SIMD kernels.

use numpy::npyffi::NPY_ORDER;
use numpy::{Element, PyArray1, PyArrayDyn, PyArrayMethods as _, PyUntypedArrayMethods as _};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyFloat;

use glint_lobe::{Lobe, LobeKind, Real};

use crate::arrays;
use crate::errors;

/// Evaluates `lobe` over a contiguous array of `T` into a new array of the same shape
/// and memory order. The input is copied with the GIL held; the evaluation runs
/// without it.
fn eval_array<'py, T: Real + Element>(
    py: Python<'py>,
    arr: &Bound<'py, PyArrayDyn<T>>,
    lobe: Lobe<T>,
) -> PyResult<Bound<'py, PyAny>> {
    let cos: Vec<T> = arr
        .try_readonly()
        .map_err(|e| PyValueError::new_err(format!("cos is being written elsewhere: {e}")))?
        .as_slice()
        .map_err(|e| PyValueError::new_err(format!("cos: {e}")))?
        .to_vec();
    let out = crate::pool::detach(py, move || {
        let mut out = vec![T::zero(); cos.len()];
        lobe.eval_slice(&cos, &mut out);
        out
    })?;
    // An element-wise map keeps the memory order: a Fortran-ordered input's output is
    // Fortran-ordered too (C for 0-D and 1-D, where both coincide).
    let order = if arr.is_c_contiguous() {
        NPY_ORDER::NPY_CORDER
    } else {
        NPY_ORDER::NPY_FORTRANORDER
    };
    Ok(PyArray1::from_vec(py, out)
        .reshape_with_order(arr.shape(), order)?
        .into_any())
}

/// `kind` as a lobe kind, or a ValueError listing the kinds.
fn parse_kind(kind: &str) -> PyResult<LobeKind> {
    kind.parse().map_err(|e| errors::value_error(&e))
}

/// Lobe values for `cos` (a float32 or float64 numpy array of any shape, or a Python
/// float): a new array of the same shape and dtype. float32 runs the SIMD kernels
/// (AVX-512, AVX2 or scalar, chosen at run time), float64 the scalar reference. The GIL
/// is released while evaluating.
#[pyfunction]
#[pyo3(signature = (kind, cos, n, v=4))]
pub fn lobe<'py>(
    py: Python<'py>,
    kind: &str,
    cos: &Bound<'py, PyAny>,
    n: f64,
    v: u32,
) -> PyResult<Bound<'py, PyAny>> {
    let kind = parse_kind(kind)?;
    if let Ok(c) = cos.cast::<PyFloat>() {
        let lobe = Lobe::<f64>::new(kind, n, v).map_err(|e| errors::value_error(&e))?;
        return Ok(PyFloat::new(py, lobe.eval(c.value())).into_any());
    }
    let arr = arrays::as_ndarray(cos, "cos")?;
    arrays::require_contiguous(arr, "cos")?;
    if let Ok(a) = arr.cast::<PyArrayDyn<f32>>() {
        let lobe = Lobe::<f32>::new(kind, n, v).map_err(|e| errors::value_error(&e))?;
        return eval_array(py, a, lobe);
    }
    if let Ok(a) = arr.cast::<PyArrayDyn<f64>>() {
        let lobe = Lobe::<f64>::new(kind, n, v).map_err(|e| errors::value_error(&e))?;
        return eval_array(py, a, lobe);
    }
    Err(PyTypeError::new_err(format!(
        "cos must be float32 or float64, got {} (convert with cos.astype(numpy.float32))",
        arrays::dtype_name(arr)
    )))
}

/// The lobe names `glint.lobe` accepts, in the order tables list them.
#[pyfunction]
pub fn lobe_kinds() -> Vec<&'static str> {
    LobeKind::ALL.iter().map(|k| k.name()).collect()
}
