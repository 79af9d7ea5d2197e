//! One garment on one body, as GarFitNet's two networks read it (§4.2.2, §4.3.1).
//!
//! A [`FitPair`] holds what stays fixed while the body moves: the garment as it sits on
//! this body in the rest pose (draped, so a garment made for another body is tight or
//! loose here), its association with the body's vertices (G5: nearest body vertex in the
//! rest pose), the fit parameter α of the pair and the garment vertices' volumetric
//! distances to the joints (`x_i`, G10). Per frame it gives the coarse regressor's
//! features on the associated body vertices and, from a coarse garment, the refinement
//! network's features and the frame's GarFit parameters `(β, θ, α)`.
//!
//! Positions are read relative to the posed root joint, in world axes: a translated body
//! gives the same features and corrections. Corrections are in [`COARSE_UNIT`] for the
//! coarse regressor (the garment hangs centimetres to decimetres from its body vertex)
//! and [`REFINE_UNIT`] for the refinement (the folds: millimetres to centimetres), so both
//! networks regress values of order one.

use serde::{Deserialize, Serialize};
use weft_body::features::volumetric::{VolumetricDistance, VolumetricParams};
use weft_body::features::{transfer_weights_diffused, DiffusionParams};
use weft_body::query::BodySurface;
use weft_body::skinning::{skin, SkinWeights};
use weft_body::{BodyModel, Pose, ShapedBody, Skinning};
use weft_mesh::{Graph, TriMesh};

use super::coarse::association;
use crate::error::ModelError;

/// Metres per unit of the coarse regressor's corrections (decimetres).
pub const COARSE_UNIT: f64 = 0.1;
/// Metres per unit of the refinement's corrections (centimetres).
pub const REFINE_UNIT: f64 = 0.01;

/// Where the coarse regressor's garment vertex starts, `M_b'` of eq. 4.6.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Anchor {
    /// The thesis's: the posed nearest body vertex (rest pose) of each garment vertex.
    /// A skirt's hem then follows one thigh, and the regressor must learn the whole
    /// offset to where the skirt hangs.
    #[default]
    BodyVertex,
    /// The garment vertex itself, skinned with the body's weights transferred to it and
    /// diffused over the garment where it stands off the body (weft-body's
    /// `transfer_weights_diffused`): a loose skirt's hem blends both legs and the pelvis,
    /// so the anchor already hangs where a skirt hangs and the regressor learns the rest.
    Skinned,
}

/// The posed body of one frame, as the pair reads it.
#[derive(Clone, Debug)]
pub struct BodyFrame {
    /// Where every garment vertex starts, posed (m): its associated body vertex, or
    /// itself skinned ([`Anchor`]).
    pub anchors: Vec<[f64; 3]>,
    /// Their vertex normals on the posed body.
    pub normals: Vec<[f64; 3]>,
    /// The posed root joint: the origin features are read from.
    pub root: [f64; 3],
    /// The frame's pose (axis-angle per joint).
    pub pose: Pose,
}

/// One garment on one body; see the module documentation.
#[derive(Clone, Debug)]
pub struct FitPair {
    /// The garment on this body in the rest pose.
    pub garment: TriMesh,
    /// The body's shape.
    pub betas: Vec<f64>,
    /// The nearest body vertex (rest pose) of every garment vertex.
    pub association: Vec<u32>,
    /// The fit parameter α of the pair.
    pub alpha: Vec<f64>,
    shaped: ShapedBody,
    /// Diffused transferred weights of the garment ([`Anchor::Skinned`]).
    skinning: Option<SkinWeights>,
    graph: Graph,
    /// `N × S` volumetric distances to the joints, m.
    joint_distances: Vec<f32>,
    joints: usize,
}

