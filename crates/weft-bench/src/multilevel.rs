//! `weft bench multilevel`: the Multilevel model (seed 000) on a skirt of N vertices on
//! weft's default body walking, per stage and per frame, with the embedding GEMM's
//! floor; optionally one training step as `weft train` runs it.
//!
//! `T` frames are inferred together as one disjoint graph of `T` copies (the batch), the
//! pair encoding computed once and reused, as at inference. Stages, each the median of
//! `reps` runs divided by `T`:
//! - `inputs`: the host-side [`FrameInputs`] (pose history, posed body and velocities,
//!   joint transforms);
//! - `t1`: E^t1 and the skinning weights W;
//! - `t2`: E^t2, the motion features;
//! - `mp`: all M^mp submodules, of which `mp_embed` is their embedding GATs (whose GEMM
//!   is the FLOP floor) and the rest pooling, GAT blocks, unpooling and output;
//! - `lbs`: the final skinning.
//!
//! The GEMM floor is `2 · N · F·S · heads·channels · submodules` FLOP per frame; the
//! same GEMM is also timed alone (`gemm_ms_per_frame`, `gemm_gflops`): the rate burn's
//! matmul reaches on this machine bounds what the embedding can.
//!
//! With `device` = wgpu (the `wgpu` feature) the same model and stages run on burn's
//! wgpu device, where every layer takes the generic tensor path. Each timed stage waits
//! for the device (`sync`) before the clock is read; the whole forward pass also reads
//! the vertices back to the host, as an application would. On the GPU the GEMM rate and
//! `memory_gbs` are the device's (a matmul, and a 128 MiB tensor scaled into a new one).
//!
//! E^t2 is a stacked LSTM (528 MB of weights at `paper` widths); a window of `m` steps
//! must read its input-side weights once and its hidden-side weights `m − 1` times (the
//! first step's hidden state is zero), shared by the whole batch, so its floor is the
//! larger of its FLOP at the GEMM rate and those bytes at the memory bandwidth
//! (`memory_gbs`, a timed parallel copy of a 256 MiB buffer): `t2_floor_ms_per_frame`.

use burn::module::Module;
use burn::optim::GradientsParams;
use burn::tensor::{Distribution, Tensor};
use serde::Serialize;
use weft_body::BodyModel;
use weft_models::multilevel::{FrameInputs, GarmentInput, Multilevel, MultilevelConfig};
use weft_models::Clip;
use weft_motion::{generate, Motion, MotionKind, ProceduralParams};
use weft_nn::backend::seeded;
use weft_nn::AdamaxConfig;
use weft_train::tasks::multilevel::{carried_sequence, Term};
use weft_train::{MultilevelTask, MultilevelTraining, TrainTask};

use crate::device::{wait, wait_for};
use crate::timing::{median_ms, try_median_ms};
use crate::{skirt, BenchDevice, BenchError, Row};

/// The first frame of the measured windows: enough history before it for E^t2.
const FIRST_FRAME: usize = 8;

/// What to measure.
#[derive(Clone, Debug)]
pub struct MultilevelBench {
    /// A preset of [`MultilevelConfig::preset`] (`cpu`, `paper`).
    pub preset: String,
    /// Vertices of the skirt (about: the generator rounds to its grid).
    pub vertices: usize,
    /// Frames inferred together (and the training window with `train`).
    pub batch: usize,
    /// Timed runs per figure (after one warm-up).
    pub reps: usize,
    /// Also time one training step.
    pub train: bool,
    /// The device the model runs on.
    pub device: BenchDevice,
}

/// Milliseconds per frame of each inference stage.
#[derive(Clone, Debug, Serialize)]
pub struct Stages {
    /// Host-side frame inputs.
    pub inputs: f64,
    /// E^t1 and the skinning weights.
    pub t1: f64,
    /// E^t2.
    pub t2: f64,
    /// All M^mp submodules.
    pub mp: f64,
    /// The final skinning.
    pub lbs: f64,
}

