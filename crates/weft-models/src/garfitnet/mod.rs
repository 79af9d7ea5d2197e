//! GarFitNet (seed 001 ch. 4, case 2): fit-aware refinement of a separate garment on a
//! body. Built so far: [`fit`], the fit parameter α (§4.2.1) that tells the networks how
//! tightly a garment sits on a body, and [`network`], the refinement network (§4.3).
//! Not yet: the coarse regressor, the data, training and evaluation.

pub mod fit;
pub mod network;

pub use fit::{garment_body_distances, FactorAnalysis, FactorAnalysisConfig};
pub use network::{Correction, GarFitNet, GarFitNetConfig};
