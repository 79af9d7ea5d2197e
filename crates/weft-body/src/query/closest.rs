//! Closest point on the body surface to a query point: the triangle, barycentric
//! coordinates, the point, the distance, the feature it lies on and its normals.
//!
//! This is what skinning-weight transfer (nearest surface point, barycentric
//! interpolation of the body's weights), the collision term of the losses (seed 000
//! supplement eq. 4, seed 004 eq. 5: a function of the signed distance `h(x)` to the
//! body) and the garment–body features all stand on.

use rayon::prelude::*;

use super::error::QueryError;
use super::surface::{check_finite, BodySurface};
use super::triangle::{closest_point_on_triangle, LocalFeature};
use weft_mesh::vec3::{add_scaled, dot, is_finite, normalize_or_zero, sub};

/// The mesh feature a closest point lies on, in the surface's own vertex and face
/// indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SurfaceFeature {
    /// A vertex.
    Vertex(u32),
    /// An edge, by its two vertices in ascending order.
    Edge([u32; 2]),
    /// The interior of a face.
    Face(u32),
}

/// The answer of a closest-point query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestPoint {
    /// The face holding the point (when the point is on an edge or a vertex, one of the
    /// faces sharing it).
    pub triangle: u32,
    /// Barycentric coordinates in `triangle`'s corner order: non-negative, sum 1.
    pub barycentric: [f64; 3],
    /// The closest point.
    pub point: [f64; 3],
    /// Euclidean distance from the query point.
    pub distance: f64,
    /// Distance with the sign of the side: negative inside a closed, outward-oriented
    /// surface, positive outside, zero on it (see [`super::signed`]).
    pub signed_distance: f64,
    /// The feature the point lies on.
    pub feature: SurfaceFeature,
    /// Unit angle-weighted pseudo-normal of `feature` (Bærentzen & Aanæs): the normal
    /// that gives the sign.
    pub normal: [f64; 3],
    /// Unit normal interpolated from the vertex pseudo-normals with `barycentric`: the
    /// smooth normal to use as a feature or for a collision response direction.
    pub interpolated_normal: [f64; 3],
}

impl BodySurface {
    /// The closest surface point to `p`. Fails only on a non-finite `p`.
    pub fn closest_point(&self, p: [f64; 3]) -> Result<ClosestPoint, QueryError> {
        if !is_finite(p) {
            return Err(QueryError::NonFinite {
                what: "query point",
                index: 0,
                position: p,
            });
        }
        // A non-empty tree answers every finite point.
        self.closest_unchecked(p, f64::INFINITY)
            .ok_or(QueryError::NonFinite {
                what: "query point",
                index: 0,
                position: p,
            })
    }

    /// The closest surface point to `p` if it is within `max_distance`, else `None`
    /// (faster than an unbounded query: the search prunes everything farther). For
    /// collision handling, where only near points matter.
    pub fn closest_point_within(
        &self,
        p: [f64; 3],
        max_distance: f64,
    ) -> Result<Option<ClosestPoint>, QueryError> {
        if !(max_distance.is_finite() && max_distance >= 0.0) {
            return Err(QueryError::BadRadius(max_distance));
        }
        if !is_finite(p) {
            return Err(QueryError::NonFinite {
                what: "query point",
                index: 0,
                position: p,
            });
        }
        // Strictly-closer search; widen by one ulp-ish so a point exactly at the bound
        // is found.
        let bound = max_distance * max_distance * (1.0 + 4.0 * f64::EPSILON);
        Ok(self
            .closest_unchecked(p, bound.max(f64::MIN_POSITIVE))
            .filter(|c| c.distance <= max_distance))
    }

    /// [`BodySurface::closest_point`] for many points, in parallel (rayon). The result
    /// has one entry per point, in order. Fails, naming the point, if one is not finite.
    pub fn closest_points(&self, points: &[[f64; 3]]) -> Result<Vec<ClosestPoint>, QueryError> {
        check_finite(points, "query point")?;
        points.par_iter().map(|&p| self.closest_point(p)).collect()
    }

    /// The query itself, on a finite point; `None` only when nothing is closer than
    /// `max_sq` (never for an unbounded query on a non-empty surface).
    pub(crate) fn closest_unchecked(&self, p: [f64; 3], max_sq: f64) -> Option<ClosestPoint> {
        let (triangle, distance_sq, tp) = self.tree.nearest(p, max_sq, |f, _| {
            let tri = self.faces[f as usize].map(|i| self.positions[i as usize]);
            let tp = closest_point_on_triangle(p, tri);
            Some((tp.distance_sq, tp))
        })?;
        let face = self.faces[triangle as usize];
        let (feature, normal) = match tp.feature {
            LocalFeature::Vertex(k) => {
                let v = face[k as usize];
                (SurfaceFeature::Vertex(v), self.vertex_normal(v))
            }
            LocalFeature::Edge(k) => {
                let e = self.normals.face_edges[triangle as usize][k as usize] as usize;
                (
                    SurfaceFeature::Edge(self.normals.edge_vertices[e]),
                    self.normals.edge[e],
                )
            }
            LocalFeature::Face => (
                SurfaceFeature::Face(triangle),
                self.normals.face[triangle as usize],
            ),
        };
        let mut smooth = [0.0; 3];
        for (&v, &b) in face.iter().zip(&tp.barycentric) {
            smooth = add_scaled(smooth, self.vertex_normal(v), b);
        }
        let smooth = normalize_or_zero(smooth);
        let distance = distance_sq.sqrt();
        let side = dot(sub(p, tp.point), normal);
        let signed_distance = if side < 0.0 { -distance } else { distance };
        Some(ClosestPoint {
            triangle,
            barycentric: tp.barycentric,
            point: tp.point,
            distance,
            signed_distance,
            feature,
            normal,
            interpolated_normal: if smooth == [0.0; 3] { normal } else { smooth },
        })
    }
}
