//! Vectorisable f32 `exp`, `tanh` and σ over slices, for the inference passes.
//!
//! Why: libm's `expf` and `tanhf` are scalar calls; as plain branch-free arithmetic
//! (Cephes' polynomials, the power of two built from its bits) the loops over a row
//! compile to SIMD inside [`crate::real::simd`]. Accuracy: `exp` within 3e-7 relative,
//! `tanh` within 3e-7 absolute of libm (tests below).

use crate::activation::Activation;

/// `eˣ`, `x` clamped to `[-87, 88]` (f32's normal range): `2ⁿ · e^r` with `n` the
/// integer nearest `x log₂e`, `|r| ≤ ln 2 / 2` and Cephes' degree-5 polynomial for `e^r`.
/// `n` is rounded by adding 1.5·2²³ (the sum's last mantissa bits are then `n`), and
/// `2ⁿ` built from those bits: no float-to-int conversion or `floor`, which do not
/// vectorise as well.
#[inline(always)]
pub(crate) fn exp(x: f32) -> f32 {
    const ROUND: f32 = 12_582_912.0;
    let x = x.clamp(-87.0, 88.0);
    let k = x * std::f32::consts::LOG2_E + ROUND;
    let n = k - ROUND;
    // ln 2 in two parts, so that `n · ln 2` is exact enough for the reduction.
    let r = x - n * 0.693_359_4 + n * 2.121_944_4e-4;
    let p = 1.987_569_1e-4;
    let p = p * r + 1.398_199_9e-3;
    let p = p * r + 8.333_452e-3;
    let p = p * r + 4.166_579_6e-2;
    let p = p * r + 1.666_666_5e-1;
    let p = p * r + 5e-1;
    let y = p * r * r + r + 1.0;
    let bits = k.to_bits().wrapping_sub(ROUND.to_bits()).wrapping_add(127) << 23;
    y * f32::from_bits(bits)
}

/// `tanh x`: Cephes' odd polynomial below |x| = 0.625, `1 − 2 / (e^{2|x|} + 1)` with the
/// sign of `x` above.
#[inline(always)]
pub(crate) fn tanh(x: f32) -> f32 {
    let a = x.abs();
    let z = x * x;
    let p = -5.704_988_7e-3;
    let p = p * z + 2.063_909e-2;
    let p = p * z - 5.373_971_6e-2;
    let p = p * z + 1.333_144_2e-1;
    let p = p * z - 3.333_328e-1;
    let small = p * z * x + x;
    let large = (1.0 - 2.0 / (exp(2.0 * a) + 1.0)).copysign(x);
    if a < 0.625 {
        small
    } else {
        large
    }
}

/// `σ(x) = 1 / (1 + e⁻ˣ)`, with [`exp`].
#[inline(always)]
pub(crate) fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + exp(-x))
}

/// `x ← eˣ` element-wise.
#[inline(always)]
pub(crate) fn exp_in_place(x: &mut [f32]) {
    for v in x {
        *v = exp(*v);
    }
}

/// `x ← σ(x)` element-wise, as [`Activation::forward`].
#[inline(always)]
pub(crate) fn activate(activation: Activation, x: &mut [f32]) {
    match activation {
        Activation::None => {}
        Activation::Relu => x.iter_mut().for_each(|v| *v = v.max(0.0)),
        Activation::Tanh => x.iter_mut().for_each(|v| *v = tanh(*v)),
        Activation::Tanhshrink => x.iter_mut().for_each(|v| *v -= tanh(*v)),
        Activation::LeakyRelu(slope) => {
            let slope = slope as f32;
            x.iter_mut()
                .for_each(|v| *v = v.max(0.0) + slope * v.min(0.0));
        }
        Activation::Elu => x
            .iter_mut()
            .for_each(|v| *v = v.max(0.0) + exp(v.min(0.0)) - 1.0),
        Activation::Sigmoid => x.iter_mut().for_each(|v| *v = sigmoid(*v)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> impl Iterator<Item = f32> {
        (-200_000..=200_000).map(|k| k as f32 * 1e-4)
    }

    #[test]
    fn exp_and_tanh_match_libm() {
        for x in grid().map(|x| x * 4.0) {
            let (got, want) = (exp(x), x.exp());
            assert!((got - want).abs() <= 3e-7 * want, "exp {x}: {got} {want}");
        }
        assert!(exp(-200.0) < 1e-37 && exp(-200.0) >= 0.0);
        for x in grid().chain([30.0, -30.0, 1e-30, 0.0]) {
            let (got, want) = (tanh(x), x.tanh());
            assert!((got - want).abs() <= 3e-7, "tanh {x}: {got} {want}");
            // Relative accuracy where tanhshrink needs it, near zero.
            assert!(
                (got - want).abs() <= 3e-7 * want.abs().max(1e-30),
                "tanh {x}"
            );
        }
    }

    #[test]
    fn activations_match_the_tensor_forms() {
        let xs: Vec<f32> = grid().step_by(997).collect();
        let want = |a: Activation| -> Vec<f32> {
            xs.iter()
                .map(|&x| {
                    let x = f64::from(x);
                    (match a {
                        Activation::None => x,
                        Activation::Relu => x.max(0.0),
                        Activation::Tanh => x.tanh(),
                        Activation::Tanhshrink => x - x.tanh(),
                        Activation::LeakyRelu(s) => {
                            if x > 0.0 {
                                x
                            } else {
                                s * x
                            }
                        }
                        Activation::Elu => x.max(0.0) + x.min(0.0).exp() - 1.0,
                        Activation::Sigmoid => 1.0 / (1.0 + (-x).exp()),
                    }) as f32
                })
                .collect()
        };
        for a in [
            Activation::None,
            Activation::Relu,
            Activation::Tanh,
            Activation::Tanhshrink,
            Activation::LeakyRelu(0.1),
            Activation::Elu,
            Activation::Sigmoid,
        ] {
            let mut got = xs.clone();
            activate(a, &mut got);
            for (g, w) in got.iter().zip(want(a)) {
                assert!((g - w).abs() <= 1e-6 * w.abs().max(1.0), "{a:?}: {g} {w}");
            }
        }
    }
}
