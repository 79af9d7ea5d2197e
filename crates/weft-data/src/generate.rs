//! `weft data generate`: simulate every planned sequence into its shard.
//!
//! Order of work: load the body model, compute the plan ([`crate::plan`]), reconcile it
//! with a manifest already in the directory (resume), write the garment templates,
//! build the motions, then simulate the pending sequences of this job in parallel
//! (rayon, one sequence per task; the simulator parallelises inside a step too).
//!
//! Resuming: a sequence whose manifest record is done (or diverged) and whose shard is
//! present, has the SHA-256 the manifest recorded and the expected header and tensor
//! shapes is kept; anything else — no shard, a torn or foreign file, a shard changed
//! since it was written, a temporary file left by a kill — is simulated again, and the
//! progress says which and why. A record from a manifest written before digests were
//! kept has no SHA-256 to compare: its shard is checked as before and its digest is
//! recorded now.
//! Shards and stats are written to temporary files and renamed, and the manifest is
//! rewritten atomically after each finished shard, so a kill at any moment loses at most
//! the sequences in flight.
//!
//! Determinism: the plan, the garments, the motions and the simulator are functions of
//! the config and seed alone, and records keep plan order whatever order the sequences
//! finish in, so the same config and seed give byte-identical shards and manifest
//! (the stats files hold wall times and differ).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;
use weft_body::BodyModel;
use weft_garment::{FitBody, Garment, GarmentKind, Style};
use weft_mesh::io::lock::{remove_stale_temps, Access, DirLock, LOCK_FILE};
use weft_motion::{
    body_rest_joints, generate as procedural_motion, load_motion, resample, Motion,
    MotionFileOptions, MotionKind, ProceduralParams,
};
use weft_sim::Material;

use crate::config::DataConfig;
use crate::dataset::shape_of;
use crate::error::DataError;
use crate::manifest::{
    GarmentRecord, Job, Manifest, MotionOrigin, MotionRecord, SequenceRecord, Status, MANIFEST_FILE,
};
use crate::plan::plan;
use crate::shard::{self, ShardData};

/// What a simulator needs for one sequence.
pub struct SimInput<'a> {
    /// The garment's rest shape: fitted to this body in its rest pose, or with the
    /// config's `garment_body` the pattern made for that body.
    pub garment: &'a weft_mesh::TriMesh,
    /// With `garment_body`: where the garment starts on this body in its rest pose (the
    /// pattern fitted onto it, [`weft_garment::prepare::fit_onto`]); `None`: it starts as
    /// `garment`.
    pub start_positions: Option<&'a [[f64; 3]]>,
    /// Its material.
    pub material: &'a Material,
    /// The body model.
    pub body: &'a BodyModel,
    /// The body's shape.
    pub betas: &'a [f64],
    /// The motion, already cut to the sequence's frames.
    pub motion: &'a Motion,
    /// Sub-steps per frame.
    pub substeps: usize,
    /// Warm-up frames before the first stored frame.
    pub warmup_frames: usize,
}

/// What a simulator made of one sequence.
pub enum SimOutcome {
    /// Every frame.
    Finished {
        /// Garment positions per frame.
        frames: Vec<Vec<[f32; 3]>>,
        /// Per-frame statistics (a JSON array).
        stats: serde_json::Value,
    },
    /// Diverged at `frame`; `frames` holds the frames before it.
    Diverged {
        /// The frame that failed.
        frame: usize,
        /// What the simulator detected.
        message: String,
        /// The finished frames.
        frames: Vec<Vec<[f32; 3]>>,
        /// Their statistics.
        stats: serde_json::Value,
    },
}

/// Simulates one sequence. [`Physics`] is the real one (weft-sim's implicit-Euler
/// simulator); the trait lets tests exercise planning, resuming and sharding with a
/// cheap deterministic stand-in.
pub trait SequenceSimulator: Sync {
    /// Simulates `input`, calling `on_frame` after each output frame. `Err` is a
    /// refused input (the record becomes [`Status::Failed`]); divergence is an outcome.
    fn simulate(
        &self,
        input: &SimInput<'_>,
        on_frame: &mut dyn FnMut(),
    ) -> Result<SimOutcome, String>;
}

/// weft-sim's ground-truth simulator ([`weft_sim::sequence::simulate_sequence`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Physics;

