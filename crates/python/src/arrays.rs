//! numpy arrays to and from the glint crates' buffers.
//!
//! Volumes are indexed `[i, j, k]` (x, y, z) as nibabel's `get_fdata()` returns them;
//! glint stores them x fastest, which is numpy's Fortran order for that shape, so a
//! volume's samples are shown to Python without a copy.

use numpy::ndarray::{ArrayView3, ShapeBuilder as _};
use numpy::{
    Element, PyArray3, PyArrayDyn, PyArrayMethods as _, PyUntypedArray, PyUntypedArrayMethods as _,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

use glint_io::Samples;

/// The sample types a volume holds, as numpy names them (`glint_io::Samples`).
pub const VOLUME_DTYPES: &str = "uint8, int8, uint16, int16, uint32, int32, float32, float64";

/// The object as a numpy array, or a `TypeError` naming what was expected.
pub fn as_ndarray<'a, 'py>(
    obj: &'a Bound<'py, PyAny>,
    what: &str,
) -> PyResult<&'a Bound<'py, PyUntypedArray>> {
    obj.cast::<PyUntypedArray>().map_err(|_| {
        let ty = obj
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into());
        PyTypeError::new_err(format!(
            "{what} must be a numpy array, got {ty} (use numpy.asarray)"
        ))
    })
}

/// The array's dtype name (`float32`, ...).
pub fn dtype_name(arr: &Bound<'_, PyUntypedArray>) -> String {
    arr.dtype()
        .str()
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// Refuses strided views: the element order would not be the one the caller sees.
pub fn require_contiguous(arr: &Bound<'_, PyUntypedArray>, what: &str) -> PyResult<()> {
    if arr.is_contiguous() {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{what} is not contiguous (a strided view, shape {:?}); pass numpy.ascontiguousarray({what})",
            arr.shape()
        )))
    }
}

/// Copies a C- or Fortran-contiguous array of `T` in x-fastest order (`[i, j, k]` with
/// `i` fastest), the order of `glint_io::Volume` samples. Called with the GIL held: the
/// result is owned, so the caller can release the GIL afterwards.
fn copy_x_fastest<T: Element + Copy>(arr: &Bound<'_, PyArrayDyn<T>>) -> PyResult<Vec<T>> {
    let ro = arr
        .try_readonly()
        .map_err(|e| PyValueError::new_err(format!("array is being written elsewhere: {e}")))?;
    if arr.is_fortran_contiguous() {
        // Memory order is already i fastest.
        if let Ok(s) = ro.as_slice() {
            return Ok(s.to_vec());
        }
    }
    // Reversing the axes makes the logical (row-major) iteration order i fastest.
    Ok(ro.as_array().reversed_axes().iter().copied().collect())
}

/// The dims and samples of a 3-D numpy array indexed `[i, j, k]`, copied.
pub fn samples_from_array(obj: &Bound<'_, PyAny>) -> PyResult<([usize; 3], Samples)> {
    let arr = as_ndarray(obj, "array")?;
    let shape = arr.shape();
    let dims: [usize; 3] = shape.try_into().map_err(|_| {
        PyValueError::new_err(format!(
            "expected a 3-D array indexed [i, j, k], got {} dimensions (shape {shape:?}); \
             take one volume of a 4-D series with a[..., t]",
            shape.len()
        ))
    })?;
    require_contiguous(arr, "array")?;
    macro_rules! try_types {
        ($($t:ty => $variant:ident),*) => {
            $(if let Ok(a) = arr.cast::<PyArrayDyn<$t>>() {
                return Ok((dims, Samples::$variant(copy_x_fastest(a)?)));
            })*
        };
    }
    try_types!(u8 => U8, i8 => I8, u16 => U16, i16 => I16, u32 => U32, i32 => I32,
               f32 => F32, f64 => F64);
    Err(PyTypeError::new_err(format!(
        "unsupported sample type {} (expected one of {VOLUME_DTYPES}; convert with a.astype(numpy.float32))",
        dtype_name(arr)
    )))
}

/// A read-only numpy view `[i, j, k]` of a volume's samples, kept alive by `owner`.
///
/// # Safety
/// `samples` must stay at the same address and unmodified for as long as `owner` lives
/// (the owner holds them behind an `Arc` it never mutates).
pub unsafe fn borrow_samples<'py>(
    dims: [usize; 3],
    samples: &Samples,
    owner: Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    macro_rules! view {
        ($v:expr) => {{
            let view = ArrayView3::from_shape(dims.f(), $v.as_slice())
                .map_err(|e| PyValueError::new_err(format!("volume samples: {e}")))?;
            // SAFETY: forwarded from this function's contract.
            let arr = unsafe { PyArray3::borrow_from_array(&view, owner) };
            read_only(&arr)?;
            Ok(arr.into_any())
        }};
    }
    match samples {
        Samples::U8(v) => view!(v),
        Samples::I8(v) => view!(v),
        Samples::U16(v) => view!(v),
        Samples::I16(v) => view!(v),
        Samples::U32(v) => view!(v),
        Samples::I32(v) => view!(v),
        Samples::F32(v) => view!(v),
        Samples::F64(v) => view!(v),
    }
}

/// Clears the array's writeable flag.
fn read_only<T: Element>(arr: &Bound<'_, PyArray3<T>>) -> PyResult<()> {
    let rw = arr
        .try_readwrite()
        .map_err(|e| PyValueError::new_err(format!("volume samples: {e}")))?;
    drop(rw.make_nonwriteable());
    Ok(())
}
