//! GarFitNet (seed 001 ch. 4, case 2): fit-aware refinement of a separate garment on a
//! body. Built so far: [`fit`], the fit parameter α (§4.2.1) that tells the networks how
//! tightly a garment sits on a body, [`coarse`], the coarse regressor that moves the
//! garment with the body (§4.2.2), and [`network`], the refinement network (§4.3). Not
//! yet: the data, training and evaluation.

pub mod coarse;
pub mod fit;
pub mod network;

pub use coarse::{association, coarse_target, CoarseRegressor, CoarseRegressorConfig};
pub use fit::{garment_body_distances, FactorAnalysis, FactorAnalysisConfig};
pub use network::{Correction, GarFitNet, GarFitNetConfig};
