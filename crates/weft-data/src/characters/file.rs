//! One character per safetensors file: its rest mesh, rig, features, poses and the
//! ground-truth deformation of every pose.
//!
//! | name              | dtype | shape     | what                                          |
//! |-------------------|-------|-----------|-----------------------------------------------|
//! | `rest_positions`  | f32   | [N, 3]    | the character in its rest pose (m)            |
//! | `faces`           | u32   | [F, 3]    | its triangles                                 |
//! | `parts`           | u32   | [N]       | 0 body, k the k-th garment layer              |
//! | `weights`         | f32   | [N, S]    | skinning weights (rows sum to 1)              |
//! | `joint_distances` | f32   | [N, S]    | volumetric vertex–joint distances, rest (m)   |
//! | `joints`          | f32   | [S, 3]    | rest joint positions J(β)                     |
//! | `parents`         | u32   | [S]       | parent joint; the root holds `u32::MAX`       |
//! | `betas`           | f32   | [B]       | body shape β                                  |
//! | `poses`           | f32   | [P, 3S]   | axis-angle per joint per pose                 |
//! | `truth`           | f32   | [P, N, 3] | the ground-truth deformation of each pose     |
//!
//! The coarse deformations (LBS with k influences, DQS) are not stored: they are cheap
//! and depend on the model's k, so [`CharacterData::coarse`] computes them.
//! Sizes are read from the file and checked against each other; the header's
//! `__metadata__` holds the character id.

use std::collections::HashMap;
use std::path::Path;

use safetensors::tensor::Dtype;
use weft_body::kinematics::Skeleton;
use weft_body::skinning::{dqs, lbs, SkinWeights};
use weft_body::{Pose, Skinning};

use crate::error::DataError;
use crate::shard::sha256_hex;
use crate::tensors::{f32_tensor, f32s, faces, parse, shape_of, tensor, triples, u32_tensor};

/// Marks the root in `parents`.
const NO_PARENT: u32 = u32::MAX;

/// Everything one character file holds.
#[derive(Clone, Debug, PartialEq)]
pub struct CharacterData {
    /// `[N]` rest positions.
    pub rest_positions: Vec<[f32; 3]>,
    /// `[F]` triangles.
    pub faces: Vec<[u32; 3]>,
    /// `[N]` part of each vertex.
    pub parts: Vec<u32>,
    /// `[N × S]` skinning weights, row-major.
    pub weights: Vec<f32>,
    /// `[N × S]` volumetric joint distances, row-major.
    pub joint_distances: Vec<f32>,
    /// `[S]` rest joints.
    pub joints: Vec<[f32; 3]>,
    /// `[S]` parents.
    pub parents: Vec<Option<usize>>,
    /// `[B]` shape.
    pub betas: Vec<f32>,
    /// `[P]` poses (SMPL's 24 joints).
    pub poses: Vec<Pose>,
    /// `[P][N]` ground truth.
    pub truth: Vec<Vec<[f32; 3]>>,
}

impl CharacterData {
    /// Vertices N.
    pub fn vertex_count(&self) -> usize {
        self.rest_positions.len()
    }

    /// Joints S.
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// The skinning weights, at most `k` influences per vertex (renormalised).
    pub fn skin_weights(&self, k: usize) -> SkinWeights {
        let dense: Vec<f64> = self.weights.iter().map(|&w| f64::from(w)).collect();
        SkinWeights::from_dense(&dense, self.joint_count()).truncated(k)
    }

    /// The skeleton.
    pub fn skeleton(&self) -> Result<Skeleton, DataError> {
        Skeleton::new(self.parents.clone()).map_err(|e| DataError::config("parents", e.to_string()))
    }

    /// The rest mesh deformed into `pose` (root at `translation`) by `method` with
    /// `weights` (from [`Self::skin_weights`]).
    pub fn coarse(
        &self,
        skeleton: &Skeleton,
        weights: &SkinWeights,
        pose: &Pose,
        translation: [f64; 3],
        method: Skinning,
    ) -> Result<Vec<[f32; 3]>, DataError> {
        let joints: Vec<[f64; 3]> = self.joints.iter().map(|j| j.map(f64::from)).collect();
        let pose: Vec<[f64; 3]> = pose.iter().map(|r| r.map(f64::from)).collect();
        let transforms = skeleton
            .skinning_transforms_axis_angle(&joints, &pose, translation)
            .map_err(|e| DataError::config("poses", e.to_string()))?;
        let rest: Vec<[f64; 3]> = self
            .rest_positions
            .iter()
            .map(|p| p.map(f64::from))
            .collect();
        let out = match method {
            Skinning::Lbs => lbs(&rest, weights, &transforms),
            Skinning::Dqs => dqs(&rest, weights, &transforms),
        };
        Ok(out.into_iter().map(|p| p.map(|x| x as f32)).collect())
    }
}

