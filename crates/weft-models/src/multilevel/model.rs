//! The Multilevel model (seed 000 §3.2–3.3): garment–body encoding once per pair, then per
//! frame the temporal skinning weights `Wᵗ`, blend shapes `Bᵗ` and linear blend skinning.
//!
//! Pair encoding ([`Multilevel::encode_pair`], eq. 4–5):
//! `X^gg = E^gg(X)` (GAT blocks, heads averaged, ReLU);
//! `X̂^gg = GAT(X^gg ⊙ E^gs(λ))` (S heads of F channels, concatenated: `[N, S, F]`);
//! `X^fuse = X̂^gg ⊙ E^bs(Dᵀ)` (`E^bs` maps each joint's row of distances to F numbers).
//!
//! Per window of `T` frames ([`Multilevel::forward`], eq. 6–8, 2–3):
//! `Wᵗ = softmax_S(ln(w_transfer + ε) + g_W · X^fuse ⊗ E^t1(Θᵗ))` — the prior term is this
//! implementation's (config `weight_prior`, docs/multilevel.md: the untrained model skins
//! like the LBS baseline and learns a correction);
//! `Bᵗ = Σ_submodules M^mp(X^fuse ⊙ E^t2(Vᵗ))` (with `body_contact`, each submodule's
//! embedding also reads the body contact of every vertex, [`super::contact`]);
//! `Mᵗ = Σ_j Wᵗ_j A_j(θ_t) (T + Bᵗ)`.

use burn::module::{Module, ModuleVisitor, Param};
use burn::tensor::activation::softmax;
use burn::tensor::{Device, Tensor, TensorData};
use weft_nn::{
    Activation, GatBlock, GatBlockConfig, HeadMerge, LstmEncoder, LstmEncoderConfig, Mlp, MlpConfig,
};

use super::config::MultilevelConfig;
use super::contact::CONTACT_FEATURES;
use super::frames::{FrameInputs, POSE_FEATURES};
use super::garment::GarmentInput;
use super::mp::MpSubmodule;
use crate::error::ModelError;

/// `ε` of the skinning-weight prior `ln(w_transfer + ε)`: joints the transfer gives no
/// weight start at `ε`, small but with a gradient.
pub const PRIOR_EPSILON: f32 = 1e-4;

/// The Multilevel model; see the module documentation.
#[derive(Module, Debug)]
pub struct Multilevel {
    /// E^gg: GAT blocks before the style fusion.
    pub gg: Vec<GatBlock>,
    /// E^gg's last block, on `X^gg ⊙ C^gs`: S heads of F channels, concatenated.
    pub gg_fuse: GatBlock,
    /// E^gs: Nyström eigenvalues → style cues (width of the last E^gg block).
    pub gs: Mlp,
    /// E^bs: one joint's body distances → F.
    pub bs: Mlp,
    /// E^t1: pose history → F.
    pub t1: LstmEncoder,
    /// E^t2: body-vertex velocities → F·S.
    pub t2: LstmEncoder,
    /// M^mp submodules; their blend shapes add up.
    pub mp: Vec<MpSubmodule>,
    /// Gain of the learned skinning-weight logits.
    pub weight_gain: Param<Tensor<1>>,
    #[module(skip)]
    config: MultilevelConfig,
}

/// The garment–body encoding `X^fuse` of one pair, `[N, S·F]` (joint-major), computed
/// once per pair and reused for every frame.
#[derive(Clone, Debug)]
pub struct PairEncoding {
    /// `X^fuse`.
    pub fused: Tensor<2>,
}

/// The model's output for a window of `T` frames.
#[derive(Clone, Debug)]
pub struct Prediction {
    /// Skinned garment vertices `[T, N, 3]` (metres, world frame).
    pub vertices: Tensor<3>,
    /// Skinning weights `Wᵗ`, `[T, N, S]`, rows summing to one.
    pub weights: Tensor<3>,
    /// Blend shapes `Bᵗ` (rest-pose offsets), `[T, N, 3]`, all submodules summed.
    pub blend: Tensor<3>,
}

/// Draws every lazily initialised parameter.
struct Materialise;

impl ModuleVisitor for Materialise {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
        let _ = param.val();
    }
}

/// Rows × cols host data as a tensor on `device`.
fn tensor2(data: &[f32], shape: [usize; 2], device: &Device) -> Tensor<2> {
    Tensor::from_data(TensorData::new(data.to_vec(), shape), device)
}

