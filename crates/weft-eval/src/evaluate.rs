//! `weft eval`: any list of deformers (a trained run's model, other runs, the LBS and
//! DQS baselines) against the simulated ground truth of a dataset split, in one loop,
//! with inference speed and a report.
//!
//! Every sequence of the split is animated by each method through the same
//! [`Deformer::animate`] users call (so what is measured is what ships), and scored frame
//! by frame into per-garment-kind accumulators ([`FrameMetrics`]). Speed is timed on the
//! first sequence the way each method is meant to run ([`Deformer::time`]; for
//! Multilevel: the pair encoding cached, windows of 1 and 16 frames, as seed 000 reports
//! it).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use weft_body::query::BodySurface;
use weft_body::{BodyModel, PosedSequence};
use weft_data::{Dataset, Sequence, Split};
use weft_mesh::TriMesh;
use weft_models::{Clip, Deformer, Frames, StepJudge};
use weft_render::{Colormap, Report};

use crate::error::EvalError;
use crate::metrics::{vertex_errors_mm, FrameMetrics, GarmentTopology};
use crate::pictures::{comparison_sheet, heat_map, per_frame_plot, MethodFrames, ERROR_LABEL};
use crate::report::{write_text, EvalReport, MethodResult, SequenceScore, REPORT_VERSION};

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
    /// Score every method's steps by the judge's potential when one is given (one
    /// implicit Euler step per frame and method: the slow part of a HOOD evaluation).
    pub potential: bool,
}

