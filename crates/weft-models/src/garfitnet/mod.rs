//! GarFitNet (seed 001 ch. 4, case 2): fit-aware refinement of a separate garment on a
//! body. [`fit`] is the fit parameter α (§4.2.1) that tells the networks how tightly a
//! garment sits on a body, [`coarse`] the coarse regressor that moves the garment with
//! the body (§4.2.2), [`network`] the refinement network (§4.3), [`pair`] what both read
//! of one garment on one body, [`model`] the two networks as one trained model and
//! [`predictor`] a trained run opened for inference.

pub mod coarse;
pub mod fit;
pub mod model;
pub mod network;
pub mod pair;
pub mod predictor;

pub use coarse::{association, coarse_target, CoarseRegressor, CoarseRegressorConfig};
pub use fit::{fit_sample, garment_body_distances, FactorAnalysis, FactorAnalysisConfig};
pub use model::{GarFit, GarFitConfig};
pub use network::{Correction, GarFitNet, GarFitNetConfig};
pub use pair::{Anchor, BodyFrame, FitPair, COARSE_UNIT, REFINE_UNIT};
pub use predictor::{GarFitPredictor, GarFitStats, PairFit, STATS_FILE};
