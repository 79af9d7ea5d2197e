//! Adamax (Kingma & Ba 2015, Algorithm 2): Adam with the infinity norm in place of the
//! second moment, the optimiser of seed 000 (supplement §4, initial rate 3e-3).
//!
//! Per parameter, at step `t` with gradient `g` (plus `λθ` with weight decay λ):
//! `m_t = β₁ m_{t−1} + (1 − β₁) g`,
//! `u_t = max(β₂ u_{t−1}, |g| + ε)`,
//! `θ_t = θ_{t−1} − (lr / (1 − β₁ᵗ)) · m_t / u_t`.
//! ε sits inside the max as in PyTorch's `torch.optim.Adamax`, so the two agree step for
//! step.

use std::mem::MaybeUninit;

use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{backend_extension, Backend, Dispatch, Flex};
use burn::config::Config;
use burn::optim::LearningRate;
use burn::optim::{ModuleOptimizer, Optimizer, RecordState, StateSink, StateSource};
use burn::tensor::{DType, Device, Tensor};
use rayon::prelude::*;

use crate::backend::is_flex;
use crate::flex::{contiguous, elements, from_vec, PARALLEL_CHUNK as CHUNK};
use crate::real::{simd, Real};

/// Configuration of [`Adamax`]; defaults are PyTorch's.
#[derive(Config, Debug)]
pub struct AdamaxConfig {
    /// β₁, decay of the first moment.
    #[config(default = 0.9)]
    pub beta_1: f64,
    /// β₂, decay of the infinity norm.
    #[config(default = 0.999)]
    pub beta_2: f64,
    /// ε, floor of the infinity norm.
    #[config(default = 1e-8)]
    pub epsilon: f64,
    /// L2 weight decay λ (added to the gradient).
    #[config(default = 0.0)]
    pub weight_decay: f64,
}

impl AdamaxConfig {
    /// The bare optimiser (for [`ModuleOptimizer::with_group`]).
    pub fn build(&self) -> Adamax {
        Adamax {
            beta_1: self.beta_1,
            beta_2: self.beta_2,
            epsilon: self.epsilon,
            weight_decay: self.weight_decay,
        }
    }

    /// The optimiser for a whole module.
    pub fn init(&self) -> ModuleOptimizer {
        ModuleOptimizer::from(self.build())
    }
}

/// The Adamax optimiser; see the module documentation.
#[derive(Clone, Debug)]
pub struct Adamax {
    beta_1: f64,
    beta_2: f64,
    epsilon: f64,
    weight_decay: f64,
}

/// Adamax state of one parameter.
#[derive(Clone, Debug)]
pub struct AdamaxState<const D: usize> {
    /// Steps taken `t`.
    pub time: usize,
    /// First moment `m`.
    pub moment: Tensor<D>,
    /// Infinity norm `u`.
    pub inf_norm: Tensor<D>,
}

impl<const D: usize> RecordState for AdamaxState<D> {
    fn state_flatten(&self, prefix: &str, out: &mut StateSink) {
        out.push_scalar(prefix, "time", (self.time as u64).into());
        out.push_tensor(prefix, "moment", self.moment.to_data());
        out.push_tensor(prefix, "inf_norm", self.inf_norm.to_data());
    }

    /// `None` (the parameter's state starts afresh, as burn does for a state it cannot
    /// rebuild) when a leaf is missing or damaged: not of rank `D`, not floating point, or
    /// the two moments of different shapes. `Tensor::from_data` would panic on those.
    fn state_unflatten(prefix: &str, src: &mut StateSource, device: &Device) -> Option<Self> {
        let time = u64::try_from(src.take_scalar(prefix, "time")?).ok()? as usize;
        // Keep the stored precision (an f64 parameter has an f64 state).
        let load = |data: burn::tensor::TensorData| {
            let dtype = data.dtype();
            (data.rank() == D && dtype.is_float()).then(|| Tensor::from_data(data, (device, dtype)))
        };
        let moment: Tensor<D> = load(src.take_tensor(prefix, "moment")?)?;
        let inf_norm: Tensor<D> = load(src.take_tensor(prefix, "inf_norm")?)?;
        if moment.dims() != inf_norm.dims() {
            return None;
        }
        Some(AdamaxState {
            time,
            moment,
            inf_norm,
        })
    }
}