impl Default for EvalOptions {
    /// The test split, every sequence, collisions on, batches 1 and 16 over 32 frames,
    /// the steps' potential scored when there is a judge.
    fn default() -> Self {
        EvalOptions {
            split: Split::Test,
            max_sequences: None,
            collisions: true,
            fps_batches: vec![1, 16],
            fps_frames: 32,
            command: String::new(),
            potential: true,
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
    pub truth: Frames,
    /// Each method's frames, in the order of the methods.
    pub methods: Vec<(String, Frames)>,
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

    fn result(&self, method: &dyn Deformer, fps: Vec<weft_models::Timing>) -> MethodResult {
        let mut overall = FrameMetrics::new();
        for m in self.0.values() {
            overall.merge(m);
        }
        MethodResult {
            name: method.name(),
            model: method.kind().map(|k| k.name().to_owned()),
            variant: method.variant(),
            overall: overall.summary(),
            per_kind: self
                .0
                .iter()
                .map(|(k, m)| (k.clone(), m.summary()))
                .collect(),
            fps,
        }
    }
}

/// Evaluates `methods` (the first is the run's model, named by `run_dir`) on
/// `opts.split` of `dataset`, reporting progress through `progress` (one line per
/// sequence); with a `judge`, every method's steps are also scored by its potential
/// ([`Evaluator::judged_by`]).
pub fn evaluate(
    methods: &[&dyn Deformer],
    judge: Option<&dyn StepJudge>,
    run_dir: &Path,
    dataset: &Dataset,
    opts: &EvalOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Evaluation, EvalError> {
    let body = dataset.body_model()?;
    let mut records = dataset.records_in(opts.split);
    if records.is_empty() {
        return Err(EvalError::Invalid(format!(
            "{} has no loadable sequence in the {} split",
            dataset.dir().display(),
            opts.split
        )));
    }
    if let Some(k) = opts.max_sequences {
        if k == 0 {
            return Err(EvalError::Invalid(
                "at most 0 sequences: nothing to evaluate (give at least 1)".to_owned(),
            ));
        }
        records.truncate(k);
    }
    let total = records.len();
    let mut ev = Evaluator::new(methods, &body, opts)?;
    if let Some(judge) = judge.filter(|_| opts.potential) {
        ev = ev.judged_by(judge);
    }
    for (k, record) in records.iter().enumerate() {
        let started = Instant::now();
        let seq = dataset.load(record)?;
        let (id, kind, vertices, frames) = (
            seq.record.id.clone(),
            seq.record.garment_kind.clone(),
            seq.record.vertices,
            seq.positions.len(),
        );
        let means = ev.add(seq)?;
        let errors: Vec<String> = methods
            .iter()
            .zip(&means)
            .map(|(m, e)| format!("{} {e:.2} mm", m.name()))
            .collect();
        progress(&format!(
            "[{}/{total}] {id} ({kind}, {vertices} vertices, {frames} frames): E_verts {} ({:.1} s)",
            k + 1,
            errors.join(", "),
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
    methods: &'a [&'a dyn Deformer],
    body: &'a BodyModel,
    opts: &'a EvalOptions,
    judge: Option<&'a dyn StepJudge>,
    scores: Vec<ByKind>,
    fps: Vec<Vec<weft_models::Timing>>,
    example: Option<Example>,
    frames: u64,
    sequences: usize,
    per_sequence: Vec<SequenceScore>,
}

impl<'a> Evaluator<'a> {
    /// Nothing scored yet; `methods` must not be empty, and their names must differ (the
    /// report and the pictures tell them apart by name).
    pub fn new(
        methods: &'a [&'a dyn Deformer],
        body: &'a BodyModel,
        opts: &'a EvalOptions,
    ) -> Result<Self, EvalError> {
        if methods.is_empty() {
            return Err(EvalError::Invalid(
                "nothing to evaluate: give at least one method".to_owned(),
            ));
        }
        let mut names: Vec<String> = methods.iter().map(|m| m.name()).collect();
        names.sort();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(EvalError::Invalid(format!(
                "two methods are both named {:?}; evaluate each once",
                w[0]
            )));
        }
        Ok(Evaluator {
            methods,
            body,
            opts,
            judge: None,
            scores: methods.iter().map(|_| ByKind::default()).collect(),
            fps: methods.iter().map(|_| Vec::new()).collect(),
            example: None,
            frames: 0,
            sequences: 0,
            per_sequence: Vec::new(),
        })
    }

    /// Also scores every method's steps by `judge`'s potential: per step, how far above
    /// its minimiser from the method's own state it lies ([`StepJudge`]).
    pub fn judged_by(mut self, judge: &'a dyn StepJudge) -> Self {
        self.judge = Some(judge);
        self
    }

    /// Animates `seq` with every method (in the material it was simulated in, for a
    /// method that takes one: [`Deformer::animate_in`]) and scores each against its
    /// simulated frames; times inference on the first sequence. Returns each method's
    /// mean vertex error (mm) on this sequence.
    pub fn add(&mut self, mut seq: Sequence) -> Result<Vec<f64>, EvalError> {
        let body = self.body;
        if seq.positions.is_empty() || seq.positions.len() > seq.poses.len() {
            return Err(EvalError::Count {
                what: "simulated frames vs motion frames",
                expected: seq.poses.len(),
                found: seq.positions.len(),
            });
        }
        // A diverged sequence keeps the frames before the divergence: score those (no
        // method looks ahead, so the cut motion gives the same predictions).
        seq.poses.truncate(seq.positions.len());
        seq.trans.truncate(seq.positions.len());
        let clip = Clip {
            betas: &seq.record.betas,
            poses: &seq.poses,
            trans: &seq.trans,
            fps: seq.record.fps,
        };
        let predicted: Vec<Frames> = self
            .methods
            .iter()
            .map(|m| m.animate_in(&seq.garment, body, &clip, &seq.record.material))
            .collect::<Result<_, _>>()?;
        let bodies = if self.opts.collisions || self.example.is_none() {
            Some(PosedSequence::new(
                body, clip.betas, clip.poses, clip.trans,
            )?)
        } else {
            None
        };
        let topology = GarmentTopology::new(&seq.garment)?;
        let kind = seq.record.garment_kind.clone();
        // This sequence's metrics per method, merged into the per-kind ones below.
        let mut this: Vec<FrameMetrics> =
            self.methods.iter().map(|_| FrameMetrics::new()).collect();
        let mut score = |t: usize, surface: Option<&BodySurface>| -> Result<(), EvalError> {
            for (scores, frames) in this.iter_mut().zip(&predicted) {
                scores.push_frame(&topology, &frames[t], &seq.positions[t], surface)?;
            }
            Ok(())
        };
        // `bodies` holds one frame per ground-truth frame (the clip was cut to them).
        match (&bodies, self.opts.collisions) {
            (Some(b), true) => b.for_each_surface(|t, s| score(t, Some(s)))?,
            _ => (0..seq.positions.len()).try_for_each(|t| score(t, None))?,
        }
        if let Some(judge) = self.judge {
            for (scores, frames) in this.iter_mut().zip(&predicted) {
                let material = &seq.record.material;
                scores.push_potential_gaps(&judge.potential_gaps(
                    &seq.garment,
                    body,
                    &clip,
                    material,
                    frames,
                )?);
            }
        }
        for (scores, m) in self.scores.iter_mut().zip(&this) {
            scores.get(&kind).merge(m);
        }
        self.frames += seq.positions.len() as u64;
        if self.sequences == 0 && !self.opts.fps_batches.is_empty() {
            for (m, fps) in self.methods.iter().zip(&mut self.fps) {
                *fps = m
                    .time(
                        &seq.garment,
                        body,
                        &clip,
                        &self.opts.fps_batches,
                        self.opts.fps_frames,
                    )?
                    .unwrap_or_default();
            }
        }
        self.sequences += 1;
        let means = predicted
            .iter()
            .map(|p| vertex_mean(p, &seq.positions))
            .collect::<Result<Vec<f64>, _>>()?;
        self.per_sequence.push(SequenceScore {
            id: seq.record.id.clone(),
            garment: seq.record.garment_id.clone(),
            body: seq.record.body_id.clone(),
            motion: seq.record.motion_id.clone(),
            betas: seq.record.betas.clone(),
            frames: seq.positions.len(),
            e_verts_mm: means.clone(),
            collision_rate: this.iter().map(|m| m.summary().collision_rate).collect(),
        });
        if self.example.is_none() {
            if let Some(bodies) = bodies {
                self.example = Some(Example {
                    id: seq.record.id.clone(),
                    kind,
                    faces: seq.garment.faces.clone(),
                    bodies: (0..bodies.len()).filter_map(|t| bodies.mesh(t)).collect(),
                    truth: seq.positions,
                    methods: self
                        .methods
                        .iter()
                        .map(|m| m.name())
                        .zip(predicted)
                        .collect(),
                });
            }
        }
        Ok(means)
    }

    /// The report of everything added; `run` and `data` name the run and dataset.
    pub fn finish(self, run: &str, data: &str) -> Evaluation {
        let methods = self
            .methods
            .iter()
            .zip(&self.scores)
            .zip(self.fps)
            .map(|((m, s), fps)| s.result(*m, fps))
            .collect();
        let report = EvalReport {
            version: REPORT_VERSION,
            run: run.to_owned(),
            data: data.to_owned(),
            split: self.opts.split.name().to_owned(),
            sequences: self.sequences,
            frames: self.frames,
            methods,
            per_sequence: self.per_sequence,
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

/// Frames to draw: start, middle and end of the sequence (fewer for short ones).
fn picture_frames(count: usize) -> Vec<usize> {
    let mut f = vec![0, count / 2, count.saturating_sub(1)];
    f.dedup();
    f
}

/// The error table, the per-sequence table and, when timed, the speed table of `r` as
/// HTML sections (the evaluation report and the demo report show the same ones).
pub fn error_and_speed_tables(r: &EvalReport, html: &mut Report) {
    html.heading("Errors against the simulated ground truth");
    let (h, rows) = r.table();
    html.table(h, rows);
    if !r.per_sequence.is_empty() {
        html.heading("Per sequence");
        let (h, rows) = r.sequence_table();
        html.table(h, rows);
    }
    if r.timed() {
        html.heading("Inference speed");
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
        "Split {} of {}: {} sequences, {} frames. Methods: {}.",
        r.split,
        r.data,
        r.sequences,
        r.frames,
        r.methods_line()
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
        let (model_name, model_frames) = match ex.methods.first() {
            Some((name, frames)) => (name.as_str(), frames),
            None => return Err(EvalError::Invalid("no method to draw".to_owned())),
        };
        html.heading(format!("Sequence {} ({})", ex.id, ex.kind));
        let frames = picture_frames(ex.truth.len());
        let columns: Vec<MethodFrames> = ex
            .methods
            .iter()
            .map(|(name, frames)| MethodFrames { name, frames })
            .collect();
        let names: Vec<&str> = ex.methods.iter().map(|(n, _)| n.as_str()).collect();
        let sheet = comparison_sheet(
            &ex.faces,
            &ex.truth,
            &columns,
            Some(&ex.bodies),
            &frames,
            360,
            &format!("ground truth | {}", names.join(" | ")),
        )?;
        sheet.write_png(&dir.join("comparison.png"))?;
        html.image(
            &sheet,
            format!(
                "Rows: frames; columns: simulated ground truth, then {}; colour: vertex error (mm), one scale for all tiles.",
                names.join(", ")
            ),
        )?;
        let last = ex.truth.len().saturating_sub(1);
        let err = vertex_errors_mm(&model_frames[last], &ex.truth[last])?;
        let pos: Vec<[f64; 3]> = model_frames[last]
            .iter()
            .map(|p| p.map(f64::from))
            .collect();
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
        html.image(
            &map,
            format!("{model_name}: vertex error on the last frame."),
        )?;
        let curves = ex
            .methods
            .iter()
            .map(|(name, frames)| Ok((name.as_str(), per_frame_means(frames, &ex.truth)?)))
            .collect::<Result<Vec<_>, EvalError>>()?;
        let plot = per_frame_plot(&curves, &format!("mean vertex error per frame, {}", ex.id))?;
        plot.write_png(&dir.join("per_frame.png"))?;
        html.image(&plot, "Mean vertex error per frame.")?;
    }
    html.heading("Reproduce");
    html.code(r.command.clone());
    let path = dir.join("eval.html");
    html.write(&path)?;
    Ok(path)
}
