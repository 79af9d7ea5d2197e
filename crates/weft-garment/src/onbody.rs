//! Generation on an actual body model: measure it, build the garment, move it into the
//! body's frame and push any vertex closer than a margin out of the body.
//!
//! Tubes of ellipses follow the body's cross sections only approximately: the shoulder
//! blades and the inner thighs bulge past an ellipse or a strap's arc. The push-out moves
//! just those vertices (by at most a few centimetres) to the body's closest surface point
//! plus the margin along the outward direction, the same step a drape's first frame
//! performs, so the template starts collision-free for the simulator.

use weft_body::features::volumetric::{VolumetricDistance, VolumetricParams};
use weft_body::features::{transfer_weights, SkinningWeights};
use weft_body::query::BodySurface;
use weft_body::BodyModel;
use weft_mesh::TriMesh;

use crate::build::{add, norm, scale, sub};
use crate::{generate, Garment, GarmentError, GarmentKind, Measurements, Style};

/// Distance kept between a pushed-out vertex and the body (m).
pub const PUSH_OUT_MARGIN: f64 = 0.004;

/// The rest-pose body a garment is fitted to: its measurements, mesh and query surface.
pub struct FitBody {
    /// Measurements (pelvis-relative).
    pub measurements: Measurements,
    /// The body mesh at β, in the model's own frame.
    pub mesh: TriMesh,
    /// Closest-point / signed-distance queries on `mesh`.
    pub surface: BodySurface,
    /// The pelvis joint: garments are built around the origin and moved here.
    pub origin: [f64; 3],
}

impl FitBody {
    /// Measures `model` at shape `betas`.
    pub fn new(model: &BodyModel, betas: &[f64]) -> Result<Self, GarmentError> {
        let measurements = Measurements::from_body(model, betas)?;
        let mesh = model.shape(betas)?;
        let origin = model.joints(betas)?.first().copied().unwrap_or([0.0; 3]);
        let surface = BodySurface::from_mesh(&mesh)
            .map_err(|e| GarmentError::Measurements(format!("body surface: {e}")))?;
        Ok(FitBody {
            measurements,
            mesh,
            surface,
            origin,
        })
    }

    /// Builds `kind` on this body with about `vertices` vertices.
    pub fn generate(
        &self,
        kind: GarmentKind,
        style: &Style,
        vertices: usize,
    ) -> Result<Garment, GarmentError> {
        let mut g = generate(kind, style, &self.measurements, vertices)?;
        for p in &mut g.mesh.positions {
            *p = add(*p, self.origin);
        }
        let before = g.mesh.positions.clone();
        self.push_out(&mut g.mesh.positions, PUSH_OUT_MARGIN)?;
        spread_displacements(&mut g.mesh, &before, 20);
        self.push_out(&mut g.mesh.positions, PUSH_OUT_MARGIN)?;
        Ok(g)
    }

    /// [`push_out`] on this body.
    pub fn push_out(&self, points: &mut [[f64; 3]], margin: f64) -> Result<(), GarmentError> {
        push_out(&self.surface, points, margin).map(|_| ())
    }

    /// Fills `garment.weights` with `model`'s skinning weights transferred to the
    /// garment vertices (closest body surface point, barycentric; weft-body's
    /// `features::transfer`), for the LBS baselines and for initialising sequences. The
    /// garment must have been built by [`FitBody::generate`] on this body.
    pub fn transfer_weights(
        &self,
        model: &BodyModel,
        garment: &mut Garment,
    ) -> Result<(), GarmentError> {
        garment.weights = Some(self.weights_at(model, &garment.mesh.positions)?);
        Ok(())
    }

    /// `model`'s skinning weights at `points` (any garment on this body, e.g. one read
    /// from an OBJ file): closest body surface point, barycentric.
    pub fn weights_at(
        &self,
        model: &BodyModel,
        points: &[[f64; 3]],
    ) -> Result<SkinningWeights, GarmentError> {
        let w = model.weights();
        let (n, s) = (w.vertex_count(), w.joint_count());
        let mut dense = vec![0.0; n * s];
        for v in 0..n {
            for (j, x) in w.influences(v) {
                if let Some(slot) = dense.get_mut(v * s + j) {
                    *slot = x;
                }
            }
        }
        let body_weights = SkinningWeights::new(dense, s)
            .map_err(|e| GarmentError::Measurements(format!("body skinning weights: {e}")))?;
        let t = transfer_weights(&self.surface, &body_weights, points)
            .map_err(|e| GarmentError::Measurements(format!("weight transfer: {e}")))?;
        Ok(t.weights)
    }

