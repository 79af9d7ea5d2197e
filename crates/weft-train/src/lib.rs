//! Training for weft's learned systems.
//!
//! The loop and what every system shares:
//! - [`task`]: what a system supplies ([`TrainTask`]: items, named weighted loss terms,
//!   its own stages, named validation metrics).
//! - [`trainer`]: the loop, generic over a [`TrainTask`].
//! - [`config`]: the loop's `[train]` settings, with the `cpu` and `paper` presets.
//! - [`optim`]: the optimisers and learning-rate schedules a config can choose.
//! - [`sampler`]: the seeded order of training items.
//! - [`run`]: the run directory and checkpoints that resume bit for bit.
//! - [`run_config`]: a run's configuration (preset, `[model]`, `[train]`), any model.
//! - [`metrics`]: metrics.jsonl and curves.png.
//! - [`loss`]: loss building blocks: supervised terms as burn tensor code, physics terms
//!   as a custom autodiff operation over weft-sim's energies.
//!
//! Each system's task, terms, stages and configuration: [`tasks`] (Multilevel, seed 000
//! supplement §2 and §4: [`tasks::multilevel`]).

pub mod config;
pub mod error;
pub mod loss;
pub mod metrics;
pub mod optim;
pub mod run;
pub mod run_config;
pub mod sampler;
pub mod task;
pub mod tasks;
pub mod trainer;

pub use config::{TrainConfig, TrainTable};
pub use error::{Result, TrainError};
pub use optim::{LrSchedule, LrScheduleConfig, LrState, OptimizerConfig};
pub use run::{RunDir, TrainerState, FORMAT_VERSION};
pub use task::{LossTerm, Metrics, StepEnd, TrainTask};
pub use tasks::multilevel::{MultilevelRun, MultilevelTask, MultilevelTraining};
pub use trainer::{train, Outcome, RunOptions};
