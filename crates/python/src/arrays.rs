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
use rayon::prelude::*;
use std::mem::MaybeUninit;

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
fn copy_x_fastest<T: Element + Copy + Send + Sync>(
    arr: &Bound<'_, PyArrayDyn<T>>,
) -> PyResult<Vec<T>> {
    let ro = arr
        .try_readonly()
        .map_err(|e| PyValueError::new_err(format!("array is being written elsewhere: {e}")))?;
    let slice = ro
        .as_slice()
        .map_err(|e| PyValueError::new_err(format!("array: {e}")))?;
    if arr.is_fortran_contiguous() {
        // Memory order is already i fastest.
        return Ok(parallel_copy(slice));
    }
    let s = arr.shape();
    Ok(c_to_x_fastest(slice, [s[0], s[1], s[2]]))
}

/// A copy of `src` made by the pool's threads in 1 MiB pieces: the first touch of a
/// fresh buffer's pages (most of a plain copy's time for a volume of hundreds of MB)
/// is then shared between the cores.
fn parallel_copy<T: Copy + Send + Sync>(src: &[T]) -> Vec<T> {
    let piece = (1 << 20) / std::mem::size_of::<T>().max(1);
    let mut dst: Vec<T> = Vec::with_capacity(src.len());
    dst.spare_capacity_mut()[..src.len()]
        .par_chunks_mut(piece)
        .zip(src.par_chunks(piece))
        .for_each(|(out, from)| {
            for (o, v) in out.iter_mut().zip(from) {
                *o = MaybeUninit::new(*v);
            }
        });
    // SAFETY: the zipped chunks cover all src.len() elements, each written above, and
    // the capacity is src.len().
    unsafe { dst.set_len(src.len()) };
    dst
}

/// Side of the square tiles [`c_to_x_fastest`] copies: 32 x 32 elements of up to 8
/// bytes read 32 rows of 256 bytes and write 32 rows of 256 bytes, which stay in L1.
const TILE: usize = 32;

/// Reorders C-ordered samples `src[i][j][k]` (k fastest) into x-fastest order
/// (`dst[i + ni * (j + nj * k)]`), swapping the i and k axes tile by tile.
///
/// Written here rather than taken from the `transpose` crate, which transposes
/// contiguous 2-D matrices only: each `j` plane of a C-ordered volume is a strided
/// ni x nk matrix (row stride nj * nk), and copying through a contiguous intermediate
/// would double the memory traffic. The element-by-element walk this replaces read the
/// source with a stride of nj * nk elements and took 4.5 s for 512^3 (issue 45).
/// Slabs of `dst` with the same `k` are disjoint and contiguous, so they are filled in
/// parallel.
pub fn c_to_x_fastest<T: Copy + Send + Sync>(src: &[T], [ni, nj, nk]: [usize; 3]) -> Vec<T> {
    let plane = ni * nj;
    assert_eq!(src.len(), plane * nk, "samples for the shape");
    if src.is_empty() {
        return Vec::new();
    }
    let mut dst: Vec<T> = Vec::with_capacity(src.len());
    // Written in place without first filling the buffer: a fill would be one more pass
    // over the whole volume (0.3 s of a 512^3 float32 copy).
    dst.spare_capacity_mut()[..src.len()]
        .par_chunks_mut(plane * TILE.min(nk))
        .enumerate()
        .for_each(|(block, out)| {
            let k0 = block * TILE.min(nk);
            let kn = out.len() / plane;
            for j in 0..nj {
                for i0 in (0..ni).step_by(TILE) {
                    let i1 = (i0 + TILE).min(ni);
                    for dk in 0..kn {
                        let row = &mut out[dk * plane + j * ni..][..ni];
                        let from = j * nk + k0 + dk;
                        for i in i0..i1 {
                            row[i] = MaybeUninit::new(src[i * nj * nk + from]);
                        }
                    }
                }
            }
        });
    // SAFETY: the chunks cover all src.len() elements (the k slabs tile the buffer:
    // each holds kn whole planes), every (i, j) of each plane is written above, and
    // the capacity is src.len().
    unsafe { dst.set_len(src.len()) };
    dst
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
    if dims.contains(&0) {
        return Err(PyValueError::new_err(format!(
            "array of shape ({}, {}, {}) is empty: every axis needs at least one sample",
            dims[0], dims[1], dims[2]
        )));
    }
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