impl SequenceSimulator for Physics {
    fn simulate(
        &self,
        input: &SimInput<'_>,
        on_frame: &mut dyn FnMut(),
    ) -> Result<SimOutcome, String> {
        use weft_sim::sequence::{simulate_sequence, SequenceError, SequenceOptions};
        let opts = SequenceOptions {
            substeps: input.substeps,
            warmup_frames: input.warmup_frames,
            start_positions: input.start_positions.map(<[[f64; 3]]>::to_vec),
            ..SequenceOptions::default()
        };
        let stats_json = |s: &[weft_sim::sequence::FrameStats]| {
            serde_json::to_value(s).unwrap_or(serde_json::Value::Null)
        };
        match simulate_sequence(
            input.garment,
            input.material,
            input.body,
            input.betas,
            input.motion,
            &opts,
            &mut |p| {
                if let weft_sim::SequenceProgress::Frame(_) = p {
                    on_frame()
                }
            },
        ) {
            Ok(s) => Ok(SimOutcome::Finished {
                stats: stats_json(&s.stats),
                frames: s.frames,
            }),
            Err(SequenceError::Diverged {
                frame,
                message,
                finished,
            }) => Ok(SimOutcome::Diverged {
                frame,
                message,
                stats: stats_json(&finished.stats),
                frames: finished.frames,
            }),
            Err(e) => Err(e.to_string()),
        }
    }
}

/// Progress of a generation run. The CLI draws a bar ([`crate::progress`]); tests
/// ignore it.
pub trait Progress: Sync {
    /// Work is about to start: `total` frames to simulate in `sequences` sequences
    /// (`kept` sequences were already finished).
    fn start(&self, total: u64, sequences: usize, kept: usize);
    /// One frame finished.
    fn frame(&self);
    /// Something to tell the user (a diverged or failed sequence).
    fn message(&self, text: &str);
    /// All work done.
    fn finish(&self);
}

/// A [`Progress`] that shows nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _: u64, _: usize, _: usize) {}
    fn frame(&self) {}
    fn message(&self, _: &str) {}
    fn finish(&self) {}
}

/// Options of [`generate`].
#[derive(Clone, Copy, Debug, Default)]
pub struct GenerateOptions {
    /// Generate only the sequences of this `--shard i/n` job (and write
    /// `manifest.part-i-of-n.json`).
    pub job: Option<Job>,
}

/// What a run did.
#[derive(Clone, Debug, PartialEq)]
pub struct GenerateReport {
    /// The manifest written.
    pub manifest_path: PathBuf,
    /// Sequences of this job.
    pub owned: usize,
    /// Of them, already finished before this run.
    pub kept: usize,
    /// Simulated to the end in this run.
    pub done: usize,
    /// Diverged in this run (`(sequence id, frame)`).
    pub diverged: Vec<(String, usize)>,
    /// Failed in this run (`(sequence id, reason)`).
    pub failed: Vec<(String, String)>,
    /// Sequences the manifest said were finished but whose shard was missing, broken or
    /// changed since it was written, so they were simulated again (`(sequence id,
    /// reason)`).
    pub redone: Vec<(String, String)>,
    /// Kept shards whose SHA-256 was recorded by this run (their manifest predates
    /// digests).
    pub digests_recorded: usize,
    /// Frames simulated in this run.
    pub frames: usize,
    /// Wall time of the simulation stage, s.
    pub seconds: f64,
}

/// Takes `out` for this process until the returned locks drop: a whole run holds it
/// alone (and removes the temporary files an interrupted run left); a `--shard i/n` job
/// shares it with the other jobs and holds its own part alone.
fn lock_output(out: &Path, job: Option<Job>) -> Result<Vec<DirLock>, DataError> {
    const HOLDER: &str = "weft data generate";
    match job {
        None => {
            let lock = DirLock::acquire(out, LOCK_FILE, Access::Exclusive, HOLDER)?;
            remove_stale_temps(out, 1)
                .map_err(|e| DataError::io(out, "cannot remove stale temporary files", e))?;
            Ok(vec![lock])
        }
        Some(j) => {
            let shared = DirLock::acquire(out, LOCK_FILE, Access::Shared, HOLDER)?;
            let own = format!(".{}.lock", j.manifest_file());
            let holder = format!("{HOLDER} --shard {}/{}", j.index, j.count);
            let part = DirLock::acquire(out, &own, Access::Exclusive, &holder)?;
            Ok(vec![shared, part])
        }
    }
}

