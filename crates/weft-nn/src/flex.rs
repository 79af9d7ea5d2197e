//! Plain-slice access to flex tensors for the hand-written CPU kernels.

use burn::backend::flex::FlexTensor;
use burn::tensor::TensorData;

use crate::real::Real;

/// A contiguous, offset-free view of a flex tensor.
pub(crate) fn contiguous(t: FlexTensor) -> FlexTensor {
    if t.is_contiguous() && t.layout().start_offset() == 0 {
        t
    } else {
        t.to_contiguous()
    }
}

/// The elements of a contiguous flex tensor of dtype `T`.
pub(crate) fn elements<T: Real>(t: &FlexTensor) -> &[T] {
    t.as_slice::<T>()
        .expect("fused kernels: inputs are made contiguous and of one dtype before the kernel")
}

/// A flex tensor from a row-major buffer.
pub(crate) fn from_vec<T: Real>(values: Vec<T>, shape: Vec<usize>) -> FlexTensor {
    FlexTensor::from_data(TensorData::new(values, shape))
}

/// Threads for a `gemm` product of `m × k` by `k × n`, as burn flex decides them: only
/// where the product is big enough to pay for them.
pub(crate) fn gemm_parallelism(m: usize, n: usize, k: usize) -> gemm::Parallelism {
    if m * n * k >= 192 * 192 * 192 {
        gemm::Parallelism::Rayon(0)
    } else {
        gemm::Parallelism::None
    }
}

/// Elements per parallel chunk of an element-wise pass on flex: smaller tensors stay on
/// one thread (waking the other costs more than it saves).
pub(crate) const PARALLEL_CHUNK: usize = 1 << 14;
