//! `weft eval`: a trained run against the simulated ground truth of a dataset split,
//! next to the LBS-only baseline, with inference speed and a report.
//!
//! Every sequence of the split is animated by the model (through the same
//! [`Predictor::animate`] users call, so what is measured is what ships) and by the
//! baseline; both are scored frame by frame into per-garment-kind accumulators
//! ([`FrameMetrics`]). Speed is timed separately on the first sequence with the pair
//! encoding computed once, as seed 000 reports it: windows of 1 and 16 frames per forward
//! pass, network alone and with the per-frame inputs.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use weft_body::BodyModel;
use weft_data::{Dataset, Sequence, Split};
use weft_mesh::TriMesh;
use weft_models::multilevel::{FrameInputs, GarmentInput, Predictor};
use weft_render::{Colormap, Report};

use crate::baseline::{LbsBaseline, PosedBodies};
use crate::error::EvalError;
use crate::metrics::{vertex_errors_mm, FrameMetrics, GarmentTopology};
use crate::pictures::{comparison_sheet, heat_map, per_frame_plot, MethodFrames, ERROR_LABEL};
use crate::report::{
    pooling_label, write_text, EvalReport, FpsResult, MethodResult, LBS_NAME, REPORT_VERSION,
};

/// What to evaluate and how much.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// The split (test for reported numbers).
    pub split: Split,
    /// Evaluate at most this many sequences (all when `None`).
    pub max_sequences: Option<usize>,
    /// Check garment–body collisions (one signed-distance query per vertex and frame).
    pub collisions: bool,
    /// Frames per forward pass to time (seed 000: 1 and 16); empty skips timing.
    pub fps_batches: Vec<usize>,
    /// Frames timed per batch size (at least one window).
    pub fps_frames: usize,
    /// The command line that reproduces the evaluation, for the report.
    pub command: String,
}

impl Default for EvalOptions {
    /// The test split, every sequence, collisions on, batches 1 and 16 over 32 frames.
    fn default() -> Self {
        EvalOptions {
            split: Split::Test,
            max_sequences: None,
            collisions: true,
            fps_batches: vec![1, 16],
            fps_frames: 32,
            command: String::new(),
        }
    }
}

/// The frames of one sequence kept for the report's pictures.
pub struct Example {
    /// Sequence id.
    pub id: String,
    /// Garment kind.
    pub kind: String,
    /// Faces of the garment.
    pub faces: Vec<[u32; 3]>,
    /// Simulated frames.
    pub truth: Vec<Vec<[f32; 3]>>,
    /// The model's frames.
    pub model: Vec<Vec<[f32; 3]>>,
    /// The baseline's frames.
    pub lbs: Vec<Vec<[f32; 3]>>,
    /// The posed body per frame.
    pub bodies: Vec<TriMesh>,
}

/// An evaluation: the figures and one sequence to draw.
pub struct Evaluation {
    /// The figures (`eval.json`).
    pub report: EvalReport,
    /// The first evaluated sequence, for pictures.
    pub example: Option<Example>,
}

/// Per-method accumulators by garment kind.
#[derive(Default)]
struct ByKind(BTreeMap<String, FrameMetrics>);

impl ByKind {
    fn get(&mut self, kind: &str) -> &mut FrameMetrics {
        self.0.entry(kind.to_owned()).or_default()
    }

    fn result(&self, name: &str) -> MethodResult {
        let mut overall = FrameMetrics::new();
        for m in self.0.values() {
            overall.merge(m);
        }
        MethodResult {
            name: name.to_owned(),
            overall: overall.summary(),
            per_kind: self
                .0
                .iter()
                .map(|(k, m)| (k.clone(), m.summary()))
                .collect(),
        }
    }
}

fn model_err(e: weft_models::ModelError) -> EvalError {
    EvalError::Network(e.to_string())
}

fn data_err(e: weft_data::DataError) -> EvalError {
    EvalError::Invalid(format!("dataset: {e}"))
}

