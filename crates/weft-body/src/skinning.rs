//! Skinning: moving rest-pose vertices with joint transforms and per-vertex weights.
//!
//! - **LBS**, linear blend skinning (seed 001 eq. 2.1): `p' = Σ_j w_ij A_j p`, the
//!   weighted sum of what each joint's skinning transform `A_j = T_j R_j⁻¹` does to `p`.
//!   Cheap and what SMPL is trained with, but the blended matrix is not a rotation, so
//!   bent or twisted joints lose volume.
//! - **DQS**, dual quaternion skinning (Kavan et al. 2007, seed 001 eq. 2.2): blend the
//!   joints' unit dual quaternions, normalise, apply the resulting rigid transform.
//!   Keeps volume under twist; bulges slightly at bends. The blend first flips each
//!   quaternion into the hemisphere of the vertex's dominant joint (**antipodality**:
//!   `q` and `−q` are the same rotation, and adding one of each would cancel).
//!
//! Weights are stored sparse ([`SkinWeights`]): a body vertex has 1–8 influences out of
//! 24, so the sparse loops are 3–10× faster than dense ones.

use nalgebra::{Matrix3, Vector3};

use crate::kinematics::Rigid;
use crate::rotation::DualQuat;

/// Sparse skinning weights: for each vertex, the joints that move it and how much.
///
/// Built from a dense `V × J` matrix, keeping the nonzero entries.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinWeights {
    /// `offsets[v]..offsets[v + 1]` indexes vertex `v`'s entries.
    offsets: Vec<usize>,
    joints: Vec<u32>,
    weights: Vec<f64>,
    joint_count: usize,
}

impl SkinWeights {
    /// The nonzero entries of a dense row-major `V × joint_count` matrix.
    ///
    /// # Panics
    /// If `dense.len()` is not a multiple of `joint_count` (a programming error; model
    /// loading checks shapes before).
    pub fn from_dense(dense: &[f64], joint_count: usize) -> Self {
        assert!(joint_count > 0 && dense.len() % joint_count == 0);
        let mut offsets = vec![0];
        let mut joints = Vec::new();
        let mut weights = Vec::new();
        for row in dense.chunks_exact(joint_count) {
            for (j, &w) in row.iter().enumerate() {
                if w != 0.0 {
                    joints.push(j as u32);
                    weights.push(w);
                }
            }
            offsets.push(joints.len());
        }
        SkinWeights {
            offsets,
            joints,
            weights,
            joint_count,
        }
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joint_count
    }

    /// The influences of vertex `v`: `(joint, weight)` pairs.
    pub fn influences(&self, v: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let r = self.offsets[v]..self.offsets[v + 1];
        self.joints[r.clone()]
            .iter()
            .zip(&self.weights[r])
            .map(|(&j, &w)| (j as usize, w))
    }

    /// The largest number of influences on one vertex.
    pub fn max_influences(&self) -> usize {
        self.offsets
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0)
    }

    /// At most `k` influences per vertex: the `k` largest weights of each vertex (ties
    /// to the lower joint), renormalised to sum to one. Seed 001 skins its coarse mesh
    /// with at most eight (DenseGATs) or four (MultiResGNet) influences, as game engines
    /// do; `k = 0` is taken as 1.
    pub fn truncated(&self, k: usize) -> SkinWeights {
        let k = k.max(1);
        let mut offsets = vec![0];
        let mut joints = Vec::with_capacity(self.joints.len());
        let mut weights = Vec::with_capacity(self.weights.len());
        for v in 0..self.vertex_count() {
            let mut row: Vec<(usize, f64)> = self.influences(v).collect();
            row.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            row.truncate(k);
            row.sort_by_key(|&(j, _)| j);
            let sum: f64 = row.iter().map(|&(_, w)| w).sum();
            for (j, w) in row {
                joints.push(j as u32);
                weights.push(if sum > 0.0 { w / sum } else { w });
            }
            offsets.push(joints.len());
        }
        SkinWeights {
            offsets,
            joints,
            weights,
            joint_count: self.joint_count,
        }
    }

    /// The dense row-major `V × J` matrix.
    pub fn to_dense(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.vertex_count() * self.joint_count];
        for v in 0..self.vertex_count() {
            for (j, w) in self.influences(v) {
                out[v * self.joint_count + j] = w;
            }
        }
        out
    }
}