/// The file's bytes.
pub fn encode(id: &str, d: &CharacterData) -> Result<Vec<u8>, DataError> {
    let (n, s, p) = (d.vertex_count(), d.joint_count(), d.poses.len());
    let bad = |m: String| DataError::Simulation {
        id: id.to_string(),
        message: m,
    };
    if d.weights.len() != n * s || d.joint_distances.len() != n * s || d.parts.len() != n {
        return Err(bad(format!(
            "{} weights, {} joint distances and {} parts for {n} vertices × {s} joints",
            d.weights.len(),
            d.joint_distances.len(),
            d.parts.len()
        )));
    }
    if d.parents.len() != s || s * 3 != weft_body::joints::SMPL_JOINT_COUNT * 3 {
        return Err(bad(format!(
            "{} parents for {s} joints; character files hold SMPL's {} joints",
            d.parents.len(),
            weft_body::joints::SMPL_JOINT_COUNT
        )));
    }
    if d.truth.len() != p || d.truth.iter().any(|t| t.len() != n) {
        return Err(bad(format!("truth must hold {p} poses of {n} vertices")));
    }
    let parents: Vec<u32> = d
        .parents
        .iter()
        .map(|p| p.map_or(NO_PARENT, |x| x as u32))
        .collect();
    let tensors = [
        (
            "rest_positions",
            f32_tensor(vec![n, 3], d.rest_positions.iter().flatten()),
        ),
        (
            "faces",
            u32_tensor(vec![d.faces.len(), 3], d.faces.iter().flatten()),
        ),
        ("parts", u32_tensor(vec![n], d.parts.iter())),
        ("weights", f32_tensor(vec![n, s], d.weights.iter())),
        (
            "joint_distances",
            f32_tensor(vec![n, s], d.joint_distances.iter()),
        ),
        ("joints", f32_tensor(vec![s, 3], d.joints.iter().flatten())),
        ("parents", u32_tensor(vec![s], parents.iter())),
        ("betas", f32_tensor(vec![d.betas.len()], d.betas.iter())),
        (
            "poses",
            f32_tensor(vec![p, 3 * s], d.poses.iter().flatten().flatten()),
        ),
        (
            "truth",
            f32_tensor(vec![p, n, 3], d.truth.iter().flatten().flatten()),
        ),
    ];
    let metadata = HashMap::from([("character".to_string(), id.to_string())]);
    safetensors::tensor::serialize(tensors.iter().map(|(k, v)| (*k, v)), Some(metadata))
        .map_err(|e| bad(format!("cannot encode the character file: {e}")))
}

/// Writes a character file atomically; returns the SHA-256 of its bytes.
pub fn write(path: &Path, id: &str, d: &CharacterData) -> Result<String, DataError> {
    let bytes = encode(id, d)?;
    weft_mesh::io::write_atomic(path, |w| w.write_all(&bytes))
        .map_err(|e| DataError::io(path, "cannot write the character file", e))?;
    Ok(sha256_hex(&bytes))
}

/// Reads a character file, checking its SHA-256 against `sha256` when given.
pub fn read(path: &Path, sha256: Option<&str>) -> Result<CharacterData, DataError> {
    let bytes = weft_mesh::io::read_input(path)
        .map_err(|e| DataError::io(path, "cannot read the character file", e))?;
    if let Some(expected) = sha256 {
        let found = sha256_hex(&bytes);
        if found != expected {
            return Err(DataError::Digest {
                path: path.to_path_buf(),
                expected: expected.to_string(),
                found,
            });
        }
    }
    decode(path, &bytes)
}

