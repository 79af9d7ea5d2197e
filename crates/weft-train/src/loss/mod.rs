//! Loss building blocks: the terms of seed 000 (supplement §2) as differentiable
//! functions of a prediction, for any task to weight and combine (Multilevel's names and
//! weights are in [`crate::tasks::multilevel`]).
//!
//! - [`supervised`]: vertex, edge and normal terms (eq. 1–3) as burn tensor code.
//! - [`physics`]: collision, gravity, stretch and shear (eq. 4–8) as one custom autodiff
//!   operation over weft-sim's energies; [`collision_energies`] ([`collision_energy`]
//!   per frame), [`gravity_energy`] and [`membrane_energies`] build those energies for a
//!   garment.

pub mod physics;
pub mod supervised;
#[cfg(test)]
mod tests;

use std::sync::Arc;

use weft_mesh::TriMesh;
use weft_sim::{
    lumped_masses, BodyProximity, Gravity, LinearCollision, RestFrames, UvShear, UvStretch,
    VertexContact,
};

use crate::error::Result;
pub use physics::{physics_loss, FrameEnergies, PhysicsImpl, PotentialTerm};
pub use supervised::{
    edge_loss, mean_vertex_error_mm, normal_loss, vertex_loss, GarmentTopology, Targets,
    WindowIndex,
};

/// Eq. 4 for a window: one [`LinearCollision`] per frame, with the contacts of the
/// predicted positions `x` (`T·N`, frame-major) against that frame's posed body
/// ([`collision_energy`] per frame).
pub fn collision_energies<P: BodyProximity + Sync>(
    bodies: &[P],
    x: &[[f64; 3]],
    vertex_count: usize,
    eps: f64,
    radius: f64,
) -> Result<FrameEnergies> {
    check_window_positions(x, bodies.len(), vertex_count)?;
    let frames = bodies
        .iter()
        .zip(x.chunks(vertex_count.max(1)))
        .map(|(body, xt)| collision_energy(body, xt, eps, radius))
        .collect::<Result<_>>()?;
    FrameEnergies::per_frame(frames)
}

/// Checks that the collision term's positions `x` are `frames` frames of `vertex_count`
/// vertices.
pub(crate) fn check_window_positions(
    x: &[[f64; 3]],
    frames: usize,
    vertex_count: usize,
) -> Result<()> {
    if x.len() != frames * vertex_count {
        return Err(crate::TrainError::Shape {
            what: "collision loss positions".into(),
            expected: format!("{frames} frames × {vertex_count} vertices"),
            found: x.len().to_string(),
        });
    }
    Ok(())
}

/// Eq. 4 for one frame: the contacts of the garment's vertices `x` against `body`, found
/// in parallel.
///
/// The contacts are taken at the current prediction and held fixed through the
/// backward pass (as the simulator refreshes them once per step): the hinge is then a
/// plane per vertex, whose gradient is exact. `eps` is the threshold ε of eq. 4 (m);
/// contacts farther than `radius` (m) from a vertex are ignored.
pub fn collision_energy<P: BodyProximity + Sync>(
    body: &P,
    x: &[[f64; 3]],
    eps: f64,
    radius: f64,
) -> Result<Arc<dyn weft_sim::Energy + Send + Sync>> {
    use rayon::prelude::*;
    let contacts: Vec<VertexContact> = x
        .par_iter()
        .enumerate()
        .filter_map(|(v, &p)| {
            let contact = body.closest(p)?;
            let d = contact.signed_distance(p);
            // Outside and beyond the radius: no contact can act this step.
            (d < radius).then_some(VertexContact {
                vertex: v as u32,
                contact,
            })
        })
        .collect();
    Ok(Arc::new(LinearCollision::new(x.len(), eps, contacts)?))
}

/// Eq. 5 over `frames` frames: lumped masses of the rest garment at area density
/// `density` (kg/m²), weft's Y-up gravity.
pub fn gravity_energy(rest: &TriMesh, frames: usize, density: f64) -> Result<FrameEnergies> {
    let masses = lumped_masses(rest, &vec![density; rest.face_count()])?;
    let g = Gravity::new(masses, weft_sim::STANDARD_GRAVITY)?;
    FrameEnergies::shared(Arc::new(g), frames)
}

/// The rest frames of eq. 8: from the garment's corner UVs (the flat pattern, metres)
/// when it has them, else its rest triangles laid flat.
pub fn rest_frames(rest: &TriMesh, corner_uvs: Option<&[[[f32; 2]; 3]]>) -> Result<RestFrames> {
    Ok(match corner_uvs {
        Some(uvs) => {
            let uvs: Vec<[[f64; 2]; 3]> = uvs.iter().map(|f| f.map(|c| c.map(f64::from))).collect();
            RestFrames::from_corner_uvs(rest.vertex_count(), rest.faces.clone(), &uvs)?
        }
        None => RestFrames::from_rest_mesh(rest)?,
    })
}

/// Eq. 6 and 7 over `frames` frames of a garment with rest frames `rest`
/// ([`rest_frames`]).
pub fn membrane_energies(
    rest: &RestFrames,
    frames: usize,
) -> Result<(FrameEnergies, FrameEnergies)> {
    let stretch = FrameEnergies::shared(Arc::new(UvStretch::new(rest.clone())), frames)?;
    let shear = FrameEnergies::shared(Arc::new(UvShear::new(rest.clone())), frames)?;
    Ok((stretch, shear))
}
