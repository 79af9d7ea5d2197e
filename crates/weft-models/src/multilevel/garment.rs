//! [`GarmentInput`]: everything constant for one garment–body pair, computed once on the
//! host (f64 geometry, stored as f32 network inputs).
//!
//! - node features of the garment graph (seed 000 §3.2): rest position relative to the
//!   pelvis joint `J_0(β)`, unit vertex normal, Euclidean distance to each of the `S`
//!   joints — `6 + S` numbers per vertex, in metres (no further scaling: positions and
//!   distances are O(1) for a human-sized garment, normals are unit);
//! - the garment style descriptor: the Nyström eigenvalues of the geodesic distance matrix
//!   (weft-mesh), divided by the vertex count `N` so that it describes the shape and not
//!   the resolution (the dominant eigenvalue of an `N × N` distance matrix grows like
//!   `N ×` the mean distance);
//! - the body-shape input `D` of E^bs: distances from `body_samples` body vertices (evenly
//!   spaced indices of the shaped rest body) to every joint, one row per joint;
//! - the body's skinning weights transferred to the garment by closest surface point
//!   (weft-body), the LBS baseline and the prior of the learned skinning weights;
//! - the structure-preserving hierarchy (weft-hierarchy) M^mp pools along, and its
//!   batches of `T` copies (one per frame of a window), built on first use and cached.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use weft_body::features::{
    joint_distances, transfer_weights, transfer_weights_diffused, DiffusionParams,
};
use weft_body::BodyModel;
use weft_hierarchy::Hierarchy;
use weft_mesh::nystrom::NystromSpectrum;
use weft_mesh::TriMesh;
use weft_nn::HierarchyBatch;

use super::config::{MultilevelConfig, PoolingKind};
use crate::error::{check_finite, ModelError};

/// Everything constant for one garment–body pair; see the module documentation.
pub struct GarmentInput {
    vertex_count: usize,
    joints: usize,
    /// Rest template `T`, `[N, 3]` row-major (metres, the shaped body's frame).
    pub rest: Vec<f32>,
    /// Node features `[N, 6 + S]`.
    pub node_features: Vec<f32>,
    /// Nyström eigenvalues divided by `N`, `[N*]`.
    pub eigenvalues: Vec<f32>,
    /// Joint–vertex distances of the sampled body vertices, one row per joint,
    /// `[S, body_samples]`.
    pub body_distances: Vec<f32>,
    /// Body skinning weights transferred to the garment, `[N, S]`, rows summing to one.
    pub transfer_weights: Vec<f32>,
    /// The garment hierarchy (one level unless the pooling is structure-preserving).
    pub hierarchy: Hierarchy,
    batches: Mutex<HashMap<usize, Arc<HierarchyBatch>>>,
}

impl Clone for GarmentInput {
    fn clone(&self) -> Self {
        let batches = self.batches.lock().map(|b| b.clone()).unwrap_or_default();
        GarmentInput {
            vertex_count: self.vertex_count,
            joints: self.joints,
            rest: self.rest.clone(),
            node_features: self.node_features.clone(),
            eigenvalues: self.eigenvalues.clone(),
            body_distances: self.body_distances.clone(),
            transfer_weights: self.transfer_weights.clone(),
            hierarchy: self.hierarchy.clone(),
            batches: Mutex::new(batches),
        }
    }
}

impl std::fmt::Debug for GarmentInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GarmentInput")
            .field("vertices", &self.vertex_count)
            .field("joints", &self.joints)
            .field("levels", &self.hierarchy.len())
            .finish()
    }
}

/// Indices of `samples` body vertices spread evenly over `0..count`.
pub(crate) fn body_sample_indices(count: usize, samples: usize) -> Result<Vec<usize>, ModelError> {
    if samples > count {
        return Err(ModelError::mismatch(
            "body vertices (config body_samples needs at least that many)",
            format!("at least {samples}"),
            count,
        ));
    }
    Ok((0..samples).map(|k| k * count / samples).collect())
}

