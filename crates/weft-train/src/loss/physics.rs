//! The physics loss terms of seed 000 (supplement eq. 4–8: collision, gravity, stretch,
//! shear) as one custom burn autodiff operation whose value and gradient come from
//! weft-sim's energies, the same code the simulator minimises.
//!
//! Why a custom operation: the energies are f64 host code with exact, finite-difference
//! checked gradients (`weft_sim::penalties`). Writing them again as burn tensor
//! expressions would give a second, untested copy of every formula (and a much longer
//! autodiff graph: the stretch term alone is a 3×2 deformation gradient, two norms and a
//! product per face). Instead the prediction crosses to f64 at one boundary, the energy
//! is evaluated there, and its gradient comes back as the operation's backward.
//!
//! - [`EnergyOps`]: the burn backend extension (flex, and autodiff over flex with the
//!   hand-written backward [`EnergyBackward`]), as weft-nn registers its fused GAT.
//! - [`physics_loss`]: the public entry point; checks shapes, routes to the extension on
//!   flex, and on other devices to [`PhysicsImpl::Reference`], an exact surrogate
//!   `E(x̄) + ⟨∇E(x̄), x − x̄⟩` (x̄ the detached value) whose value and first derivative
//!   equal the energy's; the tests compare the two paths.
//!
//! The value is the mean over the frames of a window: `(1/T) Σ_t E_t(x_t)`, so a term's
//! weight does not depend on the window length.

use std::fmt;
use std::sync::Arc;

use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::CheckpointStrategy;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::autodiff::Autodiff;
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{backend_extension, Backend, Dispatch, Flex};
use burn::tensor::{DType, Tensor, TensorData};
use rayon::prelude::*;
use weft_sim::{BlockCsr, Energy, HessianKind, IncrementalPotential, SimError};

use crate::error::{Result, TrainError};

/// An energy per frame of a window of `T` frames over `N` garment vertices.
///
/// Frame-independent terms (gravity, stretch, shear) share one energy for all frames;
/// collision has one per frame (contacts with that frame's posed body).
#[derive(Clone)]
pub struct FrameEnergies {
    name: &'static str,
    vertex_count: usize,
    frames: Vec<Arc<dyn Energy + Send + Sync>>,
}

impl fmt::Debug for FrameEnergies {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FrameEnergies")
            .field("name", &self.name)
            .field("vertex_count", &self.vertex_count)
            .field("frames", &self.frames.len())
            .finish()
    }
}

impl FrameEnergies {
    /// One energy for each frame; errors when there are none or their vertex counts
    /// differ.
    pub fn per_frame(frames: Vec<Arc<dyn Energy + Send + Sync>>) -> Result<Self> {
        let first = frames.first().ok_or_else(|| TrainError::Shape {
            what: "physics loss frames".into(),
            expected: "at least one frame".into(),
            found: "none".into(),
        })?;
        let (name, vertex_count) = (first.name(), first.vertex_count());
        if let Some(e) = frames.iter().find(|e| e.vertex_count() != vertex_count) {
            return Err(TrainError::Shape {
                what: format!("physics loss `{name}` frames"),
                expected: format!("{vertex_count} vertices in every frame"),
                found: format!("{} in one", e.vertex_count()),
            });
        }
        Ok(FrameEnergies {
            name,
            vertex_count,
            frames,
        })
    }

    /// The same energy for `frames` frames.
    pub fn shared(energy: Arc<dyn Energy + Send + Sync>, frames: usize) -> Result<Self> {
        Self::per_frame(vec![energy; frames])
    }

    /// The energy's name (for logs).
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Frames `T`.
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// Vertices `N` per frame.
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// The energy of frame `t`.
    pub fn frame(&self, t: usize) -> Option<&Arc<dyn Energy + Send + Sync>> {
        self.frames.get(t)
    }

    /// `(1/T) Σ_t E_t(x_t)` for `x` holding `T·N` positions, frame-major.
    pub fn value(&self, x: &[[f64; 3]]) -> Result<f64> {
        self.check(x.len())?;
        let values: Vec<f64> = self
            .frames
            .par_iter()
            .zip(x.par_chunks(self.vertex_count))
            .map(|(e, xt)| e.value(xt))
            .collect::<Result<_, _>>()?;
        // Summed in frame order whatever the thread count: deterministic.
        Ok(values.iter().sum::<f64>() / self.frames.len() as f64)
    }

    /// The value and `scale · ∇` of [`Self::value`] (a `T·N` gradient).
    pub fn gradient(&self, x: &[[f64; 3]], scale: f64) -> Result<(f64, Vec<[f64; 3]>)> {
        self.check(x.len())?;
        let t = self.frames.len() as f64;
        let mut grad = vec![[0.0; 3]; x.len()];
        let values: Vec<f64> = self
            .frames
            .par_iter()
            .zip(x.par_chunks(self.vertex_count))
            .zip(grad.par_chunks_mut(self.vertex_count))
            .map(|((e, xt), gt)| e.add_gradient(xt, scale / t, gt))
            .collect::<Result<_, _>>()?;
        Ok((values.iter().sum::<f64>() / t, grad))
    }

