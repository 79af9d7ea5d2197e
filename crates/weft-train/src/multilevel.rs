//! Training the Multilevel model (seed 000) on a weft-data dataset: the [`TrainTask`] that
//! turns sequences into windows of frames, evaluates the loss terms of supplement §2 on
//! the model's predictions, and measures the validation error.
//!
//! - Items are windows of `window` consecutive frames of a training sequence (starts
//!   `0, w, 2w, …`, plus one window ending at the last frame when they do not reach it;
//!   a sequence shorter than a window is one shorter window). The order
//!   is shuffled per epoch by the seed ([`crate::sampler`]).
//! - Per garment–body pair, what does not depend on the parameters is computed once
//!   ([`GarmentInput`]: rest graph, hierarchy, features, Nyström eigenvalues, transferred
//!   weights); per window, the frame inputs and the ground-truth targets are cached on
//!   first use. The pair encoding `X^fuse` depends on the encoders' parameters, so it is
//!   recomputed every step while they train (step 1) and cached per pair once they are
//!   frozen (step 2), as inference caches it.
//! - Collision contacts come from the posed body of each frame (weft-sim's `PosedBody`,
//!   the simulator's own body query), at the current prediction.
//! - Validation: mean vertex error (mm) over at most `validation_windows` windows spread
//!   evenly over the validation sequences.

use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

use burn::module::ParamGroup;
use burn::tensor::{Device, Tensor};
use weft_body::{BodyModel, Pose, PosedSequence};
use weft_data::{Dataset, Sequence, Split};
use weft_models::multilevel::{
    FrameInputs, GarmentInput, Multilevel, MultilevelConfig, PairEncoding,
};
use weft_models::run::RunHeader;
use weft_models::Clip;
use weft_models::ModelKind;
use weft_sim::{PosedBody, RestFrames};

use crate::config::TrainConfig;
use crate::error::{Result, TrainError};
use crate::loss::{
    collision_energies, edge_loss, gravity_energy, mean_vertex_error_mm, membrane_energies,
    normal_loss, physics_loss, rest_frames, vertex_loss, FrameEnergies, GarmentTopology,
    PhysicsImpl, Targets, Term, TermWeights,
};
use crate::run::RunDir;
use crate::schedule::Phase;
use crate::trainer::TrainTask;

/// The configuration of a Multilevel run: preset name, model and training tables.
#[derive(Clone, Debug, PartialEq)]
pub struct MultilevelRun {
    /// The preset the run started from (`cpu` or `paper`).
    pub preset: String,
    /// The model (`[model]`).
    pub model: MultilevelConfig,
    /// The training (`[train]`).
    pub train: TrainConfig,
}

impl MultilevelRun {
    /// The preset `name` (model and training sides).
    pub fn preset(name: &str) -> Result<Self> {
        Ok(MultilevelRun {
            preset: name.to_string(),
            model: MultilevelConfig::preset(name)?,
            train: TrainConfig::preset(name)?,
        })
    }

    /// A preset with a config file's `[model]` and `[train]` fields laid over it. The
    /// preset is `preset`, else the file's `preset`, else `cpu`. Unknown fields and
    /// values out of range are errors naming the file and the field.
    pub fn resolve(preset: Option<&str>, file: Option<&Path>) -> Result<Self> {
        let table: Option<toml::Table> = match file {
            Some(path) => {
                let text = std::fs::read_to_string(path).map_err(|e| TrainError::io(path, e))?;
                Some(toml::from_str(&text).map_err(|source| TrainError::Toml {
                    path: path.to_path_buf(),
                    source,
                })?)
            }
            None => None,
        };
        let name = preset
            .map(str::to_string)
            .or_else(|| {
                table
                    .as_ref()
                    .and_then(|t| t.get("preset"))
                    .and_then(toml::Value::as_str)
                    .map(str::to_string)
            })
            .unwrap_or_else(|| "cpu".to_string());
        let mut run = Self::preset(&name)?;
        let Some(table) = table else {
            return Ok(run);
        };
        let path = file.unwrap_or(Path::new("config"));
        let origin = path.display().to_string();
        weft_config::check_keys(
            &table,
            &["format_version", "model_kind", "preset", "model", "train"],
            &origin,
        )?;
        if let Some(v) = table.get("model_kind") {
            if v.as_str() != Some(ModelKind::Multilevel.name()) {
                return Err(TrainError::Mismatch {
                    path: path.to_path_buf(),
                    field: "model_kind".into(),
                    found: v.to_string(),
                    expected: ModelKind::Multilevel.name().into(),
                });
            }
        }
        if let Some(v) = table.get("format_version") {
            if v.as_integer() != Some(crate::run::FORMAT_VERSION) {
                return Err(TrainError::Mismatch {
                    path: path.to_path_buf(),
                    field: "format_version".into(),
                    found: v.to_string(),
                    expected: crate::run::FORMAT_VERSION.to_string(),
                });
            }
        }
        let section = |name: &str| match table.get(name) {
            None => Ok(None),
            Some(toml::Value::Table(t)) => Ok(Some(t)),
            Some(other) => Err(TrainError::Parse {
                path: path.to_path_buf(),
                message: format!(
                    "`{name}` must be a table ([{name}]), found {}",
                    other.type_str()
                ),
            }),
        };
        if let Some(m) = section("model")? {
            run.model = weft_config::overlay(&run.model, m, &origin, "model")?;
            run.model.validate().map_err(|e| TrainError::Parse {
                path: path.to_path_buf(),
                message: format!("[model]: {e}"),
            })?;
        }
        if let Some(t) = section("train")? {
            run.train = weft_config::overlay(&run.train, t, &origin, "train")?;
        }
        run.train.validate()?;
        Ok(run)
    }