/// Evaluates `predictor` (the run at `run_dir`) on `opts.split` of `dataset`, reporting
/// progress through `progress` (one line per sequence).
pub fn evaluate(
    predictor: &Predictor,
    run_dir: &Path,
    dataset: &Dataset,
    opts: &EvalOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Evaluation, EvalError> {
    let body = dataset.body_model().map_err(data_err)?;
    let mut records = dataset.records_in(opts.split);
    if records.is_empty() {
        return Err(EvalError::Invalid(format!(
            "{} has no loadable sequence in the {} split",
            dataset.dir().display(),
            opts.split
        )));
    }
    if let Some(k) = opts.max_sequences {
        records.truncate(k.max(1));
    }
    let total = records.len();
    let mut ev = Evaluator::new(predictor, &body, opts);
    for (k, record) in records.iter().enumerate() {
        let started = Instant::now();
        let seq = dataset.load(record).map_err(data_err)?;
        let (id, kind, vertices, frames) = (
            seq.record.id.clone(),
            seq.record.garment_kind.clone(),
            seq.record.vertices,
            seq.positions.len(),
        );
        let (m, l) = ev.add(seq)?;
        progress(&format!(
            "[{}/{total}] {id} ({kind}, {vertices} vertices, {frames} frames): E_verts {m:.2} mm, LBS {l:.2} mm ({:.1} s)",
            k + 1,
            started.elapsed().as_secs_f64()
        ));
    }
    Ok(ev.finish(
        &run_dir.display().to_string(),
        &dataset.dir().display().to_string(),
    ))
}

/// Scores sequences one at a time (the loop of [`evaluate`], usable on sequences built in
/// memory).
pub struct Evaluator<'a> {
    predictor: &'a Predictor,
    body: &'a BodyModel,
    opts: &'a EvalOptions,
    model: ByKind,
    lbs: ByKind,
    example: Option<Example>,
    frames: u64,
    sequences: usize,
    fps: Vec<FpsResult>,
}

impl<'a> Evaluator<'a> {
    /// Nothing scored yet.
    pub fn new(predictor: &'a Predictor, body: &'a BodyModel, opts: &'a EvalOptions) -> Self {
        Evaluator {
            predictor,
            body,
            opts,
            model: ByKind::default(),
            lbs: ByKind::default(),
            example: None,
            frames: 0,
            sequences: 0,
            fps: Vec::new(),
        }
    }

    /// Animates `seq` with the model and the baseline and scores both against its
    /// simulated frames; times inference on the first sequence. Returns the mean vertex
    /// errors (mm) of the model and of the baseline on this sequence.
    pub fn add(&mut self, mut seq: Sequence) -> Result<(f64, f64), EvalError> {
        let body = self.body;
        if seq.positions.is_empty() || seq.positions.len() > seq.poses.len() {
            return Err(EvalError::Count {
                what: "simulated frames vs motion frames",
                expected: seq.poses.len(),
                found: seq.positions.len(),
            });
        }
        // A diverged sequence keeps the frames before the divergence: score those (the
        // model never looks ahead, so the cut motion gives the same predictions).
        seq.poses.truncate(seq.positions.len());
        seq.trans.truncate(seq.positions.len());
        let betas = &seq.record.betas;
        let predicted = self
            .predictor
            .animate(
                &seq.garment,
                body,
                betas,
                &seq.poses,
                &seq.trans,
                seq.record.fps,
            )
            .map_err(model_err)?;
        let lbs =
            LbsBaseline::new(&seq.garment, body, betas)?.animate(body, &seq.poses, &seq.trans)?;
        let bodies = if self.opts.collisions || self.example.is_none() {
            Some(PosedBodies::new(body, betas, &seq.poses, &seq.trans)?)
        } else {
            None
        };
        let topology = GarmentTopology::new(&seq.garment)?;
        let kind = seq.record.garment_kind.clone();
        for (t, truth) in seq.positions.iter().enumerate() {
            let surface = match (&bodies, self.opts.collisions) {
                (Some(b), true) => Some(b.surface(t)?),
                _ => None,
            };
            self.model
                .get(&kind)
                .push_frame(&topology, &predicted[t], truth, surface.as_ref())?;
            self.lbs
                .get(&kind)
                .push_frame(&topology, &lbs[t], truth, surface.as_ref())?;
            self.frames += 1;
        }
        if self.sequences == 0 && !self.opts.fps_batches.is_empty() {
            self.fps = time_inference(
                self.predictor,
                body,
                &seq,
                &self.opts.fps_batches,
                self.opts.fps_frames,
            )?;
        }
        self.sequences += 1;
        let means = (
            vertex_mean(&predicted, &seq.positions)?,
            vertex_mean(&lbs, &seq.positions)?,
        );
        if self.example.is_none() {
            if let Some(bodies) = bodies {
                self.example = Some(Example {
                    id: seq.record.id.clone(),
                    kind,
                    faces: seq.garment.faces.clone(),
                    bodies: (0..bodies.len()).filter_map(|t| bodies.mesh(t)).collect(),
                    truth: seq.positions,
                    model: predicted,
                    lbs,
                });
            }
        }
        Ok(means)
    }

