//! Skinned glTF: what Unity, Unreal and Godot play as skeletal animation. A skeleton of
//! joint nodes animated joint by joint (a rotation per joint and the root's translation
//! per frame), meshes bound to it with four influences per vertex (`JOINTS_0`,
//! `WEIGHTS_0`, inverse bind matrices of the bind pose), and per frame one corrective
//! morph target in the bind pose: what linear blend skinning alone cannot do (the
//! garment's folds and swing), so that a player shows the simulated or predicted frame.
//!
//! The correctives are computed by the caller, who owns the skinning (weft-body): for
//! frame `k` the corrective is `M_v(k)⁻¹ x_v(k)`, the frame's position carried back to
//! the bind pose by the inverse of the vertex's blended skinning transform, since glTF
//! applies morph targets before skinning. A mesh that skinning reproduces (the body)
//! needs none. Joints and morph weights interpolate linearly between frames (one-hot
//! morph weights at each frame's time), so frame `k` is exact at `k / fps` and playback
//! at another rate blends neighbouring frames.

use std::path::Path;

use serde_json::{json, Value};

use super::{
    vec3_accessor, write_le, write_vec3s, AnimatedMesh, Document, ExportError, GlbOptions, Layout,
    SeamSplit,
};
use super::{ARRAY_BUFFER, FLOAT};
use crate::io::write_atomic;

/// `accessor.componentType` for `u16`.
const UNSIGNED_SHORT: u32 = 5123;

/// A skeleton in its bind pose (every joint unrotated) and its animation.
#[derive(Clone, Copy, Debug)]
pub struct Skeleton<'a> {
    /// Joint names (node names in the file).
    pub names: &'a [&'a str],
    /// Each joint's parent; joint 0 is the only root and parents come first.
    pub parents: &'a [Option<usize>],
    /// Joint positions in the bind pose (m).
    pub rest: &'a [[f32; 3]],
    /// Per frame, each joint's rotation relative to its parent, as a unit quaternion
    /// `(x, y, z, w)`.
    pub rotations: &'a [Vec<[f32; 4]>],
    /// Per frame, where the root joint is (m).
    pub root: &'a [[f32; 3]],
}

/// How one mesh of a skinned scene is bound to the skeleton.
#[derive(Clone, Copy, Debug)]
pub struct SkinBinding<'a> {
    /// The mesh in the bind pose.
    pub rest: &'a [[f32; 3]],
    /// Four joint indices per vertex.
    pub joints: &'a [[u16; 4]],
    /// Their weights per vertex (non-negative, summing to one; written normalised).
    pub weights: &'a [[f32; 4]],
}

/// A skeleton and one binding per mesh, for [`Document::build`].
pub(super) struct SkinInput<'a> {
    pub skeleton: &'a Skeleton<'a>,
    pub bindings: &'a [SkinBinding<'a>],
}

