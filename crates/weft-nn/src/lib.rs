//! Network layers for weft on burn 0.22.
//!
//! - [`gat`]: graph attention on CSR adjacency — the fused CPU kernel with its hand-written
//!   backward, the generic reference path, and the [`GatBlock`] layer.
//! - [`dense`]: GAT block → batch norm → σ ([`NormedGat`]) and the densely connected
//!   modules of seed 001 ([`DenseGatModule`], eq. 3.6).
//! - [`infer`]: inference-only forms of the MLP, GAT block and dense module on host
//!   buffers (batch norm and σ fused into the output pass), for evaluation and animation.
//! - [`adjacency`]: the destination-major adjacency (self-loops, transpose) GAT runs on.
//! - [`backend`]: the devices (flex CPU by default; wgpu / cuda behind features).
//! - [`activation`]: the nonlinearities the papers name.
//! - [`graph_net`]: message passing over typed edge sets (MeshGraphNets' block, HOOD's
//!   multi-level [`Processor`] schedule, seed 004).
//! - [`mlp`], [`lstm`]: MLP (with optional batch norm) and stacked LSTM encoders.
//! - [`multires`]: seed 001's multi-resolution module ([`MultiResGModule`]: a dense GAT
//!   branch beside a pooled one), MultiResGNet's core and GarFitNet's branches.
//! - [`pool`]: structure-preserving pooling/unpooling (seed 000) and the learned baselines
//!   TopKPool, SAGPool, ASAP with unpooling by index, and MultiResGNet's edge-contraction
//!   pooling ([`EdgePool`]).
//! - [`batch`]: several garments as one disjoint graph ([`GraphBatch`], [`HierarchyBatch`]).
//! - [`sparse`]: constant sparse × dense products with their transpose backward.
//! - [`normalizer`]: per-column z-score of node features, fitted on training rows.
//! - [`patch`]: breadth-first connected vertex patches with their induced subgraph.
//! - [`optim`]: Adamax and cosine annealing.
//! - [`init`]: Glorot for GAT blocks, Kaiming for linear and LSTM layers.

pub mod activation;
pub mod adjacency;
pub mod backend;
pub mod batch;
pub mod dense;
pub mod error;
mod flex;
pub mod gat;
pub mod graph_net;
pub mod infer;
pub mod init;
pub mod lstm;
pub mod mlp;
pub mod multires;
pub mod normalizer;
pub mod optim;
pub mod patch;
pub mod pool;
mod real;
pub mod sparse;
#[cfg(test)]
mod testutil;

pub use activation::Activation;
pub use adjacency::Adjacency;
pub use batch::{BatchLevel, GraphBatch, HierarchyBatch};
pub use dense::{DenseGatModule, DenseGatModuleConfig, NormedGat, NormedGatConfig};
pub use error::{NnError, Result};
pub use gat::{AttentionImpl, GatBlock, GatBlockConfig, HeadMerge};
pub use graph_net::{EdgeSet, GraphNetBlock, GraphNetBlockConfig, Processor, ProcessorConfig};
pub use lstm::{LstmEncoder, LstmEncoderConfig};
pub use mlp::{Mlp, MlpConfig};
pub use multires::{GlobalBranch, MultiResGModule, MultiResGModuleConfig};
pub use normalizer::{FeatureNormalizer, NormalizerFit};
pub use optim::{cosine_annealing, Adamax, AdamaxConfig};
pub use patch::Patch;
pub use pool::{edge_unpool, EdgePool, EdgePoolConfig};
pub use sparse::{sparse_matmul, SparseImpl, SparseMatrix};

pub use burn;