impl Optimizer for Adamax {
    type State<const D: usize> = AdamaxState<D>;

    fn step<const D: usize>(
        &self,
        lr: LearningRate,
        tensor: Tensor<D>,
        grad: Tensor<D>,
        state: Option<Self::State<D>>,
    ) -> (Tensor<D>, Option<Self::State<D>>) {
        if is_flex(&tensor.device()) {
            match tensor.dtype() {
                DType::F32 | DType::F64 => return self.step_flex(lr, tensor, grad, state),
                _ => {}
            }
        }
        self.step_tensors(lr, tensor, grad, state)
    }

    fn to_device<const D: usize>(state: Self::State<D>, device: &Device) -> Self::State<D> {
        AdamaxState {
            time: state.time,
            moment: state.moment.to_device(device),
            inf_norm: state.inf_norm.to_device(device),
        }
    }
}

impl Adamax {
    /// The update as burn tensor operations, for any backend.
    fn step_tensors<const D: usize>(
        &self,
        lr: LearningRate,
        tensor: Tensor<D>,
        grad: Tensor<D>,
        state: Option<AdamaxState<D>>,
    ) -> (Tensor<D>, Option<AdamaxState<D>>) {
        let grad = if self.weight_decay != 0.0 {
            grad + tensor.clone().mul_scalar(self.weight_decay)
        } else {
            grad
        };
        let floor = grad.clone().abs().add_scalar(self.epsilon);
        let (time, moment, inf_norm) = match state {
            Some(s) => (
                s.time + 1,
                s.moment.mul_scalar(self.beta_1) + grad.mul_scalar(1.0 - self.beta_1),
                s.inf_norm.mul_scalar(self.beta_2).max_pair(floor),
            ),
            None => (1, grad.mul_scalar(1.0 - self.beta_1), floor),
        };
        let step_size = lr / (1.0 - self.beta_1.powi(time as i32));
        let delta = moment.clone().div(inf_norm.clone()).mul_scalar(step_size);
        (
            tensor - delta,
            Some(AdamaxState {
                time,
                moment,
                inf_norm,
            }),
        )
    }

    /// The same update in one pass on flex ([`AdamaxOps`]).
    fn step_flex<const D: usize>(
        &self,
        lr: LearningRate,
        tensor: Tensor<D>,
        grad: Tensor<D>,
        state: Option<AdamaxState<D>>,
    ) -> (Tensor<D>, Option<AdamaxState<D>>) {
        let (time, moments) = match state {
            Some(s) => (s.time + 1, Some((s.moment, s.inf_norm))),
            None => (1, None),
        };
        let scalars = Scalars {
            step_size: lr / (1.0 - self.beta_1.powi(time as i32)),
            beta_1: self.beta_1,
            beta_2: self.beta_2,
            epsilon: self.epsilon,
            weight_decay: self.weight_decay,
        };
        let fresh = moments.is_none();
        // A first step reads no state: θ stands in for both moments.
        let (moment, inf_norm) = moments.unwrap_or_else(|| (tensor.clone(), tensor.clone()));
        let (theta, moment, inf_norm) = <Dispatch as AdamaxOps>::adamax_update(
            tensor.into_dispatch(),
            grad.into_dispatch(),
            moment.into_dispatch(),
            inf_norm.into_dispatch(),
            scalars,
            fresh,
        );
        (
            Tensor::from_dispatch(theta),
            Some(AdamaxState {
                time,
                moment: Tensor::from_dispatch(moment),
                inf_norm: Tensor::from_dispatch(inf_norm),
            }),
        )
    }
}

/// The scalars of one update: the bias-corrected step `lr / (1 − β₁ᵗ)` and the
/// configuration.
#[derive(Clone, Copy, Debug)]
pub struct Scalars {
    step_size: f64,
    beta_1: f64,
    beta_2: f64,
    epsilon: f64,
    weight_decay: f64,
}