/// Checks that `body` has the config's joint count.
pub(crate) fn check_body(body: &BodyModel, cfg: &MultilevelConfig) -> Result<(), ModelError> {
    if body.joint_count() != cfg.joints {
        return Err(ModelError::mismatch(
            "body joints (config joints)",
            cfg.joints,
            body.joint_count(),
        ));
    }
    Ok(())
}

/// `betas` as f64, checked finite.
pub(crate) fn betas_f64(betas: &[f32]) -> Result<Vec<f64>, ModelError> {
    check_finite("betas", betas)?;
    Ok(betas.iter().map(|&b| f64::from(b)).collect())
}

/// `garment` settled on the rest pose of `body` at `betas` in `material` (config
/// `drape`): weft-garment's drape with its defaults (top opening held, gravity ramped,
/// damped until still), the garment's own shape as the rest shape of the cloth.
pub fn drape_on(
    garment: &TriMesh,
    body: &BodyModel,
    betas: &[f32],
    material: &str,
) -> Result<TriMesh, ModelError> {
    let err = |e: String| ModelError::Garment(format!("draping in {material}: {e}"));
    let material = weft_sim::Material::preset(material).map_err(|e| err(e.to_string()))?;
    let fit =
        weft_garment::FitBody::new(body, &betas_f64(betas)?).map_err(|e| err(e.to_string()))?;
    let report = weft_garment::prepare::drape(
        garment,
        &fit,
        &material,
        &weft_garment::prepare::DrapeOptions::default(),
    )
    .map_err(|e| err(e.to_string()))?;
    let mut draped = garment.clone();
    draped.positions = report.positions;
    Ok(draped)
}