/// What one configuration cost.
#[derive(Clone, Debug, Serialize)]
pub struct MultilevelFigures {
    /// `"multilevel"`.
    pub bench: &'static str,
    /// The device: `cpu` (flex) or `wgpu`.
    pub device: BenchDevice,
    /// The GPU adapter's name, as its runtime reports it; absent on the CPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adapter: Option<String>,
    /// The preset.
    pub preset: String,
    /// Vertices of the skirt measured.
    pub vertices: usize,
    /// Frames per batch.
    pub batch: usize,
    /// Threads of the pool (the host's, also on a GPU device).
    pub threads: usize,
    /// The whole forward pass (pair encoding excluded), ms per frame.
    pub ms_per_frame: f64,
    /// Per stage, ms per frame.
    pub stages: Stages,
    /// Of `stages.mp`, the embedding GATs, ms per frame.
    pub mp_embed_ms_per_frame: f64,
    /// The embedding GEMM's FLOP per frame, in GFLOP.
    pub gemm_floor_gflop: f64,
    /// The embedding GEMM alone, all submodules, ms per frame.
    pub gemm_ms_per_frame: f64,
    /// Its rate, GFLOP/s.
    pub gemm_gflops: f64,
    /// Parameters of E^t2.
    pub t2_parameters: usize,
    /// E^t2's floor, ms per frame: `max(2 · (P_x · m + P_h · (m − 1)) FLOP at
    /// gemm_gflops, 4 · (P_x + P_h · (m − 1)) / T bytes at memory_gbs)` for `P_x`
    /// input-side and `P_h` hidden-side parameters and `m` history steps.
    pub t2_floor_ms_per_frame: f64,
    /// Memory bandwidth of a large copy (bytes read + written per second), GB/s: host
    /// memory on the CPU, the device's memory on a GPU.
    pub memory_gbs: f64,
    /// The pair encoding (once per garment and body), ms.
    pub pair_encoding_ms: f64,
    /// One training step (forward of the window, vertex, edge and normal terms,
    /// backward, Adamax update), ms per frame; with `train`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub train_ms_per_frame: Option<f64>,
}

impl MultilevelBench {
    fn check(&self) -> Result<MultilevelConfig, BenchError> {
        let cfg = MultilevelConfig::preset(&self.preset).map_err(|e| BenchError::Option {
            what: "--preset",
            message: e.to_string(),
        })?;
        if !(1..=256).contains(&self.batch) {
            return Err(BenchError::Option {
                what: "--batch",
                message: format!("{}; expected 1 to 256 frames", self.batch),
            });
        }
        self.device.check()?;
        if !(100..=200_000).contains(&self.vertices) {
            return Err(BenchError::Option {
                what: "--vertices",
                message: format!("{}; expected 100 to 200000", self.vertices),
            });
        }
        Ok(cfg)
    }