fn tensor3(data: &[f32], shape: [usize; 3], device: &Device) -> Tensor<3> {
    Tensor::from_data(TensorData::new(data.to_vec(), shape), device)
}

impl Multilevel {
    /// Builds the model with fresh parameters on `device` (Glorot for GAT blocks, Kaiming
    /// for linear and LSTM layers; seed the device with `weft_nn::backend::seeded`).
    pub fn new(cfg: &MultilevelConfig, device: &Device) -> Result<Self, ModelError> {
        cfg.validate()?;
        let (s, f) = (cfg.joints, cfg.feature_width);
        let mut gg = Vec::with_capacity(cfg.gg_widths.len());
        let mut d = cfg.node_features();
        for &w in &cfg.gg_widths {
            gg.push(
                GatBlockConfig::new(d, w)
                    .with_heads(cfg.gg_heads)
                    .with_merge(HeadMerge::Mean)
                    .with_activation(Activation::Relu)
                    .with_negative_slope(cfg.negative_slope)
                    .init(device)?,
            );
            d = w;
        }
        let gg_fuse = GatBlockConfig::new(d, f)
            .with_heads(s)
            .with_merge(HeadMerge::Concat)
            .with_activation(Activation::Relu)
            .with_negative_slope(cfg.negative_slope)
            .init(device)?;
        let mlp = |d_in: usize, hidden: &[usize], out: usize| {
            let mut widths = hidden.to_vec();
            widths.push(out);
            MlpConfig::new(d_in, widths).init(device)
        };
        let gs = mlp(cfg.nystrom_landmarks, &cfg.gs_hidden, d)?;
        let bs = mlp(cfg.body_samples, &cfg.bs_hidden, f)?;
        let t1 = LstmEncoderConfig::new(POSE_FEATURES, f)
            .with_layers(cfg.t1_layers)
            .init(device)?;
        let t2 = LstmEncoderConfig::new(3 * cfg.body_samples, cfg.fused_width())
            .with_layers(cfg.t2_layers)
            .init(device)?;
        let mp = (0..cfg.mp_submodules)
            .map(|_| MpSubmodule::new(cfg, device))
            .collect::<Result<Vec<_>, _>>()?;
        let weight_gain =
            Param::from_tensor(Tensor::<1>::from_floats([cfg.weight_gain as f32], device));
        let model = Multilevel {
            gg,
            gg_fuse,
            gs,
            bs,
            t1,
            t2,
            mp,
            weight_gain,
            config: cfg.clone(),
        };
        // burn initialises parameters lazily, on first use, from the device's shared
        // generator: drawing them all now makes the model a function of the seed alone,
        // whatever else draws from the generator later (other models, other threads).
        model.visit(&mut Materialise);
        Ok(model)
    }

    /// The configuration the model was built from.
    pub fn config(&self) -> &MultilevelConfig {
        &self.config
    }

    /// The device the parameters live on.
    pub fn device(&self) -> Device {
        self.weight_gain.val().device()
    }

    fn check_garment(&self, g: &GarmentInput) -> Result<(), ModelError> {
        let cfg = &self.config;
        if g.joint_count() != cfg.joints {
            return Err(ModelError::mismatch(
                "garment input joints (config joints)",
                cfg.joints,
                g.joint_count(),
            ));
        }
        if g.node_feature_width() != cfg.node_features() {
            return Err(ModelError::mismatch(
                "garment node features (6 + joints)",
                cfg.node_features(),
                g.node_feature_width(),
            ));
        }
        if g.eigenvalues.len() != cfg.nystrom_landmarks {
            return Err(ModelError::mismatch(
                "garment style eigenvalues (config nystrom_landmarks)",
                cfg.nystrom_landmarks,
                g.eigenvalues.len(),
            ));
        }
        if g.body_sample_count() != cfg.body_samples {
            return Err(ModelError::mismatch(
                "body samples of the garment input (config body_samples)",
                cfg.body_samples,
                g.body_sample_count(),
            ));
        }
        Ok(())
    }

    /// `X^fuse` of a garment–body pair (eq. 4–5); compute once, reuse for every window.
    pub fn encode_pair(&self, g: &GarmentInput) -> Result<PairEncoding, ModelError> {
        let n = g.vertex_count();
        let x = tensor2(
            &g.node_features,
            [n, g.node_feature_width()],
            &self.device(),
        );
        self.encode_pair_features(g, x)
    }

