//! A garment's frames and the body that moved it as a **skinned** glTF: the body's
//! skeleton animated by the motion, the body and the garment bound to it with four
//! influences per vertex (the body's own weights; the garment's transferred from the
//! nearest body point), and per frame one corrective morph target per mesh, so that a
//! game engine plays the simulated or predicted frames exactly at their times with a
//! skeleton it can retarget, blend and cull.
//!
//! The correctives undo skinning: glTF morphs a vertex before skinning it, so the target
//! of frame `k` is `M_v(k)⁻¹ x_v(k)` with `M_v = Σ w_j A_j` the blend of the skinning
//! transforms `A_j = G_j · T(−J_j)` of the four written influences. For the body that is
//! its rest shape whenever weft's posing is pure linear blend skinning with at most four
//! influences; the body gets correctives only where it is not (more influences, pose
//! blend shapes).

use std::path::Path;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use weft_body::features::transfer::transfer_weights;
use weft_body::features::SkinningWeights;
use weft_body::joints::SMPL_JOINT_NAMES;
use weft_body::kinematics::Rigid;
use weft_body::query::BodySurface;
use weft_body::{BodyModel, PosedSequence};
use weft_mesh::export::{
    write_skinned_glb, AnimatedMesh, CornerUvs, Frames, GlbOptions, Skeleton, SkinBinding,
    BODY_COLOR, GARMENT_COLOR,
};
use weft_mesh::TriMesh;
use weft_motion::Motion;

use crate::error::EvalError;

/// Correctives smaller than this everywhere (m) are left out: skinning alone is exact.
const NEGLIGIBLE: f64 = 1e-5;

fn invalid(what: &str, e: impl std::fmt::Display) -> EvalError {
    EvalError::Invalid(format!("skinned glTF: {what}: {e}"))
}

/// Writes `frames` of `garment` (rest pose on `body` at `betas`, with its corner `uvs`)
/// and the body, both skinned to the body's skeleton moving through `motion`, as one
/// `.glb` at the motion's rate.
pub fn write_skinned_animation(
    garment: &TriMesh,
    uvs: Option<&CornerUvs>,
    frames: &[Vec<[f32; 3]>],
    body: &BodyModel,
    betas: &[f32],
    motion: &Motion,
    out: &Path,
) -> Result<(), EvalError> {
    let t = frames.len();
    if t == 0 || motion.frame_count() < t {
        return Err(invalid(
            "frames",
            format!(
                "{t} garment frames for a motion of {}; expected at least one, at most the motion's",
                motion.frame_count()
            ),
        ));
    }
    let betas64: Vec<f64> = betas.iter().map(|&b| f64::from(b)).collect();
    let shaped = body.shaped(&betas64).map_err(|e| invalid("shape", e))?;
    let tree = body.skeleton();
    let joints = &shaped.joints;

    // The skeleton's animation and each frame's skinning transforms.
    let mut rotations = Vec::with_capacity(t);
    let mut root = Vec::with_capacity(t);
    let mut transforms = Vec::with_capacity(t);
    for k in 0..t {
        let pose: Vec<[f64; 3]> = motion.poses()[k].iter().map(|w| w.map(f64::from)).collect();
        let trans = motion.trans()[k].map(f64::from);
        rotations.push(
            pose.iter()
                .map(|&w| {
                    let q = UnitQuaternion::from_scaled_axis(Vector3::from(w));
                    [q.i as f32, q.j as f32, q.k as f32, q.w as f32]
                })
                .collect::<Vec<[f32; 4]>>(),
        );
        root.push([0, 1, 2].map(|c| (joints[0][c] + trans[c]) as f32));
        transforms.push(
            tree.skinning_transforms_axis_angle(joints, &pose, trans)
                .map_err(|e| invalid("pose", e))?,
        );
    }
    let names: Vec<String> = (0..joints.len())
        .map(|j| {
            SMPL_JOINT_NAMES
                .get(j)
                .map_or_else(|| format!("joint_{j}"), |n| (*n).to_owned())
        })
        .collect();
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let rest_joints: Vec<[f32; 3]> = joints.iter().map(|p| p.map(|c| c as f32)).collect();
    let skeleton = Skeleton {
        names: &name_refs,
        parents: tree.parents(),
        rest: &rest_joints,
        rotations: &rotations,
        root: &root,
    };

    // The body: its own weights, posed as weft poses it.
    let body_rest: Vec<[f32; 3]> = shaped
        .vertices
        .iter()
        .map(|p| p.map(|c| c as f32))
        .collect();
    let body_influences: Vec<[(u16, f32); 4]> = (0..body.vertex_count())
        .map(|v| top4(body.weights().influences(v)))
        .collect();
    let posed = PosedSequence::new(body, betas, &motion.poses()[..t], &motion.trans()[..t])
        .map_err(|e| invalid("posing the body", e))?;
    let body_frames = posed.into_frames();
    let body_correctives = correctives(&body_influences, &body_frames, &transforms, &body_rest)?;

    // The garment: weights from the nearest body point.
    let body_mesh = TriMesh::new(shaped.vertices.clone(), body.faces().to_vec());
    let surface = BodySurface::from_mesh(&body_mesh).map_err(|e| invalid("body surface", e))?;
    let dense = SkinningWeights::try_from(body.weights()).map_err(|e| invalid("weights", e))?;
    let transfer = transfer_weights(&surface, &dense, &garment.positions)
        .map_err(|e| invalid("weight transfer", e))?;
    let garment_influences: Vec<[(u16, f32); 4]> = (0..garment.vertex_count())
        .map(|v| {
            top4(
                transfer
                    .weights
                    .row(v)
                    .iter()
                    .enumerate()
                    .map(|(j, &w)| (j, w)),
            )
        })
        .collect();
    let garment_rest: Vec<[f32; 3]> = garment
        .positions
        .iter()
        .map(|p| p.map(|c| c as f32))
        .collect();
    let garment_correctives = correctives(&garment_influences, frames, &transforms, &garment_rest)?;

    let split = |inf: &[[(u16, f32); 4]]| -> (Vec<[u16; 4]>, Vec<[f32; 4]>) {
        inf.iter()
            .map(|row| (row.map(|(j, _)| j), row.map(|(_, w)| w)))
            .unzip()
    };
    let (gj, gw) = split(&garment_influences);
    let (bj, bw) = split(&body_influences);
    let still = |rest: &[[f32; 3]]| Frames::from_frames(&[rest.to_vec()]);
    let export_err = |e| invalid("export", e);
    let garment_frames = match garment_correctives {
        Some(f) => f,
        None => still(&garment_rest).map_err(export_err)?,
    };
    let body_frames = match body_correctives {
        Some(f) => f,
        None => still(&body_rest).map_err(export_err)?,
    };
    let meshes = [
        AnimatedMesh {
            name: "garment",
            faces: &garment.faces,
            uvs,
            frames: &garment_frames,
            color: GARMENT_COLOR,
        },
        AnimatedMesh {
            name: "body",
            faces: body.faces(),
            uvs: None,
            frames: &body_frames,
            color: BODY_COLOR,
        },
    ];
    let bindings = [
        SkinBinding {
            rest: &garment_rest,
            joints: &gj,
            weights: &gw,
        },
        SkinBinding {
            rest: &body_rest,
            joints: &bj,
            weights: &bw,
        },
    ];
    let options = GlbOptions {
        fps: motion.fps() as f32,
        normals: true,
    };
    write_skinned_glb(out, &skeleton, &meshes, &bindings, options).map_err(export_err)
}

