//! Spatial queries against the (posed) body: closest point, signed distance, and body
//! vertices within a radius of garment nodes.
//!
//! * [`AabbTree`]: a static, balanced bounding-volume hierarchy of axis-aligned boxes,
//!   written here rather than taken from parry3d, whose dependency tree is much larger
//!   than the three queries we need; built in `O(n log n)`, refit in `O(n)` when the
//!   topology is fixed (a body moving from frame to frame).
//! * [`BodySurface`]: the body's triangles in such a tree, with angle-weighted
//!   pseudo-normals; answers [`BodySurface::closest_point`] (triangle, barycentric
//!   coordinates, point, distance, feature, normals) and
//!   [`BodySurface::signed_distance`] (sign from the pseudo-normal of the closest
//!   feature, exact on closed surfaces), one point at a time or batched with rayon.
//! * [`MovingSurface`]: a [`BodySurface`] following a body's frames, built once and
//!   refit per frame.
//! * [`VertexTree`]: the body's vertices in such a tree, for HOOD's body edges
//!   ([`VertexTree::body_edges`], seed 004 §3.1).
//!
//! Everything is `f64`. Inputs a user can get wrong (out-of-range faces, NaN positions,
//! negative radii, a refit with another vertex count) are [`QueryError`]s, never panics.

pub mod aabb_tree;
pub mod closest;
pub mod error;
pub mod moving;
mod pseudo_normal;
pub mod radius;
pub mod signed;
pub mod surface;
pub mod triangle;

pub use aabb_tree::AabbTree;
pub use closest::{ClosestPoint, SurfaceFeature};
pub use error::QueryError;
pub use moving::MovingSurface;
pub use radius::{BodyEdge, BodyEdgeRule, VertexTree};
pub use surface::BodySurface;
pub use triangle::{closest_point_on_triangle, LocalFeature, TrianglePoint};