/// The backend extension: one Adamax update of one parameter as a single pass.
///
/// Why: as tensor operations the update is nine element-wise passes per parameter, each
/// with its own allocation and thread dispatch; on the `cpu` preset's Multilevel that was
/// 13.7 ms of a 150 ms training step (docs/benchmarks.md). The pass reads θ, g and the
/// state where they lie, without copying them out first, and writes in place when
/// nothing else holds them, else new buffers (the trainer's rollback snapshot holds the
/// previous θ and state). A pass over copies taken with `into_data`, with the branches
/// of the weight decay and the first step inside its loop (scalar code), took 12.6 ms of
/// a step; this one 6.4 ms.
#[backend_extension(Flex)]
pub trait AdamaxOps: Backend {
    /// `(θ', m', u')` from `(θ, g, m, u)`; with `fresh`, `m` and `u` are not read.
    ///
    /// Low level: shapes are not checked and only f32/f64 tensors are supported; called
    /// by [`Adamax`] on flex.
    fn adamax_update(
        theta: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        moment: FloatTensor<Self>,
        inf_norm: FloatTensor<Self>,
        scalars: Scalars,
        fresh: bool,
    ) -> (FloatTensor<Self>, FloatTensor<Self>, FloatTensor<Self>);
}

impl AdamaxOps for Flex {
    fn adamax_update(
        theta: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        moment: FloatTensor<Self>,
        inf_norm: FloatTensor<Self>,
        scalars: Scalars,
        fresh: bool,
    ) -> (FloatTensor<Self>, FloatTensor<Self>, FloatTensor<Self>) {
        let [theta, grad, moment, inf_norm] = [theta, grad, moment, inf_norm].map(contiguous);
        match theta.dtype() {
            DType::F64 => update::<f64>(theta, &grad, moment, inf_norm, scalars, fresh),
            DType::F32 => update::<f32>(theta, &grad, moment, inf_norm, scalars, fresh),
            other => panic!("the one-pass Adamax supports f32 and f64 tensors, got {other:?}"),
        }
    }
}

/// [`Scalars`] in the parameter's precision.
#[derive(Clone, Copy)]
struct Constants<T> {
    beta_1: T,
    beta_2: T,
    one_minus_beta_1: T,
    epsilon: T,
    weight_decay: T,
    step_size: T,
}

/// One element: `(θ', m', u')` from `(θ, g, m, u)`, with the same `T` operations in the
/// same order as [`Adamax::step_tensors`], so the two agree bit for bit (a test checks
/// it). With `FRESH`, `m` and `u` are not read. The two flags are constants so that the
/// loops over elements have no branch left to stop them vectorising.
#[inline(always)]
fn element<T: Real, const FRESH: bool, const DECAY: bool>(
    c: &Constants<T>,
    theta: T,
    grad: T,
    m: T,
    u: T,
) -> [T; 3] {
    let g = if DECAY {
        grad + theta * c.weight_decay
    } else {
        grad
    };
    let magnitude = if g < T::ZERO { T::ZERO - g } else { g };
    let floor = magnitude + c.epsilon;
    let (m, u) = if FRESH {
        (g * c.one_minus_beta_1, floor)
    } else {
        let m = m * c.beta_1 + g * c.one_minus_beta_1;
        let decayed = u * c.beta_2;
        (m, if floor > decayed { floor } else { decayed })
    };
    [theta - m / u * c.step_size, m, u]
}