    /// The configuration of the run in `dir` (its config.toml).
    pub fn from_run_dir(dir: &Path) -> Result<Self> {
        let path = dir.join("config.toml");
        if !path.exists() {
            return Err(TrainError::RunDir {
                path: dir.to_path_buf(),
                message: "no config.toml: not a training run directory".into(),
            });
        }
        Self::resolve(None, Some(&path))
    }

    /// The run directory `dir` for this configuration.
    pub fn run_dir(&self, dir: &Path) -> Result<RunDir> {
        RunDir::new(
            dir,
            ModelKind::Multilevel,
            &self.preset,
            &self.model,
            &self.train,
        )
    }

    /// The full configuration as config.toml text (every default written out).
    pub fn to_toml(&self) -> Result<String> {
        crate::run::config_text(
            &RunHeader::new(ModelKind::Multilevel, &self.preset),
            &crate::run::to_table("model config", &self.model)?,
            &self.train,
        )
    }
}

/// One garment–body–motion sequence with everything constant precomputed.
struct Pair {
    seq: Sequence,
    input: GarmentInput,
    topology: GarmentTopology,
    frames: RestFrames,
}

/// Windows `[start, start + w)` covering `frames` frames.
fn windows(frames: usize, w: usize) -> Vec<Range<usize>> {
    if frames == 0 {
        return Vec::new();
    }
    if frames <= w {
        return std::iter::once(0..frames).collect();
    }
    let mut out: Vec<Range<usize>> = (0..=frames - w).step_by(w).map(|s| s..s + w).collect();
    // The tail frames go into one last window, overlapping the previous one.
    if out.last().is_some_and(|r| r.end < frames) {
        out.push(frames - w..frames);
    }
    out
}

/// Inputs of one window, built on first use.
struct WindowData {
    frames: FrameInputs,
    targets: Targets,
}

/// The Multilevel model's training task; see the module documentation.
pub struct MultilevelTask {
    cfg: MultilevelConfig,
    weights: TermWeights,
    body: BodyModel,
    device: Device,
    train: Vec<Pair>,
    validation: Vec<Pair>,
    items: Vec<(usize, Range<usize>)>,
    validation_items: Vec<(usize, Range<usize>)>,
    cache: HashMap<usize, Arc<WindowData>>,
    encodings: HashMap<usize, PairEncoding>,
    cache_encodings: bool,
}

impl Pair {
    fn new(seq: Sequence, body: &BodyModel, cfg: &MultilevelConfig) -> Result<Self> {
        let input =
            GarmentInput::new(&seq.garment, body, &seq.record.betas, cfg).map_err(|source| {
                TrainError::Sequence {
                    id: seq.record.id.clone(),
                    source,
                }
            })?;
        let topology = GarmentTopology::new(&seq.garment)?;
        let uvs = (seq.corner_uvs.len() == seq.garment.face_count()).then_some(&seq.corner_uvs[..]);
        let frames = rest_frames(&seq.garment, uvs)?;
        Ok(Pair {
            seq,
            input,
            topology,
            frames,
        })
    }

