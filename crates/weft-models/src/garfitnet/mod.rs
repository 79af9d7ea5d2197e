//! GarFitNet (seed 001 ch. 4, case 2): fit-aware refinement of a separate garment on a
//! body. Built so far: [`fit`], the fit parameter α (§4.2.1) that tells the networks how
//! tightly a garment sits on a body.

pub mod fit;

pub use fit::{garment_body_distances, FactorAnalysis, FactorAnalysisConfig};