/// Generates (or resumes) the dataset of `config` in `out`.
pub fn generate(
    config: &DataConfig,
    out: &Path,
    options: &GenerateOptions,
    simulator: &dyn SequenceSimulator,
    progress: &dyn Progress,
) -> Result<GenerateReport, DataError> {
    config.validate()?;
    let model =
        BodyModel::load_or_default(config.body.as_deref()).map_err(|source| DataError::Body {
            what: "model".into(),
            source: Box::new(source),
        })?;
    let mut manifest = plan(config, model.num_betas(), model.source())?;
    manifest.job = options.job;
    let owns = |i: usize| options.job.map_or(true, |j| j.owns(i));
    // The motions before anything is written: a motion file that is missing, malformed
    // or too short is the config's error, refused before hours of simulation.
    let motions = build_motions(&manifest, &owns, config.fps, &model, out)?;
    let _locks = lock_output(out, options.job)?;
    for sub in ["", "garments", "shards", "stats"] {
        let d = out.join(sub);
        std::fs::create_dir_all(&d)
            .map_err(|e| DataError::io(&d, "cannot create the dataset directory", e))?;
    }
    let manifest_path = out.join(
        options
            .job
            .map_or_else(|| MANIFEST_FILE.to_string(), |j| j.manifest_file()),
    );
    let resumed = resume(&mut manifest, &manifest_path, out, &owns)?;
    let kept = resumed.kept;
    for (id, why) in &resumed.redone {
        progress.message(&format!(
            "sequence {id}: the manifest says it is finished but {why}; simulating it again"
        ));
    }
    manifest.write(&manifest_path)?;

    // The body every garment is made for: the zero shape, or the config's
    // `garment_body` (fit data).
    let made_for = match &config.garment_body {
        Some(b) => {
            let mut b = b.clone();
            b.resize(model.num_betas(), 0.0);
            b
        }
        None => vec![0.0; model.num_betas()],
    };
    write_garment_templates(&manifest.garments, &model, &made_for, out)?;

    let pending: Vec<usize> = manifest
        .sequences
        .iter()
        .filter(|s| owns(s.index) && s.status == Status::Pending)
        .map(|s| s.index)
        .collect();
    let owned = manifest.sequences.iter().filter(|s| owns(s.index)).count();

    // File motions learn their length here: fix the frame ranges of their sequences.
    for &i in &pending {
        let key = motion_key(&manifest, &manifest.sequences[i]);
        if let Some(m) = motions.get(&key) {
            let s = &mut manifest.sequences[i];
            s.frame_range[1] = s.frame_range[0] + m.frame_count();
        }
    }
    let body_ids: Vec<&String> = {
        let mut ids: Vec<&String> = pending
            .iter()
            .map(|&i| &manifest.sequences[i].body_id)
            .collect();
        ids.sort();
        ids.dedup();
        ids
    };
    let fits: BTreeMap<String, Result<FitBody, String>> = body_ids
        .par_iter()
        .map(|id| {
            let betas = manifest
                .bodies
                .iter()
                .find(|b| &b.id == *id)
                .map(|b| betas_f64(&b.betas))
                .unwrap_or_default();
            let fit = FitBody::new(&model, &betas).map_err(|e| error_chain(&e));
            ((*id).clone(), fit)
        })
        .collect();

    let fitted = match &config.garment_body {
        Some(_) => fit_patterns(&manifest, &pending, &model, &made_for, &fits, progress)?,
        None => Fitted::default(),
    };

    // Longest first, so the last tasks of the parallel loop are short.
    let mut order = pending.clone();
    order.sort_by_key(|&i| {
        let s = &manifest.sequences[i];
        let g = manifest.garments.iter().find(|g| g.id == s.garment_id);
        let cost = g.map_or(0, |g| g.target_vertices)
            * (s.frame_range[1] - s.frame_range[0] + config.warmup_frames);
        (std::cmp::Reverse(cost), i)
    });
    let total: u64 = order
        .iter()
        .map(|&i| {
            let r = manifest.sequences[i].frame_range;
            (r[1] - r[0]) as u64
        })
        .sum();
    progress.start(total, order.len(), kept);

    let started = Instant::now();
    let shared = Mutex::new((
        manifest,
        GenerateReport {
            manifest_path: manifest_path.clone(),
            owned,
            kept,
            done: 0,
            diverged: Vec::new(),
            failed: Vec::new(),
            redone: resumed.redone,
            digests_recorded: resumed.digests_recorded,
            frames: 0,
            seconds: 0.0,
        },
    ));
    let snapshot: Manifest = lock(&shared).0.clone();
    let results: Vec<Result<(), DataError>> = order
        .par_iter()
        .map(|&i| {
            let record = &snapshot.sequences[i];
            let outcome = run_sequence(
                record, &snapshot, config, &model, &motions, &fits, &fitted, out, simulator,
                progress,
            )?;
            let mut guard = lock(&shared);
            let (manifest, report) = &mut *guard;
            let s = &mut manifest.sequences[i];
            report.frames += outcome.frames;
            *s = outcome.record;
            match s.status {
                Status::Done => report.done += 1,
                Status::Diverged => {
                    let frame = s.diverged_at.unwrap_or(0);
                    progress.message(&format!(
                        "sequence {} diverged at frame {frame}: {} ({} frames kept)",
                        s.id,
                        s.message.as_deref().unwrap_or(""),
                        s.frames
                    ));
                    report.diverged.push((s.id.clone(), frame));
                }
                Status::Failed => {
                    let why = s.message.clone().unwrap_or_default();
                    progress.message(&format!("sequence {} failed: {why}", s.id));
                    report.failed.push((s.id.clone(), why));
                }
                Status::Pending => {}
            }
            manifest.write(&manifest_path)
        })
        .collect();
    progress.finish();
    results
        .into_iter()
        .collect::<Result<Vec<()>, DataError>>()?;
    let (manifest, mut report) = shared
        .into_inner()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    manifest.write(&manifest_path)?;
    report.seconds = started.elapsed().as_secs_f64();
    report.diverged.sort();
    report.failed.sort();
    Ok(report)
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// An error and its sources on one line.
pub(crate) fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

fn betas_f64(b: &[f32]) -> Vec<f64> {
    b.iter().map(|&x| f64::from(x)).collect()
}

/// What [`resume`] took over.
struct Resumed {
    /// Owned sequences kept.
    kept: usize,
    /// Owned sequences the old manifest called finished whose shard or stats file was
    /// missing, broken or changed: `(id, why)`.
    redone: Vec<(String, String)>,
    /// Kept sequences whose SHA-256 was recorded now (the old manifest had none).
    digests_recorded: usize,
}

/// Takes over what an existing manifest at `path` says is finished, after checking the
/// shards against their recorded SHA-256, header and shapes. Refuses a manifest of
/// another plan. Removes temporary files that killed runs left for owned sequences.
fn resume(
    manifest: &mut Manifest,
    path: &Path,
    out: &Path,
    owns: &dyn Fn(usize) -> bool,
) -> Result<Resumed, DataError> {
    for s in manifest.sequences.iter().filter(|s| owns(s.index)) {
        for rel in [&s.shard, &s.stats] {
            remove_temp_files(&out.join(rel))?;
        }
    }
    remove_temp_files(path)?;
    // Garment files are shared by all jobs; another job may be writing one right now, so
    // only a single-job run clears their leftovers.
    if manifest.job.is_none() {
        for g in &manifest.garments {
            remove_temp_files(&out.join(&g.file))?;
        }
    }
    let mut resumed = Resumed {
        kept: 0,
        redone: Vec::new(),
        digests_recorded: 0,
    };
    if !path.exists() {
        return Ok(resumed);
    }
    let old = Manifest::read(path)?;
    let same_plan = old.config == manifest.config
        && old.seed == manifest.seed
        && old.body_model == manifest.body_model
        && old.job == manifest.job
        && old.garments == manifest.garments
        && old.bodies == manifest.bodies
        && old.motions == manifest.motions
        && old.sequences.len() == manifest.sequences.len()
        && old
            .sequences
            .iter()
            .zip(&manifest.sequences)
            .all(|(a, b)| a.id == b.id);
    if !same_plan {
        return Err(DataError::Conflict {
            path: path.to_path_buf(),
            message: "the directory holds a dataset generated from another config, seed, body model or --shard split; use a new directory (or delete this one) to generate this config".into(),
        });
    }
    for (new, mut old) in manifest.sequences.iter_mut().zip(old.sequences) {
        if !owns(new.index) {
            continue;
        }
        let keep = match old.status {
            Status::Done | Status::Diverged if old.frames > 0 => {
                let shard_path = out.join(&old.shard);
                match shard::check(&shard_path, shape_of(&old), old.sha256.as_deref()) {
                    Err(e) => {
                        let why = match &e {
                            DataError::Io { source, .. }
                                if source.kind() == std::io::ErrorKind::NotFound =>
                            {
                                format!("its shard {} is missing", shard_path.display())
                            }
                            DataError::Digest { .. } => error_chain(&e),
                            _ => format!("its shard is unreadable: {}", error_chain(&e)),
                        };
                        resumed.redone.push((old.id.clone(), why));
                        false
                    }
                    Ok(_) if !out.join(&old.stats).is_file() => {
                        let stats = out.join(&old.stats);
                        let why = format!("its statistics {} are missing", stats.display());
                        resumed.redone.push((old.id.clone(), why));
                        false
                    }
                    Ok(digest) => {
                        if old.sha256.is_none() {
                            old.sha256 = Some(digest);
                            resumed.digests_recorded += 1;
                        }
                        true
                    }
                }
            }
            // A sequence that diverged on its first frame has no shard: nothing to check.
            Status::Diverged => true,
            Status::Pending | Status::Done | Status::Failed => false,
        };
        if keep {
            *new = old;
            resumed.kept += 1;
        }
    }
    Ok(resumed)
}

/// Removes `.NAME.*.tmp` files beside `path` (what `write_atomic` leaves when killed).
fn remove_temp_files(path: &Path) -> Result<(), DataError> {
    let (Some(dir), Some(name)) = (path.parent(), path.file_name().and_then(|n| n.to_str())) else {
        return Ok(());
    };
    let prefix = format!(".{name}.");
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(DataError::io(dir, "cannot list the directory", e)),
    };
    for entry in entries.filter_map(Result::ok) {
        let file = entry.file_name();
        let Some(file) = file.to_str() else { continue };
        if file.starts_with(&prefix) && file.ends_with(".tmp") {
            let p = entry.path();
            std::fs::remove_file(&p)
                .map_err(|e| DataError::io(&p, "cannot remove a stale temporary file", e))?;
        }
    }
    Ok(())
}

