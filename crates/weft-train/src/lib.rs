//! Training for weft's learned systems (seed 000 supplement §2 and §4).
//!
//! - [`loss`]: the supervised terms (vertex, edge, normal) as burn tensor code and the
//!   physics terms (collision, gravity, stretch, shear) as a custom autodiff operation
//!   over weft-sim's energies.

pub mod error;
pub mod loss;

pub use error::{Result, TrainError};