/// The skinning method (in configs: `lbs`, `dqs`).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Skinning {
    /// Linear blend skinning (SMPL's).
    #[default]
    Lbs,
    /// Dual quaternion skinning.
    Dqs,
}

impl std::str::FromStr for Skinning {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "lbs" => Ok(Skinning::Lbs),
            "dqs" => Ok(Skinning::Dqs),
            _ => Err(format!(
                "unknown skinning method `{s}`; expected lbs or dqs"
            )),
        }
    }
}

impl std::fmt::Display for Skinning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Skinning::Lbs => "lbs",
            Skinning::Dqs => "dqs",
        })
    }
}

/// Skins `rest` (one position per vertex of `weights`) by `transforms` (one per joint),
/// calling `out(v, p)` with each posed position. The one loop both precisions share.
///
/// # Panics
/// If the counts disagree (callers check them).
pub fn skin_with(
    method: Skinning,
    rest: &[[f64; 3]],
    weights: &SkinWeights,
    transforms: &[Rigid],
    mut out: impl FnMut(usize, [f64; 3]),
) {
    assert_eq!(rest.len(), weights.vertex_count());
    assert_eq!(transforms.len(), weights.joint_count());
    match method {
        Skinning::Lbs => {
            for (v, &p) in rest.iter().enumerate() {
                let mut m = Matrix3::zeros();
                let mut t = Vector3::zeros();
                for (j, w) in weights.influences(v) {
                    m += transforms[j].rotation * w;
                    t += transforms[j].translation * w;
                }
                out(v, (m * Vector3::from(p) + t).into());
            }
        }
        Skinning::Dqs => {
            let dq = dual_quats(transforms);
            for (v, &p) in rest.iter().enumerate() {
                out(v, dqs_vertex(&dq, weights, v, p));
            }
        }
    }
}

/// The joints' skinning transforms as flat dual quaternions `[w, x, y, z | w, x, y, z]`:
/// the per-vertex loops of DQS stay on plain arrays.
fn dual_quats(transforms: &[Rigid]) -> Vec<[f64; 8]> {
    transforms
        .iter()
        .map(|a| {
            let q = DualQuat::from_rigid(&a.rotation, &a.translation);
            [
                q.real.w, q.real.i, q.real.j, q.real.k, q.dual.w, q.dual.i, q.dual.j, q.dual.k,
            ]
        })
        .collect()
}

/// Vertex `v`'s blended dual quaternion (Kavan et al. 2007, Alg. 1): the joints' dual
/// quaternions, each flipped into the hemisphere of the dominant joint's, summed and
/// divided by the norm of the real part. `None` for a vertex without (positive) weights.
fn blend_vertex(dq: &[[f64; 8]], weights: &SkinWeights, v: usize) -> Option<[f64; 8]> {
    let mut pivot = 0;
    let mut best = f64::NEG_INFINITY;
    for (j, w) in weights.influences(v) {
        if w > best {
            best = w;
            pivot = j;
        }
    }
    let q0 = &dq[pivot];
    let mut b = [0.0f64; 8];
    for (j, w) in weights.influences(v) {
        let q = &dq[j];
        let dot = q0[0] * q[0] + q0[1] * q[1] + q0[2] * q[2] + q0[3] * q[3];
        let s = if dot < 0.0 { -w } else { w };
        for k in 0..8 {
            b[k] += s * q[k];
        }
    }
    let n = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2] + b[3] * b[3]).sqrt();
    if n.is_nan() || n <= 1e-12 {
        return None;
    }
    Some(b.map(|x| x / n))
}

