//! Body vertices near garment nodes: HOOD's *body edges* (seed 004 §3.1, "Basic
//! structure": "for each garment node we find the nearest vertex on the body model and
//! add a new edge if the distance is below a threshold r"), and the more general "all
//! body vertices within r" used by contact-aware message passing.
//!
//! A [`VertexTree`] is the same [`AabbTree`] as the surface queries, over point boxes;
//! it is refit per frame like [`super::BodySurface`].

use rayon::prelude::*;
use weft_mesh::Aabb;

use super::aabb_tree::AabbTree;
use super::error::QueryError;
use super::surface::check_finite;
use weft_mesh::vec3::{dist, is_finite, norm_sq, sub};

/// A point set (the body's vertices) with its AABB tree.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexTree {
    positions: Vec<[f64; 3]>,
    tree: AabbTree,
}

/// One body edge: a garment node, a body vertex, and their distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyEdge {
    /// Garment node (index into the query points).
    pub garment: u32,
    /// Body vertex.
    pub body: u32,
    /// Euclidean distance between them (metres), `<= radius`.
    pub distance: f64,
}

/// Which body vertices within the radius a garment node connects to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BodyEdgeRule {
    /// The nearest body vertex only, if within the radius: HOOD's rule.
    Nearest,
    /// The `k` nearest body vertices within the radius.
    NearestK(usize),
    /// Every body vertex within the radius.
    All,
}

fn point_boxes(points: &[[f64; 3]]) -> Vec<Aabb> {
    points.iter().map(|&p| Aabb { min: p, max: p }).collect()
}

fn check_radius(radius: f64) -> Result<(), QueryError> {
    if radius.is_finite() && radius >= 0.0 {
        Ok(())
    } else {
        Err(QueryError::BadRadius(radius))
    }
}

impl VertexTree {
    /// A tree over `positions` (at least one, all finite).
    pub fn new(positions: &[[f64; 3]]) -> Result<Self, QueryError> {
        if positions.is_empty() {
            return Err(QueryError::Empty {
                vertices: 0,
                faces: 0,
                needed: "vertex",
            });
        }
        check_finite(positions, "vertex")?;
        Ok(VertexTree {
            positions: positions.to_vec(),
            tree: AabbTree::build(&point_boxes(positions)),
        })
    }

    /// Moves the points (same count) and refits the tree (`O(n)`).
    pub fn refit(&mut self, positions: &[[f64; 3]]) -> Result<(), QueryError> {
        if positions.len() != self.positions.len() {
            return Err(QueryError::CountMismatch {
                expected: self.positions.len(),
                found: positions.len(),
            });
        }
        check_finite(positions, "vertex")?;
        self.positions.copy_from_slice(positions);
        let _ = self.tree.refit(&point_boxes(positions));
        Ok(())
    }

    /// The points.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// The nearest point to `p` and its distance; `None` for a non-finite `p`. Ties go
    /// to the lower index.
    pub fn nearest(&self, p: [f64; 3]) -> Option<(u32, f64)> {
        if !is_finite(p) {
            return None;
        }
        let mut best = (u32::MAX, f64::INFINITY);
        self.tree.nearest(p, f64::INFINITY, |i, _| {
            let d = norm_sq(sub(self.positions[i as usize], p));
            // Keep the lower index on exact ties so the answer is independent of the
            // tree layout.
            if d < best.1 || (d == best.1 && i < best.0) {
                best = (i, d);
            }
            Some((d, ()))
        })?;
        Some((best.0, best.1.sqrt()))
    }

    /// Every point within `radius` of `p` (distance `<= radius`), as `(index,
    /// distance)` sorted by distance, then index.
    pub fn within_radius(&self, p: [f64; 3], radius: f64) -> Result<Vec<(u32, f64)>, QueryError> {
        check_radius(radius)?;
        if !is_finite(p) {
            return Err(QueryError::NonFinite {
                what: "query point",
                index: 0,
                position: p,
            });
        }
        Ok(self.within_unchecked(p, radius))
    }

    fn within_unchecked(&self, p: [f64; 3], radius: f64) -> Vec<(u32, f64)> {
        let mut out = Vec::new();
        self.tree.for_each_near(p, radius, |i| {
            let d = dist(self.positions[i as usize], p);
            if d <= radius {
                out.push((i, d));
            }
        });
        out.sort_unstable_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        out
    }

    /// Body edges from every garment node (`garment[i]`) to the body vertices within
    /// `radius`, chosen by `rule`; in parallel over the nodes. Ordered by garment node,
    /// then distance, then body vertex.
    pub fn body_edges(
        &self,
        garment: &[[f64; 3]],
        radius: f64,
        rule: BodyEdgeRule,
    ) -> Result<Vec<BodyEdge>, QueryError> {
        check_radius(radius)?;
        check_finite(garment, "query point")?;
        let per_node: Vec<Vec<BodyEdge>> = garment
            .par_iter()
            .enumerate()
            .map(|(g, &p)| {
                let mut near = match rule {
                    BodyEdgeRule::Nearest => self
                        .nearest(p)
                        .filter(|&(_, d)| d <= radius)
                        .into_iter()
                        .collect(),
                    BodyEdgeRule::NearestK(_) | BodyEdgeRule::All => {
                        self.within_unchecked(p, radius)
                    }
                };
                if let BodyEdgeRule::NearestK(k) = rule {
                    near.truncate(k);
                }
                near.into_iter()
                    .map(|(body, distance)| BodyEdge {
                        garment: g as u32,
                        body,
                        distance,
                    })
                    .collect()
            })
            .collect();
        Ok(per_node.into_iter().flatten().collect())
    }
}
