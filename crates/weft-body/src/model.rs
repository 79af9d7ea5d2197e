//! The body model in SMPL's layout, read from and written to `.npz`.
//!
//! | key            | shape        | meaning                                                        |
//! |----------------|--------------|----------------------------------------------------------------|
//! | `v_template`   | V × 3        | rest-pose vertices of the mean shape                            |
//! | `shapedirs`    | V × 3 × B    | shape blend shapes: `T + Σ_b β_b S_b` (B ≥ 1)                    |
//! | `posedirs`     | V × 3 × 9(J−1) | pose blend shapes over the features `R_j(θ) − I`, j ≥ 1 (optional, zeros when absent) |
//! | `J_regressor`  | J × V        | rest joints `J(β) = J_regressor · (T + B_s(β))`                  |
//! | `weights`      | V × J        | skinning weights, rows summing to 1                             |
//! | `kintree_table`| 2 × J        | row 0: parent of each joint (root: −1 or 4294967295); row 1: 0…J−1 |
//! | `f`            | F × 3        | triangles (any integer dtype)                                   |
//!
//! The posed body is SMPL's (seed 001 eq. 4.1–4.2): `M(β, θ) = W(T + B_s(β) + B_p(θ),
//! J(β), θ, 𝒲)` with `W` linear blend skinning (or dual quaternion skinning on request).
//! A user's SMPL `.npz` (as written by the smplx tools, or converted from the `.pkl` as in
//! docs/body.md) loads unchanged; weft's own default body uses the same layout.

use std::path::Path;

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use weft_mesh::io::npz::{Npz, NpzError, NpzWriter};
use weft_mesh::TriMesh;

use crate::error::BodyError;
use crate::kinematics::{posed_joints, Skeleton};
use crate::rotation::rodrigues;
use crate::skinning::{skin_with, SkinWeights, Skinning};

/// Pose blend shape features per non-root joint: the 9 entries of `R_j − I`.
pub const POSE_FEATURES_PER_JOINT: usize = 9;

/// The largest |β| weft accepts without being told otherwise. SMPL-format shape spaces
/// are principal components scaled to unit variance over the scanned population, so
/// |β| ≤ 3 holds for nearly everyone and 5 is already an extreme body; the linear model
/// keeps extrapolating past that into bodies no person has (β₁ = 100 is 3.9 m tall,
/// 1e308 puts vertices at 1e306 m). Commands refuse larger values unless told
/// `--allow-extreme-shapes`.
pub const BETA_LIMIT: f64 = 5.0;

/// Tolerance on each row sum of `weights` (they must sum to 1).
const WEIGHT_SUM_TOLERANCE: f64 = 1e-3;
/// Tolerance on each row sum of `J_regressor`: joints must be weighted averages of
/// vertices, or they would not follow the body when it is translated.
const REGRESSOR_SUM_TOLERANCE: f64 = 0.05;

/// The arrays of a body model, in plain form, to build a [`BodyModel`] from (see the
/// module table for the meaning; all row-major).
#[derive(Clone, Debug, PartialEq)]
pub struct BodyParts {
    /// V rest vertices of the mean shape.
    pub v_template: Vec<[f64; 3]>,
    /// V × 3 × `num_betas` shape blend shapes.
    pub shapedirs: Vec<f64>,
    /// Number of shape coefficients B.
    pub num_betas: usize,
    /// V × 3 × 9(J−1) pose blend shapes, `None` for none (all zero).
    pub posedirs: Option<Vec<f64>>,
    /// J × V joint regressor.
    pub j_regressor: Vec<f64>,
    /// V × J skinning weights.
    pub weights: Vec<f64>,
    /// Parent of each joint, `None` for the root (joint 0).
    pub parents: Vec<Option<usize>>,
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
}

/// A body of shape β, ready to pose: its rest vertices and rest joints.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapedBody {
    /// The shape coefficients (padded with zeros to the model's B).
    pub betas: Vec<f64>,
    /// `T + B_s(β)`.
    pub vertices: Vec<[f64; 3]>,
    /// `J(β)`.
    pub joints: Vec<[f64; 3]>,
}

/// A checked SMPL-format body model. See the module docs for the layout.
#[derive(Clone, Debug)]
pub struct BodyModel {
    source: String,
    v_template: Vec<[f64; 3]>,
    shapedirs: Vec<f64>,
    num_betas: usize,
    posedirs: Option<Vec<f64>>,
    /// Sparse rows of `J_regressor`: (vertex, weight).
    j_regressor: Vec<Vec<(u32, f64)>>,
    weights: SkinWeights,
    skeleton: Skeleton,
    faces: Vec<[u32; 3]>,
}

