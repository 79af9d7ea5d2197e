//! The measurements behind `weft bench`: what one configuration of a network or of the
//! simulator costs on this machine, per stage, next to the floating-point floor where
//! one exists, so that a figure in docs/benchmarks.md can be reproduced with one command
//! in the release binary and compared with other tools (each result serialises to one
//! JSON object).
//!
//! - [`timing`]: the median-of-repetitions timer every bench uses;
//! - [`device`]: `--device cpu|wgpu` (wgpu with the `wgpu` feature) and waiting for a
//!   device before the clock is read;
//! - [`multilevel`]: the Multilevel model's inference stages and training step;
//! - [`gat`]: one GAT layer, fused kernel against burn's generic path;
//! - [`densegats`]: DenseGATs per stage on a character, with the linear maps' floor;
//! - [`multiresgnet`]: MultiResGNet per stage on the same character (`refine`: what the
//!   two share);
//! - [`garfitnet`]: GarFitNet per stage (posed body, coarse regressor, refinement) on a
//!   garment;
//! - [`simulate`]: the cloth simulator on a garment and a motion, cost and quality.
//!
//! Figures are wall-clock times on the calling thread pool (rayon's, sized by
//! `RAYON_NUM_THREADS`); each result records the thread count, its device and, on a GPU,
//! the adapter, and a GPU timing stops only once the device has finished
//! ([`device::wait`]).

pub mod densegats;
pub mod device;
pub mod error;
pub mod garfitnet;
pub mod gat;
pub mod hood;
pub mod multilevel;
pub mod multiresgnet;
mod refine;
pub mod simulate;
pub mod timing;

pub use device::BenchDevice;
pub use error::BenchError;

/// A measured configuration as a row of a human table: `(column, value)` pairs.
pub trait Row {
    /// The row's cells, in column order.
    fn cells(&self) -> Vec<(&'static str, String)>;
}

/// The benchmark garment: a skirt of about `vertices` vertices (style seed 1) fitted to
/// `body` in its rest pose at β = 0, as `weft garment generate --kind skirt` makes it.
pub fn skirt(
    body: &weft_body::BodyModel,
    vertices: usize,
) -> Result<weft_mesh::TriMesh, BenchError> {
    use weft_garment::{FitBody, GarmentKind, Style};
    let fit = FitBody::new(body, &[]).map_err(BenchError::stage("fitting the skirt"))?;
    let style = Style::from_seed(GarmentKind::Skirt, 1);
    Ok(fit
        .generate(GarmentKind::Skirt, &style, vertices)
        .map_err(BenchError::stage("generating the skirt"))?
        .mesh)
}