/// Decodes a character file's bytes.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<CharacterData, DataError> {
    let st = parse(path, bytes)?;
    let n = shape_of(path, &st, "rest_positions")?
        .first()
        .copied()
        .unwrap_or(0);
    let s = shape_of(path, &st, "joints")?.first().copied().unwrap_or(0);
    let f = shape_of(path, &st, "faces")?.first().copied().unwrap_or(0);
    let b = shape_of(path, &st, "betas")?.first().copied().unwrap_or(0);
    let p = shape_of(path, &st, "poses")?.first().copied().unwrap_or(0);
    if s != weft_body::joints::SMPL_JOINT_COUNT {
        return Err(DataError::Tensor {
            path: path.to_path_buf(),
            tensor: "joints".into(),
            expected: format!("{} joints (SMPL's)", weft_body::joints::SMPL_JOINT_COUNT),
            found: s.to_string(),
        });
    }
    let get = |name: &str, dtype: Dtype, shape: &[usize]| tensor(path, &st, name, dtype, shape);
    let parents: Vec<Option<usize>> = get("parents", Dtype::U32, &[s])?
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .map(|x| (x != NO_PARENT).then_some(x as usize))
        .collect();
    let parts = get("parts", Dtype::U32, &[n])?
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let pose_values: Vec<f32> = f32s(get("poses", Dtype::F32, &[p, 3 * s])?).collect();
    let poses = pose_values
        .chunks_exact(3 * s)
        .map(|c| std::array::from_fn(|j| [c[3 * j], c[3 * j + 1], c[3 * j + 2]]))
        .collect();
    let truth_all = triples(get("truth", Dtype::F32, &[p, n, 3])?);
    let truth = if n == 0 {
        vec![Vec::new(); p]
    } else {
        truth_all.chunks_exact(n).map(<[_]>::to_vec).collect()
    };
    let data = CharacterData {
        rest_positions: triples(get("rest_positions", Dtype::F32, &[n, 3])?),
        faces: faces(path, "faces", get("faces", Dtype::U32, &[f, 3])?, n)?,
        parts,
        weights: f32s(get("weights", Dtype::F32, &[n, s])?).collect(),
        joint_distances: f32s(get("joint_distances", Dtype::F32, &[n, s])?).collect(),
        joints: triples(get("joints", Dtype::F32, &[s, 3])?),
        parents,
        betas: f32s(get("betas", Dtype::F32, &[b])?).collect(),
        poses,
        truth,
    };
    if let Some(i) = data
        .parents
        .iter()
        .enumerate()
        .position(|(i, p)| p.is_some_and(|p| p >= i))
    {
        return Err(DataError::Tensor {
            path: path.to_path_buf(),
            tensor: "parents".into(),
            expected: "each parent before its child".into(),
            found: format!("joint {i} has parent {:?}", data.parents[i]),
        });
    }
    let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
    for (name, ok) in [
        (
            "rest_positions",
            data.rest_positions.iter().all(|p| finite(p)),
        ),
        ("weights", finite(&data.weights)),
        ("poses", data.poses.iter().flatten().all(|r| finite(r))),
        ("truth", data.truth.iter().flatten().all(|p| finite(p))),
    ] {
        if !ok {
            return Err(DataError::Tensor {
                path: path.to_path_buf(),
                tensor: name.into(),
                expected: "finite numbers".into(),
                found: "NaN or infinity".into(),
            });
        }
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn sample() -> CharacterData {
        let s = weft_body::joints::SMPL_JOINT_COUNT;
        let n = 3;
        let mut weights = vec![0.0; n * s];
        weights[0] = 1.0;
        weights[s + 1] = 1.0;
        weights[2 * s] = 0.5;
        weights[2 * s + 1] = 0.5;
        let parents = weft_body::default_body()
            .unwrap()
            .skeleton()
            .parents()
            .to_vec();
        CharacterData {
            rest_positions: vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0]],
            faces: vec![[0, 1, 2]],
            parts: vec![0, 0, 1],
            weights,
            joint_distances: vec![0.25; n * s],
            joints: vec![[0.0, 0.0, 0.0]; s],
            parents,
            betas: vec![0.5, -0.5],
            poses: vec![[[0.1; 3]; 24], [[0.0; 3]; 24]],
            truth: vec![vec![[0.0; 3]; n], vec![[0.5; 3]; n]],
        }
    }

    #[test]
    fn round_trip_deterministic_and_checked() {
        let d = sample();
        let bytes = encode("c0", &d).unwrap();
        assert_eq!(bytes, encode("c0", &d).unwrap());
        assert_eq!(decode(Path::new("c0.safetensors"), &bytes).unwrap(), d);
        for cut in [0, 10, bytes.len() - 1] {
            assert!(decode(Path::new("c0.safetensors"), &bytes[..cut]).is_err());
        }
        let mut bad = d.clone();
        bad.truth[1][2][0] = f32::NAN;
        let e = decode(Path::new("c.safetensors"), &encode("c", &bad).unwrap())
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.safetensors") && e.contains("truth"), "{e}");
        let mut bad = d.clone();
        bad.weights.pop();
        assert!(encode("c", &bad)
            .unwrap_err()
            .to_string()
            .contains("weights"));
    }

    #[test]
    fn coarse_lbs_is_the_rest_mesh_at_the_rest_pose() {
        let d = sample();
        let sk = d.skeleton().unwrap();
        let w = d.skin_weights(4);
        let out = d
            .coarse(&sk, &w, &[[0.0; 3]; 24], [0.0; 3], Skinning::Lbs)
            .unwrap();
        assert_eq!(out, d.rest_positions);
        let moved = d
            .coarse(&sk, &w, &[[0.0; 3]; 24], [1.0, 0.0, 0.0], Skinning::Dqs)
            .unwrap();
        assert!((moved[1][0] - 1.1).abs() < 1e-6);
    }
}