    /// Volumetric distance from every point to every joint through this body (weft-body's
    /// `VolumetricDistance`, seed 001's `x_i`), row-major `points × joints`.
    pub fn joint_distances(
        &self,
        joints: &[[f64; 3]],
        parents: &[Option<usize>],
        points: &[[f64; 3]],
    ) -> Result<Vec<f32>, GarmentError> {
        VolumetricDistance::new(&self.surface, joints, parents, VolumetricParams::default())
            .and_then(|d| d.matrix(points))
            .map(|m| m.to_f32())
            .map_err(|e| GarmentError::Measurements(format!("volumetric joint distances: {e}")))
    }
}

/// Moves every point closer to `surface` than `margin` (or inside it) to the closest
/// surface point plus `margin` outwards, and returns how many points moved. Four passes:
/// a moved point can land near another part of the body (armpit, crotch). A pass after
/// the first queries only the points the one before moved: the others would be found
/// where they were, at least `margin` out.
pub fn push_out(
    surface: &BodySurface,
    points: &mut [[f64; 3]],
    margin: f64,
) -> Result<usize, GarmentError> {
    let mut moved = vec![false; points.len()];
    let mut active: Vec<usize> = (0..points.len()).collect();
    for _ in 0..4 {
        if active.is_empty() {
            break;
        }
        let query: Vec<[f64; 3]> = active.iter().map(|&i| points[i]).collect();
        let closest = surface
            .closest_points(&query)
            .map_err(|e| GarmentError::Measurements(format!("closest points: {e}")))?;
        let mut next = Vec::new();
        for (&i, c) in active.iter().zip(&closest) {
            if c.signed_distance >= margin {
                continue;
            }
            let p = &mut points[i];
            let offset = sub(*p, c.point);
            let d = norm(offset);
            let out = if d > 1e-9 {
                scale(offset, c.signed_distance.signum() / d)
            } else {
                surface.face_normals()[c.triangle as usize]
            };
            *p = add(c.point, scale(out, margin));
            moved[i] = true;
            next.push(i);
        }
        active = next;
    }
    Ok(moved.iter().filter(|&&m| m).count())
}

/// Carries the push-out displacements to the neighbourhood of the moved vertices.
///
/// Moving only the vertices inside the body by a few centimetres folds their triangles
/// over their unmoved neighbours (the garment then crosses itself). Here every vertex
/// that was not moved takes the mean displacement of its neighbours, damped, for
/// `rounds` rounds: a smooth, decaying bump instead of a spike. Moved vertices keep
/// their own displacement.
pub(crate) fn spread_displacements(mesh: &mut TriMesh, before: &[[f64; 3]], rounds: usize) {
    let graph = mesh.graph();
    let moved: Vec<bool> = mesh
        .positions
        .iter()
        .zip(before)
        .map(|(p, q)| norm(sub(*p, *q)) > 1e-12)
        .collect();
    let mut d: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .zip(before)
        .map(|(p, q)| sub(*p, *q))
        .collect();
    for _ in 0..rounds {
        let next: Vec<[f64; 3]> = (0..d.len())
            .map(|i| {
                if moved[i] {
                    return d[i];
                }
                let nb = graph.neighbors(i);
                if nb.is_empty() {
                    return d[i];
                }
                let sum = nb.iter().fold([0.0; 3], |s, &j| add(s, d[j as usize]));
                let mean = scale(sum, 1.0 / nb.len() as f64);
                // Never shrink a displacement already carried here.
                if norm(mean) * 0.9 > norm(d[i]) {
                    scale(mean, 0.9)
                } else {
                    d[i]
                }
            })
            .collect();
        d = next;
    }
    for ((p, q), di) in mesh.positions.iter_mut().zip(before).zip(&d) {
        *p = add(*q, *di);
    }
}
