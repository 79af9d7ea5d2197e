//! The safetensors reading and writing every weft-data file shares: little-endian f32
//! and u32 tensors out, and tensors in with their dtype and shape checked, so every
//! file (sequence shards, character files) names the file, the tensor and what was
//! expected in the same words when something is wrong.

use std::borrow::Cow;
use std::path::Path;

use safetensors::tensor::{Dtype, SafeTensors, View};

use crate::error::DataError;

/// A tensor to write: dtype, shape and little-endian bytes.
pub(crate) struct TensorOut {
    dtype: Dtype,
    shape: Vec<usize>,
    bytes: Vec<u8>,
}

impl View for &TensorOut {
    fn dtype(&self) -> Dtype {
        self.dtype
    }
    fn shape(&self) -> &[usize] {
        &self.shape
    }
    fn data(&self) -> Cow<'_, [u8]> {
        Cow::Borrowed(&self.bytes)
    }
    fn data_len(&self) -> usize {
        self.bytes.len()
    }
}

/// An f32 tensor of `shape` from `values` in row-major order.
pub(crate) fn f32_tensor<'a>(
    shape: Vec<usize>,
    values: impl Iterator<Item = &'a f32>,
) -> TensorOut {
    TensorOut {
        dtype: Dtype::F32,
        shape,
        bytes: values.flat_map(|x| x.to_le_bytes()).collect(),
    }
}

/// A u32 tensor of `shape` from `values` in row-major order.
pub(crate) fn u32_tensor<'a>(
    shape: Vec<usize>,
    values: impl Iterator<Item = &'a u32>,
) -> TensorOut {
    TensorOut {
        dtype: Dtype::U32,
        shape,
        bytes: values.flat_map(|x| x.to_le_bytes()).collect(),
    }
}

/// Parses safetensors bytes; a torn or foreign file is [`DataError::Shard`].
pub(crate) fn parse<'a>(path: &Path, bytes: &'a [u8]) -> Result<SafeTensors<'a>, DataError> {
    SafeTensors::deserialize(bytes).map_err(|e| DataError::Shard {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

fn describe(dtype: Dtype, shape: &[usize]) -> String {
    format!("{} {shape:?}", format!("{dtype:?}").to_lowercase())
}

/// The bytes of tensor `name`, after checking its dtype and shape.
pub(crate) fn tensor<'a>(
    path: &Path,
    st: &SafeTensors<'a>,
    name: &str,
    dtype: Dtype,
    shape: &[usize],
) -> Result<&'a [u8], DataError> {
    let err = |found: String| DataError::Tensor {
        path: path.to_path_buf(),
        tensor: name.to_string(),
        expected: describe(dtype, shape),
        found,
    };
    let view = st.tensor(name).map_err(|_| err("missing".into()))?;
    if view.dtype() != dtype || view.shape() != shape {
        return Err(err(describe(view.dtype(), view.shape())));
    }
    Ok(view.data())
}

/// The shape of tensor `name` (for files whose sizes are read from the file itself).
pub(crate) fn shape_of(
    path: &Path,
    st: &SafeTensors<'_>,
    name: &str,
) -> Result<Vec<usize>, DataError> {
    st.tensor(name)
        .map(|v| v.shape().to_vec())
        .map_err(|_| DataError::Tensor {
            path: path.to_path_buf(),
            tensor: name.to_string(),
            expected: "present".into(),
            found: "missing".into(),
        })
}

/// Little-endian f32 values.
pub(crate) fn f32s(bytes: &[u8]) -> impl Iterator<Item = f32> + '_ {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
}

/// Little-endian f32 values as 3-vectors.
pub(crate) fn triples(bytes: &[u8]) -> Vec<[f32; 3]> {
    let v: Vec<f32> = f32s(bytes).collect();
    v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// Little-endian u32 triangles, each index checked below `n` (`name` in the error).
pub(crate) fn faces(
    path: &Path,
    name: &str,
    bytes: &[u8],
    n: usize,
) -> Result<Vec<[u32; 3]>, DataError> {
    let values: Vec<u32> = bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let faces: Vec<[u32; 3]> = values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    if let Some((i, f)) = faces
        .iter()
        .enumerate()
        .find(|(_, f)| f.iter().any(|&v| v as usize >= n))
    {
        return Err(DataError::Tensor {
            path: path.to_path_buf(),
            tensor: name.into(),
            expected: format!("vertex indices below {n}"),
            found: format!("face {i} = {f:?}"),
        });
    }
    Ok(faces)
}