/// A garment's template on the body `fit`.
fn build_garment(g: &GarmentRecord, fit: &FitBody) -> Result<Garment, DataError> {
    let kind = GarmentKind::parse(&g.kind).map_err(|source| DataError::Garment {
        id: g.id.clone(),
        source: Box::new(source),
    })?;
    let mut style = Style::from_seed(kind, g.seed);
    if let Some(name) = &g.length {
        style.length = crate::config::parse_length(name).ok_or_else(|| {
            DataError::config(
                format!("garment {}.length", g.id),
                format!(
                    "{name:?}; expected one of {}",
                    crate::config::LENGTH_NAMES.join(", ")
                ),
            )
        })?;
    }
    fit.generate(kind, &style, g.target_vertices)
        .map_err(|source| DataError::Garment {
            id: g.id.clone(),
            source: Box::new(source),
        })
}

/// Writes `garments/<id>.obj` (fitted to the body at `betas`: β = 0, or the config's
/// `garment_body`) for garments that have none yet.
fn write_garment_templates(
    garments: &[GarmentRecord],
    model: &BodyModel,
    betas: &[f64],
    out: &Path,
) -> Result<(), DataError> {
    let missing: Vec<&GarmentRecord> = garments
        .iter()
        .filter(|g| !out.join(&g.file).is_file())
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let zero = FitBody::new(model, betas).map_err(|source| DataError::Garment {
        id: "(template body fit)".into(),
        source: Box::new(source),
    })?;
    missing.par_iter().try_for_each(|g| {
        let garment = build_garment(g, &zero)?;
        weft_garment::obj::write_obj(&out.join(&g.file), &garment).map_err(|source| {
            DataError::Garment {
                id: g.id.clone(),
                source: Box::new(source),
            }
        })
    })
}

