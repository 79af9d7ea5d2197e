//! `weft data info DIR`: what a dataset holds, per split, and what is wrong with it.

use std::collections::BTreeSet;
use std::fmt;
use std::path::Path;

use serde::Serialize;

use crate::dataset::Dataset;
use crate::error::DataError;
use crate::generate::error_chain;
use crate::manifest::Status;
use crate::split::Split;

/// Counts of one split.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SplitInfo {
    /// The split.
    pub split: Split,
    /// Sequences planned.
    pub planned: usize,
    /// Sequences with frames on disk (done, or diverged after some frames).
    pub sequences: usize,
    /// Frames on disk.
    pub frames: usize,
    /// Distinct garments, body shapes and motions of the split.
    pub garments: usize,
    /// Body shapes.
    pub bodies: usize,
    /// Motions.
    pub motions: usize,
    /// Garment kinds, sorted.
    pub kinds: Vec<String>,
}

/// A sequence that did not finish.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Problem {
    /// The sequence.
    pub id: String,
    /// Its status.
    pub status: Status,
    /// The frame it diverged at, if it did.
    pub frame: Option<usize>,
    /// Frames kept.
    pub frames: usize,
    /// Why.
    pub message: Option<String>,
}

/// The summary `weft data info` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DatasetInfo {
    /// The directory.
    pub dir: String,
    /// Dataset seed.
    pub seed: u64,
    /// The body model.
    pub body_model: String,
    /// Frames per second.
    pub fps: f64,
    /// One entry per split.
    pub splits: Vec<SplitInfo>,
    /// Smallest and largest garment vertex count over generated sequences.
    pub vertices: Option<[usize; 2]>,
    /// Material presets used.
    pub materials: Vec<String>,
    /// Bytes of every file in the directory and its subdirectories.
    pub disk_bytes: u64,
    /// Sequences not simulated yet.
    pub pending: usize,
    /// Diverged or failed sequences.
    pub problems: Vec<Problem>,
    /// Sequences the manifest lists with frames whose shard file is missing.
    pub missing_shards: Vec<String>,
    /// Set by [`DatasetInfo::verify`]: every shard loaded and checked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verified: Option<Verification>,
}

/// What loading every shard found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Verification {
    /// Shards loaded and matching their records.
    pub loaded: usize,
    /// Frames in them.
    pub frames: usize,
    /// Wall time of loading them all, s.
    pub seconds: f64,
    /// Shards that failed, with the loader's error (a changed shard: its SHA-256
    /// differs from the manifest's).
    pub broken: Vec<(String, String)>,
    /// Sequences whose manifest records no SHA-256 (written before digests were kept):
    /// only their header and shapes could be checked.
    pub unrecorded: Vec<String>,
}

impl DatasetInfo {
    /// Summarises the dataset in `dir`.
    pub fn of(dir: &Path) -> Result<Self, DataError> {
        let ds = Dataset::open(dir)?;
        let m = ds.manifest();
        let mut splits = Vec::new();
        for split in Split::ALL {
            let all: Vec<_> = m.sequences_in(split).collect();
            let done: Vec<_> = all.iter().filter(|s| s.has_frames()).collect();
            let kinds: BTreeSet<String> = m
                .garments
                .iter()
                .filter(|g| g.split == split)
                .map(|g| g.kind.clone())
                .collect();
            splits.push(SplitInfo {
                split,
                planned: all.len(),
                sequences: done.len(),
                frames: done.iter().map(|s| s.frames).sum(),
                garments: m.garments.iter().filter(|g| g.split == split).count(),
                bodies: m.bodies.iter().filter(|b| b.split == split).count(),
                motions: m.motions.iter().filter(|x| x.split == split).count(),
                kinds: kinds.into_iter().collect(),
            });
        }
        let generated: Vec<_> = m.sequences.iter().filter(|s| s.has_frames()).collect();
        let vertices = generated
            .iter()
            .map(|s| s.vertices)
            .min()
            .zip(generated.iter().map(|s| s.vertices).max())
            .map(|(a, b)| [a, b]);
        let materials: BTreeSet<String> = m.sequences.iter().map(|s| s.material.clone()).collect();
        let problems = m
            .sequences
            .iter()
            .filter(|s| matches!(s.status, Status::Diverged | Status::Failed))
            .map(|s| Problem {
                id: s.id.clone(),
                status: s.status,
                frame: s.diverged_at,
                frames: s.frames,
                message: s.message.clone(),
            })
            .collect();
        let missing_shards = generated
            .iter()
            .filter(|s| !dir.join(&s.shard).is_file())
            .map(|s| s.id.clone())
            .collect();
        Ok(DatasetInfo {
            dir: dir.display().to_string(),
            seed: m.seed,
            body_model: m.body_model.clone(),
            fps: m.fps,
            splits,
            vertices,
            materials: materials.into_iter().collect(),
            disk_bytes: disk_size(dir)?,
            pending: m
                .sequences
                .iter()
                .filter(|s| s.status == Status::Pending)
                .count(),
            problems,
            missing_shards,
            verified: None,
        })
    }

