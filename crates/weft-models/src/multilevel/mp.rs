//! One submodule of the multilevel processing module M^mp (seed 000 §3.3, supplement §1),
//! Graph U-Net style:
//!
//! 1. embedding GAT: the motion-informed encoding `X̃ = X^fuse ⊙ E^t2(Vᵗ)` to
//!    `heads × channels` (with `body_contact`, plus a linear map of each vertex's contact
//!    features, [`super::contact`]), tanh;
//! 2. encoder: `levels` blocks of pooling then GAT (tanh);
//! 3. decoder: `levels` blocks of unpooling, additive skip from the encoder at the same
//!    resolution, GAT (tanh);
//! 4. output GAT: 3 channels, heads averaged, no activation, times a learned gain → the
//!    blend shape offsets (metres).
//!
//! The pooling is chosen by [`PoolingKind`]: structure-preserving (the hierarchy of the
//! garment, precomputed), none (the same blocks in cascade on the full graph), or the
//! learned TopK / SAG / ASAP layers with unpooling by index.
//!
//! The embedding never materialises `X̃` (`T·N × F·S`, 49 MB per frame at the paper's
//! widths on a 4 000-vertex garment): `(X ⊙ e_t) W = X (diag(e_t) W)`, so the `T` frames'
//! scaled weights are laid side by side and one GEMM `X [diag(e_1)W | … | diag(e_T)W]`
//! gives every frame's transformed features. That GEMM is the FLOP floor of a frame
//! (docs/multilevel.md).

use burn::module::{Module, Param};
use burn::nn::{Linear, LinearConfig};
use burn::tensor::Tensor;
use weft_nn::activation::tanh;
use weft_nn::pool::{
    unpool_by_index, AsapPool, AsapPoolConfig, SagPool, SagPoolConfig, Selection, StructurePool,
    StructureUnpool, TopKPool, TopKPoolConfig,
};
use weft_nn::{
    gat::attention, Activation, AttentionImpl, GatBlock, GatBlockConfig, GraphBatch, HeadMerge,
    HierarchyBatch,
};

use super::config::{MultilevelConfig, PoolingKind};
use super::contact::CONTACT_FEATURES;
use crate::error::ModelError;

/// One M^mp submodule; see the module documentation.
#[derive(Module, Debug)]
pub struct MpSubmodule {
    /// Embedding GAT `F·S → heads × channels` (its `weight` is scaled per frame).
    pub embed: GatBlock,
    /// Contact features → `heads × channels`, added to the embedding's transform
    /// (`body_contact` only).
    pub contact: Option<Linear>,
    /// Encoder GAT blocks, one per level.
    pub down: Vec<GatBlock>,
    /// Decoder GAT blocks, one per level (finest last).
    pub up: Vec<GatBlock>,
    /// Output GAT: 3 channels, heads averaged.
    pub out: GatBlock,
    /// TopK layers (pooling `top_k` only).
    pub topk: Vec<TopKPool>,
    /// SAG layers (pooling `sag` only).
    pub sag: Vec<SagPool>,
    /// ASAP layers (pooling `asap` only).
    pub asap: Vec<AsapPool>,
    /// Metres per unit of the output GAT.
    pub gain: Param<Tensor<1>>,
    #[module(skip)]
    pooling: PoolingKind,
}

