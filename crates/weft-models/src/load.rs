//! [`load_deformer`]: any trained run directory opened as a [`Deformer`], whatever the
//! system that trained it. The run's header (`model`, written by weft-train) picks the
//! loader; this is the one `match` on [`ModelKind`] a new system adds an arm to.

use std::path::Path;

use crate::deformer::Deformer;
use crate::error::ModelError;
use crate::garfitnet::GarFitPredictor;
use crate::kind::ModelKind;
use crate::multilevel::Predictor;
use crate::refine::RefinePredictor;
use crate::run::read_run_config;

/// The trained system in `dir` (its config.toml and latest checkpoint), on the CPU.
///
/// Errors name the file: a missing or unreadable config, a format version this build
/// does not read, a model kind this build cannot run, a checkpoint that does not fit.
pub fn load_deformer(dir: &Path) -> Result<Box<dyn Deformer + Send>, ModelError> {
    let (header, _) = read_run_config(dir)?;
    match header.model {
        ModelKind::Multilevel => Ok(Box::new(Predictor::load(dir)?)),
        ModelKind::DenseGats | ModelKind::MultiResGnet => Ok(Box::new(RefinePredictor::load(dir)?)),
        ModelKind::GarFitNet => Ok(Box::new(GarFitPredictor::load(dir)?)),
        ModelKind::Hood => Ok(Box::new(crate::hood::HoodPredictor::load(dir)?)),
    }
}