/// Dual quaternion skinning of one vertex: its blended dual quaternion applied as
/// `p' = p + 2 r⃗ × (r⃗ × p + r₀ p) + 2 (r₀ d⃗ − d₀ r⃗ + r⃗ × d⃗)`.
/// The translation term ignores any part of `d` along `r` (it is scalar in `d r*`), so
/// no re-orthogonalisation is needed.
fn dqs_vertex(dq: &[[f64; 8]], weights: &SkinWeights, v: usize, p: [f64; 3]) -> [f64; 3] {
    // A vertex without weights stays where it is.
    let Some(b) = blend_vertex(dq, weights, v) else {
        return p;
    };
    let (r0, r) = (b[0], [b[1], b[2], b[3]]);
    let (d0, d) = (b[4], [b[5], b[6], b[7]]);
    let cross = |a: [f64; 3], c: [f64; 3]| {
        [
            a[1] * c[2] - a[2] * c[1],
            a[2] * c[0] - a[0] * c[2],
            a[0] * c[1] - a[1] * c[0],
        ]
    };
    let rp = cross(r, p);
    let inner = [rp[0] + r0 * p[0], rp[1] + r0 * p[1], rp[2] + r0 * p[2]];
    let rot = cross(r, inner);
    let rd = cross(r, d);
    [0, 1, 2].map(|k| p[k] + 2.0 * rot[k] + 2.0 * (r0 * d[k] - d0 * r[k] + rd[k]))
}

/// Each vertex's DQS transform: the rigid transform dual quaternion skinning applies to
/// it (`dqs(rest)[v] == frames[v].apply(rest[v])`), identity for a vertex without
/// weights. A smooth per-vertex frame that follows the bones: learned refinement reads
/// its features and predicts its corrections in it.
pub fn dqs_frames(weights: &SkinWeights, transforms: &[Rigid]) -> Vec<Rigid> {
    assert_eq!(transforms.len(), weights.joint_count());
    let dq = dual_quats(transforms);
    (0..weights.vertex_count())
        .map(|v| {
            blend_vertex(&dq, weights, v)
                .and_then(|b| {
                    let q = DualQuat {
                        real: nalgebra::Quaternion::new(b[0], b[1], b[2], b[3]),
                        dual: nalgebra::Quaternion::new(b[4], b[5], b[6], b[7]),
                    };
                    q.to_rigid()
                })
                .map_or_else(Rigid::identity, |(rotation, translation)| Rigid {
                    rotation,
                    translation,
                })
        })
        .collect()
}

/// Skins `rest` into new `f64` positions; see [`skin_with`].
pub fn skin(
    method: Skinning,
    rest: &[[f64; 3]],
    weights: &SkinWeights,
    transforms: &[Rigid],
) -> Vec<[f64; 3]> {
    let mut posed = vec![[0.0; 3]; rest.len()];
    skin_with(method, rest, weights, transforms, |v, p| posed[v] = p);
    posed
}

/// Linear blend skinning; see the module docs.
pub fn lbs(rest: &[[f64; 3]], weights: &SkinWeights, transforms: &[Rigid]) -> Vec<[f64; 3]> {
    skin(Skinning::Lbs, rest, weights, transforms)
}