impl GarmentInput {
    /// Precomputes the inputs of `garment` (rest pose of `body` at shape `betas`).
    ///
    /// Errors: a config that does not validate, a body whose joint count differs from the
    /// config's `joints`, fewer body vertices than `body_samples`, non-finite garment
    /// positions or betas, a garment without faces, or one too small for `mp_levels`
    /// structure-preserving poolings.
    pub fn new(
        garment: &TriMesh,
        body: &BodyModel,
        betas: &[f32],
        cfg: &MultilevelConfig,
    ) -> Result<Self, ModelError> {
        cfg.validate()?;
        check_body(body, cfg)?;
        let n = garment.vertex_count();
        if n == 0 || garment.faces.is_empty() {
            return Err(ModelError::Garment(format!(
                "needs vertices and faces, got {n} vertices and {} faces",
                garment.faces.len()
            )));
        }
        if let Some(index) = garment
            .positions
            .iter()
            .flatten()
            .position(|x| !x.is_finite())
        {
            return Err(ModelError::NonFinite {
                what: "garment positions",
                index,
            });
        }
        if let Some((f, &face)) = garment
            .faces
            .iter()
            .enumerate()
            .find(|(_, f)| f.iter().any(|&v| v as usize >= n))
        {
            return Err(ModelError::Garment(format!(
                "face {f} = {face:?} indexes past the {n} vertices"
            )));
        }
        let draped;
        let garment = match cfg.drape_material() {
            Some(material) => {
                draped = drape_on(garment, body, betas, material)?;
                &draped
            }
            None => garment,
        };
        let shaped = body
            .shaped(&betas_f64(betas)?)
            .map_err(crate::error::body_err("shaping the body"))?;
        let s = cfg.joints;
        let pelvis = shaped.joints[0];

        // Node features: position (pelvis-relative), normal, joint distances.
        let normals = garment.vertex_normals();
        let dist = joint_distances(&garment.positions, &shaped.joints)
            .map_err(|e| ModelError::Body(format!("garment joint distances: {e}")))?;
        let width = cfg.node_features();
        let mut node_features = Vec::with_capacity(n * width);
        let mut rest = Vec::with_capacity(n * 3);
        for (i, (p, normal)) in garment.positions.iter().zip(&normals).enumerate() {
            rest.extend(p.map(|x| x as f32));
            node_features.extend((0..3).map(|k| (p[k] - pelvis[k]) as f32));
            node_features.extend(normal.map(|x| x as f32));
            node_features.extend(dist.row(i).iter().map(|&d| d as f32));
        }

        // Garment style: Nyström spectrum per vertex.
        let spectrum = NystromSpectrum::compute(garment, cfg.nystrom_landmarks)
            .map_err(|e| ModelError::Garment(format!("Nyström spectrum: {e}")))?;
        let eigenvalues = spectrum
            .eigenvalues
            .iter()
            .map(|&l| (l / n as f64) as f32)
            .collect();

        // Body shape: sampled joint–vertex distances, one row per joint.
        let idx = body_sample_indices(shaped.vertices.len(), cfg.body_samples)?;
        let sampled: Vec<[f64; 3]> = idx.iter().map(|&i| shaped.vertices[i]).collect();
        let d = joint_distances(&sampled, &shaped.joints)
            .map_err(|e| ModelError::Body(format!("body joint distances: {e}")))?;
        let mut body_distances = vec![0.0f32; s * idx.len()];
        for (v, row) in (0..idx.len()).map(|v| (v, d.row(v))) {
            for (j, &x) in row.iter().enumerate() {
                body_distances[j * idx.len() + v] = x as f32;
            }
        }

        // Transferred skinning weights.
        let surface = body
            .body_surface(&shaped.vertices)
            .map_err(|e| ModelError::Body(format!("body surface: {e}")))?;
        let body_weights = body
            .skinning_weights()
            .map_err(|e| ModelError::Body(format!("body skinning weights: {e}")))?;
        let transfer = if cfg.weight_diffusion {
            transfer_weights_diffused(
                &surface,
                &body_weights,
                garment,
                &DiffusionParams::default(),
            )
        } else {
            transfer_weights(&surface, &body_weights, &garment.positions)
        }
        .map_err(|e| ModelError::Body(format!("weight transfer: {e}")))?;
        let transfer_weights = transfer.weights.to_f32();

        // Hierarchy for structure-preserving pooling.
        let levels = match cfg.pooling {
            PoolingKind::Structure => cfg.mp_levels + 1,
            _ => 1,
        };
        let hierarchy = Hierarchy::build(garment.graph(), levels)
            .map_err(|e| ModelError::Garment(format!("hierarchy: {e}")))?;
        if hierarchy.len() != levels {
            return Err(ModelError::Garment(format!(
                "{n} vertices pool only {} times; the config asks for {} levels (mp_levels)",
                hierarchy.len() - 1,
                cfg.mp_levels
            )));
        }

        let input = GarmentInput {
            vertex_count: n,
            joints: s,
            rest,
            node_features,
            eigenvalues,
            body_distances,
            transfer_weights,
            hierarchy,
            batches: Mutex::new(HashMap::new()),
        };
        check_finite("garment node features", &input.node_features)?;
        check_finite("garment style eigenvalues", &input.eigenvalues)?;
        check_finite("body joint distances", &input.body_distances)?;
        Ok(input)
    }

    /// Garment vertices `N`.
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Joints `S`.
    pub fn joint_count(&self) -> usize {
        self.joints
    }

    /// Node feature width `6 + S`.
    pub fn node_feature_width(&self) -> usize {
        self.node_features.len() / self.vertex_count
    }

    /// Sampled body vertices of `body_distances`.
    pub fn body_sample_count(&self) -> usize {
        self.body_distances.len() / self.joints
    }

    /// The hierarchy of `frames` copies of the garment as one disjoint batch (one copy per
    /// frame of a window), built once per window length and cached.
    pub fn frame_batch(&self, frames: usize) -> Result<Arc<HierarchyBatch>, ModelError> {
        if let Ok(cache) = self.batches.lock() {
            if let Some(b) = cache.get(&frames) {
                return Ok(b.clone());
            }
        }
        let copies: Vec<&Hierarchy> = vec![&self.hierarchy; frames];
        let batch = Arc::new(HierarchyBatch::new(&copies)?);
        if let Ok(mut cache) = self.batches.lock() {
            cache.insert(frames, batch.clone());
        }
        Ok(batch)
    }
}