/// The four largest influences, renormalised (unused ones are joint 0 with weight 0).
fn top4(influences: impl Iterator<Item = (usize, f64)>) -> [(u16, f32); 4] {
    let mut all: Vec<(usize, f64)> = influences.filter(|&(_, w)| w > 0.0).collect();
    all.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    all.truncate(4);
    let sum: f64 = all.iter().map(|&(_, w)| w).sum();
    let mut out = [(0u16, 0.0f32); 4];
    for (slot, &(j, w)) in out.iter_mut().zip(&all) {
        *slot = (j as u16, (w / sum) as f32);
    }
    out
}

/// Each frame carried back to the bind pose by the inverse of each vertex's blended
/// skinning transform, or `None` when they all equal `rest` to [`NEGLIGIBLE`].
fn correctives(
    influences: &[[(u16, f32); 4]],
    frames: &[Vec<[f32; 3]>],
    transforms: &[Vec<Rigid>],
    rest: &[[f32; 3]],
) -> Result<Option<Frames>, EvalError> {
    let mut out = Frames::with_vertex_count(rest.len()).map_err(|e| invalid("correctives", e))?;
    let mut largest = 0.0f64;
    for (frame, a) in frames.iter().zip(transforms) {
        let mut back = Vec::with_capacity(rest.len());
        for (v, (x, row)) in frame.iter().zip(influences).enumerate() {
            let mut r = Matrix3::zeros();
            let mut t = Vector3::zeros();
            for &(j, w) in row {
                let w = f64::from(w);
                r += a[usize::from(j)].rotation * w;
                t += a[usize::from(j)].translation * w;
            }
            let inv = r.try_inverse().ok_or_else(|| {
                invalid(
                    "correctives",
                    format!("vertex {v}: its blended skinning transform is singular"),
                )
            })?;
            let p = inv * (Vector3::from(x.map(f64::from)) - t);
            let d = (0..3)
                .map(|c| (p[c] - f64::from(rest[v][c])).abs())
                .fold(0.0, f64::max);
            largest = largest.max(d);
            back.push([p[0] as f32, p[1] as f32, p[2] as f32]);
        }
        out.push_frame(&back)
            .map_err(|e| invalid("correctives", e))?;
    }
    Ok((largest > NEGLIGIBLE).then_some(out))
}