    /// Runs the bench on `body`; `progress` is told of each stage as it starts.
    pub fn run(
        &self,
        body: &BodyModel,
        progress: &mut dyn FnMut(&str),
    ) -> Result<MultilevelFigures, BenchError> {
        let cfg = self.check()?;
        let (t, reps) = (self.batch, self.reps);
        let per = |ms: f64| ms / t as f64;
        progress("garment and motion");
        let garment = skirt(body, self.vertices)?;
        let n = garment.vertex_count();
        let motion = walk(FIRST_FRAME + t)?;
        let clip = Clip {
            betas: &[],
            poses: motion.poses(),
            trans: motion.trans(),
            fps: motion.fps(),
        };
        let range = FIRST_FRAME..FIRST_FRAME + t;
        let device = self.device.inference()?;
        let model = Multilevel::new(&cfg, &seeded(&device, 1)).map_err(model_error)?;
        let g = GarmentInput::new(&garment, body, &[], &cfg).map_err(model_error)?;
        progress("pair encoding");
        let pair_encoding_ms = try_median_ms(reps.min(3), || {
            wait_for(model.encode_pair(&g).map_err(model_error)?.fused)
        })?;
        let pair = model.encode_pair(&g).map_err(model_error)?;

        progress("frame inputs");
        let inputs = try_median_ms(reps, || {
            FrameInputs::new(body, &g, &clip, range.clone(), &cfg).map(drop)
        })
        .map_err(model_error)?;
        let f = FrameInputs::new(body, &g, &clip, range.clone(), &cfg).map_err(model_error)?;
        progress("E^t1 and skinning weights");
        let t1 = try_median_ms(reps, || {
            wait_for(model.skinning_weights(&pair, &g, &f).map_err(model_error)?)
        })?;
        progress("E^t2");
        let t2 = try_median_ms(reps, || {
            wait_for(model.motion_features(&g, &f).map_err(model_error)?)
        })?;
        let motion_features = model.motion_features(&g, &f).map_err(model_error)?;
        let contact = model.contact_features(&g, &f).map_err(model_error)?;
        let batch = g.frame_batch(t).map_err(model_error)?;
        let (mut embed, mut mp) = (0.0, 0.0);
        for (k, sub) in model.mp.iter().enumerate() {
            progress(if k == 0 {
                "M^mp"
            } else {
                "M^mp (next submodule)"
            });
            let run_embed = || {
                sub.embed(
                    pair.fused.clone(),
                    motion_features.clone(),
                    contact.clone(),
                    batch.batch(0),
                )
                .map_err(model_error)
            };
            embed += try_median_ms(reps, || wait_for(run_embed()?))?;
            mp += try_median_ms(reps, || {
                wait_for(sub.process(run_embed()?, &batch).map_err(model_error)?)
            })?;
        }
        progress("skinning");
        let weights = model.skinning_weights(&pair, &g, &f).map_err(model_error)?;
        let blend = Tensor::<3>::zeros([t, n, 3], &model.device());
        let lbs = try_median_ms(reps, || {
            wait_for(
                model
                    .skin(&g, &f, weights.clone(), blend.clone())
                    .map_err(model_error)?,
            )
        })?;
        progress("whole forward pass");
        let total = try_median_ms(reps, || {
            read_back(model.forward(&pair, &g, &f).map_err(model_error)?.vertices)
        })?;

        progress("embedding GEMM alone");
        let floor = 2.0 * (n * cfg.fused_width() * cfg.mp_width() * cfg.mp_submodules) as f64;
        let w = Tensor::<2>::random(
            [cfg.fused_width(), t * cfg.mp_width()],
            Distribution::Default,
            &model.device(),
        );
        let gemm = try_median_ms(reps, || wait_for(pair.fused.clone().matmul(w.clone())))?
            * cfg.mp_submodules as f64;
        let gemm_gflops = floor / (per(gemm) * 1e-3) / 1e9;

        progress("memory bandwidth");
        let memory_gbs = match self.device {
            BenchDevice::Cpu => memory_bandwidth_gbs(reps),
            BenchDevice::Wgpu => device_bandwidth_gbs(&device, reps)?,
        };
        let t2_parameters = model.t2.num_params();
        let (p_x, p_h) = model.t2.parameter_split();
        let m = cfg.history;
        let flop = 2.0 * (p_x * m + p_h * m.saturating_sub(1)) as f64;
        let bytes = 4.0 * (p_x + p_h * m.saturating_sub(1)) as f64 / t as f64;
        let t2_floor_ms_per_frame =
            f64::max(flop / (gemm_gflops * 1e9), bytes / (memory_gbs * 1e9)) * 1e3;

        let train_ms_per_frame = if self.train {
            progress("training step");
            let device = self.device.autodiff()?;
            Some(per(train_step_ms(
                &cfg, body, garment, &motion, t, reps, &device,
            )?))
        } else {
            None
        };
        Ok(MultilevelFigures {
            bench: "multilevel",
            device: self.device,
            adapter: weft_nn::backend::adapter_name(&device),
            preset: self.preset.clone(),
            vertices: n,
            batch: t,
            threads: rayon::current_num_threads(),
            ms_per_frame: per(total),
            stages: Stages {
                inputs: per(inputs),
                t1: per(t1),
                t2: per(t2),
                mp: per(mp),
                lbs: per(lbs),
            },
            mp_embed_ms_per_frame: per(embed),
            gemm_floor_gflop: floor / 1e9,
            gemm_ms_per_frame: per(gemm),
            gemm_gflops,
            t2_parameters,
            t2_floor_ms_per_frame,
            memory_gbs,
            pair_encoding_ms,
            train_ms_per_frame,
        })
    }
}

/// The rate of copying a 256 MiB buffer into another on all threads (as a GEMM streams
/// its weights), counting the bytes read and written, GB/s.
fn memory_bandwidth_gbs(reps: usize) -> f64 {
    const BYTES: usize = 256 << 20;
    let from = vec![1u8; BYTES];
    let mut to = vec![0u8; BYTES];
    let ms = median_ms(reps.min(5), || {
        use rayon::prelude::*;
        to.par_chunks_mut(1 << 20)
            .zip(from.par_chunks(1 << 20))
            .for_each(|(a, b)| a.copy_from_slice(b));
        std::hint::black_box(&mut to);
    });
    2.0 * BYTES as f64 / (ms * 1e-3) / 1e9
}