impl BodyModel {
    /// Checks `parts` and builds the model; `source` names it in errors (a file path, or
    /// `default body`).
    ///
    /// Checks: consistent shapes, finite numbers, non-negative skinning weights whose rows
    /// sum to 1, `J_regressor` rows summing to 1, faces in range, and a kinematic tree
    /// whose parents precede their children. A `posedirs` of all zeros is dropped
    /// (posing then skips the pose blend shapes).
    pub fn new(parts: BodyParts, source: &str) -> Result<Self, BodyError> {
        let invalid = |key: &'static str, message: String| BodyError::Invalid {
            source_name: source.to_string(),
            key,
            message,
        };
        let v = parts.v_template.len();
        let j = parts.parents.len();
        let b = parts.num_betas;
        if v == 0 {
            return Err(invalid(
                "v_template",
                "no vertices; expected V ≥ 1 rows".into(),
            ));
        }
        if j == 0 {
            return Err(invalid(
                "kintree_table",
                "no joints; expected J ≥ 1 columns".into(),
            ));
        }
        let expect_len = |key: &'static str, len: usize, want: usize, shape: String| {
            if len == want {
                Ok(())
            } else {
                Err(invalid(
                    key,
                    format!("{len} values; expected {shape} = {want}"),
                ))
            }
        };
        if b == 0 {
            return Err(invalid(
                "shapedirs",
                "no shape components; expected V × 3 × B with B ≥ 1".into(),
            ));
        }
        expect_len(
            "shapedirs",
            parts.shapedirs.len(),
            v * 3 * b,
            format!("{v} × 3 × {b}"),
        )?;
        let p = POSE_FEATURES_PER_JOINT * (j - 1);
        if let Some(pd) = &parts.posedirs {
            expect_len("posedirs", pd.len(), v * 3 * p, format!("{v} × 3 × {p}"))?;
        }
        expect_len(
            "J_regressor",
            parts.j_regressor.len(),
            j * v,
            format!("{j} × {v}"),
        )?;
        expect_len("weights", parts.weights.len(), v * j, format!("{v} × {j}"))?;

        finite(
            "v_template",
            parts.v_template.iter().flatten().copied(),
            &[v, 3],
            source,
        )?;
        finite(
            "shapedirs",
            parts.shapedirs.iter().copied(),
            &[v, 3, b],
            source,
        )?;
        if let Some(pd) = &parts.posedirs {
            finite("posedirs", pd.iter().copied(), &[v, 3, p], source)?;
        }
        finite(
            "J_regressor",
            parts.j_regressor.iter().copied(),
            &[j, v],
            source,
        )?;
        finite("weights", parts.weights.iter().copied(), &[v, j], source)?;

        for (vi, row) in parts.weights.chunks_exact(j).enumerate() {
            if let Some(k) = row.iter().position(|&w| w < -1e-6) {
                return Err(invalid(
                    "weights",
                    format!(
                        "weights[{vi}, {k}] = {}; expected non-negative skinning weights",
                        row[k]
                    ),
                ));
            }
            let s: f64 = row.iter().sum();
            if (s - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
                return Err(invalid(
                    "weights",
                    format!("row {vi} sums to {s}; expected each vertex's weights to sum to 1"),
                ));
            }
        }
        let mut j_sparse = Vec::with_capacity(j);
        for (ji, row) in parts.j_regressor.chunks_exact(v).enumerate() {
            let s: f64 = row.iter().sum();
            if (s - 1.0).abs() > REGRESSOR_SUM_TOLERANCE {
                return Err(invalid(
                    "J_regressor",
                    format!("row {ji} sums to {s}; expected each joint to be a weighted average of vertices (row sum 1)"),
                ));
            }
            j_sparse.push(
                row.iter()
                    .enumerate()
                    .filter(|(_, &w)| w != 0.0)
                    .map(|(i, &w)| (i as u32, w))
                    .collect(),
            );
        }
        if parts.faces.is_empty() {
            return Err(invalid("f", "no faces; expected F × 3 with F ≥ 1".into()));
        }
        for (fi, f) in parts.faces.iter().enumerate() {
            if let Some(&i) = f.iter().find(|&&i| i as usize >= v) {
                return Err(invalid(
                    "f",
                    format!("face {fi} uses vertex {i}; expected indices below {v}"),
                ));
            }
        }
        let skeleton =
            Skeleton::new(parts.parents).map_err(|e| invalid("kintree_table", e.to_string()))?;
        let posedirs = parts.posedirs.filter(|pd| pd.iter().any(|&x| x != 0.0));
        Ok(BodyModel {
            source: source.to_string(),
            v_template: parts.v_template,
            shapedirs: parts.shapedirs,
            num_betas: b,
            posedirs,
            j_regressor: j_sparse,
            weights: SkinWeights::from_dense(&parts.weights, j),
            skeleton,
            faces: parts.faces,
        })
    }

    /// Reads a model from an `.npz` file in the SMPL layout.
    pub fn load(path: &Path) -> Result<Self, BodyError> {
        let npz = Npz::open(path)?;
        Self::from_npz(npz, &path.display().to_string())
    }

    /// Reads the SMPL-format `.npz` at `path`, or weft's built-in default body when
    /// `None`: the one place a `--body` option or a config's `body` key becomes a model.
    /// Errors name the file (or the default body).
    pub fn load_or_default(path: Option<&Path>) -> Result<Self, BodyError> {
        match path {
            Some(path) => Self::load(path),
            None => crate::default_body(),
        }
    }

    /// Reads a model from `.npz` bytes; `name` names it in errors.
    pub fn from_npz_bytes(bytes: Vec<u8>, name: &str) -> Result<Self, BodyError> {
        let npz = Npz::from_bytes(bytes, Path::new(name))?;
        Self::from_npz(npz, name)
    }

    fn from_npz(mut npz: Npz, source: &str) -> Result<Self, BodyError> {
        let invalid = |key: &'static str, message: String| BodyError::Invalid {
            source_name: source.to_string(),
            key,
            message,
        };
        let vt = npz.floats("v_template", &[None, Some(3)])?;
        let v = vt.shape[0];
        let sd = npz.floats("shapedirs", &[Some(v), Some(3), None])?;
        let b = sd.shape[2];
        // The skeleton defines J; the other arrays are checked against it.
        let kt = npz.ints("kintree_table", &[Some(2), None])?;
        let j = kt.shape[1];
        let w = npz.floats("weights", &[Some(v), Some(j)])?;
        let jr = npz.floats("J_regressor", &[Some(j), Some(v)]).map_err(|e| match e {
            NpzError::Invalid { ref message, .. } if message.contains("'|O'") => invalid(
                "J_regressor",
                "stored as a Python object (a scipy sparse matrix from SMPL's .pkl?); expected a dense float array: save J_regressor.toarray() (see docs/body.md)".into(),
            ),
            e => e.into(),
        })?;
        let posedirs = if npz.contains("posedirs") {
            let p = POSE_FEATURES_PER_JOINT * j.saturating_sub(1);
            Some(npz.floats("posedirs", &[Some(v), Some(3), Some(p)])?.data)
        } else {
            None
        };
        let f = npz.ints("f", &[None, Some(3)])?;

        let mut parents = Vec::with_capacity(j);
        for c in 0..j {
            let p = kt.data[c];
            let id = kt.data[j + c];
            if id != c as i64 {
                return Err(invalid(
                    "kintree_table",
                    format!("row 1 holds {id} at column {c}; expected the joint ids 0, 1, …, {} in order", j - 1),
                ));
            }
            parents.push(if c == 0 {
                if p < 0 || p == i64::from(u32::MAX) {
                    None
                } else {
                    return Err(invalid(
                        "kintree_table",
                        format!("the root (joint 0) has parent {p}; expected -1 or 4294967295"),
                    ));
                }
            } else if (0..c as i64).contains(&p) {
                Some(p as usize)
            } else {
                return Err(invalid(
                    "kintree_table",
                    format!("joint {c} has parent {p}; expected a joint index below {c} (parents listed before children)"),
                ));
            });
        }
        let mut faces = Vec::with_capacity(f.shape[0]);
        for (fi, tri) in f.data.chunks_exact(3).enumerate() {
            let mut out = [0u32; 3];
            for k in 0..3 {
                out[k] = u32::try_from(tri[k])
                    .ok()
                    .filter(|&i| (i as usize) < v)
                    .ok_or_else(|| {
                        invalid(
                            "f",
                            format!(
                                "face {fi} uses vertex {}; expected indices in 0..{v}",
                                tri[k]
                            ),
                        )
                    })?;
            }
            faces.push(out);
        }
        let parts = BodyParts {
            v_template: vt
                .data
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            shapedirs: sd.data,
            num_betas: b,
            posedirs,
            j_regressor: jr.data,
            weights: w.data,
            parents,
            faces,
        };
        Self::new(parts, source)
    }

    /// The `.npz` bytes of this model: floats as `f32` (plenty for positions in metres
    /// and weights; keeps files small), `kintree_table` as `i64` with −1 for the root,
    /// `f` as `u32`, deflated. All seven SMPL keys are written (`posedirs` as zeros when the
    /// model has none; reading drops an all-zero `posedirs` again).
    pub fn to_npz(&self) -> Result<NpzWriter, std::io::Error> {
        let (v, j, b) = (self.vertex_count(), self.joint_count(), self.num_betas);
        let f32s = |x: &[f64]| x.iter().map(|&a| a as f32).collect::<Vec<f32>>();
        let mut w = NpzWriter::new(true);
        let vt: Vec<f64> = self.v_template.iter().flatten().copied().collect();
        w.add("v_template", &[v, 3], &f32s(&vt))?;
        w.add("shapedirs", &[v, 3, b], &f32s(&self.shapedirs))?;
        // Always written, zeros when the body has no pose correctives: SMPL tooling
        // (smplx, the chumpy loaders) reads `posedirs` unconditionally.
        let p = POSE_FEATURES_PER_JOINT * (j - 1);
        match &self.posedirs {
            Some(pd) => w.add("posedirs", &[v, 3, p], &f32s(pd))?,
            None => w.add("posedirs", &[v, 3, p], &vec![0.0f32; v * 3 * p])?,
        }
        w.add("J_regressor", &[j, v], &f32s(&self.j_regressor_dense()))?;
        w.add("weights", &[v, j], &f32s(&self.weights.to_dense()))?;
        let mut kt: Vec<i64> = self
            .skeleton
            .parents()
            .iter()
            .map(|p| p.map_or(-1, |p| p as i64))
            .collect();
        kt.extend(0..j as i64);
        w.add("kintree_table", &[2, j], &kt)?;
        let f: Vec<u32> = self.faces.iter().flatten().copied().collect();
        w.add("f", &[self.faces.len(), 3], &f)?;
        Ok(w)
    }

    /// Writes the model as `.npz` (see [`Self::to_npz`]) atomically.
    pub fn save(&self, path: &Path) -> Result<(), BodyError> {
        let w = self.to_npz().map_err(|source| NpzError::Write {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(w.write(path)?)
    }

    /// The plain arrays of the model (dense `J_regressor` and weights).
    pub fn to_parts(&self) -> BodyParts {
        BodyParts {
            v_template: self.v_template.clone(),
            shapedirs: self.shapedirs.clone(),
            num_betas: self.num_betas,
            posedirs: self.posedirs.clone(),
            j_regressor: self.j_regressor_dense(),
            weights: self.weights.to_dense(),
            parents: self.skeleton.parents().to_vec(),
            faces: self.faces.clone(),
        }
    }

    fn j_regressor_dense(&self) -> Vec<f64> {
        let v = self.vertex_count();
        let mut out = vec![0.0; self.joint_count() * v];
        for (j, row) in self.j_regressor.iter().enumerate() {
            for &(i, w) in row {
                out[j * v + i as usize] = w;
            }
        }
        out
    }

    /// Where the model came from (a path, or `default body`).
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Number of vertices V.
    pub fn vertex_count(&self) -> usize {
        self.v_template.len()
    }

    /// Number of joints J.
    pub fn joint_count(&self) -> usize {
        self.skeleton.len()
    }

    /// Number of shape coefficients B.
    pub fn num_betas(&self) -> usize {
        self.num_betas
    }

    /// Whether the model has (nonzero) pose blend shapes.
    pub fn has_pose_blend_shapes(&self) -> bool {
        self.posedirs.is_some()
    }

    /// The triangles.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// The kinematic tree.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// The skinning weights.
    pub fn weights(&self) -> &SkinWeights {
        &self.weights
    }

    /// The mean shape's rest vertices `T`.
    pub fn v_template(&self) -> &[[f64; 3]] {
        &self.v_template
    }

    /// Sparse rows of `J_regressor`: `(vertex, weight)` per joint.
    pub fn j_regressor(&self) -> &[Vec<(u32, f64)>] {
        &self.j_regressor
    }

    /// Shape blend shape `b` of vertex `v`: the displacement per unit `β_b`.
    pub fn shape_direction(&self, v: usize, b: usize) -> [f64; 3] {
        let base = v * 3 * self.num_betas;
        [0, 1, 2].map(|c| self.shapedirs[base + c * self.num_betas + b])
    }

    /// `T + B_s(β)`: rest vertices of shape `betas` (fewer than B are padded with zeros).
    pub fn shape_vertices(&self, betas: &[f64]) -> Result<Vec<[f64; 3]>, BodyError> {
        let betas = self.betas(betas)?;
        let b = self.num_betas;
        Ok(self
            .v_template
            .iter()
            .enumerate()
            .map(|(v, t)| {
                let base = v * 3 * b;
                let mut p = *t;
                for (c, pc) in p.iter_mut().enumerate() {
                    let row = &self.shapedirs[base + c * b..base + (c + 1) * b];
                    *pc += row.iter().zip(&betas).map(|(s, x)| s * x).sum::<f64>();
                }
                p
            })
            .collect())
    }

    /// The shape vector of this model for the coefficients `betas` given: padded with
    /// zeros to [`num_betas`](Self::num_betas). Refuses more coefficients than the model
    /// has (naming the count and the limit) and non-finite ones.
    pub fn betas(&self, betas: &[f64]) -> Result<Vec<f64>, BodyError> {
        if betas.len() > self.num_betas {
            return Err(BodyError::Betas {
                source_name: self.source.clone(),
                given: betas.len(),
                available: self.num_betas,
            });
        }
        if let Some((i, &x)) = betas.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(BodyError::NonFinite {
                what: "beta",
                index: i,
                value: x,
            });
        }
        let mut out = betas.to_vec();
        out.resize(self.num_betas, 0.0);
        Ok(out)
    }

    /// `J_regressor · vertices`.
    pub fn regress_joints(&self, vertices: &[[f64; 3]]) -> Vec<[f64; 3]> {
        self.j_regressor
            .iter()
            .map(|row| {
                let mut s = Vector3::zeros();
                for &(i, w) in row {
                    s += Vector3::from(vertices[i as usize]) * w;
                }
                s.into()
            })
            .collect()
    }

    /// Rest joints `J(β)`.
    pub fn joints(&self, betas: &[f64]) -> Result<Vec<[f64; 3]>, BodyError> {
        Ok(self.regress_joints(&self.shape_vertices(betas)?))
    }

    /// The body of shape `betas`, ready to pose.
    pub fn shaped(&self, betas: &[f64]) -> Result<ShapedBody, BodyError> {
        let padded = self.betas(betas)?;
        let vertices = self.shape_vertices(&padded)?;
        let joints = self.regress_joints(&vertices);
        Ok(ShapedBody {
            betas: padded,
            vertices,
            joints,
        })
    }

    /// The rest mesh of shape `betas`.
    pub fn shape(&self, betas: &[f64]) -> Result<TriMesh, BodyError> {
        Ok(TriMesh::new(
            self.shape_vertices(betas)?,
            self.faces.clone(),
        ))
    }

    /// A mesh with this model's faces and the given positions (one per vertex).
    pub fn mesh(&self, positions: Vec<[f64; 3]>) -> TriMesh {
        TriMesh::new(positions, self.faces.clone())
    }

    /// Rotation matrices of a pose (one axis-angle per joint), checked for count and
    /// finiteness.
    fn rotations(
        &self,
        pose: impl ExactSizeIterator<Item = [f64; 3]>,
    ) -> Result<Vec<Matrix3<f64>>, BodyError> {
        if pose.len() != self.joint_count() {
            return Err(crate::kinematics::KinematicsError::Count {
                what: "pose",
                expected: self.joint_count(),
                found: pose.len(),
            }
            .into());
        }
        pose.enumerate()
            .map(|(j, w)| match w.iter().position(|x| !x.is_finite()) {
                Some(k) => Err(BodyError::NonFinite {
                    what: "pose angle",
                    index: 3 * j + k,
                    value: w[k],
                }),
                None => Ok(rodrigues(w)),
            })
            .collect()
    }

    /// Posed vertices of `shaped` with local joint rotations `rotations`, root
    /// translation `translation` (the posed root joint lands at `J_0 + translation`),
    /// through `out(v, p)`.
    fn pose_with(
        &self,
        shaped: &ShapedBody,
        rotations: &[Matrix3<f64>],
        translation: [f64; 3],
        method: Skinning,
        out: impl FnMut(usize, [f64; 3]),
    ) -> Result<(), BodyError> {
        self.check_shaped(shaped)?;
        if let Some((k, &x)) = translation.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(BodyError::NonFinite {
                what: "translation",
                index: k,
                value: x,
            });
        }
        let a = self
            .skeleton
            .skinning_transforms(&shaped.joints, rotations, translation)?;
        match &self.posedirs {
            None => skin_with(method, &shaped.vertices, &self.weights, &a, out),
            Some(pd) => {
                let rest = self.pose_blend(&shaped.vertices, rotations, pd);
                skin_with(method, &rest, &self.weights, &a, out);
            }
        }
        Ok(())
    }

    /// `T + B_s(β) + B_p(θ)`: SMPL's pose blend shapes over the features `R_j − I`.
    fn pose_blend(
        &self,
        shaped: &[[f64; 3]],
        rotations: &[Matrix3<f64>],
        pd: &[f64],
    ) -> Vec<[f64; 3]> {
        let mut feature = Vec::with_capacity(POSE_FEATURES_PER_JOINT * (rotations.len() - 1));
        for r in &rotations[1..] {
            let d = r - Matrix3::identity();
            for row in 0..3 {
                for col in 0..3 {
                    feature.push(d[(row, col)]);
                }
            }
        }
        let p = feature.len();
        shaped
            .iter()
            .enumerate()
            .map(|(v, s)| {
                let mut q = *s;
                for (c, qc) in q.iter_mut().enumerate() {
                    let row = &pd[(v * 3 + c) * p..(v * 3 + c + 1) * p];
                    *qc += row.iter().zip(&feature).map(|(a, b)| a * b).sum::<f64>();
                }
                q
            })
            .collect()
    }

    fn check_shaped(&self, shaped: &ShapedBody) -> Result<(), BodyError> {
        if shaped.vertices.len() != self.vertex_count() || shaped.joints.len() != self.joint_count()
        {
            return Err(BodyError::Invalid {
                source_name: self.source.clone(),
                key: "v_template",
                message: format!(
                    "the shaped body has {} vertices and {} joints; expected {} and {} (shaped by another model?)",
                    shaped.vertices.len(),
                    shaped.joints.len(),
                    self.vertex_count(),
                    self.joint_count()
                ),
            });
        }
        Ok(())
    }

    /// Posed vertices for one pose given as one axis-angle vector per joint (radians,
    /// local to the parent; the root's is global).
    pub fn pose_vertices(
        &self,
        shaped: &ShapedBody,
        pose: &[[f64; 3]],
        translation: [f64; 3],
        method: Skinning,
    ) -> Result<Vec<[f64; 3]>, BodyError> {
        let rotations = self.rotations(pose.iter().copied())?;
        let mut out = vec![[0.0; 3]; self.vertex_count()];
        self.pose_with(shaped, &rotations, translation, method, |v, p| out[v] = p)?;
        Ok(out)
    }

    /// Posed joint positions for one pose.
    pub fn pose_joints(
        &self,
        shaped: &ShapedBody,
        pose: &[[f64; 3]],
        translation: [f64; 3],
    ) -> Result<Vec<[f64; 3]>, BodyError> {
        self.check_shaped(shaped)?;
        let rotations = self.rotations(pose.iter().copied())?;
        let g = self
            .skeleton
            .global_transforms(&shaped.joints, &rotations, translation)?;
        Ok(posed_joints(&g))
    }

    /// Posed vertices of many frames, in parallel over frames: `f32` in and out (the
    /// precision of motions and datasets), `f64` inside.
    ///
    /// `poses[t]` holds one axis-angle per joint, `trans[t]` the root translation.
    pub fn pose_frames<P>(
        &self,
        shaped: &ShapedBody,
        poses: &[P],
        trans: &[[f32; 3]],
        method: Skinning,
    ) -> Result<Vec<Vec<[f32; 3]>>, BodyError>
    where
        P: AsRef<[[f32; 3]]> + Sync,
    {
        if poses.len() != trans.len() {
            return Err(crate::kinematics::KinematicsError::Count {
                what: "root translations",
                expected: poses.len(),
                found: trans.len(),
            }
            .into());
        }
        poses
            .par_iter()
            .zip(trans.par_iter())
            .map(|(pose, t)| {
                let mut out = vec![[0.0f32; 3]; self.vertex_count()];
                self.pose_frame_f32(shaped, pose.as_ref(), *t, method, &mut out)?;
                Ok(out)
            })
            .collect()
    }

    /// One frame of [`Self::pose_frames`] into a caller's buffer (V entries).
    pub fn pose_frame_f32(
        &self,
        shaped: &ShapedBody,
        pose: &[[f32; 3]],
        translation: [f32; 3],
        method: Skinning,
        out: &mut [[f32; 3]],
    ) -> Result<(), BodyError> {
        if out.len() != self.vertex_count() {
            return Err(crate::kinematics::KinematicsError::Count {
                what: "output buffer",
                expected: self.vertex_count(),
                found: out.len(),
            }
            .into());
        }
        let rotations = self.rotations(pose.iter().map(|w| w.map(f64::from)))?;
        self.pose_with(
            shaped,
            &rotations,
            translation.map(f64::from),
            method,
            |v, p| out[v] = p.map(|x| x as f32),
        )
    }
}

