//! `manifest.json`: the index of a dataset directory.
//!
//! It echoes the config and seed, lists every garment, body shape and motion with its
//! split, and has one [`SequenceRecord`] per planned sequence with its shard file and
//! status. The generator rewrites it atomically after each finished shard, so after a
//! kill it still describes exactly the shards that are complete; the loader
//! ([`crate::Dataset`]) reads nothing else to find its way around.
//!
//! Layout of a dataset directory:
//!
//! ```text
//! DIR/manifest.json                    this file
//! DIR/garments/<garment_id>.obj        each garment fitted to the zero shape (β = 0)
//! DIR/shards/<sequence_id>.safetensors one shard per sequence (see crate::shard)
//! DIR/stats/<sequence_id>.json         the simulator's per-frame statistics
//! ```
//!
//! With the config's `garment_body` (fit data, GarFitNet) `garments/<id>.obj` is the
//! garment's pattern, made for that body (every sequence's rest shape), and each shard's
//! `rest_positions` the pattern fitted onto the sequence's body (see [`crate::shard`]):
//! what α, the garment–body association and the joint distances are computed from.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::config::{DataConfig, FORMAT_VERSION};
use crate::error::DataError;
use crate::import::ImportSpec;
use crate::split::Split;

/// The `format` field of every manifest.
pub const MANIFEST_FORMAT: &str = "weft-dataset";
/// The merged (or single-job) manifest's file name.
pub const MANIFEST_FILE: &str = "manifest.json";

/// Where a sequence stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Not simulated yet (or by another `--shard` job whose manifest is not merged).
    Pending,
    /// Simulated to the last frame; the shard holds every frame.
    Done,
    /// The simulator diverged at `diverged_at`; the shard holds the frames before it
    /// (none when it diverged on the first frame).
    Diverged,
    /// Could not be simulated (bad input); `message` says why. No shard.
    Failed,
}

impl Status {
    /// The lowercase name.
    pub fn name(self) -> &'static str {
        match self {
            Status::Pending => "pending",
            Status::Done => "done",
            Status::Diverged => "diverged",
            Status::Failed => "failed",
        }
    }
}

/// A garment: a procedural template, fitted to every body it is simulated on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GarmentRecord {
    /// `g<index>-<kind>`, unique in the dataset.
    pub id: String,
    /// Its split.
    pub split: Split,
    /// Garment kind (weft-garment's name).
    pub kind: String,
    /// Requested vertex count.
    pub target_vertices: usize,
    /// Style seed.
    pub seed: u64,
    /// Material preset name.
    pub material: String,
    /// Skirt or dress length (mini, knee, maxi) overriding the style seed's; absent in
    /// manifests of garments that name none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<String>,
    /// The template, relative to the dataset directory: the garment fitted to the zero
    /// shape, or with the config's `garment_body` its pattern, made for that body.
    pub file: String,
}

/// A body shape.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyRecord {
    /// `b<index>`, unique in the dataset.
    pub id: String,
    /// Its split.
    pub split: Split,
    /// Shape coefficients β (as many as the body model has).
    pub betas: Vec<f32>,
}

/// Where a motion comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum MotionOrigin {
    /// weft-body's procedural library.
    Procedural {
        /// The motion kind.
        kind: String,
        /// Seed of its variations.
        seed: u64,
        /// Speed (m/s for walk/run, tempo factor else); `None`: the kind's default.
        speed: Option<f64>,
        /// Amplitude factor.
        amplitude: f64,
    },
    /// An AMASS `.npz` or `.bvh` file, resampled to the dataset's frame rate.
    File {
        /// The file, as given in the config.
        path: String,
        /// First frame taken (after resampling).
        start: usize,
    },
}

/// A motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionRecord {
    /// `m<index>-<kind or file stem>`, unique in the dataset.
    pub id: String,
    /// Its split.
    pub split: Split,
    /// Where it comes from.
    pub origin: MotionOrigin,
    /// Frames requested (`None`: the rest of the file).
    pub frames: Option<usize>,
}

