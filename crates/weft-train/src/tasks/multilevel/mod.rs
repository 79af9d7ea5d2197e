//! Training the Multilevel model (seed 000) on a weft-data dataset: the [`TrainTask`] that
//! turns sequences into windows of frames, evaluates the loss terms of supplement §2 on
//! the model's predictions ([`terms`]), moves through the two-step schedule
//! ([`schedule`]) and measures the validation error. [`config`] holds the run's
//! configuration.
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
//!   the simulator's own body query, one surface moved through each window), at the
//!   current prediction.
//! - Validation: mean vertex error (`e_verts_mm`) over at most `validation_windows`
//!   windows spread evenly over the validation sequences.

pub mod config;
pub mod schedule;
pub mod terms;

use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

use burn::module::{Module, ParamGroup};
use burn::tensor::{Device, Tensor};
use weft_body::{BodyModel, Pose, PosedSequence};
use weft_data::{Dataset, Sequence, Split};
use weft_models::multilevel::{
    FrameInputs, GarmentInput, Multilevel, MultilevelConfig, PairEncoding,
};
use weft_models::Clip;
use weft_sim::{PosedBody, RestFrames};

pub use config::{MultilevelRun, MultilevelTraining};
pub use schedule::{Phase, ScheduleConfig, ScheduleState};
pub use terms::{Term, TermWeights};

use crate::error::{Result, TrainError};
use crate::loss::{
    check_window_positions, collision_energy, edge_loss, gravity_energy, mean_vertex_error_mm,
    membrane_energies, normal_loss, physics_loss, rest_frames, vertex_loss, FrameEnergies,
    GarmentTopology, PhysicsImpl, Targets,
};
use crate::task::{Metrics, StepEnd, TrainTask};

/// The name of Multilevel's validation metric: mean vertex error on the validation
/// windows, mm.
pub const E_VERTS_MM: &str = "e_verts_mm";

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
    training: MultilevelTraining,
    body: BodyModel,
    device: Device,
    train: Vec<Pair>,
    validation: Vec<Pair>,
    items: Vec<(usize, Range<usize>)>,
    validation_items: Vec<(usize, Range<usize>)>,
    cache: HashMap<usize, Arc<WindowData>>,
    encodings: HashMap<usize, PairEncoding>,
    cache_encodings: bool,
    /// The collision term's body surface ([`Pair::collision`]).
    surface: Option<PosedBody>,
    /// The collision threshold ε of the current phase, m.
    collision_eps: f64,
}

/// Garment inputs already built, by garment and body shape: a dataset puts each
/// garment–body pair on several motions, and a pair's inputs (a drape, the Nyström
/// spectrum, the hierarchy) do not depend on the motion.
type InputCache = HashMap<(String, Vec<u32>), GarmentInput>;

impl Pair {
    fn new(
        seq: Sequence,
        body: &BodyModel,
        cfg: &MultilevelConfig,
        inputs: &mut InputCache,
    ) -> Result<Self> {
        let key = (
            seq.record.garment_id.clone(),
            seq.record.betas.iter().map(|b| b.to_bits()).collect(),
        );
        let input = match inputs.get(&key) {
            Some(input) if input.vertex_count() == seq.garment.vertex_count() => input.clone(),
            _ => {
                let input = GarmentInput::new(&seq.garment, body, &seq.record.betas, cfg).map_err(
                    |source| TrainError::Sequence {
                        id: seq.record.id.clone(),
                        source,
                    },
                )?;
                inputs.insert(key, input.clone());
                input
            }
        };
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
        let frames = FrameInputs::new(body, &self.input, &self.clip(), range.clone(), cfg)
            .map_err(|source| TrainError::Sequence {
                id: s.record.id.clone(),
                source,
            })?;
        let targets = Targets::new(
            &self.topology,
            &s.garment.faces,
            &s.positions[range],
            device,
        )?;
        Ok(WindowData { frames, targets })
    }

    /// Eq. 4's energies for the window `range` at the prediction `x` (`T·N`,
    /// frame-major), threshold `eps`, contacts within `radius`. `surface` follows the
    /// posed body through the window: rebuilt on its first frame (or built, on the run's
    /// first collision term), refit on the next ones (a small motion between frames),
    /// and each frame's contacts are found against it before it moves on. One surface
    /// for the whole run keeps the numbering of its pseudo-normals' edges (a sort of
    /// every half-edge) out of the step, and no frame needs a copy of it: with a surface
    /// built and copied per window frame, the term took 28 ms of a 150 ms `cpu` step on
    /// the tiny dataset; with one moved surface, 20 ms (bit-identical losses).
    fn collision(
        &self,
        range: Range<usize>,
        body: &BodyModel,
        surface: &mut Option<PosedBody>,
        x: &[[f64; 3]],
        eps: f64,
        radius: f64,
    ) -> Result<FrameEnergies> {
        let s = &self.seq;
        let posed = PosedSequence::new(
            body,
            &s.record.betas,
            &s.poses[range.clone()],
            &s.trans[range],
        )?;
        let n = self.topology.vertex_count();
        check_window_positions(x, posed.len(), n)?;
        let mut frames = Vec::with_capacity(posed.len());
        for (t, (frame, xt)) in posed.frames().zip(x.chunks_exact(n.max(1))).enumerate() {
            let p: Vec<[f64; 3]> = frame.iter().map(|q| q.map(f64::from)).collect();
            let b = match surface.as_mut() {
                Some(b) if t == 0 => {
                    b.rebuild(&p)?;
                    b
                }
                Some(b) => {
                    b.refit(&p)?;
                    b.settle();
                    b
                }
                None => surface.insert(PosedBody::new(&p, posed.faces())?),
            };
            frames.push(collision_energy(b, xt, eps, radius)?);
        }
        FrameEnergies::per_frame(frames)
    }
}

