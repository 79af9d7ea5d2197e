//! weft's garment deformation systems behind one interface.
//!
//! - [`deformer`]: [`Deformer`] and [`Clip`], what every system implements and every
//!   consumer (evaluation, `weft animate`, the demo) calls;
//! - [`baseline`]: the no-learning LBS and DQS baselines;
//! - [`refine`]: seed 001's learned refinement of skinning (case 1: dressed characters),
//!   shared by [`densegats`] (DenseGATs, §3.2) and [`multiresgnet`] (MultiResGNet, §3.3);
//! - [`garfitnet`]: seed 001's fit-aware garment refinement (case 2, ch. 4);
//! - [`hood`]: HOOD (seed 004), cloth dynamics learned from the incremental potential;
//! - [`multilevel`]: the Multilevel model of seed 000 (multi-source garment graph,
//!   structure-preserving pooling, temporal skinning weights and blend shapes, LBS);
//! - [`kind`]: [`ModelKind`], the systems by name;
//! - [`run`]: the one owner of the run directory; [`load_deformer`] opens any run.

pub mod baseline;
pub mod deformer;
pub mod densegats;
pub mod error;
pub mod garfitnet;
pub mod hood;
pub mod kind;
pub mod load;
pub mod multilevel;
pub mod multiresgnet;
pub mod refine;
pub mod run;

pub use baseline::{SkinningBaseline, DQS_NAME, LBS_NAME};
pub use deformer::{Clip, Deformer, Frames, StepJudge, Timing};
pub use error::ModelError;
pub use kind::{ModelKind, UnknownModelKind};
pub use load::load_deformer;
pub use run::{RunHeader, RunLayout};
