//! Signed distance to the body surface: negative inside, positive outside.
//!
//! The sign is that of `(p − c) · n`, `c` the closest surface point and `n` the
//! angle-weighted pseudo-normal of the feature (vertex, edge or face) `c` lies on
//! (Bærentzen & Aanæs 2005; docs/body-features.md). Unlike ray parity or the
//! normal of the nearest face, this is exact for every point when the surface is a
//! closed, outward-oriented 2-manifold, including points whose closest point is a sharp
//! edge or vertex; on an open or inconsistently oriented mesh it degrades gracefully to
//! "the side of the nearest feature".
//!
//! Used by the collision term of the losses (seed 000 supplement eq. 4,
//! `max(ε − h(x), 0)³` with `h` this function; seed 004 eq. 5), by the simulator's
//! contact handling and by the volumetric joint distances of [`crate::features`].

use rayon::prelude::*;

use super::error::QueryError;
use super::surface::{check_finite, BodySurface};

impl BodySurface {
    /// The signed distance from `p` to the surface (metres; negative inside).
    pub fn signed_distance(&self, p: [f64; 3]) -> Result<f64, QueryError> {
        self.closest_point(p).map(|c| c.signed_distance)
    }

    /// [`BodySurface::signed_distance`] for many points, in parallel (rayon).
    pub fn signed_distances(&self, points: &[[f64; 3]]) -> Result<Vec<f64>, QueryError> {
        check_finite(points, "query point")?;
        Ok(points
            .par_iter()
            .map(|&p| self.signed_distance_unchecked(p))
            .collect())
    }

    /// Signed distance of a point already known to be finite.
    pub(crate) fn signed_distance_unchecked(&self, p: [f64; 3]) -> f64 {
        self.closest_unchecked(p, f64::INFINITY)
            .map_or(f64::INFINITY, |c| c.signed_distance)
    }
}