impl MultilevelTask {
    /// The task over in-memory sequences (`train` must not be empty).
    pub fn new(
        cfg: &MultilevelConfig,
        training: &MultilevelTraining,
        body: BodyModel,
        train: Vec<Sequence>,
        validation: Vec<Sequence>,
        device: &Device,
    ) -> Result<Self> {
        let mut inputs = InputCache::new();
        let mut build = |seqs: Vec<Sequence>| -> Result<Vec<Pair>> {
            seqs.into_iter()
                .map(|s| Pair::new(s, &body, cfg, &mut inputs))
                .collect()
        };
        let train = build(train)?;
        let validation = build(validation)?;
        // Every window of every pair, as (pair, frames).
        let windows_of = |pairs: &[Pair]| -> Vec<(usize, Range<usize>)> {
            pairs
                .iter()
                .enumerate()
                .flat_map(|(p, pair)| {
                    windows(pair.seq.positions.len(), training.window)
                        .into_iter()
                        .map(move |r| (p, r))
                })
                .collect()
        };
        let items = windows_of(&train);
        if items.is_empty() {
            return Err(TrainError::config(
                "data",
                "no training frames",
                "at least one training sequence with frames",
            ));
        }
        let all_val = windows_of(&validation);
        let cap = training.validation_windows.max(1);
        let validation_items = if all_val.len() <= cap {
            all_val
        } else {
            (0..cap)
                .map(|k| all_val[k * all_val.len() / cap].clone())
                .collect()
        };
        Ok(MultilevelTask {
            cfg: cfg.clone(),
            training: training.clone(),
            body,
            device: device.clone(),
            train,
            validation,
            items,
            validation_items,
            cache: HashMap::new(),
            encodings: HashMap::new(),
            cache_encodings: false,
            surface: None,
            collision_eps: training.weights.collision_eps,
        })
    }

    /// The task over the train and validation splits of the dataset in `dir`.
    pub fn from_dataset(
        dir: &Path,
        cfg: &MultilevelConfig,
        training: &MultilevelTraining,
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
        Self::new(cfg, training, body, train, validation, device)
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
        sha256: None,
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
    type Term = Term;
    type Stage = ScheduleState;

    fn item_count(&self) -> usize {
        self.items.len()
    }

    fn terms(&self, stage: &ScheduleState) -> Vec<(Term, f64)> {
        stage
            .phase
            .weighted_terms(&self.training.weights, &self.training.schedule)
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
                    let host = host_positions(&x)?;
                    let e = pair.collision(
                        range.clone(),
                        &self.body,
                        &mut self.surface,
                        &host,
                        self.collision_eps,
                        self.training.weights.collision_radius,
                    )?;
                    physics(e)?
                }
                (Term::Gravity, _) => physics(gravity_energy(
                    &pair.seq.garment,
                    t,
                    self.training.weights.density,
                )?)?,
                (Term::Stretch, _) => physics(membrane_energies(&pair.frames, t)?.0)?,
                (Term::Shear, _) => physics(membrane_energies(&pair.frames, t)?.1)?,
            };
            out.push(l);
        }
        Ok(out)
    }

    fn validate(&mut self, model: &Multilevel) -> Result<Metrics> {
        let mm = self.vertex_error_mm(model)?;
        Ok(Metrics::from([(E_VERTS_MM.to_string(), mm)]))
    }

    fn primary_metric(&self) -> &'static str {
        E_VERTS_MM
    }

    fn stage_name(&self, stage: &ScheduleState) -> String {
        stage.phase.name().to_string()
    }

    fn advance(&self, stage: &mut ScheduleState, end: &StepEnd<'_, Term>) -> bool {
        stage.advance(&self.training.schedule, end)
    }

    fn enter_stage(&mut self, model: Multilevel, stage: &ScheduleState) -> Multilevel {
        self.collision_eps = stage
            .phase
            .collision_eps(&self.training.weights, &self.training.schedule);
        // Step 2 trains the second (last) M^mp submodule only; the pair encoding is then
        // constant and cached.
        let frozen = stage.phase.is_frozen();
        self.cache_encodings = frozen;
        self.encodings.clear();
        if !frozen {
            return model;
        }
        let group = Self::physics_group(&model);
        model.no_grad().set_require_grad_group(group, true)
    }
}

impl MultilevelTask {
    /// The parameters step 2 trains: the second (last) M^mp submodule.
    pub fn physics_group(model: &Multilevel) -> ParamGroup {
        match model.mp.last() {
            Some(sub) => ParamGroup::ids_from_module(sub.clone()),
            None => ParamGroup::from_ids(Vec::new()),
        }
    }

    /// Mean vertex error over the validation windows, mm (NaN without any).
    fn vertex_error_mm(&mut self, model: &Multilevel) -> Result<f64> {
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
            let frames = FrameInputs::new(
                &self.body,
                &pair.input,
                &pair.clip(),
                range.clone(),
                &self.cfg,
            )?;
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_tile_the_sequence() {
        assert_eq!(windows(20, 8), vec![0..8, 8..16, 12..20]);
        assert_eq!(windows(16, 8), vec![0..8, 8..16]);
        assert_eq!(windows(5, 8), std::iter::once(0..5).collect::<Vec<_>>());
        assert!(windows(0, 8).is_empty());
    }
}