    /// The sequence's motion on its body shape.
    fn clip(&self) -> Clip<'_> {
        Clip {
            betas: &self.seq.record.betas,
            poses: &self.seq.poses,
            trans: &self.seq.trans,
            fps: self.seq.record.fps,
        }
    }

    fn window_data(
        &self,
        range: Range<usize>,
        body: &BodyModel,
        cfg: &MultilevelConfig,
        device: &Device,
    ) -> Result<WindowData> {
        let s = &self.seq;
        let frames =
            FrameInputs::new(body, &self.clip(), range.clone(), cfg).map_err(|source| {
                TrainError::Sequence {
                    id: s.record.id.clone(),
                    source,
                }
            })?;
        let targets = Targets::new(
            &self.topology,
            &s.garment.faces,
            &s.positions[range],
            device,
        )?;
        Ok(WindowData { frames, targets })
    }

    /// The posed body of each frame of `range`, as collision surfaces.
    fn posed_bodies(&self, range: Range<usize>, body: &BodyModel) -> Result<Vec<PosedBody>> {
        let s = &self.seq;
        let posed = PosedSequence::new(
            body,
            &s.record.betas,
            &s.poses[range.clone()],
            &s.trans[range],
        )?;
        (0..posed.len())
            .map(|t| {
                let frame = posed.frame(t).unwrap_or(&[]);
                let p: Vec<[f64; 3]> = frame.iter().map(|q| q.map(f64::from)).collect();
                PosedBody::new(&p, posed.faces()).map_err(TrainError::from)
            })
            .collect()
    }
}

impl MultilevelTask {
    /// The task over in-memory sequences (`train` must not be empty).
    pub fn new(
        cfg: &MultilevelConfig,
        train_cfg: &TrainConfig,
        body: BodyModel,
        train: Vec<Sequence>,
        validation: Vec<Sequence>,
        device: &Device,
    ) -> Result<Self> {
        let build = |seqs: Vec<Sequence>| -> Result<Vec<Pair>> {
            seqs.into_iter().map(|s| Pair::new(s, &body, cfg)).collect()
        };
        let train = build(train)?;
        let validation = build(validation)?;
        let items: Vec<(usize, Range<usize>)> = train
            .iter()
            .enumerate()
            .flat_map(|(p, pair)| {
                windows(pair.seq.positions.len(), train_cfg.window)
                    .into_iter()
                    .map(move |r| (p, r))
            })
            .collect();
        if items.is_empty() {
            return Err(TrainError::config(
                "data",
                "no training frames",
                "at least one training sequence with frames",
            ));
        }
        let all_val: Vec<(usize, Range<usize>)> = validation
            .iter()
            .enumerate()
            .flat_map(|(p, pair)| {
                windows(pair.seq.positions.len(), train_cfg.window)
                    .into_iter()
                    .map(move |r| (p, r))
            })
            .collect();
        let cap = train_cfg.validation_windows.max(1);
        let validation_items = if all_val.len() <= cap {
            all_val
        } else {
            (0..cap)
                .map(|k| all_val[k * all_val.len() / cap].clone())
                .collect()
        };
        Ok(MultilevelTask {
            cfg: cfg.clone(),
            weights: train_cfg.weights.clone(),
            body,
            device: device.clone(),
            train,
            validation,
            items,
            validation_items,
            cache: HashMap::new(),
            encodings: HashMap::new(),
            cache_encodings: false,
        })
    }

    /// The task over the train and validation splits of the dataset in `dir`.
    pub fn from_dataset(
        dir: &Path,
        cfg: &MultilevelConfig,
        train_cfg: &TrainConfig,
        device: &Device,
    ) -> Result<Self> {
        let dataset = Dataset::open(dir)?;
        let load = |split: Split| -> Result<Vec<Sequence>> {
            dataset
                .records_in(split)
                .into_iter()
                .map(|r| dataset.load(r).map_err(TrainError::from))
                .collect()
        };
        let train = load(Split::Train)?;
        if train.is_empty() {
            return Err(TrainError::RunDir {
                path: dir.to_path_buf(),
                message: "the dataset has no generated training sequences".into(),
            });
        }
        let validation = load(Split::Validation)?;
        let body = dataset.body_model()?;
        Self::new(cfg, train_cfg, body, train, validation, device)
    }

    /// Validation windows measured per validation.
    pub fn validation_window_count(&self) -> usize {
        self.validation_items.len()
    }

    /// Training sequences.
    pub fn sequence_count(&self) -> usize {
        self.train.len()
    }

    fn window(&mut self, item: usize) -> Result<Arc<WindowData>> {
        if let Some(w) = self.cache.get(&item) {
            return Ok(w.clone());
        }
        let (p, range) = self.items[item].clone();
        let w = Arc::new(self.train[p].window_data(range, &self.body, &self.cfg, &self.device)?);
        self.cache.insert(item, w.clone());
        Ok(w)
    }