/// With `garment_body`: each garment's pattern (built once on that body) and, per
/// garment–body pair, the pattern fitted onto that body in its rest pose. A garment or
/// pair that could not be made holds the reason, which fails its sequences.
#[derive(Default)]
struct Fitted {
    patterns: BTreeMap<String, Result<Garment, String>>,
    pairs: BTreeMap<(String, String), FitResult>,
}

/// A garment fitted onto a body (rest-pose positions), or why it could not be.
type FitResult = Result<Vec<[f64; 3]>, String>;

/// Builds the patterns of the garments of `pending` sequences on the body at `made_for`
/// and fits each garment–body pair once ([`weft_garment::prepare::fit_onto`]), in
/// parallel.
fn fit_patterns(
    manifest: &Manifest,
    pending: &[usize],
    model: &BodyModel,
    made_for: &[f64],
    fits: &BTreeMap<String, Result<FitBody, String>>,
    progress: &dyn Progress,
) -> Result<Fitted, DataError> {
    use weft_garment::prepare::{fit_onto, FitOntoOptions};
    let pairs: Vec<(String, String)> = {
        let mut p: Vec<(String, String)> = pending
            .iter()
            .map(|&i| {
                let s = &manifest.sequences[i];
                (s.garment_id.clone(), s.body_id.clone())
            })
            .collect();
        p.sort();
        p.dedup();
        p
    };
    if pairs.is_empty() {
        return Ok(Fitted::default());
    }
    let reference = FitBody::new(model, made_for).map_err(|source| DataError::Garment {
        id: "(garment_body fit)".into(),
        source: Box::new(source),
    })?;
    let mut garment_ids: Vec<&String> = pairs.iter().map(|(g, _)| g).collect();
    garment_ids.dedup();
    let started = Instant::now();
    progress.message(&format!(
        "garment_body: fitting {} garments onto their bodies ({} garment-body pairs)",
        garment_ids.len(),
        pairs.len()
    ));
    let patterns: BTreeMap<String, Result<Garment, String>> = garment_ids
        .par_iter()
        .map(|id| {
            let pattern = match manifest.garments.iter().find(|g| &g.id == *id) {
                Some(g) => build_garment(g, &reference).map_err(|e| error_chain(&e)),
                None => Err(format!("garment {id} is not listed")),
            };
            ((*id).clone(), pattern)
        })
        .collect();
    let fitted: BTreeMap<(String, String), FitResult> = pairs
        .par_iter()
        .map(|(g, b)| {
            let fit = || -> FitResult {
                let pattern = match patterns.get(g) {
                    Some(Ok(p)) => p,
                    Some(Err(e)) => return Err(format!("making garment {g}: {e}")),
                    None => return Err(format!("garment {g} was not made")),
                };
                let body = match fits.get(b) {
                    Some(Ok(f)) => f,
                    Some(Err(e)) => return Err(format!("fitting to body {b}: {e}")),
                    None => return Err(format!("body {b} was not fitted")),
                };
                let material = manifest
                    .garments
                    .iter()
                    .find(|r| &r.id == g)
                    .map(|r| Material::preset(&r.material))
                    .unwrap_or_else(|| Ok(Material::silk()))
                    .map_err(|e| e.to_string())?;
                fit_onto(
                    &pattern.mesh,
                    &reference,
                    body,
                    &material,
                    &FitOntoOptions::default(),
                )
                .map(|(positions, _)| positions)
                .map_err(|e| {
                    format!(
                        "fitting garment {g} (made for garment_body) onto body {b}: {}",
                        error_chain(&e)
                    )
                })
            };
            ((g.clone(), b.clone()), fit())
        })
        .collect();
    let failed = fitted.values().filter(|r| r.is_err()).count();
    progress.message(&format!(
        "garment_body: {} pairs fitted in {:.1} s{}",
        pairs.len() - failed,
        started.elapsed().as_secs_f64(),
        if failed > 0 {
            format!(", {failed} failed (their sequences fail)")
        } else {
            String::new()
        }
    ));
    Ok(Fitted {
        patterns,
        pairs: fitted,
    })
}