    fn check(&self, len: usize) -> Result<()> {
        let want = self.frames.len() * self.vertex_count;
        if len != want {
            return Err(TrainError::Shape {
                what: format!("physics loss `{}` positions", self.name),
                expected: format!(
                    "{} frames × {} vertices = {want}",
                    self.frames.len(),
                    self.vertex_count
                ),
                found: len.to_string(),
            });
        }
        Ok(())
    }
}

/// Term `index` of a shared incremental potential, with its weight, as an energy of its
/// own: a task builds a step's potential once (seed 004 eq. 5) and still logs each of its
/// terms, whose sum is the potential.
pub struct PotentialTerm {
    potential: Arc<IncrementalPotential>,
    index: usize,
}

impl PotentialTerm {
    /// Every term of `potential`, in its order.
    pub fn all(potential: IncrementalPotential) -> Vec<Arc<dyn Energy + Send + Sync>> {
        let potential = Arc::new(potential);
        (0..potential.terms().len())
            .map(|index| {
                Arc::new(PotentialTerm {
                    potential: potential.clone(),
                    index,
                }) as Arc<dyn Energy + Send + Sync>
            })
            .collect()
    }

    fn weighted(&self) -> (f64, &dyn Energy) {
        let t = &self.potential.terms()[self.index];
        (t.weight, t.term.energy())
    }
}

impl Energy for PotentialTerm {
    fn name(&self) -> &'static str {
        self.weighted().1.name()
    }

    fn vertex_count(&self) -> usize {
        self.potential.vertex_count()
    }

    fn value(&self, x: &[[f64; 3]]) -> std::result::Result<f64, SimError> {
        let (w, e) = self.weighted();
        Ok(w * e.value(x)?)
    }

    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> std::result::Result<f64, SimError> {
        let (w, e) = self.weighted();
        Ok(w * e.add_gradient(x, scale * w, grad)?)
    }

    fn add_hessian(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        kind: HessianKind,
        hess: &mut BlockCsr,
    ) -> std::result::Result<(), SimError> {
        let (w, e) = self.weighted();
        e.add_hessian(x, scale * w, kind, hess)
    }

    fn for_each_stencil(&self, kind: HessianKind, f: &mut dyn FnMut(&[u32])) {
        self.weighted().1.for_each_stencil(kind, f)
    }
}

/// Which implementation [`physics_loss`] runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PhysicsImpl {
    /// The custom operation on flex, the reference surrogate elsewhere.
    #[default]
    Auto,
    /// `E(x̄) + ⟨∇E(x̄), x − x̄⟩` with burn ops (any device).
    Reference,
}

/// The backend extension: one operation, an energy of the positions.
#[backend_extension(Flex, Autodiff)]
pub trait EnergyOps: Backend {
    /// `[1]` tensor holding `energy.value(x)` for `x` of shape `[T, N, 3]` (any float
    /// dtype the flex backend stores as f32 or f64).
    ///
    /// Low level: shapes are not checked here; call [`physics_loss`].
    fn energy_value(x: FloatTensor<Self>, energy: Arc<FrameEnergies>) -> FloatTensor<Self>;
}

/// Positions of a contiguous flex tensor as f64 triples.
fn positions(x: &FlexTensor) -> Vec<[f64; 3]> {
    match x.dtype() {
        DType::F64 => triples(x.as_slice::<f64>().expect("f64 positions"), |v| v),
        DType::F32 => triples(x.as_slice::<f32>().expect("f32 positions"), f64::from),
        other => panic!("physics loss supports f32 and f64 tensors, got {other:?}"),
    }
}

fn triples<T: Copy>(v: &[T], f: impl Fn(T) -> f64) -> Vec<[f64; 3]> {
    v.chunks_exact(3)
        .map(|c| [f(c[0]), f(c[1]), f(c[2])])
        .collect()
}

/// A flex tensor of `dtype` from f64 values.
fn flex_from(values: Vec<f64>, shape: Vec<usize>, dtype: DType) -> FlexTensor {
    match dtype {
        DType::F64 => FlexTensor::from_data(TensorData::new(values, shape)),
        _ => FlexTensor::from_data(TensorData::new(
            values.into_iter().map(|v| v as f32).collect::<Vec<f32>>(),
            shape,
        )),
    }
}

fn contiguous(t: FlexTensor) -> FlexTensor {
    if t.is_contiguous() && t.layout().start_offset() == 0 {
        t
    } else {
        t.to_contiguous()
    }
}

/// The value, or NaN when the energy rejects the positions (the shapes were checked by
/// [`physics_loss`], so only non-finite input gets here; the trainer's non-finite guard
/// then skips the step).
fn value_or_nan(energy: &FrameEnergies, x: &[[f64; 3]]) -> f64 {
    energy.value(x).unwrap_or(f64::NAN)
}

