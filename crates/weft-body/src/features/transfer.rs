//! Skinning-weight transfer from the body to a garment: each garment vertex takes the
//! body's weights at its nearest body surface point, interpolated with that point's
//! barycentric coordinates.
//!
//! This is the standard initialisation of garment skinning in the papers weft follows
//! (seed 000 starts its learned `W^t` from a garment on a body; seed 001 §4 needs
//! `w_{s,i}` for garment vertices to evaluate eq. 3.9 on the garment; the LBS-based
//! baselines HOOD compares against skin garments this way). Barycentric interpolation
//! on the closest *surface point* rather than copying the nearest *vertex* keeps the
//! weights continuous across the garment — a nearest-vertex copy is piecewise constant
//! and tears garments at the body's Voronoi boundaries.
//!
//! It is exact for garment vertices on the body surface and right for tight garments.
//! For loose ones (skirts, dresses) a vertex between the legs snaps to whichever thigh is
//! nearer and the garment tears when the legs part; [`super::diffusion`] smooths the
//! transferred weights over the garment for that case.

use super::error::FeatureError;
use super::matrix::FeatureMatrix;
use super::weights::SkinningWeights;
use crate::query::{BodySurface, ClosestPoint};

/// Transferred weights and the body points they came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Transfer {
    /// One row per garment vertex, non-negative, summing to one.
    pub weights: SkinningWeights,
    /// The closest body surface point of each garment vertex (its distance is the
    /// garment–body distance the diffused variant uses).
    pub closest: Vec<ClosestPoint>,
}

/// Transfers `body_weights` (one row per vertex of `body`) to the `garment` vertices
/// by closest surface point and barycentric interpolation; closest points in parallel.
pub fn transfer_weights(
    body: &BodySurface,
    body_weights: &SkinningWeights,
    garment: &[[f64; 3]],
) -> Result<Transfer, FeatureError> {
    if body_weights.vertex_count() != body.positions().len() {
        return Err(FeatureError::CountMismatch {
            what: "body skinning weight rows vs body vertices",
            expected: body.positions().len(),
            found: body_weights.vertex_count(),
        });
    }
    let closest = body.closest_points(garment)?;
    let s = body_weights.joint_count();
    let mut m = FeatureMatrix::zeros(garment.len(), s);
    for (i, c) in closest.iter().enumerate() {
        let face = body.faces()[c.triangle as usize];
        let row = m.row_mut(i);
        for (&b, &v) in c.barycentric.iter().zip(&face) {
            if b > 0.0 {
                for (o, &w) in row.iter_mut().zip(body_weights.row(v as usize)) {
                    *o += b * w;
                }
            }
        }
    }
    // Convex combinations of rows summing to one: non-negative, and the renormalisation
    // only removes rounding.
    Ok(Transfer {
        weights: SkinningWeights::from_matrix(m)?,
        closest,
    })
}
