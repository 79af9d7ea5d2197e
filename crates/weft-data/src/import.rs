//! `weft data import`: a user's own simulations — garment caches from Marvelous
//! Designer, Houdini, Blender or any simulator, with the garment's rest mesh, the body's
//! shape and its motion — turned into a weft dataset that every model trains and
//! evaluates on like a generated one.
//!
//! The import is described by a TOML file ([`ImportSpec`]); paths in it are relative to
//! the file. Each sequence pairs a cache (`.pc2`, `.mdd`, `.npy` of shape `(T, N, 3)` or a
//! directory of OBJ frames, in the rest mesh's vertex order) with the motion the body
//! performed (AMASS-style `.npz` or `.bvh`, read against the body's rest joints at the
//! sequence's β as every weft command reads motions, resampled to the import's frame
//! rate) and the body shape β. Units and up axis of the meshes are converted
//! (`scale`, `up`) so that everything is in weft's metres, Y up.
//!
//! Checks before anything is written, each naming the file: a cache with another vertex
//! count than its rest mesh, non-finite values, a motion shorter than the cache, a
//! garment used in two splits, ids that are not safe file names, and a cache that is not
//! on the body (every vertex of frame 0 more than [`MAX_GARMENT_GAP`] from the posed
//! body: another unit, axis or frame offset). The dataset is written into a temporary
//! directory beside `out` and renamed into place when complete, so an import is all or
//! nothing.
//!
//! A rest mesh without UVs gets each triangle laid flat in its own plane as its corner
//! UVs: the rest frames of the stretch losses are then the rest mesh's own triangles,
//! which is what the simulator does without UVs too.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use weft_body::{BodyModel, PosedSequence};
use weft_mesh::export::{write_obj_with_uvs, Frames};
use weft_motion::{body_rest_joints, load_motion, Motion, MotionFileOptions, UpAxis};
use weft_sim::{PosedBody, MAX_GARMENT_GAP};

use crate::config::FORMAT_VERSION;
use crate::error::DataError;
use crate::manifest::{
    garment_path, is_safe_id, shard_path, stats_path, BodyRecord, GarmentRecord, Manifest,
    MotionOrigin, MotionRecord, SequenceRecord, Status, MANIFEST_FILE, MANIFEST_FORMAT,
};
use crate::shard::{self, ShardData};
use crate::split::Split;

/// What to import (the TOML file of `weft data import`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImportSpec {
    /// Frames per second of every cache; motions are resampled to it.
    pub fps: f64,
    /// The SMPL-format body model the β belong to (default: weft's default body).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    /// Metres per unit of the rest meshes and caches (0.01 for centimetres). Default 1.
    #[serde(default = "one")]
    pub scale: f64,
    /// Up axis of the rest meshes and caches (`y` or `z`; Z up is turned into Y up).
    /// Default `y`.
    #[serde(default)]
    pub up: Axis,
    /// The garments.
    pub garments: Vec<ImportGarment>,
    /// The simulated sequences.
    pub sequences: Vec<ImportSequence>,
}

fn one() -> f64 {
    1.0
}

/// An up axis in an import file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// Y up (weft, glTF, Maya, Houdini, Marvelous Designer).
    #[default]
    Y,
    /// Z up (Blender, 3ds Max, AMASS).
    Z,
}

impl Axis {
    /// `p` (in this axis convention) in weft's Y-up frame: Z up maps (x, y, z) to
    /// (x, z, −y), the rotation Blender's Y-up exporters apply.
    fn to_y_up(self, p: [f64; 3]) -> [f64; 3] {
        match self {
            Axis::Y => p,
            Axis::Z => [p[0], p[2], -p[1]],
        }
    }
}

/// A garment of an import.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImportGarment {
    /// Its id: letters, digits, `-` and `_`.
    pub id: String,
    /// Its rest mesh (`.obj` with UVs, or `.ply`), on the body in the rest pose, in the
    /// caches' vertex order.
    pub template: String,
    /// What it is (`skirt`, `dress`, …; a label). Default `custom`.
    #[serde(default = "custom")]
    pub kind: String,
    /// Its material (a label). Default `custom`.
    #[serde(default = "custom")]
    pub material: String,
}

