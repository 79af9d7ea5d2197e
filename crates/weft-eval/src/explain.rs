//! Attribution of the Multilevel model (seed 000 §4.1): which garment vertices, through
//! their graph features `X` (position, normal, joint distances), move vertex `i` at frame
//! `t`.
//!
//! The output `f_i` is the predicted position of vertex `i` projected on the direction it
//! actually moves (from its rest position to its prediction at `t`; the vertical when it
//! does not move): one scalar per eq. 9, the component a viewer sees. The heat map uses
//! the attribution of the three normal columns of `X`, as the paper's figures do.

use std::ops::Range;

use burn::tensor::Tensor;
use weft_body::BodyModel;
use weft_mesh::TriMesh;
use weft_models::multilevel::{FrameInputs, GarmentInput, Multilevel};
use weft_models::Clip;
use weft_nn::burn;

use crate::attribution::{attribute, tensor2, Attribution};
use crate::error::EvalError;

/// Columns of the node features holding the vertex normal (after the 3 position columns).
pub const NORMAL_COLUMNS: Range<usize> = 3..6;

/// What [`explain_vertex`] found.
pub struct VertexAttribution {
    /// Eq. 9 over every node feature.
    pub attribution: Attribution,
    /// One score per garment vertex: the attribution of its normal columns.
    pub scores: Vec<f64>,
    /// The predicted garment at frame `t` (for drawing the map on it).
    pub predicted: TriMesh,
    /// The unit direction `f_i` measures along.
    pub direction: [f32; 3],
}

/// The vertices `[T, N, 3]` of a prediction for frame `k` of the window.
fn frame_vertices(v: Tensor<3>, k: usize) -> Result<Vec<[f32; 3]>, EvalError> {
    let [_, n, _] = v.dims();
    let data = v
        .slice([k..k + 1, 0..n, 0..3])
        .into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .map_err(|e| EvalError::Network(format!("reading the prediction: {e:?}")))?;
    Ok(data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// Eq. 9 for vertex `vertex` at frame `frame` of `clip`, with `model` on an autodiff
/// device and `samples` Gauss–Legendre nodes.
pub fn explain_vertex(
    model: &Multilevel,
    garment: &TriMesh,
    body: &BodyModel,
    clip: &Clip,
    vertex: usize,
    frame: usize,
    samples: usize,
) -> Result<VertexAttribution, EvalError> {
    let poses = clip.poses;
    let n = garment.vertex_count();
    if vertex >= n {
        return Err(EvalError::Invalid(format!(
            "vertex {vertex} does not exist: the garment has {n} vertices (0 to {})",
            n.saturating_sub(1)
        )));
    }
    if frame >= poses.len() {
        return Err(EvalError::Invalid(format!(
            "frame {frame} does not exist: the motion has {} frames (0 to {})",
            poses.len(),
            poses.len().saturating_sub(1)
        )));
    }
    let cfg = model.config();
    let device = model.device();
    let g = GarmentInput::new(garment, body, clip.betas, cfg)?;
    let f = FrameInputs::new(body, &g, clip, frame..frame + 1, cfg)?;
    let width = cfg.node_features();
    let x = tensor2(&g.node_features, [n, width], &device)?;
    let predicted = {
        let pair = model.encode_pair(&g)?;
        frame_vertices(model.forward(&pair, &g, &f)?.vertices, 0)?
    };
    let rest = garment.positions[vertex];
    let p = predicted[vertex];
    let d = [0, 1, 2].map(|k| f64::from(p[k]) - rest[k]);
    let len = weft_mesh::vec3::norm(d);
    let direction: [f32; 3] = if len > 1e-6 {
        d.map(|x| (x / len) as f32)
    } else {
        [0.0, 1.0, 0.0]
    };
    let dir = Tensor::<1>::from_floats(direction, &device);
    let attribution = attribute(&x, None, samples, |x| {
        let pair = model.encode_pair_features(&g, x)?;
        let v = model.forward(&pair, &g, &f)?.vertices;
        let row = v.slice([0..1, vertex..vertex + 1, 0..3]).reshape([3]);
        Ok((row * dir.clone()).sum())
    })?;
    let scores = attribution.row_scores(NORMAL_COLUMNS)?;
    Ok(VertexAttribution {
        attribution,
        scores,
        predicted: TriMesh::new(
            predicted.iter().map(|q| q.map(f64::from)).collect(),
            garment.faces.clone(),
        ),
        direction,
    })
}
