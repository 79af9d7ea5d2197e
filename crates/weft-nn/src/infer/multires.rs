//! [`MultiResGModule`]'s inference form: both branches' GAT blocks on the inference
//! forms of [`super::gat`]; the pooling's scores and greedy contraction stay on the burn
//! layer (a product to `F` channels and one pass over the edges), the unpooling is a
//! host gather.

use crate::batch::GraphBatch;
use crate::multires::MultiResGModule;
use crate::pool::edge::MIN_SCORE;
use crate::pool::EdgePool;

use super::{Features, InferDenseModule, InferGat};

/// The global branch for inference.
#[derive(Clone, Debug)]
pub struct InferGlobal {
    /// Edge-contraction pooling (the burn layer, on the inference device).
    pub pool: EdgePool,
    /// GAT blocks on the pooled graph.
    pub coarse: InferDenseModule,
    /// The block after unpooling.
    pub after: InferGat,
}

/// [`MultiResGModule`] for inference; equal to its forward on the inference device.
#[derive(Clone, Debug)]
pub struct InferMultiRes {
    /// The local branch.
    pub local: InferDenseModule,
    /// The global branch, or none.
    pub global: Option<InferGlobal>,
}

impl From<&MultiResGModule> for InferMultiRes {
    fn from(m: &MultiResGModule) -> Self {
        InferMultiRes {
            local: InferDenseModule::from(&m.local),
            global: m.global.as_ref().map(|g| InferGlobal {
                pool: g.pool.clone(),
                coarse: InferDenseModule::from(&g.coarse),
                after: InferGat::from(&g.after),
            }),
        }
    }
}

impl InferGlobal {
    /// `x` on `graph` → `[N, after.output_width]`.
    pub fn forward(&self, x: &Features, graph: &GraphBatch) -> crate::Result<Features> {
        let device = self.pool.weight.device();
        let pooled = self.pool.forward(x.clone().into_tensor(&device), graph)?;
        let clusters = &pooled.clusters;
        let coarse = Features::from_tensor(pooled.features)?;
        let g = self.coarse.forward(&coarse, clusters.coarse.adjacency())?;
        let scores = Features::from_tensor(clusters.scores.clone())?;
        let w = g.width();
        let mut unpooled = Features::zeros(x.rows(), w);
        for (row, &c) in unpooled.data.chunks_exact_mut(w).zip(&clusters.assignment) {
            let c = c as usize;
            let s = scores.values()[c].max(MIN_SCORE as f32);
            for (o, v) in row.iter_mut().zip(&g.values()[c * w..(c + 1) * w]) {
                *o = v / s;
            }
        }
        self.after.forward(&unpooled, graph.adjacency())
    }
}

impl InferMultiRes {
    /// Input features per node.
    pub fn input_width(&self) -> usize {
        self.local.input_width()
    }

    /// Output features per node: the local branch's, then the global branch's.
    pub fn output_width(&self) -> usize {
        self.local.output_width() + self.global.as_ref().map_or(0, |g| g.after.output_width())
    }

    /// `x`: `[N, input_width]` on `graph` → `[N, output_width]`.
    pub fn forward(&self, x: &Features, graph: &GraphBatch) -> crate::Result<Features> {
        let local = self.local.forward(x, graph.adjacency())?;
        let Some(global) = &self.global else {
            return Ok(local);
        };
        let global = global.forward(x, graph)?;
        let mut out = Features::zeros(x.rows(), self.output_width());
        out.write_columns(0, &local);
        out.write_columns(local.width(), &global);
        Ok(out)
    }
}