/// Fails on the first non-finite value of `values`, naming its multi-index in `shape`.
fn finite(
    key: &'static str,
    values: impl Iterator<Item = f64>,
    shape: &[usize],
    source: &str,
) -> Result<(), BodyError> {
    for (i, x) in values.enumerate() {
        if !x.is_finite() {
            let mut idx = vec![0; shape.len()];
            let mut r = i;
            for k in (0..shape.len()).rev() {
                idx[k] = r % shape[k].max(1);
                r /= shape[k].max(1);
            }
            let idx: Vec<String> = idx.iter().map(ToString::to_string).collect();
            return Err(BodyError::Invalid {
                source_name: source.to_string(),
                key,
                message: format!("{key}[{}] is {x}; expected finite numbers", idx.join(", ")),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::kinematics::Rigid;
    use proptest::prelude::*;

    /// A small articulated test body: a vertical "torso" box over joint 0 and an "arm"
    /// bar along +X over joints 1 (shoulder) and 2 (elbow); three joints, two betas
    /// (β1 scales the arm length, β2 moves the torso up).
    pub(crate) fn toy_parts() -> BodyParts {
        let mut v_template = Vec::new();
        let mut weights = Vec::new();
        // Torso: 4 vertices around the root, weight on joint 0.
        for &(x, y) in &[(-0.2, -0.5), (0.2, -0.5), (0.2, 0.5), (-0.2, 0.5)] {
            v_template.push([x, y, 0.0]);
            weights.extend([1.0, 0.0, 0.0]);
        }
        // Arm: vertices along x in [0.3, 1.3], blend shoulder → elbow around x = 0.8.
        for i in 0..11 {
            let x = 0.3 + 0.1 * f64::from(i);
            for z in [-0.05, 0.05] {
                v_template.push([x, 0.4, z]);
                let w2 = ((x - 0.7) / 0.2).clamp(0.0, 1.0);
                weights.extend([0.0, 1.0 - w2, w2]);
            }
        }
        let v = v_template.len();
        let mut shapedirs = vec![0.0; v * 3 * 2];
        for (i, p) in v_template.iter().enumerate() {
            // β1: arm points move along x proportionally to their distance past 0.3.
            if p[0] >= 0.3 {
                shapedirs[i * 6] = 0.1 * (p[0] - 0.3);
            }
            // β2: everything moves up by 0.05.
            shapedirs[i * 6 + 2 + 1] = 0.05;
        }
        // Joints: root = torso centre (average of the 4 torso vertices), shoulder =
        // average of the two arm vertices at x = 0.3, elbow = those at x = 0.8.
        let mut j_regressor = vec![0.0; 3 * v];
        j_regressor[..4].fill(0.25);
        j_regressor[v + 4] = 0.5;
        j_regressor[v + 5] = 0.5;
        j_regressor[2 * v + 4 + 10] = 0.5;
        j_regressor[2 * v + 4 + 11] = 0.5;
        let mut faces = Vec::new();
        faces.push([0, 1, 2]);
        faces.push([0, 2, 3]);
        for i in 0..10u32 {
            let a = 4 + 2 * i;
            faces.push([a, a + 2, a + 1]);
            faces.push([a + 1, a + 2, a + 3]);
        }
        BodyParts {
            v_template,
            shapedirs,
            num_betas: 2,
            posedirs: None,
            j_regressor,
            weights,
            parents: vec![None, Some(0), Some(1)],
            faces,
        }
    }

    pub(crate) fn toy() -> BodyModel {
        BodyModel::new(toy_parts(), "toy").unwrap()
    }

    fn near(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        (Vector3::from(a) - Vector3::from(b)).norm() <= tol
    }

    #[test]
    fn shapes_and_joints_follow_the_betas() {
        let m = toy();
        assert_eq!(m.shape_vertices(&[]).unwrap(), m.v_template());
        let j0 = m.joints(&[]).unwrap();
        assert!(near(j0[0], [0.0, 0.0, 0.0], 1e-15));
        assert!(near(j0[1], [0.3, 0.4, 0.0], 1e-15));
        assert!(near(j0[2], [0.8, 0.4, 0.0], 1e-15));
        let j = m.joints(&[2.0, 1.0]).unwrap();
        assert!(near(j[2], [0.8 + 0.2 * 0.5, 0.45, 0.0], 1e-15));
        let e = m.joints(&[0.0, 0.0, 1.0]).unwrap_err().to_string();
        assert_eq!(
            e,
            "toy: 3 shape coefficients (betas) given but the model has 2; expected at most 2"
        );
        assert!(m.joints(&[f64::NAN]).is_err());
    }

    #[test]
    fn betas_are_padded_and_too_many_are_refused() {
        let m = toy();
        assert_eq!(m.betas(&[]).unwrap(), [0.0, 0.0]);
        assert_eq!(m.betas(&[-1.5]).unwrap(), [-1.5, 0.0]);
        assert_eq!(m.betas(&[0.5, 2.0]).unwrap(), [0.5, 2.0]);
        let e = m.betas(&[1.0, 2.0, 3.0]).unwrap_err();
        assert!(
            matches!(
                e,
                BodyError::Betas {
                    given: 3,
                    available: 2,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("at most 2"), "{e}");
        assert!(matches!(
            m.betas(&[f64::INFINITY]),
            Err(BodyError::NonFinite { index: 0, .. })
        ));
    }

    #[test]
    fn load_or_default_reads_the_file_or_the_default_body() {
        let d =
            std::env::temp_dir().join(format!("weft-body-load-or-default-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let path = d.join("toy.npz");
        toy().save(&path).unwrap();
        // Every SMPL key, posedirs included though the toy has no pose correctives.
        let mut keys = weft_mesh::io::npz::Npz::open(&path).unwrap().keys();
        keys.sort();
        assert_eq!(
            keys,
            [
                "J_regressor",
                "f",
                "kintree_table",
                "posedirs",
                "shapedirs",
                "v_template",
                "weights"
            ]
        );
        let m = BodyModel::load_or_default(Some(&path)).unwrap();
        assert!(!m.has_pose_blend_shapes());
        assert_eq!((m.num_betas(), m.joint_count()), (2, 3));
        assert_eq!(m.source(), path.display().to_string());
        let m = BodyModel::load_or_default(None).unwrap();
        assert_eq!(m.source(), crate::default_body::DEFAULT_BODY_NAME);
        assert_eq!(m.num_betas(), 10);
        let missing = d.join("missing.npz");
        let e = BodyModel::load_or_default(Some(&missing)).unwrap_err();
        assert!(e.to_string().contains("missing.npz"), "{e}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn identity_pose_gives_the_shaped_rest_mesh() {
        let m = toy();
        let s = m.shaped(&[1.5, -0.5]).unwrap();
        for method in [Skinning::Lbs, Skinning::Dqs] {
            let p = m
                .pose_vertices(&s, &[[0.0; 3]; 3], [0.0; 3], method)
                .unwrap();
            for (a, b) in p.iter().zip(&s.vertices) {
                assert!(near(*a, *b, 1e-14));
            }
        }
    }

    #[test]
    fn elbow_rotation_in_closed_form() {
        let m = toy();
        let s = m.shaped(&[]).unwrap();
        let mut pose = [[0.0; 3]; 3];
        pose[2] = [0.0, 0.0, std::f64::consts::FRAC_PI_2];
        for method in [Skinning::Lbs, Skinning::Dqs] {
            let p = m.pose_vertices(&s, &pose, [0.0; 3], method).unwrap();
            // The arm tip (x = 1.3, fully on the elbow) swings up about (0.8, 0.4).
            let tip = 4 + 20;
            let r = s.vertices[tip];
            assert!(
                near(p[tip], [0.8, 0.4 + (r[0] - 0.8), r[2]], 1e-12),
                "{method}"
            );
            // Torso and upper arm do not move.
            for (a, b) in p.iter().zip(&s.vertices).take(8) {
                assert!(near(*a, *b, 1e-14));
            }
        }
        let joints = m.pose_joints(&s, &pose, [0.0; 3]).unwrap();
        assert!(near(joints[2], [0.8, 0.4, 0.0], 1e-14));
    }

    #[test]
    fn pose_blend_shapes_use_rotation_minus_identity() {
        let mut parts = toy_parts();
        let v = parts.v_template.len();
        let p = 9 * 2;
        let mut pd = vec![0.0; v * 3 * p];
        // Vertex 0's y moves by 1 × (R_1 − I)[0][0] (feature 0 of joint 1).
        pd[p] = 1.0; // row (vertex 0, coordinate y)
        parts.posedirs = Some(pd);
        let m = BodyModel::new(parts, "toy").unwrap();
        assert!(m.has_pose_blend_shapes());
        let s = m.shaped(&[]).unwrap();
        let t = 0.7f64;
        let mut pose = [[0.0; 3]; 3];
        pose[1] = [0.0, 0.0, t];
        let out = m.pose_vertices(&s, &pose, [0.0; 3], Skinning::Lbs).unwrap();
        // Vertex 0 hangs on the root only, so it moves by the blend shape alone.
        assert!(near(out[0], [-0.2, -0.5 + (t.cos() - 1.0), 0.0], 1e-14));
    }

    #[test]
    fn npz_round_trip_and_f32_batches() {
        let m = toy();
        let bytes = m.to_npz().unwrap().to_bytes().unwrap();
        let back = BodyModel::from_npz_bytes(bytes, "toy.npz").unwrap();
        assert_eq!(back.vertex_count(), m.vertex_count());
        assert_eq!(back.skeleton(), m.skeleton());
        assert_eq!(back.faces(), m.faces());
        let s1 = m.shaped(&[0.3]).unwrap();
        let s2 = back.shaped(&[0.3]).unwrap();
        for (a, b) in s1.vertices.iter().zip(&s2.vertices) {
            assert!(near(*a, *b, 1e-6));
        }
        let poses = vec![[[0.1f32, 0.2, 0.3]; 3], [[0.0f32; 3]; 3]];
        let trans = vec![[0.0f32, 1.0, 0.0], [0.5, 0.0, 0.0]];
        let frames = m.pose_frames(&s1, &poses, &trans, Skinning::Dqs).unwrap();
        for (k, f) in frames.iter().enumerate() {
            let pose: Vec<[f64; 3]> = poses[k].iter().map(|w| w.map(f64::from)).collect();
            let exact = m
                .pose_vertices(&s1, &pose, trans[k].map(f64::from), Skinning::Dqs)
                .unwrap();
            for (a, b) in f.iter().zip(&exact) {
                assert!(near(a.map(f64::from), *b, 1e-6));
            }
        }
        assert!(m
            .pose_frames(&s1, &poses, &trans[..1], Skinning::Lbs)
            .is_err());
    }

    #[test]
    fn bad_models_are_refused_with_the_key() {
        let check = |f: &dyn Fn(&mut BodyParts), want: &str| {
            let mut p = toy_parts();
            f(&mut p);
            let e = BodyModel::new(p, "bad.npz").unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
        };
        check(
            &|p| p.v_template[3][1] = f64::NAN,
            "bad.npz: `v_template`: v_template[3, 1] is NaN",
        );
        check(&|p| p.weights[0] = 0.5, "`weights`: row 0 sums to 0.5");
        check(&|p| p.weights[1] = -0.2, "weights[0, 1] = -0.2");
        check(&|p| p.j_regressor[0] = 2.0, "`J_regressor`: row 0 sums to");
        check(
            &|p| p.parents[1] = Some(2),
            "`kintree_table`: joint 1: parent Some(2)",
        );
        check(&|p| p.faces[0][2] = 999, "`f`: face 0 uses vertex 999");
        check(
            &|p| p.shapedirs.pop().map(drop).unwrap_or(()),
            "`shapedirs`: 155 values; expected 26 × 3 × 2 = 156",
        );
    }

    #[test]
    fn kintree_roots_may_be_minus_one_or_u32_max() {
        let m = toy();
        for root in [-1i64, 4294967295] {
            let mut w = NpzWriter::new(false);
            let parts = m.to_parts();
            let v = m.vertex_count();
            let vt: Vec<f64> = parts.v_template.iter().flatten().copied().collect();
            w.add("v_template", &[v, 3], &vt).unwrap();
            w.add("shapedirs", &[v, 3, 2], &parts.shapedirs).unwrap();
            w.add("J_regressor", &[3, v], &parts.j_regressor).unwrap();
            w.add("weights", &[v, 3], &parts.weights).unwrap();
            w.add("kintree_table", &[2, 3], &[root, 0, 1, 0, 1, 2])
                .unwrap();
            let f: Vec<i32> = parts.faces.iter().flatten().map(|&i| i as i32).collect();
            w.add("f", &[parts.faces.len(), 3], &f).unwrap();
            let m2 = BodyModel::from_npz_bytes(w.to_bytes().unwrap(), "smpl.npz").unwrap();
            assert_eq!(m2.skeleton().parents(), &[None, Some(0), Some(1)]);
        }
        // Arrays are checked against J from the kintree.
        let mut w = NpzWriter::new(false);
        let parts = m.to_parts();
        let v = m.vertex_count();
        let vt: Vec<f64> = parts.v_template.iter().flatten().copied().collect();
        w.add("v_template", &[v, 3], &vt).unwrap();
        w.add("shapedirs", &[v, 3, 2], &parts.shapedirs).unwrap();
        w.add("kintree_table", &[2, 3], &[-1i64, 0, 1, 0, 1, 2])
            .unwrap();
        w.add("weights", &[v, 2], &vec![0.5f64; v * 2]).unwrap();
        let e = BodyModel::from_npz_bytes(w.to_bytes().unwrap(), "w.npz")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            format!("w.npz: `weights` has shape ({v}, 2); expected ({v}, 3)")
        );
        // A missing key and a wrong shape name the key and the expectation.
        let mut w = NpzWriter::new(false);
        w.add("v_template", &[2, 3], &[0.0f64; 6]).unwrap();
        w.add("shapedirs", &[2, 3], &[0.0f64; 6]).unwrap();
        let e = BodyModel::from_npz_bytes(w.to_bytes().unwrap(), "x.npz")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "x.npz: `shapedirs` has shape (2, 3); expected (2, 3, *)");
    }

    proptest! {
        #[test]
        fn whole_body_rigid_motion_of_a_shaped_body(w in prop::array::uniform3(-3.0f64..3.0), t in prop::array::uniform3(-2.0f64..2.0), b in prop::array::uniform2(-2.0f64..2.0)) {
            let m = toy();
            let s = m.shaped(&b).unwrap();
            let mut pose = [[0.0; 3]; 3];
            pose[0] = w;
            let r = rodrigues(w);
            let j0 = Vector3::from(s.joints[0]);
            let rigid = Rigid { rotation: r, translation: j0 + Vector3::from(t) - r * j0 };
            for method in [Skinning::Lbs, Skinning::Dqs] {
                let p = m.pose_vertices(&s, &pose, t, method).unwrap();
                for (a, q) in p.iter().zip(&s.vertices) {
                    prop_assert!(near(*a, rigid.apply(*q), 1e-12));
                }
            }
        }
    }
}
