//! Dressed characters: a body and its tight clothes as one mesh (seed 001's case 1,
//! §1.2.1: Adobe Fuse characters whose clothes are part of the skinned mesh).
//!
//! weft's bodies and garments are separate meshes, so a character here is their union
//! (thesis-reference D3): the body at its shape, then each garment layer built by
//! weft-garment on that body and shrink-wrapped to `layer_offset` above the skin, as
//! tight clothes are modelled on a game character. Each layer is its own connected
//! component of the mesh; a graph network does not mind. Garment vertices take the
//! body's skinning weights at their closest skin point (weft-body's transfer), which is
//! exact for a layer on the skin.

use weft_body::skinning::SkinWeights;
use weft_body::BodyModel;
use weft_garment::{FitBody, GarmentKind, Style};
use weft_mesh::vec3::{add, scale};
use weft_mesh::TriMesh;

use crate::error::DataError;

/// Rounds of smoothing with re-projection after the shrink-wrap (see [`shrink_wrap`]).
const WRAP_ROUNDS: usize = 4;

/// A character mesh with everything its deformations and features need.
#[derive(Clone, Debug)]
pub struct DressedCharacter {
    /// The rest mesh: the body's vertices first, then each garment layer's.
    pub mesh: TriMesh,
    /// Skinning weights, one row per vertex.
    pub weights: SkinWeights,
    /// What each vertex belongs to: 0 the body, `k` the `k`-th garment layer.
    pub parts: Vec<u32>,
    /// Rest joint positions `J(β)`.
    pub joints: Vec<[f64; 3]>,
    /// Each joint's parent (`None` for the root).
    pub parents: Vec<Option<usize>>,
    /// Volumetric distance of every vertex to every joint in the rest pose, row-major
    /// `N × S` (seed 001 §3.2.1's `x_i`, weft-body's approximation of Dionne & de Lasa).
    pub joint_distances: Vec<f32>,
}

impl DressedCharacter {
    /// Vertices.
    pub fn vertex_count(&self) -> usize {
        self.mesh.positions.len()
    }

    /// Joints.
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }
}

/// Builds the character of `model` at `betas` wearing `garments` (each with about
/// `vertices` vertices) `offset` metres above the skin.
pub fn dress(
    model: &BodyModel,
    betas: &[f64],
    garments: &[(GarmentKind, Style)],
    vertices: usize,
    offset: f64,
) -> Result<DressedCharacter, DataError> {
    let garment_err = |what: &str, e: &dyn std::error::Error| {
        DataError::config("characters", format!("{what}: {e}"))
    };
    let fit = FitBody::new(model, betas).map_err(|e| garment_err("fitting the body", &e))?;
    let mut mesh = fit.mesh.clone();
    let body_n = mesh.positions.len();
    let mut parts = vec![0u32; body_n];
    let body_dense = model.weights().to_dense();
    let s = model.joint_count();
    let mut dense = body_dense;
    for (k, (kind, style)) in garments.iter().enumerate() {
        let g = fit
            .generate(*kind, style, vertices)
            .map_err(|e| garment_err(&format!("building the {}", kind.name()), &e))?;
        let mut layer = g.mesh;
        shrink_wrap(&fit, &mut layer, offset)
            .map_err(|e| garment_err(&format!("wrapping the {}", kind.name()), &e))?;
        let w = fit
            .weights_at(model, &layer.positions)
            .map_err(|e| garment_err(&format!("weights of the {}", kind.name()), &e))?;
        dense.extend_from_slice(w.as_slice());
        let base = mesh.positions.len() as u32;
        parts.extend(std::iter::repeat_n(k as u32 + 1, layer.positions.len()));
        mesh.positions.extend_from_slice(&layer.positions);
        mesh.faces
            .extend(layer.faces.iter().map(|f| f.map(|v| v + base)));
    }
    let joints = model
        .joints(betas)
        .map_err(|e| garment_err("rest joints", &e))?;
    let parents = model.skeleton().parents().to_vec();
    let joint_distances = fit
        .joint_distances(&joints, &parents, &mesh.positions)
        .map_err(|e| garment_err("volumetric joint distances", &e))?;
    Ok(DressedCharacter {
        weights: SkinWeights::from_dense(&dense, s),
        joint_distances,
        mesh,
        parts,
        joints,
        parents,
    })
}

/// Puts every vertex of `layer` at `offset` above its closest skin point, then smooths
/// and re-projects a few rounds: a loose template projected straight onto the skin
/// bunches up where the body curves inwards (armpits, crotch); averaging each vertex
/// with its neighbours before projecting again spreads those triangles out.
fn shrink_wrap(
    fit: &FitBody,
    layer: &mut TriMesh,
    offset: f64,
) -> Result<(), weft_body::query::QueryError> {
    let graph = layer.graph();
    for round in 0..=WRAP_ROUNDS {
        if round > 0 {
            let before = layer.positions.clone();
            for (v, p) in layer.positions.iter_mut().enumerate() {
                let nb = graph.neighbors(v);
                if nb.is_empty() {
                    continue;
                }
                let mut mean = [0.0; 3];
                for &u in nb {
                    mean = add(mean, before[u as usize]);
                }
                *p = scale(add(scale(mean, 1.0 / nb.len() as f64), before[v]), 0.5);
            }
        }
        let closest = fit.surface.closest_points(&layer.positions)?;
        for (p, c) in layer.positions.iter_mut().zip(&closest) {
            *p = add(c.point, scale(c.interpolated_normal, offset));
        }
    }
    Ok(())
}