/// One simulated sequence: a garment on a body shape performing a motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceRecord {
    /// `<split>-<garment_id>-<body_id>-<motion_id>`, unique in the dataset.
    pub id: String,
    /// Position in the plan (what `--shard i/n` partitions).
    pub index: usize,
    /// Its split.
    pub split: Split,
    /// Shard file, relative to the dataset directory.
    pub shard: String,
    /// Per-frame simulator statistics, relative to the dataset directory.
    pub stats: String,
    /// The garment.
    pub garment_id: String,
    /// Its kind.
    pub garment_kind: String,
    /// Vertex count of the garment as fitted to this body (0 until generated).
    pub vertices: usize,
    /// Face count of the garment as fitted to this body (0 until generated).
    pub faces: usize,
    /// The body shape.
    pub body_id: String,
    /// Its β.
    pub betas: Vec<f32>,
    /// The motion.
    pub motion_id: String,
    /// Frames `[start, end)` of the motion (at the dataset frame rate) the shard covers.
    pub frame_range: [usize; 2],
    /// Material preset name.
    pub material: String,
    /// Frames per second.
    pub fps: f64,
    /// Frames stored in the shard (fewer than the range when the simulation diverged).
    pub frames: usize,
    /// SHA-256 of the shard file as written (64 lowercase hex digits); set for every
    /// record with a shard. Absent in manifests written before digests were kept: a
    /// resumed `weft data generate` records it then, and `weft data info --verify`
    /// says it cannot check those shards' bytes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sha256: Option<String>,
    /// Where it stands.
    pub status: Status,
    /// The first frame that failed, when diverged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diverged_at: Option<usize>,
    /// Why it diverged or failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
}

impl SequenceRecord {
    /// Whether a shard with at least one frame exists for it (done, or diverged after
    /// some frames): what training can use.
    pub fn has_frames(&self) -> bool {
        matches!(self.status, Status::Done | Status::Diverged) && self.frames > 0
    }
}

/// Which part of the sequences a `--shard i/n` job generates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Job {
    /// This job's index, `0..count`.
    pub index: usize,
    /// Number of jobs.
    pub count: usize,
}

impl Job {
    /// Whether sequence `index` belongs to this job (`index % count == self.index`).
    pub fn owns(&self, index: usize) -> bool {
        index % self.count == self.index
    }

    /// The partial manifest's file name, `manifest.part-<i>-of-<n>.json`.
    pub fn manifest_file(&self) -> String {
        format!("manifest.part-{}-of-{}.json", self.index, self.count)
    }

    /// Parses `i/n` (0 ≤ i < n).
    pub fn parse(text: &str) -> Result<Self, DataError> {
        let bad = || {
            DataError::config(
                "--shard",
                format!("{text:?}; expected i/n with 0 ≤ i < n, e.g. 0/4"),
            )
        };
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Job { index, count })
    }
}

/// The whole manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Always [`MANIFEST_FORMAT`].
    pub format: String,
    /// Layout version ([`FORMAT_VERSION`]).
    pub version: u32,
    /// The dataset seed.
    pub seed: u64,
    /// The body model the shapes belong to ("default body …" or the file given).
    pub body_model: String,
    /// Frames per second of every sequence.
    pub fps: f64,
    /// Set in the partial manifest of a `--shard i/n` job; absent once merged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub job: Option<Job>,
    /// The config it was generated from (`weft data generate`); absent for an import.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub config: Option<DataConfig>,
    /// What it was imported from (`weft data import`); absent for a generated dataset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub import: Option<ImportSpec>,
    /// Garments, train then validation then test.
    pub garments: Vec<GarmentRecord>,
    /// Body shapes, same order.
    pub bodies: Vec<BodyRecord>,
    /// Motions, same order.
    pub motions: Vec<MotionRecord>,
    /// Sequences in plan order.
    pub sequences: Vec<SequenceRecord>,
}