fn custom() -> String {
    "custom".to_owned()
}

/// One simulated sequence of an import.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImportSequence {
    /// The garment's id.
    pub garment: String,
    /// The garment's vertices per frame: `.pc2`, `.mdd`, `.npy` or a directory of OBJs.
    pub cache: String,
    /// The body's motion: AMASS-style `.npz` or `.bvh`.
    pub motion: String,
    /// Up axis of the motion file (default: as the file records, else the format's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion_up: Option<Axis>,
    /// The motion frame (after resampling) that cache frame 0 shows. Default 0.
    #[serde(default)]
    pub start: usize,
    /// The body shape β (missing ones are 0).
    #[serde(default)]
    pub betas: Vec<f32>,
    /// `train`, `validation` or `test`.
    pub split: Split,
    /// This sequence's own rest mesh when the garment was fitted to this body shape
    /// (default: the garment's template).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest: Option<String>,
}

/// What an import wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportReport {
    /// The dataset directory.
    pub dir: PathBuf,
    /// Sequences per split (train, validation, test).
    pub sequences: [usize; 3],
    /// Frames over all sequences.
    pub frames: usize,
    /// Rest meshes without UVs (each triangle laid flat instead).
    pub flattened: Vec<String>,
}

impl ImportSpec {
    /// Reads an import file; errors name the file, the line and the key.
    pub fn read(path: &Path) -> Result<Self, DataError> {
        let text = weft_mesh::io::read_input_to_string(path)
            .map_err(|e| DataError::io(path, "cannot read the import file", e))?;
        toml::from_str(&text).map_err(|e| DataError::ConfigSyntax {
            path: path.to_path_buf(),
            message: e.to_string().trim_end().replace('\n', " "),
        })
    }

    /// Checks the values that need no file: rate, scale, ids, references, splits.
    pub fn validate(&self, origin: &Path) -> Result<(), DataError> {
        let bad = |message: String| DataError::Import {
            path: origin.to_path_buf(),
            message,
        };
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= weft_motion::MAX_FPS) {
            return Err(bad(format!(
                "fps = {}; expected a frame rate in (0, {}]",
                self.fps,
                weft_motion::MAX_FPS
            )));
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(bad(format!(
                "scale = {}; expected metres per unit > 0 (0.01 for centimetres)",
                self.scale
            )));
        }
        if self.sequences.is_empty() {
            return Err(bad("no [[sequences]]; expected at least one".into()));
        }
        let mut splits: BTreeMap<&str, Split> = BTreeMap::new();
        for g in &self.garments {
            if !is_safe_id(&g.id) {
                return Err(bad(format!(
                    "garment id {:?}: expected letters, digits, '-' and '_' only",
                    g.id
                )));
            }
            if splits.contains_key(g.id.as_str()) {
                return Err(bad(format!("garment id {:?} appears twice", g.id)));
            }
            splits.insert(&g.id, Split::Train);
        }
        let mut used: BTreeMap<&str, Split> = BTreeMap::new();
        for (i, s) in self.sequences.iter().enumerate() {
            if !splits.contains_key(s.garment.as_str()) {
                return Err(bad(format!(
                    "sequences[{i}]: garment {:?} is not among the [[garments]]",
                    s.garment
                )));
            }
            if let Some(&first) = used.get(s.garment.as_str()) {
                if first != s.split {
                    return Err(bad(format!(
                        "sequences[{i}]: garment {:?} is in {first} and {}; a test garment must be unseen in training, so each garment belongs to one split",
                        s.garment, s.split
                    )));
                }
            }
            used.insert(&s.garment, s.split);
            if let Some(b) = s.betas.iter().find(|b| !b.is_finite()) {
                return Err(bad(format!(
                    "sequences[{i}]: betas hold {b}; expected finite values"
                )));
            }
        }
        Ok(())
    }
}