/// The rate of writing twice a 128 MiB tensor into a new one on `device` (one elementwise
/// kernel reading and writing it, more than a GPU's L2 holds), counting the bytes read and
/// written, GB/s. A last product is read back in part and checked, so that a kernel the
/// device refused (an over-large binding, say) cannot pass for a fast one.
fn device_bandwidth_gbs(device: &burn::tensor::Device, reps: usize) -> Result<f64, BenchError> {
    const FLOATS: usize = 32 << 20;
    let from = Tensor::<1>::random([FLOATS], Distribution::Default, device);
    let ms = try_median_ms(reps.min(5), || wait_for(from.clone() * 2.0))?;
    let tail = FLOATS - 4..FLOATS;
    let read = |t: Tensor<1>| -> Result<Vec<f32>, BenchError> {
        t.slice(tail.clone())
            .try_into_data()
            .map_err(|e| BenchError::Device(format!("{e:?}")))?
            .try_into_vec::<f32>()
            .map_err(|e| BenchError::Device(format!("{e:?}")))
    };
    let (x, y) = (read(from.clone())?, read(from * 2.0)?);
    if x.iter().zip(&y).any(|(x, y)| (2.0 * x - y).abs() > 1e-6) {
        return Err(BenchError::Device(format!(
            "the bandwidth kernel wrote {y:?} for 2 × {x:?}"
        )));
    }
    Ok(2.0 * (4 * FLOATS) as f64 / (ms * 1e-3) / 1e9)
}

/// One training step of `weft train`'s Multilevel task on a window of `t` frames of the
/// garment carried rigidly by the walk (the step's cost does not depend on the targets),
/// supervised terms, Adamax, on `device` (with autodiff), waiting for the device after
/// the update: the median in ms.
fn train_step_ms(
    cfg: &MultilevelConfig,
    body: &BodyModel,
    garment: weft_mesh::TriMesh,
    motion: &Motion,
    t: usize,
    reps: usize,
    device: &burn::tensor::Device,
) -> Result<f64, BenchError> {
    let seq = carried_sequence(
        "bench",
        garment,
        motion.poses().to_vec(),
        motion.trans().to_vec(),
        motion.fps(),
    );
    let training = MultilevelTraining {
        window: t,
        ..MultilevelTraining::default()
    };
    let train_error = BenchError::stage("training step");
    let mut task = MultilevelTask::new(cfg, &training, body.clone(), vec![seq], Vec::new(), device)
        .map_err(train_error)?;
    let mut model = Multilevel::new(cfg, &seeded(device, 0)).map_err(model_error)?;
    let mut optim = AdamaxConfig::new().init();
    let terms = [Term::Vertex, Term::Edge, Term::Normal];
    try_median_ms(reps, || -> Result<(), BenchError> {
        let losses = task
            .losses(&model, 0, &terms)
            .map_err(BenchError::stage("training step"))?;
        if let Some(total) = losses.into_iter().reduce(|a, b| a + b) {
            let grads = GradientsParams::from_grads(total.backward(), &model);
            model = optim.step(1e-4, model.clone(), grads);
        }
        wait(device)
    })
}

impl Row for MultilevelFigures {
    fn cells(&self) -> Vec<(&'static str, String)> {
        let ms = |x: f64| format!("{x:.2}");
        let mut cells = vec![
            ("device", crate::device::label(self.device, &self.adapter)),
            ("preset", self.preset.clone()),
            ("N", self.vertices.to_string()),
            ("T", self.batch.to_string()),
            ("inputs", ms(self.stages.inputs)),
            ("t1", ms(self.stages.t1)),
            ("t2", ms(self.stages.t2)),
            ("(t2 floor)", ms(self.t2_floor_ms_per_frame)),
            ("mp", ms(self.stages.mp)),
            ("(embed)", ms(self.mp_embed_ms_per_frame)),
            ("lbs", ms(self.stages.lbs)),
            ("ms/frame", ms(self.ms_per_frame)),
            ("GEMM floor GFLOP", format!("{:.3}", self.gemm_floor_gflop)),
            ("GEMM ms", ms(self.gemm_ms_per_frame)),
            ("GEMM GFLOP/s", format!("{:.0}", self.gemm_gflops)),
            ("memory GB/s", format!("{:.1}", self.memory_gbs)),
        ];
        if let Some(train) = self.train_ms_per_frame {
            cells.push(("train ms/frame", ms(train)));
        }
        cells
    }
}

/// A procedural walk of `frames` frames at 30 fps.
fn walk(frames: usize) -> Result<Motion, BenchError> {
    let mut params = ProceduralParams::new(MotionKind::Walk);
    params.frames = frames;
    generate(&params).map_err(BenchError::stage("generating the walk"))
}

fn model_error(e: weft_models::ModelError) -> BenchError {
    BenchError::stage("Multilevel")(e)
}

/// Reads a tensor back to the host (which waits for the operations that computed it).
fn read_back<const D: usize>(t: Tensor<D>) -> Result<(), BenchError> {
    t.try_into_data()
        .map(drop)
        .map_err(|e| BenchError::Device(format!("{e:?}")))
}
