//! Diffused skinning weights for loose garments: the transferred weights
//! ([`super::transfer`]) smoothed over the garment graph, more strongly the farther a
//! vertex hangs from the body.
//!
//! Why. Closest-point transfer is right where the garment touches the body and wrong
//! where it does not: the hem of a skirt between the legs takes the weights of whichever
//! thigh is nearer, and the skirt tears down the middle when the legs part. The papers'
//! answer is the same in spirit each time — extend the body's skinning smoothly into
//! the space around it and let loose cloth inherit a *blend* of the nearby bones:
//! SSCH's diffused body model (Santesteban et al. 2021, cited by seed 004 §2) diffuses
//! the body's weights into 3D; SNUG and HOOD's LBS baselines use such weights for
//! their skirts and dresses. weft diffuses on the garment itself, which needs no
//! volumetric grid and respects the garment's own connectivity.
//!
//! Method: `K` explicit heat-diffusion (Jacobi) steps on the garment graph,
//!
//! ```text
//! w_i ← w_i + τ_i (Σ_j c_ij w_j / Σ_j c_ij − w_i),   c_ij = 1 / ‖x_i − x_j‖,
//! τ_i = τ_max · smoothstep((d_i − d_tight) / (d_loose − d_tight)),
//! ```
//!
//! with `d_i` the vertex's distance outside the body (`max(signed distance, 0)`, so a
//! vertex that has sunk into the body counts as tight). Vertices within `d_tight` have
//! `τ = 0` and keep their transferred weights exactly: they anchor the diffusion, so a
//! skirt's waistband follows the pelvis and its hem becomes a smooth blend of pelvis,
//! hips and thighs. Inverse-edge-length weights make the average less sensitive to
//! irregular triangulations than the uniform graph Laplacian. Each step is a convex
//! combination of rows that sum to one, so weights stay non-negative with rows summing
//! to one (renormalised at the end against rounding).
//!
//! Iteration count: `K = ⌈(L / h̄)² / τ_max⌉` (at most `max_iterations`), `h̄` the mean
//! edge length, so that the weights spread over roughly the smoothing length `L`
//! whatever the garment's resolution (a random walk moving one edge with probability
//! `τ` per step spreads about `h̄·√(τK)` after `K` steps).

use rayon::prelude::*;
use weft_mesh::{Graph, TriMesh};

use super::error::FeatureError;
use super::transfer::{transfer_weights, Transfer};
use super::weights::SkinningWeights;
use crate::query::BodySurface;
use weft_mesh::vec3::dist;

/// Parameters of [`diffuse_weights`]; the defaults suit skirts and dresses on an adult
/// body in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffusionParams {
    /// Vertices at most this far outside the body keep their transferred weights
    /// (metres; default 0.01).
    pub tight_distance: f64,
    /// Vertices at least this far outside diffuse at the full rate (metres; default
    /// 0.10). Must exceed `tight_distance`.
    pub loose_distance: f64,
    /// Full diffusion rate `τ_max` per step, in `(0, 1]` (default 0.5; above 0.5 the
    /// explicit step starts to oscillate on bipartite stretches of the graph).
    pub rate: f64,
    /// Smoothing length `L` in metres (default 0.15): about how far the weights spread.
    pub smoothing_length: f64,
    /// Upper bound on the number of steps (default 5 000).
    pub max_iterations: usize,
}

impl Default for DiffusionParams {
    fn default() -> Self {
        DiffusionParams {
            tight_distance: 0.01,
            loose_distance: 0.10,
            rate: 0.5,
            smoothing_length: 0.15,
            max_iterations: 5_000,
        }
    }
}

impl DiffusionParams {
    fn check(&self) -> Result<(), FeatureError> {
        let bad = |name, value, expected| {
            Err(FeatureError::BadParameter {
                name,
                value,
                expected,
            })
        };
        if !(self.tight_distance.is_finite() && self.tight_distance >= 0.0) {
            return bad("tight_distance", self.tight_distance, "finite and >= 0");
        }
        if !(self.loose_distance.is_finite() && self.loose_distance > self.tight_distance) {
            return bad(
                "loose_distance",
                self.loose_distance,
                "finite and greater than tight_distance",
            );
        }
        if !(self.rate > 0.0 && self.rate <= 1.0) {
            return bad("rate", self.rate, "in (0, 1]");
        }
        if !(self.smoothing_length.is_finite() && self.smoothing_length >= 0.0) {
            return bad("smoothing_length", self.smoothing_length, "finite and >= 0");
        }
        Ok(())
    }