impl MpSubmodule {
    /// Builds a submodule for `cfg` on `device`.
    pub fn new(cfg: &MultilevelConfig, device: &burn::tensor::Device) -> Result<Self, ModelError> {
        let width = cfg.mp_width();
        let block = |d_input: usize| {
            GatBlockConfig::new(d_input, cfg.mp_channels)
                .with_heads(cfg.mp_heads)
                .with_merge(HeadMerge::Concat)
                .with_activation(Activation::None)
                .with_negative_slope(cfg.negative_slope)
                .init(device)
        };
        let levels = cfg.mp_levels;
        let embed = block(cfg.fused_width())?;
        let contact = cfg.body_contact.then(|| {
            LinearConfig::new(CONTACT_FEATURES, width)
                .with_bias(false)
                .init(device)
        });
        let down = (0..levels)
            .map(|_| block(width))
            .collect::<Result<Vec<_>, _>>()?;
        let up = (0..levels)
            .map(|_| block(width))
            .collect::<Result<Vec<_>, _>>()?;
        let out = GatBlockConfig::new(width, 3)
            .with_heads(cfg.out_heads)
            .with_merge(HeadMerge::Mean)
            .with_negative_slope(cfg.negative_slope)
            .init(device)?;
        let (mut topk, mut sag, mut asap) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..levels {
            match cfg.pooling {
                PoolingKind::TopK => topk.push(
                    TopKPoolConfig::new(width)
                        .with_ratio(cfg.pool_ratio)
                        .init(device)?,
                ),
                PoolingKind::Sag => sag.push(
                    SagPoolConfig::new(width)
                        .with_ratio(cfg.pool_ratio)
                        .init(device)?,
                ),
                PoolingKind::Asap => asap.push(
                    AsapPoolConfig::new(width)
                        .with_ratio(cfg.pool_ratio)
                        .init(device)?,
                ),
                PoolingKind::Structure | PoolingKind::None => {}
            }
        }
        let gain = Param::from_tensor(Tensor::<1>::from_floats([cfg.blend_gain as f32], device));
        Ok(MpSubmodule {
            embed,
            contact,
            down,
            up,
            out,
            topk,
            sag,
            asap,
            gain,
            pooling: cfg.pooling,
        })
    }

    /// Blend shapes `[T·N, 3]` of the `T` frames of `batch` from the pair encoding
    /// `fused` (`[N, F·S]`), the E^t2 features `motion` (`[T, F·S]`) and, with
    /// `body_contact`, the contact features `[T·N, 4]`.
    pub fn forward(
        &self,
        fused: Tensor<2>,
        motion: Tensor<2>,
        contact: Option<Tensor<2>>,
        batch: &HierarchyBatch,
    ) -> Result<Tensor<2>, ModelError> {
        let x = self.embed(fused, motion, contact, batch.batch(0))?;
        self.process(x, batch)
    }

    /// The embedding GAT of every frame, `[T·N, heads·channels]`: one GEMM
    /// `X [diag(e_1)W | … | diag(e_T)W]` (plus the contact map), then attention on the
    /// `T` copies of the graph.
    pub fn embed(
        &self,
        fused: Tensor<2>,
        motion: Tensor<2>,
        contact: Option<Tensor<2>>,
        level0: &GraphBatch,
    ) -> Result<Tensor<2>, ModelError> {
        let [n, fs] = fused.dims();
        let t = motion.dims()[0];
        if motion.dims()[1] != fs {
            return Err(ModelError::mismatch(
                "E^t2 features (F·S per frame)",
                fs,
                motion.dims()[1],
            ));
        }
        let hc = self.embed.heads * self.embed.channels;
        // [FS, T, HC]: column block t is diag(e_t) W.
        let w = motion.transpose().unsqueeze_dim::<3>(2) * self.embed.weight.val().unsqueeze_dim(1);
        let z = fused
            .matmul(w.reshape([fs, t * hc]))
            .reshape([n, t, hc])
            .swap_dims(0, 1)
            .reshape([t * n, hc]);
        let z = match (&self.contact, contact) {
            (None, None) => z,
            (Some(map), Some(c)) if c.dims() == [t * n, CONTACT_FEATURES] => z + map.forward(c),
            (Some(_), Some(c)) => {
                return Err(ModelError::mismatch(
                    "body contact features (frames × vertices, 4)",
                    format!("{:?}", [t * n, CONTACT_FEATURES]),
                    format!("{:?}", c.dims()),
                ))
            }
            (Some(_), None) => {
                return Err(ModelError::Config(
                    "the model was built with body_contact but the frame inputs have none".into(),
                ))
            }
            (None, Some(_)) => {
                return Err(ModelError::Config(
                    "the frame inputs carry body contact but the model was built without it".into(),
                ))
            }
        };
        let mut x = attention(
            z,
            self.embed.att_src.val(),
            self.embed.att_dst.val(),
            level0.adjacency(),
            self.embed.negative_slope,
            AttentionImpl::Auto,
        )?;
        if let Some(bias) = &self.embed.bias {
            x = x + bias.val().unsqueeze_dim(0);
        }
        Ok(tanh(x))
    }