/// The update of [`AdamaxOps`]: in place where θ and its state are not shared, else into
/// new buffers (the trainer's rollback snapshot shares them on the steps it is taken).
fn update<T: Real>(
    mut theta: FlexTensor,
    grad: &FlexTensor,
    mut moment: FlexTensor,
    mut inf_norm: FlexTensor,
    s: Scalars,
    fresh: bool,
) -> (FlexTensor, FlexTensor, FlexTensor) {
    let c = Constants {
        beta_1: T::from_f64(s.beta_1),
        beta_2: T::from_f64(s.beta_2),
        one_minus_beta_1: T::from_f64(1.0 - s.beta_1),
        epsilon: T::from_f64(s.epsilon),
        weight_decay: T::from_f64(s.weight_decay),
        step_size: T::from_f64(s.step_size),
    };
    let decay = s.weight_decay != 0.0;
    let n = theta.layout().num_elements();
    let grad = &elements::<T>(grad)[..n];
    if !fresh {
        if let (Some(t), Some(m), Some(u)) = (
            theta.try_storage_mut::<T>(),
            moment.try_storage_mut::<T>(),
            inf_norm.try_storage_mut::<T>(),
        ) {
            let state = [&mut t[..n], &mut m[..n], &mut u[..n]];
            match decay {
                true => in_place::<T, true>(&c, grad, state),
                false => in_place::<T, false>(&c, grad, state),
            }
            return (theta, moment, inf_norm);
        }
    }
    let shape = theta.layout().shape().to_vec();
    let t = &elements::<T>(&theta)[..n];
    let (m, u) = if fresh {
        (t, t)
    } else {
        (&elements::<T>(&moment)[..n], &elements::<T>(&inf_norm)[..n])
    };
    // Outputs written once each, so not zeroed first (that pass cost 4 ms of a step).
    let mut out = [(); 3].map(|_| Vec::<T>::with_capacity(n));
    let spare = out.each_mut().map(|v| &mut v.spare_capacity_mut()[..n]);
    let state = [t, m, u];
    match (fresh, decay) {
        (true, true) => into_new::<T, true, true>(&c, grad, state, spare),
        (true, false) => into_new::<T, true, false>(&c, grad, state, spare),
        (false, true) => into_new::<T, false, true>(&c, grad, state, spare),
        (false, false) => into_new::<T, false, false>(&c, grad, state, spare),
    }
    let [t, m, u] = out.map(|mut v| {
        // SAFETY: `into_new` wrote all `n` elements of the spare capacity.
        unsafe { v.set_len(n) };
        from_vec(v, shape.clone())
    });
    (t, m, u)
}

// The pass is split into chunks of `CHUNK` over rayon's threads: it is memory-bound,
// and one core does not reach the memory bandwidth of two (on one thread the update of
// the `cpu` preset's 8.5 M parameters was 4.6 % of a training step's samples, with the
// other core idle; docs/benchmarks.md). Each element is updated alone, so the result
// does not depend on the split.

fn in_place<T: Real, const DECAY: bool>(c: &Constants<T>, grad: &[T], [t, m, u]: [&mut [T]; 3]) {
    let run = |grad: &[T], t: &mut [T], m: &mut [T], u: &mut [T]| {
        simd(|| {
            for i in 0..grad.len() {
                [t[i], m[i], u[i]] = element::<T, false, DECAY>(c, t[i], grad[i], m[i], u[i]);
            }
        })
    };
    if grad.len() <= CHUNK {
        return run(grad, t, m, u);
    }
    grad.par_chunks(CHUNK)
        .zip(t.par_chunks_mut(CHUNK))
        .zip(m.par_chunks_mut(CHUNK))
        .zip(u.par_chunks_mut(CHUNK))
        .for_each(|(((g, t), m), u)| run(g, t, m, u));
}

