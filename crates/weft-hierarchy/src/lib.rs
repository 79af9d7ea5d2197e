//! Multilevel mesh graphs for weft.
//!
//! - [`pool`]: structure-preserving pooling (seed 000, Algorithm 1).
//! - [`Unpooling`]: its neighbour-weighted unpooling (Algorithm 2) as a sparse matrix.
//! - [`Hierarchy`]: pooling applied recursively, with the nested view of HOOD
//!   (seed 004 §3.2) — every coarser vertex set is a subset of the finer one.
//!
//! Plain index maps and sparse weights, no learning dependency: the network layers
//! (weft-nn) turn them into tensors.

mod error;
mod hierarchy;
mod pooling;
mod unpooling;

pub use error::HierarchyError;
pub use hierarchy::{Hierarchy, Level};
pub use pooling::{pool, pool_from, Pooling};
pub use unpooling::Unpooling;