    /// Encoder, decoder and output GAT on embedded features `x` (`[T·N, heads·channels]`).
    pub fn process(&self, x: Tensor<2>, batch: &HierarchyBatch) -> Result<Tensor<2>, ModelError> {
        let level0 = batch.batch(0);
        let x = match self.pooling {
            PoolingKind::Structure => self.unet_structure(x, batch)?,
            PoolingKind::None => self.cascade(x, level0)?,
            PoolingKind::TopK | PoolingKind::Sag | PoolingKind::Asap => {
                self.unet_learned(x, level0)?
            }
        };
        let b = self.out.forward(x, level0.adjacency())?;
        Ok(b * self.gain.val().unsqueeze_dim(0))
    }

    fn unet_structure(
        &self,
        x: Tensor<2>,
        batch: &HierarchyBatch,
    ) -> Result<Tensor<2>, ModelError> {
        let levels = self.down.len();
        if batch.len() != levels + 1 {
            return Err(ModelError::mismatch(
                "garment hierarchy levels (config mp_levels + 1)",
                levels + 1,
                batch.len(),
            ));
        }
        let mut skips = Vec::with_capacity(levels + 1);
        let mut x = x;
        for (l, block) in self.down.iter().enumerate() {
            let level = batch.level(l + 1).ok_or_else(|| {
                ModelError::Garment(format!("hierarchy level {} is missing", l + 1))
            })?;
            skips.push(x.clone());
            x = StructurePool.forward(x, level)?;
            x = tanh(block.forward(x, level.batch.adjacency())?);
        }
        for (l, block) in self.up.iter().enumerate() {
            let coarse = levels - l;
            let level = batch.level(coarse).ok_or_else(|| {
                ModelError::Garment(format!("hierarchy level {coarse} is missing"))
            })?;
            let skip = skips
                .pop()
                .ok_or_else(|| ModelError::Garment("skip connection missing".into()))?;
            x = StructureUnpool::default().forward(x, level)? + skip;
            x = tanh(block.forward(x, batch.batch(coarse - 1).adjacency())?);
        }
        Ok(x)
    }

    fn cascade(&self, x: Tensor<2>, batch: &GraphBatch) -> Result<Tensor<2>, ModelError> {
        let mut skips = Vec::with_capacity(self.down.len());
        let mut x = x;
        for block in &self.down {
            skips.push(x.clone());
            x = tanh(block.forward(x, batch.adjacency())?);
        }
        for block in &self.up {
            if let Some(skip) = skips.pop() {
                x = x + skip;
            }
            x = tanh(block.forward(x, batch.adjacency())?);
        }
        Ok(x)
    }

    fn pool(
        &self,
        l: usize,
        x: Tensor<2>,
        batch: &GraphBatch,
    ) -> Result<(Tensor<2>, Selection), ModelError> {
        let pooled = match self.pooling {
            PoolingKind::TopK => self.topk[l].forward(x, batch)?,
            PoolingKind::Sag => self.sag[l].forward(x, batch)?,
            PoolingKind::Asap => self.asap[l].forward(x, batch)?,
            PoolingKind::Structure | PoolingKind::None => {
                return Err(ModelError::Config(format!(
                    "pooling {} has no learned layer",
                    self.pooling.name()
                )))
            }
        };
        Ok((pooled.features, pooled.selection))
    }

    fn unet_learned(&self, x: Tensor<2>, level0: &GraphBatch) -> Result<Tensor<2>, ModelError> {
        let mut skips = Vec::with_capacity(self.down.len());
        let mut selections: Vec<Selection> = Vec::with_capacity(self.down.len());
        let mut batches = vec![level0.clone()];
        let mut x = x;
        for (l, block) in self.down.iter().enumerate() {
            skips.push(x.clone());
            let current = batches.last().cloned().unwrap_or_else(|| level0.clone());
            let (pooled, selection) = self.pool(l, x, &current)?;
            x = tanh(block.forward(pooled, selection.coarse.adjacency())?);
            batches.push(selection.coarse.clone());
            selections.push(selection);
        }
        for block in &self.up {
            let selection = selections
                .pop()
                .ok_or_else(|| ModelError::Config("pooling selection missing".into()))?;
            let skip = skips
                .pop()
                .ok_or_else(|| ModelError::Config("skip connection missing".into()))?;
            batches.pop();
            let finer = batches.last().cloned().unwrap_or_else(|| level0.clone());
            x = unpool_by_index(x, &selection)? + skip;
            x = tanh(block.forward(x, finer.adjacency())?);
        }
        Ok(x)
    }
}