    /// Loads every shard the manifest lists with frames through
    /// [`Dataset::load_verified`] (SHA-256 against the manifest's, header, dtypes,
    /// shapes, face indices) and records the result and the time.
    pub fn verify(&mut self, dir: &Path) -> Result<(), DataError> {
        let ds = Dataset::open(dir)?;
        let started = std::time::Instant::now();
        let mut v = Verification {
            loaded: 0,
            frames: 0,
            seconds: 0.0,
            broken: Vec::new(),
            unrecorded: Vec::new(),
        };
        for r in ds.records().iter().filter(|r| r.has_frames()) {
            if r.sha256.is_none() {
                v.unrecorded.push(r.id.clone());
            }
            match ds.load_verified(r) {
                Ok(s) => {
                    v.loaded += 1;
                    v.frames += s.positions.len();
                }
                Err(e) => v.broken.push((r.id.clone(), error_chain(&e))),
            }
        }
        v.seconds = started.elapsed().as_secs_f64();
        self.verified = Some(v);
        Ok(())
    }
}

/// Total size of the files under `dir` (recursively).
fn disk_size(dir: &Path) -> Result<u64, DataError> {
    let mut total = 0;
    let entries =
        std::fs::read_dir(dir).map_err(|e| DataError::io(dir, "cannot list the directory", e))?;
    for entry in entries.filter_map(Result::ok) {
        let Ok(meta) = entry.metadata() else { continue };
        if meta.is_dir() {
            total += disk_size(&entry.path())?;
        } else {
            total += meta.len();
        }
    }
    Ok(total)
}

fn human_bytes(b: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", units[u])
    }
}

impl fmt::Display for DatasetInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "dataset {}", self.dir)?;
        writeln!(
            f,
            "seed {}, {} fps, body model: {}",
            self.seed, self.fps, self.body_model
        )?;
        writeln!(
            f,
            "{:<11} {:>9} {:>8} {:>8} {:>6} {:>6}  kinds",
            "split", "sequences", "frames", "garments", "bodies", "motions"
        )?;
        for s in &self.splits {
            let seq = if s.sequences == s.planned {
                s.sequences.to_string()
            } else {
                format!("{}/{}", s.sequences, s.planned)
            };
            writeln!(
                f,
                "{:<11} {:>9} {:>8} {:>8} {:>6} {:>6}  {}",
                s.split.name(),
                seq,
                s.frames,
                s.garments,
                s.bodies,
                s.motions,
                s.kinds.join(", ")
            )?;
        }
        match self.vertices {
            Some([a, b]) => writeln!(f, "garment vertices: {a} to {b}")?,
            None => writeln!(f, "garment vertices: no sequence generated yet")?,
        }
        writeln!(f, "materials: {}", self.materials.join(", "))?;
        writeln!(f, "disk: {}", human_bytes(self.disk_bytes))?;
        if self.pending > 0 {
            writeln!(f, "pending: {} sequences not generated yet", self.pending)?;
        }
        for p in &self.problems {
            match p.status {
                Status::Diverged => writeln!(
                    f,
                    "diverged: {} at frame {} ({} frames kept): {}",
                    p.id,
                    p.frame.unwrap_or(0),
                    p.frames,
                    p.message.as_deref().unwrap_or("")
                )?,
                _ => writeln!(
                    f,
                    "{}: {}: {}",
                    p.status.name(),
                    p.id,
                    p.message.as_deref().unwrap_or("")
                )?,
            }
        }
        for id in &self.missing_shards {
            writeln!(f, "missing shard: {id}")?;
        }
        if let Some(v) = &self.verified {
            writeln!(
                f,
                "verified: {} shards, {} frames loaded in {:.2} s",
                v.loaded, v.frames, v.seconds
            )?;
            if !v.unrecorded.is_empty() {
                writeln!(
                    f,
                    "no SHA-256 recorded for {} shards (a manifest from before digests): only their header and shapes were checked; run `weft data generate` again with the dataset's config and `--out {}` to record them",
                    v.unrecorded.len(),
                    self.dir
                )?;
            }
            for (id, e) in &v.broken {
                writeln!(f, "broken shard: {id}: {e}")?;
            }
            if !v.broken.is_empty() {
                writeln!(
                    f,
                    "to repair: run `weft data generate` again with the dataset's config and `--out {}`; it simulates the broken or changed shards again and keeps the others",
                    self.dir
                )?;
            }
        }
        Ok(())
    }
}