/// Imports the sequences of the file `spec_path` into the new dataset directory `out`.
pub fn import(spec_path: &Path, out: &Path) -> Result<ImportReport, DataError> {
    let spec = ImportSpec::read(spec_path)?;
    spec.validate(spec_path)?;
    if out.exists() && std::fs::read_dir(out).map_or(true, |mut d| d.next().is_some()) {
        return Err(DataError::Conflict {
            path: out.to_path_buf(),
            message: "exists and is not an empty directory; import into a new directory".into(),
        });
    }
    let base = spec_path.parent().unwrap_or(Path::new("."));
    let resolve = |p: &str| base.join(p);
    // The echo in the manifest names the body by the path it was found at, so the
    // dataset loads it from anywhere.
    let body_file = spec.body.as_deref().map(resolve);
    let model =
        BodyModel::load_or_default(body_file.as_deref()).map_err(|source| DataError::Body {
            what: "model".into(),
            source: Box::new(source),
        })?;
    let echo = ImportSpec {
        body: body_file.map(|p| std::path::absolute(&p).unwrap_or(p).display().to_string()),
        ..spec.clone()
    };

    let parent = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent)
        .map_err(|e| DataError::io(parent, "cannot create the parent directory", e))?;
    let temp = TempDir::new(parent, out)?;
    for sub in ["shards", "stats", "garments"] {
        let d = temp.path().join(sub);
        std::fs::create_dir_all(&d).map_err(|e| DataError::io(&d, "cannot create", e))?;
    }

    let mut ids = Ids::default();
    let mut manifest = Manifest {
        format: MANIFEST_FORMAT.into(),
        version: FORMAT_VERSION,
        seed: 0,
        body_model: model.source().to_owned(),
        fps: spec.fps,
        job: None,
        config: None,
        import: Some(echo),
        garments: Vec::new(),
        bodies: Vec::new(),
        motions: Vec::new(),
        sequences: Vec::new(),
    };
    let mut report = ImportReport {
        dir: out.to_path_buf(),
        sequences: [0; 3],
        frames: 0,
        flattened: Vec::new(),
    };
    // Splits in manifest order, sequences in file order within each.
    let mut order: Vec<usize> = (0..spec.sequences.len()).collect();
    order.sort_by_key(|&i| spec.sequences[i].split);
    for i in order {
        let s = &spec.sequences[i];
        let g = spec
            .garments
            .iter()
            .find(|g| g.id == s.garment)
            .expect("validated");
        let rest_file = resolve(s.rest.as_deref().unwrap_or(&g.template));
        let rest = RestMesh::read(&rest_file, &spec)?;
        if rest.flattened && !report.flattened.contains(&g.id) {
            report.flattened.push(g.id.clone());
        }
        let cache_file = resolve(&s.cache);
        let positions = read_cache(&cache_file, &rest, &rest_file, &spec)?;
        let t = positions.len();

        let betas64: Vec<f64> = s.betas.iter().map(|&b| f64::from(b)).collect();
        let motion_file = resolve(&s.motion);
        let motion = read_motion(&motion_file, s, &model, &betas64, spec.fps)?;
        let available = motion.frame_count().saturating_sub(s.start);
        if available < t {
            return Err(DataError::Import {
                path: motion_file,
                message: format!(
                    "{} frames at {} fps from frame {} on, but the cache {} has {t}; expected a motion at least as long as its cache",
                    available,
                    spec.fps,
                    s.start,
                    cache_file.display()
                ),
            });
        }
        let poses = motion.poses()[s.start..s.start + t].to_vec();
        let trans = motion.trans()[s.start..s.start + t].to_vec();
        let fit = check_on_body(
            &model,
            &s.betas,
            &poses[0],
            trans[0],
            &positions[0],
            &cache_file,
        )?;

        // Records.
        let garment_id = ids.garment(&mut manifest, g, s.split);
        let body_id = ids.body(&mut manifest, &s.betas, s.split);
        let motion_id = ids.motion(&mut manifest, &s.motion, s.start, t, s.split);
        let id = format!("{}-{garment_id}-{body_id}-{motion_id}", s.split.name());
        let id = ids.unique(id);
        let path = temp.path().join(garment_path(&garment_id));
        if !path.exists() {
            let uvs = Some(rest.corner_uvs.as_slice());
            write_obj_with_uvs(&path, &rest.positions, &rest.faces, uvs).map_err(|e| {
                DataError::Import {
                    path: path.clone(),
                    message: e.to_string(),
                }
            })?;
        }
        let data = ShardData {
            positions,
            poses,
            trans,
            betas: s.betas.clone(),
            rest_positions: rest.positions.clone(),
            faces: rest.faces.clone(),
            corner_uvs: rest.corner_uvs.clone(),
        };
        let sha = shard::write(&temp.path().join(shard_path(&id)), &id, &data)?;
        let stats = serde_json::json!({
            "imported_from": {
                "cache": s.cache,
                "motion": s.motion,
                "rest": s.rest.as_deref().unwrap_or(&g.template),
                "start": s.start,
            },
            "frames": t,
            "frame0_vertices_inside_body": fit.inside,
            "frame0_nearest_vertex_m": fit.nearest,
            "rest_uvs": if rest.flattened { "flattened triangles" } else { "from the rest mesh" },
        });
        let path = temp.path().join(stats_path(&id));
        let text = format!(
            "{}\n",
            serde_json::to_string_pretty(&stats).unwrap_or_default()
        );
        weft_mesh::io::write_atomic(&path, |w| w.write_all(text.as_bytes()))
            .map_err(|e| DataError::io(&path, "cannot write the statistics", e))?;
        manifest.sequences.push(SequenceRecord {
            index: manifest.sequences.len(),
            shard: shard_path(&id),
            stats: stats_path(&id),
            split: s.split,
            garment_id,
            garment_kind: g.kind.clone(),
            vertices: rest.positions.len(),
            faces: rest.faces.len(),
            body_id,
            betas: s.betas.clone(),
            motion_id,
            frame_range: [s.start, s.start + t],
            material: g.material.clone(),
            fps: spec.fps,
            frames: t,
            sha256: Some(sha),
            status: Status::Done,
            diverged_at: None,
            message: None,
            id,
        });
        report.sequences[Split::ALL.iter().position(|&x| x == s.split).unwrap_or(0)] += 1;
        report.frames += t;
    }
    let manifest_path = temp.path().join(MANIFEST_FILE);
    manifest.validate(&manifest_path)?;
    manifest.write(&manifest_path)?;
    temp.commit(out)?;
    Ok(report)
}