    /// The report of everything added; `run` and `data` name the run and dataset.
    pub fn finish(self, run: &str, data: &str) -> Evaluation {
        let cfg = self.predictor.config();
        let model_name = pooling_label(cfg.pooling.name());
        let report = EvalReport {
            version: REPORT_VERSION,
            run: run.to_owned(),
            data: data.to_owned(),
            split: self.opts.split.name().to_owned(),
            preset: cfg.preset.clone(),
            pooling: cfg.pooling.name().to_owned(),
            checkpoint: self.predictor.checkpoint().display().to_string(),
            sequences: self.sequences,
            frames: self.frames,
            methods: vec![self.model.result(&model_name), self.lbs.result(LBS_NAME)],
            fps: self.fps,
            command: self.opts.command.clone(),
        };
        Evaluation {
            report,
            example: self.example,
        }
    }
}

/// Mean vertex error (mm) over all frames of a sequence, for progress lines and plots.
fn vertex_mean(pred: &[Vec<[f32; 3]>], truth: &[Vec<[f32; 3]>]) -> Result<f64, EvalError> {
    let per = per_frame_means(pred, truth)?;
    Ok(per.iter().sum::<f64>() / per.len().max(1) as f64)
}

/// Mean vertex error (mm) of each frame.
pub fn per_frame_means(
    pred: &[Vec<[f32; 3]>],
    truth: &[Vec<[f32; 3]>],
) -> Result<Vec<f64>, EvalError> {
    if pred.len() != truth.len() {
        return Err(EvalError::Count {
            what: "predicted frames vs ground-truth frames",
            expected: truth.len(),
            found: pred.len(),
        });
    }
    pred.iter()
        .zip(truth)
        .map(|(p, t)| {
            let e = vertex_errors_mm(p, t)?;
            Ok(e.iter().sum::<f64>() / e.len().max(1) as f64)
        })
        .collect()
}

/// Frames per second of `predictor` on `seq`'s garment and motion, per batch size: the
/// pair encoded once, then windows of `batch` frames.
pub fn time_inference(
    predictor: &Predictor,
    body: &BodyModel,
    seq: &Sequence,
    batches: &[usize],
    frames: usize,
) -> Result<Vec<FpsResult>, EvalError> {
    let cfg = predictor.config();
    let model = predictor.model();
    let betas = &seq.record.betas;
    let g = GarmentInput::new(&seq.garment, body, betas, cfg).map_err(model_err)?;
    let pair = model.encode_pair(&g).map_err(model_err)?;
    let total = seq.poses.len();
    let mut out = Vec::new();
    for &batch in batches {
        let batch = batch.clamp(1, total);
        let windows: Vec<std::ops::Range<usize>> = (0..frames.max(batch))
            .step_by(batch)
            .map(|a| {
                let a = a % total;
                a..(a + batch).min(total)
            })
            .collect();
        // One untimed window: first-use allocations and the cached frame batch.
        let warm = FrameInputs::new(
            body,
            betas,
            &seq.poses,
            &seq.trans,
            seq.record.fps,
            windows[0].clone(),
            cfg,
        )
        .map_err(model_err)?;
        model.forward(&pair, &g, &warm).map_err(model_err)?;
        let (mut inputs_s, mut network_s, mut timed) = (0.0, 0.0, 0usize);
        for w in windows {
            let t0 = Instant::now();
            let f = FrameInputs::new(
                body,
                betas,
                &seq.poses,
                &seq.trans,
                seq.record.fps,
                w.clone(),
                cfg,
            )
            .map_err(model_err)?;
            let t1 = Instant::now();
            let p = model.forward(&pair, &g, &f).map_err(model_err)?;
            // Reading the result back is part of inference (it synchronises the device).
            let _ = p.vertices.into_data();
            network_s += t1.elapsed().as_secs_f64();
            inputs_s += (t1 - t0).as_secs_f64();
            timed += w.len();
        }
        out.push(FpsResult {
            batch,
            vertices: g.vertex_count(),
            network_fps: timed as f64 / network_s.max(1e-12),
            end_to_end_fps: timed as f64 / (network_s + inputs_s).max(1e-12),
            frames: timed,
        });
    }
    Ok(out)
}