impl FitPair {
    /// The pair of `garment` (on the body of shape `betas`, rest pose) with fit `alpha`,
    /// its coarse garment anchored as `anchor` says.
    pub fn new(
        model: &BodyModel,
        betas: &[f64],
        garment: TriMesh,
        alpha: Vec<f64>,
        anchor: Anchor,
    ) -> Result<Self, ModelError> {
        if let Some(index) = garment
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(ModelError::NonFinite {
                what: "garment vertex",
                index,
            });
        }
        if let Some(i) = alpha.iter().position(|a| !a.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "fit parameter α component",
                index: i,
            });
        }
        let body_error = |e: weft_body::BodyError| ModelError::Body(e.to_string());
        let shaped = model.shaped(betas).map_err(body_error)?;
        let association = association(&shaped.vertices, &garment.positions)?;
        let body_mesh = TriMesh::new(shaped.vertices.clone(), model.faces().to_vec());
        let surface =
            BodySurface::from_mesh(&body_mesh).map_err(|e| ModelError::Body(e.to_string()))?;
        let volumetric = VolumetricDistance::new(
            &surface,
            &shaped.joints,
            model.skeleton().parents(),
            VolumetricParams::default(),
        )
        .map_err(|e| ModelError::Body(e.to_string()))?;
        let joint_distances = volumetric
            .matrix(&garment.positions)
            .map_err(|e| ModelError::Body(e.to_string()))?
            .to_f32();
        let skinning = match anchor {
            Anchor::BodyVertex => None,
            Anchor::Skinned => {
                let feature =
                    |e: weft_body::features::FeatureError| ModelError::Body(e.to_string());
                let body_weights = model.skinning_weights().map_err(feature)?;
                let t = transfer_weights_diffused(
                    &surface,
                    &body_weights,
                    &garment,
                    &DiffusionParams::default(),
                )
                .map_err(feature)?;
                Some(SkinWeights::from_dense(
                    t.weights.as_slice(),
                    t.weights.joint_count(),
                ))
            }
        };
        Ok(FitPair {
            graph: garment.graph(),
            joints: volumetric.joint_count(),
            betas: shaped.betas.clone(),
            garment,
            association,
            alpha,
            shaped,
            skinning,
            joint_distances,
        })
    }

    /// Garment vertices.
    pub fn vertex_count(&self) -> usize {
        self.garment.positions.len()
    }

    /// The garment's edge graph (both networks' graph).
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// Width of the coarse regressor's node features: `[r_b', n_b', α]`.
    pub fn coarse_width(&self) -> usize {
        6 + self.alpha.len()
    }

    /// Width of the refinement's node features: `[r_i, n_i, x_i]`.
    pub fn refine_width(&self) -> usize {
        6 + self.joints
    }

    /// Width of the GarFit parameters: `|β| + |θ| + |α|`.
    pub fn garfit_width(&self) -> usize {
        self.betas.len() + 3 * weft_body::joints::SMPL_JOINT_COUNT + self.alpha.len()
    }

    /// The body posed by `pose` and `trans` (linear blend skinning, the body model's own).
    pub fn body_frame(
        &self,
        model: &BodyModel,
        pose: &Pose,
        trans: [f64; 3],
    ) -> Result<BodyFrame, ModelError> {
        let body_error = |e: weft_body::BodyError| ModelError::Body(e.to_string());
        let axis_angles: Vec<[f64; 3]> = pose.iter().map(|r| r.map(f64::from)).collect();
        let vertices = model
            .pose_vertices(&self.shaped, &axis_angles, trans, Skinning::Lbs)
            .map_err(body_error)?;
        let root = model
            .pose_joints(&self.shaped, &axis_angles, trans)
            .map_err(body_error)?
            .first()
            .copied()
            .unwrap_or(trans);
        let body = TriMesh::new(vertices, model.faces().to_vec());
        let normals = body.vertex_normals();
        let at = |values: &[[f64; 3]]| -> Vec<[f64; 3]> {
            self.association
                .iter()
                .map(|&v| values[v as usize])
                .collect()
        };
        let anchors = match &self.skinning {
            None => at(&body.positions),
            Some(weights) => {
                let transforms = model
                    .skeleton()
                    .skinning_transforms_axis_angle(&self.shaped.joints, &axis_angles, trans)
                    .map_err(|e| ModelError::Body(e.to_string()))?;
                skin(Skinning::Lbs, &self.garment.positions, weights, &transforms)
            }
        };
        Ok(BodyFrame {
            anchors,
            normals: at(&normals),
            root,
            pose: *pose,
        })
    }

    /// The coarse regressor's node features `[r_b' − root, n_b', α]`, row-major.
    pub fn coarse_features(&self, frame: &BodyFrame) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.vertex_count() * self.coarse_width());
        for (a, n) in frame.anchors.iter().zip(&frame.normals) {
            out.extend((0..3).map(|k| (a[k] - frame.root[k]) as f32));
            out.extend(n.iter().map(|&c| c as f32));
            out.extend(self.alpha.iter().map(|&c| c as f32));
        }
        out
    }

    /// `M_coarse = M_b' + Δ_coarse` (eq. 4.6) from corrections in [`COARSE_UNIT`].
    pub fn coarse_positions(&self, frame: &BodyFrame, delta: &[f32]) -> Vec<[f64; 3]> {
        offset(&frame.anchors, delta, COARSE_UNIT)
    }

    /// The coarse regressor's target corrections (row-major, [`COARSE_UNIT`]): from the
    /// body anchors to `smoothed`, the simulated garment without its folds.
    pub fn coarse_targets(&self, frame: &BodyFrame, smoothed: &[[f64; 3]]) -> Vec<f32> {
        difference(&frame.anchors, smoothed, COARSE_UNIT)
    }

    /// The refinement's node features `[r_i − root, n_i, x_i]` of the coarse garment
    /// `coarse` (eq. 4.7), row-major.
    pub fn refine_features(&self, frame: &BodyFrame, coarse: &[[f64; 3]]) -> Vec<f32> {
        let normals = TriMesh::new(coarse.to_vec(), self.garment.faces.clone()).vertex_normals();
        let mut out = Vec::with_capacity(self.vertex_count() * self.refine_width());
        for (i, (p, n)) in coarse.iter().zip(&normals).enumerate() {
            out.extend((0..3).map(|k| (p[k] - frame.root[k]) as f32));
            out.extend(n.iter().map(|&c| c as f32));
            out.extend_from_slice(&self.joint_distances[i * self.joints..(i + 1) * self.joints]);
        }
        out
    }

    /// The refinement's target corrections (row-major, [`REFINE_UNIT`]) from `coarse`
    /// to the simulated garment `truth`.
    pub fn refine_targets(&self, coarse: &[[f64; 3]], truth: &[[f64; 3]]) -> Vec<f32> {
        difference(coarse, truth, REFINE_UNIT)
    }

    /// The refined garment from corrections in [`REFINE_UNIT`].
    pub fn refined_positions(&self, coarse: &[[f64; 3]], delta: &[f32]) -> Vec<[f64; 3]> {
        offset(coarse, delta, REFINE_UNIT)
    }

    /// The frame's GarFit parameters `(β, θ, α)`.
    pub fn garfit(&self, frame: &BodyFrame) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.garfit_width());
        out.extend(self.betas.iter().map(|&b| b as f32));
        out.extend(frame.pose.iter().flatten().copied());
        out.extend(self.alpha.iter().map(|&a| a as f32));
        out
    }
}