impl Manifest {
    /// Reads and [`validate`](Self::validate)s a manifest file.
    pub fn read(path: &Path) -> Result<Self, DataError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| DataError::io(path, "cannot read the manifest", e))?;
        let manifest: Manifest = serde_json::from_str(&text).map_err(|e| DataError::Manifest {
            path: path.to_path_buf(),
            message: format!("not a weft dataset manifest: {e}"),
        })?;
        manifest.validate(path)?;
        Ok(manifest)
    }

    /// Writes the manifest atomically (pretty JSON, trailing newline).
    pub fn write(&self, path: &Path) -> Result<(), DataError> {
        let mut text = serde_json::to_string_pretty(self).map_err(|e| DataError::Manifest {
            path: path.to_path_buf(),
            message: format!("cannot serialise: {e}"),
        })?;
        text.push('\n');
        weft_mesh::io::write_atomic(path, |w| w.write_all(text.as_bytes()))
            .map_err(|e| DataError::io(path, "cannot write the manifest", e))
    }

    /// Checks the invariants the loader relies on: format and version, unique ids,
    /// every sequence's garment, body and motion listed in the same split, shard and
    /// stats paths inside the directory, frames within the range, and no garment, body
    /// or motion id in two splits.
    pub fn validate(&self, path: &Path) -> Result<(), DataError> {
        let bad = |message: String| DataError::Manifest {
            path: path.to_path_buf(),
            message,
        };
        if self.format != MANIFEST_FORMAT {
            return Err(bad(format!(
                "format {:?}; expected {MANIFEST_FORMAT:?}",
                self.format
            )));
        }
        if self.version != FORMAT_VERSION {
            return Err(bad(format!(
                "version {}; this weft reads version {FORMAT_VERSION}",
                self.version
            )));
        }
        if self.config.is_some() == self.import.is_some() {
            return Err(bad(
                "expected either the `config` of a generated dataset or the `import` of an imported one".into(),
            ));
        }
        let garments =
            index_by_id(self.garments.iter().map(|g| (&g.id, g.split)), "garment").map_err(bad)?;
        let bodies =
            index_by_id(self.bodies.iter().map(|b| (&b.id, b.split)), "body").map_err(bad)?;
        let motions =
            index_by_id(self.motions.iter().map(|m| (&m.id, m.split)), "motion").map_err(bad)?;
        let mut ids = HashSet::new();
        for (i, s) in self.sequences.iter().enumerate() {
            if !is_safe_id(&s.id) {
                return Err(bad(format!(
                    "sequence id {:?}: expected letters, digits, '-' and '_' only",
                    s.id
                )));
            }
            if !ids.insert(s.id.as_str()) {
                return Err(bad(format!("sequence id {:?} appears twice", s.id)));
            }
            if s.index != i {
                return Err(bad(format!(
                    "sequence {} has index {}; expected {i} (plan order)",
                    s.id, s.index
                )));
            }
            for (kind, id, table) in [
                ("garment", &s.garment_id, &garments),
                ("body", &s.body_id, &bodies),
                ("motion", &s.motion_id, &motions),
            ] {
                match table.get(id.as_str()) {
                    None => {
                        return Err(bad(format!(
                            "sequence {}: {kind} {id:?} is not listed",
                            s.id
                        )))
                    }
                    Some(&split) if split != s.split => {
                        return Err(bad(format!(
                            "sequence {} is in {} but its {kind} {id:?} is in {split}",
                            s.id, s.split
                        )))
                    }
                    Some(_) => {}
                }
            }
            if s.shard != shard_path(&s.id) || s.stats != stats_path(&s.id) {
                return Err(bad(format!(
                    "sequence {}: shard {:?} / stats {:?}; expected {:?} / {:?}",
                    s.id,
                    s.shard,
                    s.stats,
                    shard_path(&s.id),
                    stats_path(&s.id)
                )));
            }
            let range = s.frame_range[1].saturating_sub(s.frame_range[0]);
            if s.frames > range {
                return Err(bad(format!(
                    "sequence {}: {} frames stored but the range {:?} holds {range}",
                    s.id, s.frames, s.frame_range
                )));
            }
            if let Some(d) = &s.sha256 {
                if !crate::shard::is_sha256_hex(d) {
                    return Err(bad(format!(
                        "sequence {}: sha256 {d:?}; expected 64 lowercase hex digits",
                        s.id
                    )));
                }
                if !s.has_frames() {
                    return Err(bad(format!(
                        "sequence {} has a sha256 but no shard (status {}, {} frames)",
                        s.id,
                        s.status.name(),
                        s.frames
                    )));
                }
            }
            if s.status == Status::Done && (s.frames == 0 || s.frames != range) {
                return Err(bad(format!(
                    "sequence {} is done but stores {} of {range} frames",
                    s.id, s.frames
                )));
            }
        }
        for g in &self.garments {
            if g.file != garment_path(&g.id) {
                return Err(bad(format!(
                    "garment {}: file {:?}; expected {:?}",
                    g.id,
                    g.file,
                    garment_path(&g.id)
                )));
            }
        }
        Ok(())
    }

    /// The body model file the β belong to (`None`: weft's default body), as the config
    /// or the import file names it.
    pub fn body_file(&self) -> Option<&Path> {
        match (&self.config, &self.import) {
            (Some(c), _) => c.body.as_deref(),
            (None, Some(i)) => i.body.as_deref().map(Path::new),
            (None, None) => None,
        }
    }

    /// The sequences of one split.
    pub fn sequences_in(&self, split: Split) -> impl Iterator<Item = &SequenceRecord> {
        self.sequences.iter().filter(move |s| s.split == split)
    }

    /// Merges the partial manifests of `--shard i/n` jobs (any order) into the
    /// manifest one job would have written: each sequence's record comes from the job
    /// that owns it. Fails when they come from different configs or seeds, or a job's
    /// manifest is missing.
    pub fn merge(parts: &[(PathBuf, Manifest)]) -> Result<Manifest, DataError> {
        let Some((first_path, first)) = parts.first() else {
            return Err(DataError::Conflict {
                path: PathBuf::from("."),
                message: "no partial manifests to merge".into(),
            });
        };
        let count = match first.job {
            Some(j) => j.count,
            None => {
                return Err(DataError::Conflict {
                    path: first_path.clone(),
                    message: "not a partial manifest (no job field)".into(),
                })
            }
        };
        let mut by_index: Vec<Option<&Manifest>> = vec![None; count];
        for (path, m) in parts {
            let conflict = |message: String| DataError::Conflict {
                path: path.clone(),
                message,
            };
            let job = m
                .job
                .ok_or_else(|| conflict("not a partial manifest (no job field)".into()))?;
            if job.count != count {
                return Err(conflict(format!(
                    "job {}/{} does not match {}/{count} of {}",
                    job.index,
                    job.count,
                    first.job.map_or(0, |j| j.index),
                    first_path.display()
                )));
            }
            let same_plan = m.config == first.config
                && m.seed == first.seed
                && m.body_model == first.body_model
                && m.garments == first.garments
                && m.bodies == first.bodies
                && m.motions == first.motions
                && m.sequences.len() == first.sequences.len();
            if !same_plan {
                return Err(conflict(format!(
                    "generated from another config, seed or body than {}",
                    first_path.display()
                )));
            }
            if by_index[job.index].replace(m).is_some() {
                return Err(conflict(format!("job {}/{count} appears twice", job.index)));
            }
        }
        if let Some(missing) = by_index.iter().position(Option::is_none) {
            return Err(DataError::Conflict {
                path: first_path.clone(),
                message: format!(
                    "job {missing}/{count} has no manifest (manifest.part-{missing}-of-{count}.json)"
                ),
            });
        }
        let mut merged = first.clone();
        merged.job = None;
        for (i, s) in merged.sequences.iter_mut().enumerate() {
            if let Some(owner) = by_index[i % count] {
                *s = owner.sequences[i].clone();
            }
        }
        Ok(merged)
    }
}