/// Which built motion a sequence uses: `(motion id, body id)` for a file motion, read
/// for the sequence's body — its rest joints J(β) place the root, as `weft simulate`,
/// `weft animate` and `weft body pose` read the file for that body, so the dataset's
/// body stands where theirs does — and `(motion id, None)` for a procedural motion, the
/// same for every body.
type MotionKey = (String, Option<String>);

fn motion_key(manifest: &Manifest, s: &SequenceRecord) -> MotionKey {
    match motion_record(manifest, s) {
        Some(record) => key_of(record, s),
        None => (s.motion_id.clone(), None),
    }
}

fn key_of(record: &MotionRecord, s: &SequenceRecord) -> MotionKey {
    let file = matches!(record.origin, MotionOrigin::File { .. });
    (s.motion_id.clone(), file.then(|| s.body_id.clone()))
}

fn motion_record<'m>(manifest: &'m Manifest, s: &SequenceRecord) -> Option<&'m MotionRecord> {
    manifest.motions.iter().find(|m| m.id == s.motion_id)
}

/// The motions of the sequences `owns` picks, each built once (file motions once per
/// body, see [`MotionKey`]) in parallel; the first that fails is the error (`out`: the
/// dataset, for an id the plan lacks).
fn build_motions(
    manifest: &Manifest,
    owns: &dyn Fn(usize) -> bool,
    fps: f64,
    model: &BodyModel,
    out: &Path,
) -> Result<BTreeMap<MotionKey, Motion>, DataError> {
    let mut wanted: BTreeMap<MotionKey, (&MotionRecord, Vec<f64>)> = BTreeMap::new();
    for s in manifest.sequences.iter().filter(|s| owns(s.index)) {
        let record = motion_record(manifest, s).ok_or_else(|| DataError::UnknownId {
            kind: "motion",
            id: s.motion_id.clone(),
            dir: out.to_path_buf(),
        })?;
        wanted
            .entry(key_of(record, s))
            .or_insert_with(|| (record, betas_f64(&s.betas)));
    }
    wanted
        .into_par_iter()
        .map(|(key, (record, betas))| Ok((key, build_motion(record, fps, model, &betas)?)))
        .collect()
}