/// A rest mesh in weft's units and axes, with corner UVs.
struct RestMesh {
    positions: Vec<[f32; 3]>,
    faces: Vec<[u32; 3]>,
    corner_uvs: Vec<[[f32; 2]; 3]>,
    /// No UVs in the file: each triangle laid flat.
    flattened: bool,
}

impl RestMesh {
    fn read(path: &Path, spec: &ImportSpec) -> Result<Self, DataError> {
        let loaded = weft_mesh::io::load_mesh(path).map_err(|e| DataError::Mesh(Box::new(e)))?;
        let positions: Vec<[f32; 3]> = loaded
            .mesh
            .positions
            .iter()
            .map(|&p| spec.up.to_y_up(p.map(|c| c * spec.scale)).map(|c| c as f32))
            .collect();
        let (corner_uvs, flattened) = match loaded.corner_uvs {
            Some(uvs) => (uvs, false),
            None => (flat_triangles(&positions, &loaded.mesh.faces), true),
        };
        Ok(RestMesh {
            positions,
            faces: loaded.mesh.faces,
            corner_uvs,
            flattened,
        })
    }
}

/// Each triangle laid flat in its own plane: corner 0 at the origin, corner 1 on the
/// u axis; lengths and angles are the 3D triangle's.
fn flat_triangles(p: &[[f32; 3]], faces: &[[u32; 3]]) -> Vec<[[f32; 2]; 3]> {
    use weft_mesh::vec3::{cross, dot, norm, sub};
    let at = |i: u32| p[i as usize].map(f64::from);
    faces
        .iter()
        .map(|f| {
            let (a, b, c) = (at(f[0]), at(f[1]), at(f[2]));
            let (e1, e2) = (sub(b, a), sub(c, a));
            let l1 = norm(e1);
            if l1 == 0.0 {
                return [[0.0; 2]; 3];
            }
            let u = dot(e2, e1) / l1;
            let v = norm(cross(e1, e2)) / l1;
            [[0.0, 0.0], [l1 as f32, 0.0], [u as f32, v as f32]]
        })
        .collect()
}