/// Frames to draw: start, middle and end of the sequence (fewer for short ones).
fn picture_frames(count: usize) -> Vec<usize> {
    let mut f = vec![0, count / 2, count.saturating_sub(1)];
    f.dedup();
    f
}

/// The error table and, when timed, the speed table of `r` as HTML sections (the
/// evaluation report and the demo report show the same two).
pub(crate) fn error_and_speed_tables(r: &EvalReport, html: &mut Report) {
    html.heading("Errors against the simulated ground truth");
    let (h, rows) = r.table();
    html.table(h, rows);
    if !r.fps.is_empty() {
        html.heading("Inference speed (pair encoding cached)");
        let (h, rows) = r.fps_table();
        html.table(h, rows);
    }
}

/// Writes `dir/eval.json`, `dir/eval.md`, `dir/eval.html` and the pictures as PNG files
/// (`comparison.png`, `error_map.png`, `per_frame.png`); returns the HTML path.
pub fn write_report(eval: &Evaluation, dir: &Path) -> Result<std::path::PathBuf, EvalError> {
    std::fs::create_dir_all(dir).map_err(|source| EvalError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let r = &eval.report;
    r.write_json(&dir.join("eval.json"))?;
    write_text(&dir.join("eval.md"), &r.to_markdown())?;
    let mut html = Report::new(format!("weft evaluation: {}", r.run));
    html.paragraph(format!(
        "Split {} of {}: {} sequences, {} frames. Model: preset {}, pooling {}, checkpoint {}.",
        r.split, r.data, r.sequences, r.frames, r.preset, r.pooling, r.checkpoint
    ));
    if let Some(x) = r.reduction_vs_lbs() {
        html.paragraph(format!(
            "The model's mean vertex error is {:.1} % {} the LBS-only baseline's.",
            100.0 * x.abs(),
            if x >= 0.0 { "below" } else { "above" }
        ));
    }
    error_and_speed_tables(r, &mut html);
    if let Some(ex) = &eval.example {
        let model_name = r.model().map_or("model", |m| m.name.as_str());
        html.heading(format!("Sequence {} ({})", ex.id, ex.kind));
        let frames = picture_frames(ex.truth.len());
        let sheet = comparison_sheet(
            &ex.faces,
            &ex.truth,
            &[
                MethodFrames {
                    name: model_name,
                    frames: &ex.model,
                },
                MethodFrames {
                    name: LBS_NAME,
                    frames: &ex.lbs,
                },
            ],
            Some(&ex.bodies),
            &frames,
            360,
            "ground truth | model | LBS only",
        )?;
        sheet.write_png(&dir.join("comparison.png"))?;
        html.image(
            &sheet,
            "Rows: frames; columns: simulated ground truth, the model, the LBS-only baseline; colour: vertex error (mm), one scale for all tiles.",
        )?;
        let last = ex.truth.len().saturating_sub(1);
        let err = vertex_errors_mm(&ex.model[last], &ex.truth[last])?;
        let pos: Vec<[f64; 3]> = ex.model[last].iter().map(|p| p.map(f64::from)).collect();
        let map = heat_map(
            &pos,
            &ex.faces,
            &err,
            Colormap::Viridis,
            ERROR_LABEL,
            ex.bodies.get(last),
            640,
            &format!("{model_name}: vertex error, frame {last}"),
        )?;
        map.write_png(&dir.join("error_map.png"))?;
        html.image(&map, "The model's vertex error on the last frame.")?;
        let plot = per_frame_plot(
            &[
                (model_name, per_frame_means(&ex.model, &ex.truth)?),
                (LBS_NAME, per_frame_means(&ex.lbs, &ex.truth)?),
            ],
            &format!("mean vertex error per frame, {}", ex.id),
        )?;
        plot.write_png(&dir.join("per_frame.png"))?;
        html.image(&plot, "Mean vertex error per frame.")?;
    }
    html.heading("Reproduce");
    html.code(r.command.clone());
    let path = dir.join("eval.html");
    html.write(&path)?;
    Ok(path)
}
