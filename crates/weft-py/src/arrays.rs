//! numpy arrays to weft's slices and back, with shapes checked and named in errors.

use numpy::ndarray::{Array2, Array3, Dimension};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyReadonlyArray, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;

use crate::error::invalid;

/// Any array-like (a list, an array of another dtype) as a contiguous numpy array of
/// `dtype` ("float32", "int64"), through `numpy.ascontiguousarray`; `what` names it in
/// errors.
pub fn coerce<'py, T: numpy::Element, D: Dimension>(
    obj: &Bound<'py, PyAny>,
    dtype: &str,
    what: &str,
) -> PyResult<PyReadonlyArray<'py, T, D>> {
    let np = obj.py().import("numpy")?;
    let array = np
        .call_method1("ascontiguousarray", (obj, dtype))
        .map_err(|e| invalid(format!("{what}: {e}")))?;
    let ndim = D::NDIM.unwrap_or(0);
    array.extract().map_err(|_| {
        let shape = array
            .getattr("shape")
            .map(|s| s.to_string())
            .unwrap_or_default();
        invalid(format!("{what}: shape {shape}; expected {ndim} dimensions"))
    })
}

/// `(N, 3)` rows of an array named `what`.
pub fn rows3<T: numpy::Element + Copy>(
    a: &PyReadonlyArray2<'_, T>,
    what: &str,
) -> PyResult<Vec<[T; 3]>> {
    let v = a.as_array();
    if v.ncols() != 3 {
        return Err(invalid(format!(
            "{what}: shape {:?}; expected (N, 3)",
            v.shape()
        )));
    }
    Ok(v.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

/// `(T, N, 3)` frames of an array named `what`.
pub fn frames3<T: numpy::Element + Copy>(
    a: &PyReadonlyArray3<'_, T>,
    what: &str,
) -> PyResult<Vec<Vec<[T; 3]>>> {
    let v = a.as_array();
    if v.shape()[2] != 3 {
        return Err(invalid(format!(
            "{what}: shape {:?}; expected (T, N, 3)",
            v.shape()
        )));
    }
    Ok(v.outer_iter()
        .map(|f| f.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
        .collect())
}

/// `rows` as an `(N, K)` array.
pub fn to_2d<'py, T: numpy::Element + Copy, const K: usize>(
    py: Python<'py>,
    rows: &[[T; K]],
) -> Bound<'py, PyArray2<T>> {
    let flat: Vec<T> = rows.iter().flatten().copied().collect();
    Array2::from_shape_vec((rows.len(), K), flat)
        .expect("rows × K values")
        .into_pyarray(py)
}

/// `frames` (each of the same length) as a `(T, N, K)` array.
pub fn to_3d<'py, T: numpy::Element + Copy, const K: usize>(
    py: Python<'py>,
    frames: &[Vec<[T; K]>],
) -> PyResult<Bound<'py, PyArray3<T>>> {
    let n = frames.first().map_or(0, Vec::len);
    if frames.iter().any(|f| f.len() != n) {
        return Err(invalid("frames of different lengths"));
    }
    let flat: Vec<T> = frames.iter().flatten().flatten().copied().collect();
    Ok(Array3::from_shape_vec((frames.len(), n, K), flat)
        .expect("frames × rows × K values")
        .into_pyarray(py))
}

/// Triangles from an `(F, 3)` integer array, each index checked against `vertices`.
pub fn faces(a: &PyReadonlyArray2<'_, i64>, vertices: usize) -> PyResult<Vec<[u32; 3]>> {
    let rows = rows3(a, "faces")?;
    rows.iter()
        .enumerate()
        .map(|(i, f)| {
            let mut out = [0u32; 3];
            for (k, &v) in f.iter().enumerate() {
                if v < 0 || v as usize >= vertices {
                    return Err(invalid(format!(
                        "faces[{i}] names vertex {v}; expected 0 to {}",
                        vertices.saturating_sub(1)
                    )));
                }
                out[k] = v as u32;
            }
            Ok(out)
        })
        .collect()
}