    /// [`Self::encode_pair`] with the node features `X` given as a tensor (`[N, 6 + S]`)
    /// instead of `g.node_features`: attribution (seed 000 §4.1, eq. 9) differentiates the
    /// output with respect to `X` and evaluates it along a path of scaled features.
    pub fn encode_pair_features(
        &self,
        g: &GarmentInput,
        x: Tensor<2>,
    ) -> Result<PairEncoding, ModelError> {
        self.check_garment(g)?;
        let device = self.device();
        let cfg = &self.config;
        let n = g.vertex_count();
        if x.dims() != [n, cfg.node_features()] {
            return Err(ModelError::mismatch(
                "node feature tensor (garment vertices × (6 + joints))",
                format!("{:?}", [n, cfg.node_features()]),
                format!("{:?}", x.dims()),
            ));
        }
        let batch = g.frame_batch(1)?;
        let adjacency = batch.batch(0).adjacency();
        let mut x = x;
        for block in &self.gg {
            x = block.forward(x, adjacency)?;
        }
        let style =
            self.gs
                .forward(tensor2(&g.eigenvalues, [1, cfg.nystrom_landmarks], &device))?;
        let x = self.gg_fuse.forward(x * style, adjacency)?;
        let body = self.bs.forward(tensor2(
            &g.body_distances,
            [cfg.joints, cfg.body_samples],
            &device,
        ))?;
        let fused = x * body.reshape([1, cfg.fused_width()]);
        Ok(PairEncoding { fused })
    }

    fn check_frames(&self, g: &GarmentInput, f: &FrameInputs) -> Result<(), ModelError> {
        let cfg = &self.config;
        if f.joint_count() != cfg.joints {
            return Err(ModelError::mismatch(
                "frame transforms joints (config joints)",
                cfg.joints,
                f.joint_count(),
            ));
        }
        if f.history() != cfg.history {
            return Err(ModelError::mismatch(
                "frame history length (config history)",
                cfg.history,
                f.history(),
            ));
        }
        if f.body_sample_count() != cfg.body_samples {
            return Err(ModelError::mismatch(
                "body samples of the frame velocities (config body_samples)",
                cfg.body_samples,
                f.body_sample_count(),
            ));
        }
        if g.joint_count() != f.joint_count() {
            return Err(ModelError::mismatch(
                "frame joints (garment input joints)",
                g.joint_count(),
                f.joint_count(),
            ));
        }
        Ok(())
    }

    /// Skinning weights, blend shapes and skinned vertices of the frames of `f`.
    pub fn forward(
        &self,
        pair: &PairEncoding,
        g: &GarmentInput,
        f: &FrameInputs,
    ) -> Result<Prediction, ModelError> {
        let weights = self.skinning_weights(pair, g, f)?;
        let motion = self.motion_features(g, f)?;
        let contact = self.contact_features(g, f)?;
        let mut blend: Option<Tensor<2>> = None;
        for k in 0..self.mp.len() {
            let b = self.blend_submodule(k, pair, g, &motion, contact.as_ref())?;
            blend = Some(match blend {
                Some(acc) => acc + b,
                None => b,
            });
        }
        let (t, n) = (f.frame_count(), g.vertex_count());
        let blend = blend
            .ok_or_else(|| ModelError::Config("M^mp needs at least one submodule".into()))?
            .reshape([t, n, 3]);
        let vertices = self.skin(g, f, weights.clone(), blend.clone())?;
        Ok(Prediction {
            vertices,
            weights,
            blend,
        })
    }

    fn check_pair(&self, pair: &PairEncoding, g: &GarmentInput) -> Result<(), ModelError> {
        let expected = [g.vertex_count(), self.config.fused_width()];
        if pair.fused.dims() != expected {
            return Err(ModelError::mismatch(
                "pair encoding shape (garment vertices × F·S)",
                format!("{expected:?}"),
                format!("{:?}", pair.fused.dims()),
            ));
        }
        Ok(())
    }

    /// Stage of [`Self::forward`]: `Wᵗ` (eq. 6), `[T, N, S]`.
    pub fn skinning_weights(
        &self,
        pair: &PairEncoding,
        g: &GarmentInput,
        f: &FrameInputs,
    ) -> Result<Tensor<3>, ModelError> {
        self.check_garment(g)?;
        self.check_frames(g, f)?;
        self.check_pair(pair, g)?;
        let cfg = &self.config;
        let device = self.device();
        let (n, s, fw) = (g.vertex_count(), cfg.joints, cfg.feature_width);
        let (t, m) = (f.frame_count(), cfg.history);
        let (_, motion1) = self
            .t1
            .forward(tensor3(&f.poses, [t, m, POSE_FEATURES], &device))?;
        let logits = pair
            .fused
            .clone()
            .reshape([n * s, fw])
            .matmul(motion1.transpose())
            .reshape([n, s, t])
            .permute([2, 0, 1])
            * self.weight_gain.val().reshape([1, 1, 1]);
        let logits = if cfg.weight_prior {
            let prior: Vec<f32> = g
                .transfer_weights
                .iter()
                .map(|&w| (w + PRIOR_EPSILON).ln())
                .collect();
            logits + tensor2(&prior, [n, s], &device).unsqueeze_dim(0)
        } else {
            logits
        };
        Ok(softmax(logits, 2))
    }

