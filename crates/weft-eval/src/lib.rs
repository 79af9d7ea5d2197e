//! Evaluation for weft (seed 000 §4): how far any list of deformers (learned systems and
//! the no-learning LBS/DQS baselines of weft-models) puts garments from the simulated
//! ground truth, side by side, and why a vertex moves the way it does (attribution,
//! §4.1).
//!
//! - [`metrics`]: `E_verts` (mm), `E_norm` (°), collision rate, edge strain.
//! - [`evaluate`]: `weft eval` — deformers on a dataset split in one loop.
//! - [`explain`]: eq. 9 for one vertex of the Multilevel model (`weft attribute`).
//! - [`animate`]: `weft animate` — any garment, shape and motion, exported.
//! - [`report`]: `eval.json` / `eval.md` and the Table 1 comparison.
//! - [`pictures`]: comparison sheets, error and attribution heat maps, per-frame plots.
//! - [`stats`]: mean ± std in one pass.
//! - [`quadrature`], [`attribution`]: eq. 9, Aumann–Shapley path integrals with
//!   Gauss–Legendre quadrature.

pub mod animate;
pub mod attribution;
pub mod error;
pub mod evaluate;
pub mod explain;
pub mod metrics;
pub mod pictures;
pub mod quadrature;
pub mod report;
pub mod skinned;
pub mod stats;

pub use error::EvalError;
pub use evaluate::{evaluate, write_report, EvalOptions, Evaluation};
pub use metrics::{FrameMetrics, GarmentTopology, MetricsSummary};
pub use report::{Comparison, EvalReport, MethodResult, LBS_NAME};
pub use stats::{Accumulator, Summary};
