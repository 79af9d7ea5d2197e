//! The float types the CPU kernels run in: `f32` for training, `f64` for gradient checks.

use std::ops::{Add, AddAssign, Div, Mul, Sub};

/// A float the fused CPU kernels are generic over.
pub(crate) trait Real:
    Copy
    + Send
    + Sync
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + AddAssign
    + bytemuck::Pod
    + burn::tensor::Element
    + 'static
{
    const ZERO: Self;
    const ONE: Self;
    const NEG_INFINITY: Self;
    fn from_f64(v: f64) -> Self;
    /// 1 for true, 0 for false, without a branch.
    fn from_bool(b: bool) -> Self;
    fn exp(self) -> Self;
}

macro_rules! real {
    ($t:ty) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const NEG_INFINITY: Self = <$t>::NEG_INFINITY;
            #[inline]
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn from_bool(b: bool) -> Self {
                b as u8 as $t
            }
            #[inline]
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
        }
    };
}
real!(f32);
real!(f64);

/// `Σ a[k] b[k]` over `min(len)` elements, in eight interleaved partial sums (lane `l`
/// takes the indices `≡ l mod 8`), then the lanes in order: the fixed order keeps it
/// deterministic, the independent lanes let the compiler vectorise it (a single running sum
/// is one long chain of dependent adds).
#[inline(always)]
pub(crate) fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    let len = a.len().min(b.len());
    let (a, b) = (&a[..len], &b[..len]);
    let mut lanes = [T::ZERO; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..8 {
            lanes[l] += x[l] * y[l];
        }
    }
    let mut acc = T::ZERO;
    for (&x, &y) in ra.iter().zip(rb) {
        acc += x * y;
    }
    for lane in lanes {
        acc += lane;
    }
    acc
}

/// `y += alpha x`.
#[inline(always)]
pub(crate) fn axpy<T: Real>(alpha: T, x: &[T], y: &mut [T]) {
    for (o, &v) in y.iter_mut().zip(x) {
        *o += alpha * v;
    }
}

/// Runs `f` compiled for AVX2 when the CPU has it (x86-64), else as is.
///
/// The kernels are written as plain loops over independent lanes; built for the baseline
/// x86-64 target they vectorise 4-wide (SSE2), here 8-wide. `f` and the helpers it calls are
/// `#[inline(always)]`, so they are compiled into the AVX2 function. No floating-point
/// contraction is allowed in Rust, so both paths compute the same operations in the same
/// order and give bit-identical results.
#[inline(always)]
pub(crate) fn simd<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx2")]
        unsafe fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
            f()
        }
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            return unsafe { with_avx2(f) };
        }
    }
    f()
}