impl EnergyOps for Flex {
    fn energy_value(x: FloatTensor<Self>, energy: Arc<FrameEnergies>) -> FloatTensor<Self> {
        let x = contiguous(x);
        let v = value_or_nan(&energy, &positions(&x));
        flex_from(vec![v], vec![1], x.dtype())
    }
}

/// The autodiff step of [`EnergyOps::energy_value`] (one parent, the positions).
#[derive(Debug)]
pub(crate) struct EnergyBackward;

/// What the forward pass keeps for [`EnergyBackward`].
#[derive(Clone, Debug)]
pub(crate) struct EnergyState {
    x: FlexTensor,
    energy: Arc<FrameEnergies>,
}

impl Backward<Flex, 1> for EnergyBackward {
    type State = EnergyState;

    fn backward(self, ops: Ops<EnergyState, 1>, grads: &mut Gradients, _: &mut Checkpointer) {
        let [node_x] = ops.parents;
        let upstream = contiguous(grads.consume::<Flex>(&ops.node));
        let Some(node) = node_x else { return };
        let st = ops.state;
        // The upstream gradient of the [1] output: one value.
        let scale = match upstream.dtype() {
            DType::F64 => upstream.as_slice::<f64>().map(|s| s[0]),
            _ => upstream.as_slice::<f32>().map(|s| f64::from(s[0])),
        }
        .unwrap_or(f64::NAN);
        let x = positions(&st.x);
        let grad = match st.energy.gradient(&x, scale) {
            Ok((_, grad)) => grad.into_iter().flatten().collect(),
            Err(_) => vec![f64::NAN; x.len() * 3],
        };
        let shape = st.x.layout().shape().to_vec();
        grads.register::<Flex>(node.id, flex_from(grad, shape, st.x.dtype()));
    }
}

impl<C: CheckpointStrategy> EnergyOps for Autodiff<Flex, C> {
    fn energy_value(x: FloatTensor<Self>, energy: Arc<FrameEnergies>) -> FloatTensor<Self> {
        match EnergyBackward
            .prepare::<C>([x.node()])
            .compute_bound()
            .stateful()
        {
            OpsKind::Tracked(prep) => {
                let xp = contiguous(x.into_primitive());
                let v = value_or_nan(&energy, &positions(&xp));
                let out = flex_from(vec![v], vec![1], xp.dtype());
                prep.finish(EnergyState { x: xp, energy }, out)
            }
            OpsKind::UnTracked(prep) => prep.finish(<Flex as EnergyOps>::energy_value(
                x.into_primitive(),
                energy,
            )),
        }
    }
}

/// The physics loss `(1/T) Σ_t E_t(x_t)` of a window of predicted positions `x`
/// (`[T, N, 3]`), as a `[1]` tensor with the gradient of the energy.
///
/// Errors when `x` does not have the frames and vertices of `energy`.
pub fn physics_loss(
    x: Tensor<3>,
    energy: &Arc<FrameEnergies>,
    implementation: PhysicsImpl,
) -> Result<Tensor<1>> {
    let dims = x.dims();
    if dims != [energy.frame_count(), energy.vertex_count(), 3] {
        return Err(TrainError::Shape {
            what: format!("physics loss `{}` input", energy.name()),
            expected: format!("[{}, {}, 3]", energy.frame_count(), energy.vertex_count()),
            found: format!("{dims:?}"),
        });
    }
    let dtype = x.dtype();
    if implementation == PhysicsImpl::Auto
        && matches!(dtype, DType::F32 | DType::F64)
        && weft_nn::backend::is_flex(&x.device())
    {
        return Ok(Tensor::from_dispatch(
            <Dispatch as EnergyOps>::energy_value(x.into_dispatch(), energy.clone()),
        ));
    }
    reference(x, energy)
}

/// The surrogate `E(x̄) + ⟨∇E(x̄), x − x̄⟩`: equal to the energy in value and gradient at
/// `x = x̄`, built from burn ops so it runs on any device.
fn reference(x: Tensor<3>, energy: &FrameEnergies) -> Result<Tensor<1>> {
    let device = x.device();
    let dtype = x.dtype();
    let host: Vec<f64> = x
        .to_data()
        .convert::<f64>()
        .try_into_vec::<f64>()
        .map_err(|source| TrainError::Tensor {
            what: "the physics loss' positions",
            source,
        })?;
    let xs = triples(&host, |v| v);
    let (value, grad) = match energy.gradient(&xs, 1.0) {
        Ok(vg) => vg,
        Err(_) => (f64::NAN, vec![[f64::NAN; 3]; xs.len()]),
    };
    let g = Tensor::<3>::from_data(
        TensorData::new(grad.into_iter().flatten().collect::<Vec<f64>>(), x.dims()),
        (&device, dtype),
    );
    let linear = (x.clone() - x.detach()) * g;
    Ok(linear.sum().add_scalar(value))
}