fn index_by_id<'a>(
    items: impl Iterator<Item = (&'a String, Split)>,
    kind: &str,
) -> Result<HashMap<&'a str, Split>, String> {
    let mut map = HashMap::new();
    for (id, split) in items {
        if !is_safe_id(id) {
            return Err(format!(
                "{kind} id {id:?}: expected letters, digits, '-' and '_' only"
            ));
        }
        if let Some(other) = map.insert(id.as_str(), split) {
            return Err(format!(
                "{kind} id {id:?} appears twice (in {other} and {split})"
            ));
        }
    }
    Ok(map)
}

/// Ids name files, so they are restricted to `[A-Za-z0-9_-]+`: no separators, no `..`.
pub fn is_safe_id(id: &str) -> bool {
    !id.is_empty()
        && id
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
}

/// `shards/<id>.safetensors`.
pub fn shard_path(sequence_id: &str) -> String {
    format!("shards/{sequence_id}.safetensors")
}

/// `stats/<id>.json`.
pub fn stats_path(sequence_id: &str) -> String {
    format!("stats/{sequence_id}.json")
}

/// `garments/<id>.obj`.
pub fn garment_path(garment_id: &str) -> String {
    format!("garments/{garment_id}.obj")
}

/// The partial manifests (`manifest.part-*-of-*.json`) in `dir`, sorted by name.
pub fn partial_manifests(dir: &Path) -> Result<Vec<PathBuf>, DataError> {
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(DataError::io(dir, "cannot list the dataset directory", e)),
    };
    let mut parts: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("manifest.part-") && n.ends_with(".json"))
        })
        .collect();
    parts.sort();
    Ok(parts)
}

/// `weft data merge DIR`: merges the partial manifests of the `--shard i/n` jobs in `dir`
/// into `manifest.json` (the manifest a single job would have written) and returns
/// its path. The partial manifests are left in place.
pub fn merge_directory(dir: &Path) -> Result<PathBuf, DataError> {
    let paths = partial_manifests(dir)?;
    if paths.is_empty() {
        return Err(DataError::Conflict {
            path: dir.to_path_buf(),
            message: "no partial manifests (manifest.part-I-of-N.json) to merge".into(),
        });
    }
    let parts = paths
        .into_iter()
        .map(|p| Manifest::read(&p).map(|m| (p, m)))
        .collect::<Result<Vec<_>, _>>()?;
    let merged = Manifest::merge(&parts)?;
    let path = dir.join(MANIFEST_FILE);
    merged.write(&path)?;
    Ok(path)
}