/// A cache's frames in weft's units and axes, checked against its rest mesh.
fn read_cache(
    path: &Path,
    rest: &RestMesh,
    rest_file: &Path,
    spec: &ImportSpec,
) -> Result<Vec<Vec<[f32; 3]>>, DataError> {
    let bad = |message: String| DataError::Import {
        path: path.to_path_buf(),
        message,
    };
    let frames = Frames::load(path).map_err(|e| bad(e.to_string()))?;
    if frames.vertex_count() != rest.positions.len() {
        return Err(bad(format!(
            "{} vertices per frame but the rest mesh {} has {}; expected the rest mesh's vertices in its order",
            frames.vertex_count(),
            rest_file.display(),
            rest.positions.len()
        )));
    }
    frames.check_finite().map_err(|e| bad(e.to_string()))?;
    let mut out = Vec::with_capacity(frames.frame_count());
    for frame in frames.iter() {
        let converted: Vec<[f32; 3]> = frame
            .iter()
            .map(|p| {
                let q = spec.up.to_y_up(p.map(|c| f64::from(c) * spec.scale));
                q.map(|c| c as f32)
            })
            .collect();
        if let Some(k) = converted
            .iter()
            .position(|q| !q.iter().all(|c| c.is_finite()))
        {
            return Err(bad(format!(
                "frame {}, vertex {k} overflows 32-bit floats after scale {}",
                out.len(),
                spec.scale
            )));
        }
        out.push(converted);
    }
    Ok(out)
}

/// The sequence's motion for this body shape, at the import's frame rate.
fn read_motion(
    path: &Path,
    s: &ImportSequence,
    model: &BodyModel,
    betas: &[f64],
    fps: f64,
) -> Result<Motion, DataError> {
    let err = |source: weft_motion::MotionError| DataError::Motion {
        id: path.display().to_string(),
        source: Box::new(source),
    };
    let rest = body_rest_joints(model, betas).map_err(err)?;
    let up = s.motion_up.map(|a| match a {
        Axis::Y => UpAxis::Y,
        Axis::Z => UpAxis::Z,
    });
    let options = MotionFileOptions::for_body(rest, up);
    Ok(load_motion(path, &options, Some(fps)).map_err(err)?.motion)
}

/// How frame 0 of a cache sits on the posed body.
struct Fit {
    inside: usize,
    nearest: f64,
}

/// Refuses a cache whose frame 0 is nowhere near the body posed at the motion's first
/// frame: the cache is in another unit, axis or frame offset than the motion.
fn check_on_body(
    model: &BodyModel,
    betas: &[f32],
    pose: &weft_body::Pose,
    trans: [f32; 3],
    frame: &[[f32; 3]],
    cache: &Path,
) -> Result<Fit, DataError> {
    let body_err = |what: &str, e: String| DataError::Import {
        path: cache.to_path_buf(),
        message: format!("{what}: {e}"),
    };
    let posed = PosedSequence::new(model, betas, std::slice::from_ref(pose), &[trans])
        .map_err(|e| body_err("posing the body", e.to_string()))?;
    let mesh = posed
        .mesh(0)
        .ok_or_else(|| body_err("posing the body", "no frame".into()))?;
    let body = PosedBody::new(&mesh.positions, &mesh.faces)
        .map_err(|e| body_err("the posed body", e.to_string()))?;
    let points: Vec<[f64; 3]> = frame.iter().map(|p| p.map(f64::from)).collect();
    let signed = body
        .signed_distances(&points)
        .map_err(|e| body_err("distances to the body", e.to_string()))?;
    let nearest = signed.iter().copied().fold(f64::INFINITY, f64::min);
    if nearest > MAX_GARMENT_GAP {
        return Err(DataError::Import {
            path: cache.to_path_buf(),
            message: format!(
                "frame 0 is {nearest:.2} m from the body at its motion's first frame (every vertex); expected the garment on the body: check `scale`, `up` and `start`, and that the cache and the motion share one world frame"
            ),
        });
    }
    Ok(Fit {
        inside: signed.iter().filter(|&&d| d < 0.0).count(),
        nearest,
    })
}