/// `base + unit · delta` per vertex.
fn offset(base: &[[f64; 3]], delta: &[f32], unit: f64) -> Vec<[f64; 3]> {
    base.iter()
        .zip(delta.chunks_exact(3))
        .map(|(p, d)| [0, 1, 2].map(|k| p[k] + unit * f64::from(d[k])))
        .collect()
}

/// `(to − from) / unit` per vertex, row-major.
fn difference(from: &[[f64; 3]], to: &[[f64; 3]], unit: f64) -> Vec<f32> {
    from.iter()
        .zip(to)
        .flat_map(|(a, b)| [0, 1, 2].map(|k| ((b[k] - a[k]) / unit) as f32))
        .collect()
}

#[cfg(test)]
mod tests {
    use weft_garment::{FitBody, GarmentKind, Style};

    use super::*;

    fn skirt_pair() -> (BodyModel, FitPair) {
        let body = weft_body::default_body().unwrap();
        let betas = [0.0, 0.0, 0.0, 1.0];
        let fit = FitBody::new(&body, &betas).unwrap();
        let skirt = fit
            .generate(
                GarmentKind::Skirt,
                &Style::from_seed(GarmentKind::Skirt, 3),
                400,
            )
            .unwrap();
        let pair = FitPair::new(
            &body,
            &betas,
            skirt.mesh,
            vec![0.5, -1.0, 2.0],
            Anchor::BodyVertex,
        )
        .unwrap();
        (body, pair)
    }