    /// Stage of [`Self::forward`]: the E^t2 features of every frame, `[T, F·S]`.
    pub fn motion_features(
        &self,
        g: &GarmentInput,
        f: &FrameInputs,
    ) -> Result<Tensor<2>, ModelError> {
        self.check_garment(g)?;
        self.check_frames(g, f)?;
        let cfg = &self.config;
        let (t, m) = (f.frame_count(), cfg.history);
        let (_, motion2) = self.t2.forward(tensor3(
            &f.velocities,
            [t, m, 3 * cfg.body_samples],
            &self.device(),
        ))?;
        Ok(motion2)
    }

    /// Stage of [`Self::forward`]: the body contact of every frame and vertex,
    /// `[T·N, 4]`, with `body_contact` (`None` without).
    pub fn contact_features(
        &self,
        g: &GarmentInput,
        f: &FrameInputs,
    ) -> Result<Option<Tensor<2>>, ModelError> {
        let (t, n) = (f.frame_count(), g.vertex_count());
        match (&f.contact, self.config.body_contact) {
            (None, false) => Ok(None),
            (Some(c), true) if c.len() == t * n * CONTACT_FEATURES => {
                Ok(Some(tensor2(c, [t * n, CONTACT_FEATURES], &self.device())))
            }
            (c, _) => Err(ModelError::mismatch(
                "body contact numbers of the frame inputs (config body_contact)",
                if self.config.body_contact {
                    t * n * CONTACT_FEATURES
                } else {
                    0
                },
                c.as_ref().map_or(0, Vec::len),
            )),
        }
    }

    /// Stage of [`Self::forward`]: the blend shapes of M^mp submodule `k`, `[T·N, 3]`,
    /// from the E^t2 features `motion` of [`Self::motion_features`] and the contact of
    /// [`Self::contact_features`].
    pub fn blend_submodule(
        &self,
        k: usize,
        pair: &PairEncoding,
        g: &GarmentInput,
        motion: &Tensor<2>,
        contact: Option<&Tensor<2>>,
    ) -> Result<Tensor<2>, ModelError> {
        self.check_pair(pair, g)?;
        let sub = self.mp.get(k).ok_or_else(|| {
            ModelError::mismatch("M^mp submodule index", format!("< {}", self.mp.len()), k)
        })?;
        let t = motion.dims()[0];
        let batch = g.frame_batch(t)?;
        sub.forward(pair.fused.clone(), motion.clone(), contact.cloned(), &batch)
    }

    /// Stage of [`Self::forward`]: linear blend skinning (eq. 2–3) of `T + Bᵗ` with
    /// `Wᵗ` and the joint transforms of `f`, `[T, N, 3]`.
    pub fn skin(
        &self,
        g: &GarmentInput,
        f: &FrameInputs,
        weights: Tensor<3>,
        blend: Tensor<3>,
    ) -> Result<Tensor<3>, ModelError> {
        let device = self.device();
        let (t, n, s) = (f.frame_count(), g.vertex_count(), f.joint_count());
        for (what, dims) in [
            ("skinning weights", weights.dims()),
            ("blend shapes", blend.dims()),
        ] {
            let want = [t, n, if what == "blend shapes" { 3 } else { s }];
            if dims != want {
                return Err(ModelError::mismatch(
                    what,
                    format!("{want:?}"),
                    format!("{dims:?}"),
                ));
            }
        }
        let transforms = tensor3(&f.transforms, [t, s, 12], &device);
        let blended = weights.matmul(transforms).reshape([t, n, 3, 4]);
        let rest = tensor2(&g.rest, [n, 3], &device).unsqueeze_dim::<3>(0) + blend;
        let homogeneous = Tensor::cat(vec![rest, Tensor::ones([t, n, 1], &device)], 2);
        Ok((blended * homogeneous.unsqueeze_dim(2))
            .sum_dim(3)
            .reshape([t, n, 3]))
    }
}