/// Dual quaternion skinning; see the module docs.
pub fn dqs(rest: &[[f64; 3]], weights: &SkinWeights, transforms: &[Rigid]) -> Vec<[f64; 3]> {
    skin(Skinning::Dqs, rest, weights, transforms)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::Skeleton;
    use crate::rotation::rodrigues;
    use proptest::prelude::*;

    fn near(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        (Vector3::from(a) - Vector3::from(b)).norm() <= tol
    }

    /// A two-bone "arm" along +X: joint 0 at the origin, joint 1 at x = 1; vertices
    /// every 0.25 along the bar, weights ramping from bone 0 to bone 1 around x = 1.
    fn arm() -> (Skeleton, Vec<[f64; 3]>, Vec<[f64; 3]>, SkinWeights) {
        let s = Skeleton::new(vec![None, Some(0)]).unwrap();
        let j = vec![[0.0; 3], [1.0, 0.0, 0.0]];
        let rest: Vec<[f64; 3]> = (0..9).map(|i| [0.25 * i as f64, 0.1, 0.0]).collect();
        let mut dense = Vec::new();
        for p in &rest {
            let w1 = ((p[0] - 0.75) / 0.5).clamp(0.0, 1.0);
            dense.extend([1.0 - w1, w1]);
        }
        (s, j, rest, SkinWeights::from_dense(&dense, 2))
    }

    #[test]
    fn truncation_keeps_the_largest_influences_renormalised() {
        let w = SkinWeights::from_dense(&[0.1, 0.5, 0.0, 0.4, 0.25, 0.25, 0.25, 0.25], 4);
        let t = w.truncated(2);
        assert_eq!(t.max_influences(), 2);
        let row0: Vec<(usize, f64)> = t.influences(0).collect();
        assert_eq!(row0.len(), 2);
        assert_eq!((row0[0].0, row0[1].0), (1, 3));
        assert!((row0[0].1 - 5.0 / 9.0).abs() < 1e-12 && (row0[1].1 - 4.0 / 9.0).abs() < 1e-12);
        // Ties go to the lower joint.
        let row1: Vec<usize> = t.influences(1).map(|(j, _)| j).collect();
        assert_eq!(row1, vec![0, 1]);
        // k at or above the influence count changes nothing.
        assert_eq!(w.truncated(4), w);
    }

    #[test]
    fn sparse_weights_round_trip() {
        let dense = vec![1.0, 0.0, 0.0, 0.25, 0.0, 0.75];
        let w = SkinWeights::from_dense(&dense, 3);
        assert_eq!(w.vertex_count(), 2);
        assert_eq!(w.max_influences(), 2);
        assert_eq!(
            w.influences(1).collect::<Vec<_>>(),
            vec![(0, 0.25), (2, 0.75)]
        );
        assert_eq!(w.to_dense(), dense);
    }

    #[test]
    fn identity_transforms_keep_the_rest_pose() {
        let (_, _, rest, w) = arm();
        for m in [Skinning::Lbs, Skinning::Dqs] {
            let posed = skin(m, &rest, &w, &[Rigid::identity(); 2]);
            for (a, b) in posed.iter().zip(&rest) {
                assert!(near(*a, *b, 1e-15), "{m}");
            }
        }
    }

    #[test]
    fn rigid_bones_agree_and_follow_closed_forms() {
        let (s, j, rest, w) = arm();
        // Elbow bent by a quarter turn about Z: points fully on bone 1 at (x, 0.1)
        // go to (1 − 0.1, x − 1).
        let mut pose = [[0.0; 3]; 2];
        pose[1] = [0.0, 0.0, std::f64::consts::FRAC_PI_2];
        let a = s
            .skinning_transforms_axis_angle(&j, &pose, [0.0; 3])
            .unwrap();
        let l = lbs(&rest, &w, &a);
        let d = dqs(&rest, &w, &a);
        for (i, p) in rest.iter().enumerate() {
            if p[0] >= 1.25 - 1e-12 {
                assert!(near(l[i], [0.9, p[0] - 1.0, 0.0], 1e-12));
            }
            if p[0] <= 0.75 + 1e-12 {
                assert!(near(l[i], *p, 1e-12));
            }
            // With a single influence both methods are the same rigid motion.
            if w.influences(i).count() == 1 {
                assert!(near(l[i], d[i], 1e-12));
            }
        }
        // The blended vertex at the joint: LBS pulls it inside (candy-wrapper style
        // shrinkage), DQS keeps its distance to the joint.
        let mid = 4; // x = 1.0, weights 0.5 / 0.5
        let dist = |p: [f64; 3]| (Vector3::from(p) - Vector3::new(1.0, 0.0, 0.0)).norm();
        assert!((dist(d[mid]) - 0.1).abs() < 1e-12);
        assert!(dist(l[mid]) < 0.1 - 1e-3);
    }

    #[test]
    fn dqs_handles_antipodal_quaternions() {
        // Two joints with the same rotation by nearly a full turn written both ways:
        // their quaternions are nearly opposite, the rotations nearly equal.
        let w = SkinWeights::from_dense(&[0.5, 0.5], 2);
        let r1 = rodrigues([0.0, 0.0, std::f64::consts::PI - 0.01]);
        let r2 = rodrigues([0.0, 0.0, -(std::f64::consts::PI - 0.01)]);
        let a = [
            Rigid {
                rotation: r1,
                translation: Vector3::zeros(),
            },
            Rigid {
                rotation: r2,
                translation: Vector3::zeros(),
            },
        ];
        let p = dqs(&[[1.0, 0.0, 0.0]], &w, &a)[0];
        // Without the hemisphere fix the sum would nearly cancel; with it the point
        // lands near (−1, 0, 0) at unit distance.
        assert!((Vector3::from(p).norm() - 1.0).abs() < 1e-12);
        assert!(p[0] < -0.99);
    }

    #[test]
    fn dqs_frames_are_the_transforms_dqs_applies() {
        let (s, j, rest, w) = arm();
        let a = s
            .skinning_transforms_axis_angle(
                &j,
                &[[0.0, 0.3, 0.0], [0.2, 0.0, 1.4]],
                [0.5, 0.0, -1.0],
            )
            .unwrap();
        let frames = dqs_frames(&w, &a);
        for ((f, p), q) in frames.iter().zip(&rest).zip(dqs(&rest, &w, &a)) {
            assert!(near(f.apply(*p), q, 1e-12));
            // A rotation: orthonormal with determinant +1.
            assert!((f.rotation.transpose() * f.rotation - Matrix3::identity()).norm() < 1e-12);
            assert!((f.rotation.determinant() - 1.0).abs() < 1e-12);
        }
        // A vertex with one bone takes that bone's transform.
        assert!((frames[0].rotation - a[0].rotation).norm() < 1e-12);
        assert!((frames[8].rotation - a[1].rotation).norm() < 1e-12);
    }

    proptest! {
        /// Rigid motion of the whole body: every joint has the same transform, so every
        /// vertex moves rigidly, whatever its weights, under both methods.
        #[test]
        fn whole_body_rigid_motion(w0 in prop::array::uniform3(-3.0f64..3.0), t in prop::array::uniform3(-2.0f64..2.0), ws in prop::collection::vec(0.0f64..1.0, 9)) {
            let (s, j, rest, _) = arm();
            let dense: Vec<f64> = ws.iter().flat_map(|&x| [x, 1.0 - x]).collect();
            let weights = SkinWeights::from_dense(&dense, 2);
            let a = s.skinning_transforms_axis_angle(&j, &[w0, [0.0; 3]], t).unwrap();
            let r = rodrigues(w0);
            for m in [Skinning::Lbs, Skinning::Dqs] {
                let posed = skin(m, &rest, &weights, &a);
                for (p, q) in rest.iter().zip(&posed) {
                    let expect: [f64; 3] = (r * Vector3::from(*p) + Vector3::from(t)).into();
                    prop_assert!(near(*q, expect, 1e-12));
                }
            }
        }

        /// DQS always produces a rigid transform per vertex: for a vertex with two
        /// influences, distances to the (posed) joint 1 are preserved when joint 1 is
        /// the pivot of the rotation.
        #[test]
        fn dqs_preserves_distance_to_a_rotating_joint(w1 in prop::array::uniform3(-2.5f64..2.5)) {
            let (s, j, rest, w) = arm();
            let a = s.skinning_transforms_axis_angle(&j, &[[0.0; 3], w1], [0.0; 3]).unwrap();
            let d = dqs(&rest, &w, &a);
            let joint = Vector3::new(1.0, 0.0, 0.0);
            for (p, q) in rest.iter().zip(&d) {
                let before = (Vector3::from(*p) - joint).norm();
                let after = (Vector3::from(*q) - joint).norm();
                prop_assert!((before - after).abs() < 1e-12);
            }
        }
    }
}
