//! Body features the systems need, on plain slices (vertices `&[[f64; 3]]`, faces
//! `&[[u32; 3]]`, joints `&[[f64; 3]]`, skinning weights as [`SkinningWeights`]), so
//! they serve SMPL, the default body and any rigged mesh alike.
//!
//! | feature | paper | module |
//! |---|---|---|
//! | joint–vertex distance matrix `D ∈ ℝ^{N_b×S}` | seed 000 §3.2 (body shape encoder) | [`distances`] |
//! | distance from any point to every joint, Euclidean | seed 000 §3.2 (garment node features) | [`distances`] |
//! | … and through the body (volumetric approximation) | seed 001 §3.2.1 (`x_{i,s}`) | [`volumetric`] |
//! | body-vertex velocities over a window `V^t` | seed 000 §3.2, eq. 7 | [`velocity`] |
//! | relative skinning descriptor `r_i(θ)` | seed 001 eq. 3.7–3.9, 4.7 | [`descriptor`] |
//! | skinning-weight transfer body → garment | seed 001 §4, seed 004 (body/garment) | [`transfer`] |
//! | diffused transfer for loose garments | SSCH / SNUG / HOOD treatment of skirts | [`diffusion`] |
//!
//! Computation is `f64`; `to_f32` methods give the row-major `f32` buffers networks
//! consume. Wrong input (mismatched lengths, NaN, negative weights, bad parents) is a
//! [`FeatureError`], never a panic. Design notes: `docs/body-features.md`.

pub mod body;
pub mod descriptor;
pub mod diffusion;
pub mod distances;
pub mod error;
pub mod matrix;
pub mod transfer;
pub mod velocity;
pub mod volumetric;
pub mod weights;

pub use body::{descriptor_from_transforms, rotations_of};
pub use descriptor::{
    descriptor_for_pose, joint_rotations, relative_rotations, relative_skinning_descriptor,
    rodrigues, Rotation,
};
pub use diffusion::{diffuse_weights, transfer_weights_diffused, DiffusionParams};
pub use distances::joint_distances;
pub use error::FeatureError;
pub use matrix::FeatureMatrix;
pub use transfer::{transfer_weights, Transfer};
pub use velocity::{velocity_window, vertex_velocities, VelocityWindow};
pub use volumetric::{VolumetricDistance, VolumetricParams};
pub use weights::SkinningWeights;