    /// The number of steps for a garment of mean edge length `mean_edge`.
    pub fn iterations(&self, mean_edge: f64) -> usize {
        if !(mean_edge > 0.0 && mean_edge.is_finite()) {
            return 0;
        }
        let k = ((self.smoothing_length / mean_edge).powi(2) / self.rate).ceil();
        if k.is_finite() {
            (k as usize).min(self.max_iterations)
        } else {
            self.max_iterations
        }
    }

    /// `τ_i` for a vertex `d` metres outside the body.
    pub fn rate_at(&self, d: f64) -> f64 {
        let x = ((d - self.tight_distance) / (self.loose_distance - self.tight_distance))
            .clamp(0.0, 1.0);
        self.rate * x * x * (3.0 - 2.0 * x)
    }
}

/// Smooths `weights` (one row per vertex of `graph`, at `positions`) over the graph,
/// each vertex at a rate that grows with its distance `body_distance[i]` outside the
/// body (see the module documentation). Parallel over vertices within each step.
pub fn diffuse_weights(
    graph: &Graph,
    positions: &[[f64; 3]],
    weights: &SkinningWeights,
    body_distance: &[f64],
    params: &DiffusionParams,
) -> Result<SkinningWeights, FeatureError> {
    params.check()?;
    let n = graph.vertex_count();
    for (what, found) in [
        ("garment positions vs graph vertices", positions.len()),
        (
            "skinning weight rows vs graph vertices",
            weights.vertex_count(),
        ),
        ("body distances vs graph vertices", body_distance.len()),
    ] {
        if found != n {
            return Err(FeatureError::CountMismatch {
                what,
                expected: n,
                found,
            });
        }
    }
    super::distances::check_points(positions, "garment vertex")?;
    if let Some(index) = body_distance.iter().position(|d| !d.is_finite()) {
        return Err(FeatureError::NonFinite {
            what: "body distance",
            index,
        });
    }
    // Row-normalised inverse-length edge weights in CSR order.
    let offsets = graph.offsets();
    let adjacency = graph.adjacency();
    let mut coef = vec![0.0; adjacency.len()];
    let mut total_length = 0.0;
    for v in 0..n {
        let range = offsets[v]..offsets[v + 1];
        let mut sum = 0.0;
        for k in range.clone() {
            let len = dist(positions[v], positions[adjacency[k] as usize]);
            total_length += len;
            coef[k] = 1.0 / len.max(1e-9);
            sum += coef[k];
        }
        if sum > 0.0 {
            coef[range].iter_mut().for_each(|c| *c /= sum);
        }
    }
    let mean_edge = if adjacency.is_empty() {
        0.0
    } else {
        total_length / adjacency.len() as f64
    };
    let tau: Vec<f64> = body_distance
        .iter()
        .map(|&d| params.rate_at(d.max(0.0)))
        .collect();
    let s = weights.joint_count();
    let mut cur = weights.as_matrix().clone();
    let mut next = cur.clone();
    for _ in 0..params.iterations(mean_edge) {
        next.as_mut_slice()
            .par_chunks_mut(s)
            .enumerate()
            .for_each(|(v, out)| {
                let own = cur.row(v);
                let t = tau[v];
                let range = offsets[v]..offsets[v + 1];
                if t == 0.0 || range.is_empty() {
                    out.copy_from_slice(own);
                    return;
                }
                out.iter_mut()
                    .zip(own)
                    .for_each(|(o, &w)| *o = (1.0 - t) * w);
                for k in range {
                    let c = t * coef[k];
                    for (o, &w) in out.iter_mut().zip(cur.row(adjacency[k] as usize)) {
                        *o += c * w;
                    }
                }
            });
        std::mem::swap(&mut cur, &mut next);
    }
    SkinningWeights::from_matrix(cur)
}

/// [`transfer_weights`] then [`diffuse_weights`] over the garment mesh's graph, with
/// each vertex's distance outside the body from the transfer's closest points.
pub fn transfer_weights_diffused(
    body: &BodySurface,
    body_weights: &SkinningWeights,
    garment: &TriMesh,
    params: &DiffusionParams,
) -> Result<Transfer, FeatureError> {
    let n = garment.positions.len();
    for (face, f) in garment.faces.iter().enumerate() {
        if let Some(&vertex) = f.iter().find(|&&v| v as usize >= n) {
            return Err(crate::query::QueryError::FaceOutOfRange {
                face,
                vertex,
                vertex_count: n,
            }
            .into());
        }
    }
    let t = transfer_weights(body, body_weights, &garment.positions)?;
    let outside: Vec<f64> = t
        .closest
        .iter()
        .map(|c| c.signed_distance.max(0.0))
        .collect();
    let weights = diffuse_weights(
        &garment.graph(),
        &garment.positions,
        &t.weights,
        &outside,
        params,
    )?;
    Ok(Transfer {
        weights,
        closest: t.closest,
    })
}
