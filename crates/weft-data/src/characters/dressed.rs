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
use weft_mesh::vec3::{add, dot, scale};
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
    /// Body vertices (the first rows of the mesh) and body faces (the first faces).
    pub body_counts: (usize, usize),
    /// Where each garment-layer vertex sits on the skin, in mesh order after the body.
    pub layers: Vec<SkinPoint>,
}

/// A garment-layer vertex's place on the body: a body triangle, barycentric coordinates
/// in it and the height above the skin along the interpolated normal. Tight clothes move
/// with the skin under them, so a layer's deformation is the body's, carried out along
/// the deformed normal ([`DressedCharacter::place_layers`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkinPoint {
    /// Body triangle.
    pub triangle: u32,
    /// Barycentric coordinates in it.
    pub barycentric: [f64; 3],
    /// Height above the skin (m).
    pub offset: f64,
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

    /// The whole character given the body part's deformed vertices `body`: the body,
    /// then every layer vertex at its [`SkinPoint`] on the deformed skin.
    pub fn place_layers(&self, body: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let (_, body_faces) = self.body_counts;
        let faces = &self.mesh.faces[..body_faces];
        let normals = TriMesh {
            positions: body.to_vec(),
            faces: faces.to_vec(),
        }
        .vertex_normals();
        let mut out = body.to_vec();
        out.extend(self.layers.iter().map(|s| {
            let f = faces[s.triangle as usize];
            let mut p = [0.0; 3];
            let mut n = [0.0; 3];
            for (k, &v) in f.iter().enumerate() {
                p = add(p, scale(body[v as usize], s.barycentric[k]));
                n = add(n, scale(normals[v as usize], s.barycentric[k]));
            }
            let len = dot(n, n).sqrt();
            if len > 1e-12 {
                add(p, scale(n, s.offset / len))
            } else {
                p
            }
        }));
        out
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
    let body_faces = mesh.faces.len();
    let mut parts = vec![0u32; body_n];
    let mut layers = Vec::new();
    let body_dense = model.weights().to_dense();
    let s = model.joint_count();
    let mut dense = body_dense;
    for (k, (kind, style)) in garments.iter().enumerate() {
        let g = fit
            .generate(*kind, style, vertices)
            .map_err(|e| garment_err(&format!("building the {}", kind.name()), &e))?;
        let mut layer = g.mesh;
        layers.extend(
            shrink_wrap(&fit, &mut layer, offset)
                .map_err(|e| garment_err(&format!("wrapping the {}", kind.name()), &e))?,
        );
        let w = fit
            .weights_at(model, &layer.positions)
            .map_err(|e| garment_err(&format!("weights of the {}", kind.name()), &e))?;
        dense.extend_from_slice(w.as_slice());
        let base = mesh.positions.len() as u32;
        parts.resize(parts.len() + layer.positions.len(), k as u32 + 1);
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
    let mut character = DressedCharacter {
        weights: SkinWeights::from_dense(&dense, s),
        joint_distances,
        body_counts: (body_n, body_faces),
        layers,
        mesh,
        parts,
        joints,
        parents,
    };
    // The rest layers exactly where a deformation places them (the same normals), so the
    // rest pose's truth is the rest mesh.
    character.mesh.positions = character.place_layers(&character.mesh.positions[..body_n]);
    Ok(character)
}

/// Puts every vertex of `layer` at `offset` above its closest skin point, then smooths
/// and re-projects a few rounds: a loose template projected straight onto the skin
/// bunches up where the body curves inwards (armpits, crotch); averaging each vertex
/// with its neighbours before projecting again spreads those triangles out. Returns each
/// vertex's place on the skin.
fn shrink_wrap(
    fit: &FitBody,
    layer: &mut TriMesh,
    offset: f64,
) -> Result<Vec<SkinPoint>, weft_body::query::QueryError> {
    let mut places = Vec::new();
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
        places = closest
            .iter()
            .map(|c| SkinPoint {
                triangle: c.triangle,
                barycentric: c.barycentric,
                offset,
            })
            .collect();
    }
    Ok(places)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dressed_character_is_one_skinned_mesh_whose_layers_ride_on_the_skin() {
        let model = weft_body::default_body().unwrap();
        let kind = GarmentKind::TShirt;
        let c = dress(
            &model,
            &[0.5],
            &[(kind, Style::from_seed(kind, 1))],
            400,
            0.006,
        )
        .unwrap();
        let (body_n, body_faces) = c.body_counts;
        assert_eq!(body_n, model.vertex_count());
        assert_eq!(body_faces, model.faces().len());
        let n = c.vertex_count();
        assert_eq!(c.layers.len(), n - body_n);
        assert_eq!(c.parts.iter().filter(|&&p| p == 1).count(), n - body_n);
        assert_eq!(c.weights.vertex_count(), n);
        assert_eq!(c.joint_distances.len(), n * c.joint_count());
        for v in body_n..n {
            let sum: f64 = c.weights.influences(v).map(|(_, w)| w).sum();
            assert!((sum - 1.0).abs() < 1e-9, "vertex {v}: weights sum to {sum}");
        }
        // At rest the layers are where they were built; moved with the body, they move
        // alike, at their height above the skin.
        let body = &c.mesh.positions[..body_n];
        assert_eq!(c.place_layers(body), c.mesh.positions);
        let shift = [0.3, -0.2, 1.0];
        let moved: Vec<[f64; 3]> = body.iter().map(|&p| add(p, shift)).collect();
        for (a, b) in c.place_layers(&moved).iter().zip(&c.mesh.positions) {
            for k in 0..3 {
                assert!((a[k] - b[k] - shift[k]).abs() < 1e-9);
            }
        }
        let closest = weft_body::query::BodySurface::from_mesh(&model.shape(&[0.5]).unwrap())
            .unwrap()
            .closest_points(&c.mesh.positions[body_n..])
            .unwrap();
        assert!(
            closest.iter().all(|q| (q.distance - 0.006).abs() < 0.003),
            "layer off the skin"
        );
    }
}