/// Writes `meshes` skinned to `skeleton` as one `.glb`, atomically: mesh `i` bound by
/// `bindings[i]`, its `frames` the per-frame correctives in the bind pose (one frame:
/// none, skinning alone). Fails without touching `path` when counts disagree, a parent
/// is not an earlier joint, a value is not finite, a joint index is out of range, a
/// quaternion is not of unit length or a vertex's weights do not sum to one.
pub fn write_skinned_glb(
    path: &Path,
    skeleton: &Skeleton<'_>,
    meshes: &[AnimatedMesh<'_>],
    bindings: &[SkinBinding<'_>],
    options: GlbOptions,
) -> Result<(), ExportError> {
    let skin = SkinInput { skeleton, bindings };
    let doc = Document::build(meshes, options, Some(skin))?;
    write_atomic(path, |w| doc.write_to(w)).map_err(|e| ExportError::write(path, e))
}

fn invalid(message: String) -> ExportError {
    ExportError::format("<skinned glTF>", message)
}

impl SkinInput<'_> {
    /// Checks the skeleton and the bindings against `meshes` (whose shared frame count
    /// is `frames`) and returns the animation's frame count.
    pub(super) fn check(
        &self,
        meshes: &[AnimatedMesh<'_>],
        frames: usize,
    ) -> Result<usize, ExportError> {
        let s = self.skeleton;
        let j = s.rest.len();
        if j == 0 || s.parents.len() != j || s.names.len() != j {
            return Err(invalid(format!(
                "{} joint positions, {} parents, {} names; expected one of each per joint, at least one",
                j,
                s.parents.len(),
                s.names.len()
            )));
        }
        for (k, p) in s.parents.iter().enumerate() {
            let ok = match p {
                None => k == 0,
                Some(p) => *p < k,
            };
            if !ok {
                return Err(invalid(format!(
                    "joint {k}: parent {p:?}; expected joint 0 to be the only root and parents before children"
                )));
            }
        }
        let t = s.rotations.len();
        if t == 0 || s.root.len() != t || (frames > 1 && frames != t) {
            return Err(invalid(format!(
                "{t} frames of rotations, {} of root positions, meshes of {frames}; expected the same count",
                s.root.len()
            )));
        }
        for (f, rot) in s.rotations.iter().enumerate() {
            if rot.len() != j {
                return Err(invalid(format!(
                    "frame {f} has {} rotations; expected {j}",
                    rot.len()
                )));
            }
            for (k, q) in rot.iter().enumerate() {
                let n = q.iter().map(|c| f64::from(*c).powi(2)).sum::<f64>().sqrt();
                if !(n - 1.0).abs().lt(&1e-3) {
                    return Err(invalid(format!(
                        "frame {f}, joint {k}: quaternion of length {n}; expected a unit quaternion"
                    )));
                }
            }
        }
        let finite = |v: &[[f32; 3]]| v.iter().flatten().all(|c| c.is_finite());
        if !finite(s.rest) || !finite(s.root) {
            return Err(invalid("a joint or root position is not finite".into()));
        }
        if self.bindings.len() != meshes.len() {
            return Err(invalid(format!(
                "{} bindings for {} meshes; expected one per mesh",
                self.bindings.len(),
                meshes.len()
            )));
        }
        for (m, b) in meshes.iter().zip(self.bindings) {
            let n = m.frames.vertex_count();
            if b.rest.len() != n || b.joints.len() != n || b.weights.len() != n {
                return Err(invalid(format!(
                    "mesh `{}`: {n} vertices but {} bind positions, {} joint rows, {} weight rows",
                    m.name,
                    b.rest.len(),
                    b.joints.len(),
                    b.weights.len()
                )));
            }
            if !finite(b.rest) {
                return Err(invalid(format!(
                    "mesh `{}`: a bind position is not finite",
                    m.name
                )));
            }
            for (v, (js, ws)) in b.joints.iter().zip(b.weights).enumerate() {
                let sum: f32 = ws.iter().sum();
                let bad_joint = js.iter().any(|&x| usize::from(x) >= j);
                let bad_weight = ws.iter().any(|w| !w.is_finite() || *w < 0.0);
                if bad_joint || bad_weight || (sum - 1.0).abs() > 1e-3 {
                    return Err(invalid(format!(
                        "mesh `{}`, vertex {v}: joints {js:?} with weights {ws:?}; expected joints below {j} and non-negative weights summing to one",
                        m.name
                    )));
                }
            }
        }
        Ok(t)
    }
}

impl Skeleton<'_> {
    /// The joint nodes, numbered from `first`: name, bind-pose offset from the parent,
    /// children.
    pub(super) fn nodes(&self, first: usize) -> Vec<Value> {
        (0..self.rest.len())
            .map(|k| {
                let offset = match self.parents[k] {
                    None => self.rest[k],
                    Some(p) => [0, 1, 2].map(|c| self.rest[k][c] - self.rest[p][c]),
                };
                let children: Vec<usize> = (0..self.rest.len())
                    .filter(|&c| self.parents[c] == Some(k))
                    .map(|c| first + c)
                    .collect();
                let mut node = json!({"name": self.names[k], "translation": offset.map(f64::from)});
                if !children.is_empty() {
                    node["children"] = json!(children);
                }
                node
            })
            .collect()
    }

    /// The skin: its joints and inverse bind matrices (the bind pose has no rotation,
    /// so each is a translation by minus the joint's position).
    pub(super) fn skin(&self, l: &mut Layout<'_>, first: usize) -> Value {
        let rest = self.rest.to_vec();
        let j = rest.len();
        // Column-major 4 × 4: identity with the last column (−p, 1).
        let matrices: Vec<[f32; 16]> = rest
            .iter()
            .map(|p| {
                [
                    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -p[0], -p[1],
                    -p[2], 1.0,
                ]
            })
            .collect();
        let view = l.view(j * 64, None, None, move |w| {
            write_le(w, matrices.as_flattened())
        });
        let matrices = l.plain_accessor(view, FLOAT, j, "MAT4");
        json!({
            "name": "skeleton",
            "inverseBindMatrices": matrices,
            "joints": (first..first + j).collect::<Vec<_>>(),
            "skeleton": first,
        })
    }

    /// The animation's outputs: one rotation channel per joint and the root's
    /// translation, as (output accessor, node, path).
    pub(super) fn channels(
        &self,
        l: &mut Layout<'_>,
        first: usize,
    ) -> Vec<(usize, usize, &'static str)> {
        let t = self.rotations.len();
        let mut out = Vec::with_capacity(self.rest.len() + 1);
        for k in 0..self.rest.len() {
            let quats: Vec<[f32; 4]> = self.rotations.iter().map(|r| unit(r[k])).collect();
            let view = l.view(t * 16, None, None, move |w| {
                write_le(w, quats.as_flattened())
            });
            let output = l.plain_accessor(view, FLOAT, t, "VEC4");
            out.push((output, first + k, "rotation"));
        }
        let root = self.root.to_vec();
        let view = l.view(t * 12, None, None, move |w| {
            write_vec3s(w, root.iter().copied())
        });
        let output = l.accessor(vec3_accessor(view, 0, t, None));
        out.push((output, first, "translation"));
        out
    }
}

/// `q` scaled to unit length (the check allows 10⁻³ of slack; the file gets exact ones).
fn unit(q: [f32; 4]) -> [f32; 4] {
    let n = q.iter().map(|c| f64::from(*c).powi(2)).sum::<f64>().sqrt();
    q.map(|c| (f64::from(c) / n) as f32)
}

/// `JOINTS_0` and `WEIGHTS_0` of one mesh (weights normalised), through its seam split.
pub(super) fn attributes<'a>(
    l: &mut Layout<'a>,
    b: &SkinBinding<'a>,
    split: Option<&SeamSplit>,
    attributes: &mut Value,
) {
    let source: Vec<usize> = match split {
        Some(s) => s.source.iter().map(|&i| i as usize).collect(),
        None => (0..b.joints.len()).collect(),
    };
    let n = source.len();
    // An influence of weight zero names joint 0, as the spec asks.
    let joints: Vec<[u16; 4]> = source
        .iter()
        .map(|&i| {
            let mut js = b.joints[i];
            for (j, w) in js.iter_mut().zip(b.weights[i]) {
                if w == 0.0 {
                    *j = 0;
                }
            }
            js
        })
        .collect();
    let weights: Vec<[f32; 4]> = source
        .iter()
        .map(|&i| {
            let w = b.weights[i];
            let sum: f64 = w.iter().map(|&x| f64::from(x)).sum();
            w.map(|x| (f64::from(x) / sum) as f32)
        })
        .collect();
    let view = l.view(n * 8, Some(ARRAY_BUFFER), None, move |w| {
        write_le(w, joints.as_flattened())
    });
    attributes["JOINTS_0"] = json!(l.plain_accessor(view, UNSIGNED_SHORT, n, "VEC4"));
    let view = l.view(n * 16, Some(ARRAY_BUFFER), None, move |w| {
        write_le(w, weights.as_flattened())
    });
    attributes["WEIGHTS_0"] = json!(l.plain_accessor(view, FLOAT, n, "VEC4"));
}