    #[test]
    fn features_targets_and_positions_agree() {
        let (body, pair) = skirt_pair();
        let n = pair.vertex_count();
        let mut pose: Pose = [[0.0; 3]; weft_body::joints::SMPL_JOINT_COUNT];
        pose[1] = [-0.6, 0.0, 0.1]; // left hip forward
        pose[0] = [0.0, 0.4, 0.0];
        let frame = pair.body_frame(&body, &pose, [0.0; 3]).unwrap();
        let coarse = pair.coarse_features(&frame);
        assert_eq!(coarse.len(), n * 9);
        // α closes every row.
        assert_eq!(&coarse[6..9], &[0.5, -1.0, 2.0]);
        // The body moved the anchors: a skirt vertex sits near its body vertex.
        let far = frame
            .anchors
            .iter()
            .zip(&pair.garment.positions)
            .map(|(a, g)| (0..3).map(|k| (a[k] - g[k]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        assert!(far > 0.01, "the pose moved nothing: {far}");
        // Targets and positions are inverse maps in both units.
        let target = pair.garment.positions.clone();
        let back = pair.coarse_positions(&frame, &pair.coarse_targets(&frame, &target));
        let refined = pair.refined_positions(&back, &pair.refine_targets(&back, &target));
        for (a, b) in refined.iter().zip(&target) {
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-5, "{a:?} vs {b:?}");
            }
        }
        // Translation-invariant features.
        let moved = pair.body_frame(&body, &pose, [2.0, 0.1, -3.0]).unwrap();
        let shifted: Vec<[f64; 3]> = pair
            .garment
            .positions
            .iter()
            .map(|p| [p[0] + 2.0, p[1] + 0.1, p[2] - 3.0])
            .collect();
        let a = pair.refine_features(&frame, &pair.garment.positions);
        let b = pair.refine_features(&moved, &shifted);
        assert_eq!(a.len(), n * pair.refine_width());
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        assert!(worst < 1e-4, "{worst}");
        let c = pair.coarse_features(&moved);
        let worst = coarse
            .iter()
            .zip(&c)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        assert!(worst < 1e-4, "{worst}");
        // (β, θ, α): 10 + 72 + 3.
        let g = pair.garfit(&frame);
        assert_eq!((g.len(), pair.garfit_width()), (85, 85));
        assert_eq!(g[3], 1.0);
        assert_eq!(g[10 + 3], -0.6);
    }

    #[test]
    fn refuses_non_finite_input() {
        let (body, pair) = skirt_pair();
        let mut garment = pair.garment.clone();
        garment.positions[7][1] = f64::NAN;
        let e = FitPair::new(&body, &[0.0], garment, vec![0.0; 3], Anchor::BodyVertex).unwrap_err();
        assert!(e.to_string().contains("garment vertex"), "{e}");
        let e = FitPair::new(
            &body,
            &[0.0],
            pair.garment.clone(),
            vec![f64::NAN],
            Anchor::Skinned,
        )
        .unwrap_err();
        assert!(e.to_string().contains("α"), "{e}");
        // A garment with no body region under it (moved 2 m to the side).
        let mut away = pair.garment.clone();
        for p in &mut away.positions {
            p[0] += 2.0;
        }
        let e = FitPair::new(&body, &[0.0], away, vec![0.0; 3], Anchor::BodyVertex).unwrap_err();
        assert!(e.to_string().contains("not dressed on this body"), "{e}");
    }
}

#[cfg(test)]
mod anchor_tests {
    use weft_garment::{FitBody, GarmentKind, Style};

    use super::*;

    #[test]
    fn a_skinned_anchor_starts_on_the_garment_and_follows_the_body() {
        let body = weft_body::default_body().unwrap();
        let fit = FitBody::new(&body, &[]).unwrap();
        let skirt = fit
            .generate(
                GarmentKind::Skirt,
                &Style::from_seed(GarmentKind::Skirt, 2),
                400,
            )
            .unwrap()
            .mesh;
        let pair = FitPair::new(&body, &[], skirt, vec![0.0; 3], Anchor::Skinned).unwrap();
        let rest: Pose = [[0.0; 3]; weft_body::joints::SMPL_JOINT_COUNT];
        let frame = pair.body_frame(&body, &rest, [0.0; 3]).unwrap();
        // The rest pose leaves every vertex where it is.
        for (a, g) in frame.anchors.iter().zip(&pair.garment.positions) {
            assert!((0..3).all(|k| (a[k] - g[k]).abs() < 1e-9), "{a:?} vs {g:?}");
        }
        // Turning the pelvis turns the skirt with it.
        let mut turned = rest;
        turned[0] = [0.0, 0.8, 0.0];
        let moved = pair.body_frame(&body, &turned, [0.0; 3]).unwrap();
        let shift = moved
            .anchors
            .iter()
            .zip(&pair.garment.positions)
            .map(|(a, g)| (0..3).map(|k| (a[k] - g[k]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        assert!(shift > 0.05, "{shift}");
    }
}