/// The motion of a record at the dataset's frame rate, cut to its frames; a file is read
/// for the body at shape `betas`.
fn build_motion(
    record: &MotionRecord,
    fps: f64,
    model: &BodyModel,
    betas: &[f64],
) -> Result<Motion, DataError> {
    let err = |source| DataError::Motion {
        id: record.id.clone(),
        source: Box::new(source),
    };
    match &record.origin {
        MotionOrigin::Procedural {
            kind,
            seed,
            speed,
            amplitude,
        } => {
            let kind = MotionKind::parse(kind).ok_or_else(|| {
                DataError::config(format!("motion {}", record.id), format!("kind {kind:?}"))
            })?;
            let params = ProceduralParams {
                kind,
                frames: record.frames.unwrap_or(1),
                fps,
                seed: *seed,
                speed: *speed,
                amplitude: *amplitude,
            };
            procedural_motion(&params).map_err(err)
        }
        MotionOrigin::File { path, start } => {
            let rest = body_rest_joints(model, betas).map_err(err)?;
            let options = MotionFileOptions::for_body(rest, None);
            // The file's own rate (one that records none is an error), then the
            // dataset's.
            let read = load_motion(Path::new(path), &options, None).map_err(err)?;
            let motion = resample(&read.motion, fps).map_err(err)?;
            let available = motion.frame_count();
            let end = record.frames.map_or(available, |f| start + f);
            if *start >= available || end > available {
                return Err(DataError::config(
                    format!("motion {} ({path})", record.id),
                    format!(
                        "frames {start}..{end} requested; the file has {available} frames at {fps} fps"
                    ),
                ));
            }
            Motion::new(
                fps,
                motion.poses()[*start..end].to_vec(),
                motion.trans()[*start..end].to_vec(),
                None,
            )
            .map_err(err)
        }
    }
}

/// One sequence's result: its new record and the frames simulated.
struct SequenceResult {
    record: SequenceRecord,
    frames: usize,
}