    fn encoding(&mut self, model: &Multilevel, pair: usize) -> Result<PairEncoding> {
        if self.cache_encodings {
            if let Some(e) = self.encodings.get(&pair) {
                return Ok(e.clone());
            }
        }
        let e = model.encode_pair(&self.train[pair].input)?;
        if self.cache_encodings {
            let detached = PairEncoding {
                fused: e.fused.clone().detach(),
            };
            self.encodings.insert(pair, detached.clone());
            return Ok(detached);
        }
        Ok(e)
    }
}

/// A sequence whose "simulated" frames are the rest garment carried by the root
/// translation (with no simulation behind it): for smoke tests and benchmarks of the
/// training step, where only shapes and cost matter. `poses` and `trans` give the
/// frame count.
pub fn carried_sequence(
    id: &str,
    garment: weft_mesh::TriMesh,
    poses: Vec<Pose>,
    trans: Vec<[f32; 3]>,
    fps: f64,
) -> Sequence {
    let positions: Vec<Vec<[f32; 3]>> = trans
        .iter()
        .map(|tr| {
            garment
                .positions
                .iter()
                .map(|q| std::array::from_fn(|k| q[k] as f32 + tr[k]))
                .collect()
        })
        .collect();
    let frames = positions.len();
    let record = weft_data::SequenceRecord {
        id: id.into(),
        index: 0,
        split: Split::Train,
        shard: String::new(),
        stats: String::new(),
        garment_id: id.into(),
        garment_kind: String::new(),
        vertices: garment.vertex_count(),
        faces: garment.face_count(),
        body_id: "mean".into(),
        betas: Vec::new(),
        motion_id: id.into(),
        frame_range: [0, frames],
        material: String::new(),
        fps,
        frames,
        status: weft_data::Status::Done,
        diverged_at: None,
        message: None,
    };
    Sequence {
        record,
        corner_uvs: Vec::new(),
        garment,
        poses,
        trans,
        positions,
    }
}