fn into_new<T: Real, const FRESH: bool, const DECAY: bool>(
    c: &Constants<T>,
    grad: &[T],
    [t, m, u]: [&[T]; 3],
    [t_out, m_out, u_out]: [&mut [MaybeUninit<T>]; 3],
) {
    let run =
        |grad: &[T], [t, m, u]: [&[T]; 3], [t_out, m_out, u_out]: [&mut [MaybeUninit<T>]; 3]| {
            simd(|| {
                for i in 0..grad.len() {
                    let [ti, mi, ui] = element::<T, FRESH, DECAY>(c, t[i], grad[i], m[i], u[i]);
                    t_out[i].write(ti);
                    m_out[i].write(mi);
                    u_out[i].write(ui);
                }
            })
        };
    if grad.len() <= CHUNK {
        return run(grad, [t, m, u], [t_out, m_out, u_out]);
    }
    grad.par_chunks(CHUNK)
        .zip(t.par_chunks(CHUNK))
        .zip(m.par_chunks(CHUNK))
        .zip(u.par_chunks(CHUNK))
        .zip(t_out.par_chunks_mut(CHUNK))
        .zip(m_out.par_chunks_mut(CHUNK))
        .zip(u_out.par_chunks_mut(CHUNK))
        .for_each(|((((((g, t), m), u), to), mo), uo)| run(g, [t, m, u], [to, mo, uo]));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::{cpu, cpu_autodiff};
    use burn::module::Module;
    use burn::nn::LinearConfig;
    use burn::optim::GradientsParams;
    use burn::tensor::{DType, TensorData};

    fn vec1(values: [f64; 2]) -> Tensor<1> {
        Tensor::from_data(TensorData::new(values.to_vec(), [2]), (&cpu(), DType::F64))
    }

    /// Three steps, lr 0.1, β = (0.9, 0.999), ε = 1e-8, worked by hand:
    /// 1. m = 0.1 g = (0.05, −0.1), u = |g| + ε = (0.5, 1.0), step lr / (1 − 0.9) = 1:
    ///    θ = (1 − 0.1, −2 + 0.1) up to ε.
    /// 2. m = (0.02, 0.11), u = (max(0.4995, 0.25), max(0.999, 2)) = (0.4995, 2),
    ///    step 0.1 / 0.19: θ = (0.9 − 0.02/0.4995/1.9, −1.9 − 0.11/2/1.9).
    /// 3. m = (0.118, 0.099), u = (1, 1.998), step 0.1 / 0.271.
    #[test]
    fn matches_the_hand_computed_sequence() {
        let adamax = AdamaxConfig::new().build();
        let mut theta = vec1([1.0, -2.0]);
        let mut state = None;
        let expected = [
            [0.900000002, -1.900000001],
            [0.8789262971372425, -1.9289473692763157],
            [0.8353838621483125, -1.947231335808346],
        ];
        for (g, want) in [[0.5, -1.0], [-0.25, 2.0], [1.0, 0.0]].iter().zip(expected) {
            let (next, s) = adamax.step(0.1, theta, vec1(*g), state);
            theta = next;
            state = s;
            let got = theta
                .to_data()
                .convert::<f64>()
                .try_into_vec::<f64>()
                .unwrap();
            for (a, b) in got.iter().zip(want) {
                assert!((a - b).abs() < 1e-12, "{a} vs {b}");
            }
        }
        let s = state.unwrap();
        assert_eq!(s.time, 3);
        // The state survives flattening and rebuilding.
        let mut sink = StateSink::default();
        s.state_flatten("p", &mut sink);
        let mut src = StateSource::new(sink.scalars.into_iter().collect());
        for (name, data) in sink.tensors {
            src.insert_tensor(name, data);
        }
        let back = AdamaxState::<1>::state_unflatten("p", &mut src, &cpu()).unwrap();
        assert_eq!(back.time, 3);
        back.moment
            .into_data()
            .assert_eq(&s.moment.into_data(), true);
    }

    /// flex's one-pass update equals the tensor operations bit for bit, state included,
    /// over several steps, with and without weight decay, in f32 and f64, on a parameter
    /// that the pass splits into parallel chunks.
    #[test]
    fn host_update_equals_the_tensor_update() {
        let mut rng = crate::testutil::Rng::new(11);
        // One thread's size, and three parallel chunks and a part of one.
        for (n, dtype, decay) in [
            (185, DType::F32, 0.0),
            (185, DType::F32, 0.01),
            (185, DType::F64, 0.01),
            (CHUNK * 3 + 5, DType::F32, 0.0),
            (CHUNK * 3 + 5, DType::F64, 0.01),
        ] {
            let adamax = AdamaxConfig::new().with_weight_decay(decay).build();
            let mut random = |zeros: bool| -> Tensor<2> {
                let mut v = rng.values(n);
                if zeros {
                    v[3] = 0.0;
                    v[n - 40] = -0.0;
                }
                crate::testutil::tensor(v, [n, 1], &cpu(), dtype)
            };
            let (mut host_theta, mut host_state) = (random(false), None);
            let (mut plain_theta, mut plain_state) = (host_theta.clone(), None);
            for step in 0..4 {
                let grad = random(step == 1);
                let lr = 0.003 * (step + 1) as f64;
                // On flex, `step` takes the one-pass update: in place where θ and the
                // state are not shared, else into new buffers (step 2 shares them).
                let kept = (step == 2).then(|| (host_theta.clone(), host_state.clone()));
                let before = kept.as_ref().map(|(t, s)| {
                    let s: &AdamaxState<2> = s.as_ref().expect("a state after two steps");
                    [t.to_data(), s.moment.to_data(), s.inf_norm.to_data()]
                });
                (host_theta, host_state) = adamax.step(lr, host_theta, grad.clone(), host_state);
                (plain_theta, plain_state) =
                    adamax.step_tensors(lr, plain_theta, grad, plain_state);
                if let (Some((theta, state)), Some([t, m, u])) = (kept, before) {
                    // The shared buffers are left as they were.
                    let state = state.expect("a state after two steps");
                    theta.into_data().assert_eq(&t, true);
                    state.moment.into_data().assert_eq(&m, true);
                    state.inf_norm.into_data().assert_eq(&u, true);
                }
            }
            let (h, p) = (host_state.unwrap(), plain_state.unwrap());
            assert_eq!((h.time, host_theta.dtype()), (p.time, dtype));
            host_theta
                .into_data()
                .assert_eq(&plain_theta.into_data(), true);
            h.moment.into_data().assert_eq(&p.moment.into_data(), true);
            h.inf_norm
                .into_data()
                .assert_eq(&p.inf_norm.into_data(), true);
        }
    }

    /// A damaged record (a moment of another rank, an integer moment, moments of two
    /// shapes) rebuilds no state instead of panicking in `Tensor::from_data` (found by
    /// fuzzing checkpoints, docs/fuzzing.md).
    #[test]
    fn damaged_states_are_not_rebuilt() {
        let source = |moment: TensorData, inf_norm: TensorData| {
            let mut src = StateSource::new([("p.time".to_string(), 3u64.into())].into());
            src.insert_tensor("p.moment".into(), moment);
            src.insert_tensor("p.inf_norm".into(), inf_norm);
            src
        };
        let good = || TensorData::new(vec![1.0f32, 2.0], [2]);
        let mut src = source(good(), good());
        assert!(AdamaxState::<1>::state_unflatten("p", &mut src, &cpu()).is_some());
        for (moment, inf_norm) in [
            (TensorData::new(vec![1.0f32, 2.0], [1, 2]), good()),
            (good(), TensorData::new(vec![1.0f32, 2.0], [1, 2])),
            (TensorData::new(vec![1i32, 2], [2]), good()),
            (good(), TensorData::new(vec![true, false], [2])),
            (good(), TensorData::new(vec![1.0f32, 2.0, 3.0], [3])),
        ] {
            let mut src = source(moment, inf_norm);
            assert!(AdamaxState::<1>::state_unflatten("p", &mut src, &cpu()).is_none());
        }
    }

    /// On a module, the first step moves every parameter by `−lr · sign(g)`.
    #[test]
    fn first_module_step_is_a_sign_step() {
        let device = cpu_autodiff();
        let model = LinearConfig::new(3, 2).init(&device);
        let before = model
            .weight
            .val()
            .to_data()
            .convert::<f64>()
            .try_into_vec::<f64>()
            .unwrap();
        let x = Tensor::<2>::from_data([[1.0, -2.0, 0.5]], &device);
        let grads = model.forward(x).sum().backward();
        let grads = GradientsParams::from_grads(grads, &model);
        let mut optim = AdamaxConfig::new().init();
        let model = optim.step(0.01, model, grads);
        let after = model
            .weight
            .val()
            .to_data()
            .convert::<f64>()
            .try_into_vec::<f64>()
            .unwrap();
        // ∂L/∂W[i][j] = x[i], so row i moves by −0.01 · sign(x[i]).
        for (k, (b, a)) in before.iter().zip(&after).enumerate() {
            let sign = [1.0, -1.0, 1.0][k / 2];
            assert!((b - a - 0.01 * sign).abs() < 1e-6, "{b} {a}");
        }
        assert_eq!(model.num_params(), 8);
    }
}
