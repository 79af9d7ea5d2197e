//! Training for weft's learned systems (seed 000 supplement §2 and §4).
//!
//! - [`loss`]: the supervised terms (vertex, edge, normal) as burn tensor code and the
//!   physics terms (collision, gravity, stretch, shear) as a custom autodiff operation
//!   over weft-sim's energies.
//! - [`schedule`]: the two-step schedule (switching rules as written, configurable).
//! - [`config`]: the `[train]` table of a run, with the `cpu` and `paper` presets.
//! - [`optim`]: the optimisers and learning-rate schedules a config can choose.
//! - [`sampler`]: the seeded order of training windows.
//! - [`run`]: the run directory and checkpoints that resume bit for bit.
//! - [`metrics`]: metrics.jsonl and curves.png.
//! - [`trainer`]: the loop, generic over a [`TrainTask`].
//! - [`multilevel`]: the task of the Multilevel model on a weft-data dataset.

pub mod config;
pub mod error;
pub mod loss;
pub mod metrics;
pub mod multilevel;
pub mod optim;
pub mod run;
pub mod sampler;
pub mod schedule;
pub mod trainer;

pub use config::TrainConfig;
pub use error::{Result, TrainError};
pub use multilevel::{MultilevelRun, MultilevelTask};
pub use optim::{LrSchedule, LrScheduleConfig, LrState, OptimizerConfig};
pub use run::{RunDir, TrainerState, FORMAT_VERSION};
pub use schedule::{Phase, ScheduleConfig};
pub use trainer::{train, Outcome, RunOptions, TrainTask};