/// Positions of a `[T, N, 3]` tensor on the host, f64, frame-major.
fn host_positions(x: &Tensor<3>) -> Result<Vec<[f64; 3]>> {
    let v = x
        .to_data()
        .convert::<f64>()
        .try_into_vec::<f64>()
        .map_err(|source| TrainError::Tensor {
            what: "the prediction",
            source,
        })?;
    Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

impl TrainTask for MultilevelTask {
    type Model = Multilevel;

    fn item_count(&self) -> usize {
        self.items.len()
    }

    fn losses(
        &mut self,
        model: &Multilevel,
        item: usize,
        terms: &[Term],
    ) -> Result<Vec<Tensor<1>>> {
        let w = self.window(item)?;
        let (p, range) = self.items[item].clone();
        let enc = self.encoding(model, p)?;
        let pair = &self.train[p];
        let pred = model.forward(&enc, &pair.input, &w.frames)?;
        let x = pred.vertices;
        let t = range.len();
        let n = pair.topology.vertex_count();
        let needs_window = terms.iter().any(|t| matches!(t, Term::Edge | Term::Normal));
        let index = if needs_window {
            Some(pair.topology.window(t, &self.device)?)
        } else {
            None
        };
        let physics = |e: FrameEnergies| physics_loss(x.clone(), &Arc::new(e), PhysicsImpl::Auto);
        let mut out = Vec::with_capacity(terms.len());
        for &term in terms {
            let l = match (term, &index) {
                (Term::Vertex, _) => vertex_loss(x.clone(), w.targets.positions.clone())?,
                (Term::Edge, Some(i)) => {
                    edge_loss(x.clone(), &pair.topology, i, w.targets.edge_lengths.clone())?
                }
                (Term::Normal, Some(i)) => {
                    normal_loss(x.clone(), &pair.topology, i, w.targets.normals.clone())?
                }
                (Term::Edge | Term::Normal, None) => {
                    unreachable!("window indices are built for edge and normal terms")
                }
                (Term::Collision, _) => {
                    let bodies = pair.posed_bodies(range.clone(), &self.body)?;
                    let host = host_positions(&x)?;
                    physics(collision_energies(&bodies, &host, n, &self.weights)?)?
                }
                (Term::Gravity, _) => {
                    physics(gravity_energy(&pair.seq.garment, t, &self.weights)?)?
                }
                (Term::Stretch, _) => physics(membrane_energies(&pair.frames, t)?.0)?,
                (Term::Shear, _) => physics(membrane_energies(&pair.frames, t)?.1)?,
            };
            out.push(l);
        }
        Ok(out)
    }

    fn validate(&mut self, model: &Multilevel) -> Result<f64> {
        if self.validation_items.is_empty() {
            return Ok(f64::NAN);
        }
        let device = model.device();
        let mut encodings: HashMap<usize, PairEncoding> = HashMap::new();
        let (mut sum, mut count) = (0.0, 0usize);
        for (p, range) in self.validation_items.clone() {
            let pair = &self.validation[p];
            let enc = match encodings.get(&p) {
                Some(e) => e.clone(),
                None => {
                    let e = model.encode_pair(&pair.input)?;
                    encodings.insert(p, e.clone());
                    e
                }
            };
            let s = &pair.seq;
            let frames = FrameInputs::new(&self.body, &pair.clip(), range.clone(), &self.cfg)?;
            let pred = model.forward(&enc, &pair.input, &frames)?;
            let n = pair.topology.vertex_count();
            let host: Vec<Vec<[f32; 3]>> = host_positions(&pred.vertices.to_device(&device))?
                .chunks(n)
                .map(|f| f.iter().map(|q| q.map(|c| c as f32)).collect())
                .collect();
            let e = mean_vertex_error_mm(&host, &s.positions[range.clone()])?;
            sum += e * range.len() as f64;
            count += range.len();
        }
        Ok(sum / count.max(1) as f64)
    }

    fn physics_group(&self, model: &Multilevel) -> ParamGroup {
        // Step 2 trains the second (last) M^mp submodule only.
        match model.mp.last() {
            Some(sub) => ParamGroup::ids_from_module(sub.clone()),
            None => ParamGroup::from_ids(Vec::new()),
        }
    }

    fn on_phase(&mut self, phase: Phase) {
        self.cache_encodings = phase.is_frozen();
        self.encodings.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_configs_resolve_from_presets_and_files() {
        let cpu = MultilevelRun::resolve(None, None).unwrap();
        assert_eq!(cpu, MultilevelRun::preset("cpu").unwrap());
        // What `weft config show` prints reads back to the same configuration.
        let dir = std::env::temp_dir().join(format!("weft-train-cfg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("paper.toml");
        let paper = MultilevelRun::preset("paper").unwrap();
        std::fs::write(&path, paper.to_toml().unwrap()).unwrap();
        assert_eq!(MultilevelRun::resolve(None, Some(&path)).unwrap(), paper);
        // A partial file over a preset.
        std::fs::write(&path, "[train]\nsteps = 9\n[model]\nmp_channels = 4\n").unwrap();
        let r = MultilevelRun::resolve(Some("cpu"), Some(&path)).unwrap();
        assert_eq!((r.train.steps, r.model.mp_channels), (9, 4));
        assert_eq!(r.model.gg_widths, MultilevelConfig::cpu().gg_widths);
        // Unknown or out-of-range fields are named.
        std::fs::write(&path, "[train]\nstepz = 9\n").unwrap();
        let e = MultilevelRun::resolve(None, Some(&path))
            .unwrap_err()
            .to_string();
        assert!(e.contains("stepz"), "{e}");
        // The typo the platform issue found silently dropped: refused, dotted and with
        // the file, though MultilevelConfig (burn's Config derive) does not deny unknown
        // fields itself.
        std::fs::write(&path, "[model]\nmp_chanels = 4\n").unwrap();
        let e = MultilevelRun::resolve(None, Some(&path))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("model.mp_chanels") && e.contains("paper.toml"),
            "{e}"
        );
        // Switching the optimiser replaces its table: Adamax's fields do not leak in.
        std::fs::write(&path, "[train.optimizer]\nkind = \"adam\"\n").unwrap();
        let r = MultilevelRun::resolve(None, Some(&path)).unwrap();
        assert!(
            matches!(r.train.optimizer, crate::optim::OptimizerConfig::Adam(_)),
            "{:?}",
            r.train.optimizer
        );
        std::fs::write(&path, "[train]\nwindow = 0\n").unwrap();
        let e = MultilevelRun::resolve(None, Some(&path))
            .unwrap_err()
            .to_string();
        assert!(e.contains("train.window"), "{e}");
        std::fs::write(&path, "format_version = 7\n").unwrap();
        let e = MultilevelRun::resolve(None, Some(&path))
            .unwrap_err()
            .to_string();
        assert!(e.contains("format_version"), "{e}");
        assert!(MultilevelRun::resolve(Some("huge"), None).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn windows_tile_the_sequence() {
        assert_eq!(windows(20, 8), vec![0..8, 8..16, 12..20]);
        assert_eq!(windows(16, 8), vec![0..8, 8..16]);
        assert_eq!(windows(5, 8), std::iter::once(0..5).collect::<Vec<_>>());
        assert!(windows(0, 8).is_empty());
    }
}