#[allow(clippy::too_many_arguments)]
fn run_sequence(
    record: &SequenceRecord,
    manifest: &Manifest,
    config: &DataConfig,
    model: &BodyModel,
    motions: &BTreeMap<MotionKey, Motion>,
    fits: &BTreeMap<String, Result<FitBody, String>>,
    fitted: &Fitted,
    out: &Path,
    simulator: &dyn SequenceSimulator,
    progress: &dyn Progress,
) -> Result<SequenceResult, DataError> {
    let mut r = record.clone();
    let fail = |mut r: SequenceRecord, why: String| {
        r.status = Status::Failed;
        r.message = Some(why);
        r.frames = 0;
        r.sha256 = None;
        Ok(SequenceResult {
            record: r,
            frames: 0,
        })
    };
    let Some(motion) = motions.get(&motion_key(manifest, &r)) else {
        return fail(r, format!("motion {} was not built", record.motion_id));
    };
    let fit = match fits.get(&r.body_id) {
        Some(Ok(f)) => f,
        Some(Err(e)) => return fail(r, format!("fitting to body {}: {e}", record.body_id)),
        None => return fail(r, format!("body {} was not fitted", record.body_id)),
    };
    let Some(g) = manifest.garments.iter().find(|g| g.id == r.garment_id) else {
        return fail(r, format!("garment {} is not listed", record.garment_id));
    };
    // With `garment_body`: the pattern made for that body, started where it sits on
    // this one; else the garment made anew for this body.
    let made;
    let (garment, start) = if config.garment_body.is_some() {
        let pattern = match fitted.patterns.get(&g.id) {
            Some(Ok(p)) => p,
            Some(Err(e)) => return fail(r, format!("making garment {}: {e}", g.id)),
            None => return fail(r, format!("garment {} was not made", g.id)),
        };
        match fitted.pairs.get(&(g.id.clone(), r.body_id.clone())) {
            Some(Ok(start)) => (pattern, Some(start.as_slice())),
            Some(Err(e)) => return fail(r, e.clone()),
            None => {
                let why = format!("garment {} was not fitted onto body {}", g.id, r.body_id);
                return fail(r, why);
            }
        }
    } else {
        made = match build_garment(g, fit) {
            Ok(g) => g,
            Err(e) => return fail(r, error_chain(&e)),
        };
        (&made, None)
    };
    let material = match Material::preset(&r.material) {
        Ok(m) => m,
        Err(e) => return fail(r, e.to_string()),
    };
    let betas = betas_f64(&r.betas);
    let input = SimInput {
        garment: &garment.mesh,
        start_positions: start,
        material: &material,
        body: model,
        betas: &betas,
        motion,
        substeps: config.substeps,
        warmup_frames: config.warmup_frames,
    };
    let outcome = match simulator.simulate(&input, &mut || progress.frame()) {
        Ok(o) => o,
        Err(e) => return fail(r, e),
    };
    let (frames, stats) = match outcome {
        SimOutcome::Finished { frames, stats } => {
            r.status = Status::Done;
            r.diverged_at = None;
            r.message = None;
            (frames, stats)
        }
        SimOutcome::Diverged {
            frame,
            message,
            frames,
            stats,
        } => {
            r.status = Status::Diverged;
            r.diverged_at = Some(frame);
            r.message = Some(message);
            (frames, stats)
        }
    };
    let t = frames.len();
    let wanted = r.frame_range[1] - r.frame_range[0];
    if r.status == Status::Done && t != wanted {
        return fail(
            r,
            format!("the simulator returned {t} frames; expected {wanted}"),
        );
    }
    r.vertices = garment.mesh.vertex_count();
    r.faces = garment.mesh.face_count();
    r.frames = t;
    r.sha256 = None;
    if t > 0 {
        let data = ShardData {
            positions: frames,
            poses: motion.poses()[..t].to_vec(),
            trans: motion.trans()[..t].to_vec(),
            betas: r.betas.clone(),
            // The garment on this body in its rest pose: as made for it, or the pattern
            // fitted onto it (what fit data's α, body association and joint distances
            // are computed from).
            rest_positions: start
                .unwrap_or(&garment.mesh.positions)
                .iter()
                .map(|p| p.map(|c| c as f32))
                .collect(),
            faces: garment.mesh.faces.clone(),
            corner_uvs: garment
                .corner_uvs
                .iter()
                .map(|c| c.map(|uv| uv.map(|x| x as f32)))
                .collect(),
        };
        r.sha256 = Some(shard::write(&out.join(&r.shard), &r.id, &data)?);
    }
    let stats_path = out.join(&r.stats);
    let mut text = serde_json::to_string_pretty(&stats).unwrap_or_else(|_| "null".into());
    text.push('\n');
    weft_mesh::io::write_atomic(&stats_path, |w| w.write_all(text.as_bytes()))
        .map_err(|e| DataError::io(&stats_path, "cannot write the frame statistics", e))?;
    Ok(SequenceResult {
        record: r,
        frames: t,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A simulator that must not be reached.
    struct Unreachable;

    impl SequenceSimulator for Unreachable {
        fn simulate(&self, _: &SimInput<'_>, _: &mut dyn FnMut()) -> Result<SimOutcome, String> {
            Err("the simulator was called for a sequence whose fit failed".into())
        }
    }

    /// With `garment_body`, a garment–body pair whose fit failed (or is missing) makes
    /// its sequence `failed` with the reason, before any simulation and without a
    /// panic; so does a garment whose pattern could not be made.
    #[test]
    fn a_failed_fit_fails_its_sequences_with_the_reason() {
        let model = weft_body::default_body().unwrap();
        let mut config = DataConfig::garfit_tiny();
        for m in [
            &mut config.train.motions,
            &mut config.validation.motions,
            &mut config.test.motions,
        ] {
            for spec in m.iter_mut() {
                spec.frames = Some(2);
            }
        }
        let manifest = plan(&config, model.num_betas(), "b").unwrap();
        let dir = std::env::temp_dir().join(format!("weft-data-fit-fail-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("shards")).unwrap();
        std::fs::create_dir_all(dir.join("stats")).unwrap();
        let record = &manifest.sequences[0];
        let owns = |i: usize| i == 0;
        let motions = build_motions(&manifest, &owns, config.fps, &model, &dir).unwrap();
        let body = manifest
            .bodies
            .iter()
            .find(|b| b.id == record.body_id)
            .unwrap();
        let mut fits = BTreeMap::new();
        fits.insert(
            body.id.clone(),
            FitBody::new(&model, &betas_f64(&body.betas)).map_err(|e| error_chain(&e)),
        );
        let garment = manifest
            .garments
            .iter()
            .find(|g| g.id == record.garment_id)
            .unwrap();
        let reference = FitBody::new(&model, &[0.0]).unwrap();
        let pattern = build_garment(garment, &reference).map_err(|e| error_chain(&e));
        let key = (record.garment_id.clone(), record.body_id.clone());
        let run = |fitted: &Fitted| {
            run_sequence(
                record,
                &manifest,
                &config,
                &model,
                &motions,
                &fits,
                fitted,
                &dir,
                &Unreachable,
                &Silent,
            )
            .unwrap()
            .record
        };
        let mut fitted = Fitted::default();
        fitted
            .patterns
            .insert(garment.id.clone(), pattern.map_err(|e| e.to_string()));
        fitted
            .pairs
            .insert(key.clone(), Err("drape frame 3: diverged".into()));
        let r = run(&fitted);
        assert_eq!(r.status, Status::Failed);
        assert_eq!(r.message.as_deref(), Some("drape frame 3: diverged"));
        assert_eq!((r.frames, r.sha256.as_deref()), (0, None));

        fitted.pairs.clear();
        let r = run(&fitted);
        assert_eq!(r.status, Status::Failed);
        assert!(
            r.message
                .as_deref()
                .unwrap_or("")
                .contains("was not fitted onto body"),
            "{r:?}"
        );

        fitted
            .patterns
            .insert(garment.id.clone(), Err("no measurements".into()));
        fitted.pairs.insert(key, Ok(vec![[0.0; 3]]));
        let r = run(&fitted);
        assert_eq!(r.status, Status::Failed);
        let why = r.message.unwrap_or_default();
        assert!(
            why.contains("making garment") && why.contains("no measurements"),
            "{why}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