/// Ids of the records made so far, keyed by what makes them distinct.
#[derive(Default)]
struct Ids {
    garments: BTreeMap<String, String>,
    bodies: BTreeMap<(Split, Vec<u32>), String>,
    motions: BTreeMap<(Split, String, usize, usize), String>,
    sequences: BTreeMap<String, usize>,
}

impl Ids {
    fn garment(&mut self, m: &mut Manifest, g: &ImportGarment, split: Split) -> String {
        if let Some(id) = self.garments.get(&g.id) {
            return id.clone();
        }
        m.garments.push(GarmentRecord {
            id: g.id.clone(),
            split,
            kind: g.kind.clone(),
            target_vertices: 0,
            seed: 0,
            material: g.material.clone(),
            length: None,
            file: garment_path(&g.id),
        });
        self.garments.insert(g.id.clone(), g.id.clone());
        g.id.clone()
    }

    fn body(&mut self, m: &mut Manifest, betas: &[f32], split: Split) -> String {
        let key = (split, betas.iter().map(|b| b.to_bits()).collect::<Vec<_>>());
        if let Some(id) = self.bodies.get(&key) {
            return id.clone();
        }
        let id = format!("b{:03}", m.bodies.len());
        m.bodies.push(BodyRecord {
            id: id.clone(),
            split,
            betas: betas.to_vec(),
        });
        self.bodies.insert(key, id.clone());
        id
    }

    fn motion(
        &mut self,
        m: &mut Manifest,
        path: &str,
        start: usize,
        frames: usize,
        split: Split,
    ) -> String {
        let key = (split, path.to_owned(), start, frames);
        if let Some(id) = self.motions.get(&key) {
            return id.clone();
        }
        let stem: String = Path::new(path)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let id = format!("m{:03}-{stem}", m.motions.len());
        m.motions.push(MotionRecord {
            id: id.clone(),
            split,
            origin: MotionOrigin::File {
                path: path.to_owned(),
                start,
            },
            frames: Some(frames),
        });
        self.motions.insert(key, id.clone());
        id
    }

    /// `id`, or `id-2`, `id-3`, … when a sequence already has it (two caches of the same
    /// garment, body and motion).
    fn unique(&mut self, id: String) -> String {
        let n = self.sequences.entry(id.clone()).or_insert(0);
        *n += 1;
        if *n == 1 {
            id
        } else {
            format!("{id}-{n}")
        }
    }
}

/// The directory an import is written into before it is renamed to `out`; removed
/// unless committed.
struct TempDir(Option<PathBuf>);

impl TempDir {
    fn path(&self) -> &Path {
        self.0.as_deref().unwrap_or(Path::new("."))
    }

    fn new(parent: &Path, out: &Path) -> Result<Self, DataError> {
        let name = out
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "dataset".into());
        let path = parent.join(format!(".{name}.import-{}.tmp", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path)
            .map_err(|e| DataError::io(&path, "cannot create the temporary directory", e))?;
        Ok(TempDir(Some(path)))
    }

    fn commit(mut self, out: &Path) -> Result<(), DataError> {
        if out.exists() {
            // Empty (checked at the start): replaced by the import.
            std::fs::remove_dir(out).map_err(|e| DataError::io(out, "cannot replace", e))?;
        }
        std::fs::rename(self.path(), out)
            .map_err(|e| DataError::io(out, "cannot move the import into place", e))?;
        self.0 = None;
        Ok(())
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if let Some(path) = &self.0 {
            let _ = std::fs::remove_dir_all(path);
        }
    }
}
