//! `weft demo`: the whole path on a fresh clone, with no arguments — build the tiny
//! dataset, train the `cpu` preset, evaluate on the unseen test split against the
//! LBS-only baseline, animate an unseen garment on an unseen motion and body shape,
//! explain one vertex (eq. 9), and bundle it all in one HTML report.
//!
//! Every stage resumes: the dataset generator keeps finished shards, training continues
//! from its latest checkpoint (and does nothing when the run is complete), so running the
//! demo again after an interruption, or after it finished, costs only what is missing
//! plus the evaluation.
//!
//! The stages are the pipeline functions the commands call ([`crate::train`],
//! [`crate::evaluate`], weft-eval's animation and attribution), so `weft demo` takes the
//! same path as `weft train`, `weft eval` and `weft animate`, and a test can run it with
//! a stand-in simulator and a micro configuration ([`DemoOptions::quick`]).

use std::path::PathBuf;
use std::time::Instant;

use weft_body::PosedSequence;
use weft_data::{
    generate, DataConfig, GarmentSpec, GenerateOptions, MotionSpec as DataMotion, Progress,
    SequenceSimulator, Split,
};
use weft_eval::animate::{animate, check_animation, write_animation, AnimationCheck, MotionSpec};
use weft_eval::attribution::DEFAULT_SAMPLES;
use weft_eval::evaluate::{error_and_speed_tables, EvalOptions};
use weft_eval::explain::explain_vertex;
use weft_eval::pictures::attribution_map;
use weft_eval::LBS_NAME;
use weft_garment::{FitBody, GarmentKind, Style};
use weft_mesh::export::ExportFormat;
use weft_models::multilevel::Predictor;
use weft_models::run::latest_checkpoint;
use weft_models::Clip;
use weft_render::{
    render_sequence, Paint, RenderOptions, Report, SceneMesh, View, BODY_COLOR, GARMENT_COLOR,
};
use weft_train::{MultilevelRun, RunOptions};

use crate::error::{stage, PipelineError};
use crate::evaluate::evaluate_run;
use crate::train::train_multilevel;

/// What the demo does.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// Output directory (`data/`, `run/`, `animation/`, `report.html`).
    pub out: PathBuf,
    /// A micro configuration for tests: a two-sequence dataset of small garments, a few
    /// training steps, a short animation, 4 quadrature nodes.
    pub quick: bool,
    /// Training steps; `None`: the `cpu` preset's (10 000 steps of 2-frame windows,
    /// about as long here as the 2 500 steps of 8 frames demos trained before).
    pub steps: Option<usize>,
}

/// Where the demo wrote what, and the headline figures.
#[derive(Clone, Debug)]
pub struct DemoSummary {
    /// The report.
    pub report: PathBuf,
    /// Mean vertex error of the model on the test split (mm).
    pub model_mm: f64,
    /// Mean vertex error of the LBS baseline (mm).
    pub lbs_mm: f64,
    /// The animation's strain and vertices inside the body (the unseen garment has no
    /// ground truth: this is what shows legs through it).
    pub animation: AnimationCheck,
    /// Seconds per stage: data, training, evaluation, animation, attribution.
    pub seconds: [f64; 5],
}

/// The unseen garment, body shape and motion of the animation stage: a dress (a kind the
/// tiny training set has) with a style seed and resolution no split uses, on a shape
/// outside every split, moving through a `jump` clip (seed 7) that no split uses.
const UNSEEN_GARMENT: (GarmentKind, u64, usize) = (GarmentKind::Dress, 4242, 720);
const UNSEEN_BETAS: [f32; 2] = [0.8, -1.2];
const UNSEEN_MOTION: &str = "jump";

/// The micro dataset of [`DemoOptions::quick`]: one train and one test sequence of
/// ~300-vertex skirts, 6 frames each.
pub fn quick_data_config() -> DataConfig {
    let mut c = DataConfig::tiny();
    c.frames = 6;
    c.warmup_frames = c.warmup_frames.min(2);
    let g = |vertices: usize, seed: u64| GarmentSpec {
        kind: "skirt".into(),
        vertices,
        seed: Some(seed),
        material: None,
        length: None,
    };
    let m = |kind: &str, seed: u64| DataMotion {
        kind: Some(kind.into()),
        file: None,
        seed: Some(seed),
        speed: None,
        amplitude: None,
        start: 0,
        frames: None,
    };
    c.train.betas = vec![vec![0.0, 0.0]];
    c.train.motions_per_pair = 1;
    c.train.garments = vec![g(320, 1)];
    c.train.motions = vec![m("walk", 1)];
    c.validation.garments = vec![g(300, 2)];
    c.validation.motions = vec![m("kick", 2)];
    c.test.garments = vec![g(310, 3)];
    c.test.motions = vec![m("twist", 3)];
    c
}

fn begin(log: &mut dyn FnMut(&str), n: usize, what: &str) -> Instant {
    log(&format!("[{n}/5] {what}"));
    Instant::now()
}

/// Runs the demo; `simulator` makes the ground truth (weft-data's `Physics` in the CLI),
/// `progress` shows the generation, `log` gets one line per step.
pub fn run_demo(
    opts: &DemoOptions,
    simulator: &dyn SequenceSimulator,
    progress: &dyn Progress,
    log: &mut dyn FnMut(&str),
) -> Result<DemoSummary, PipelineError> {
    let out = &opts.out;
    let data_dir = out.join("data");
    let run_dir = out.join("run");
    let mut seconds = [0.0; 5];

    // 1. Data.
    let t = begin(
        log,
        1,
        &format!(
            "dataset ({}) in {}",
            if opts.quick { "micro" } else { "tiny preset" },
            data_dir.display()
        ),
    );
    let config = if opts.quick {
        quick_data_config()
    } else {
        DataConfig::tiny()
    };
    let report = generate(
        &config,
        &data_dir,
        &GenerateOptions::default(),
        simulator,
        progress,
    )
    .map_err(stage("generating the dataset"))?;
    if !report.failed.is_empty() {
        return Err(PipelineError::Invalid(format!(
            "{} sequences failed to simulate (see {})",
            report.failed.len(),
            report.manifest_path.display()
        )));
    }
    log(&format!(
        "      {} sequences ({} kept from an earlier run, {} simulated, {} frames in {:.1} s)",
        report.owned,
        report.kept,
        report.done + report.diverged.len(),
        report.frames,
        report.seconds
    ));
    seconds[0] = t.elapsed().as_secs_f64();

    // 2. Training.
    let t = begin(
        log,
        2,
        &format!("training the cpu preset in {}", run_dir.display()),
    );
    let mut cfg = MultilevelRun::preset("cpu")?;
    let resume = run_dir.join("checkpoints").join("latest").is_file();
    // A run an earlier demo left keeps its own budget unless `--steps` says otherwise
    // (some versions trained 2 000): with another count the resume would be refused as
    // a different run.
    let earlier_steps = (resume && opts.steps.is_none())
        .then(|| MultilevelRun::from_run_dir(&run_dir).ok())
        .flatten()
        .map(|run| run.train.trainer.steps);
    cfg.train.trainer.steps = opts.steps.or(earlier_steps).unwrap_or(if opts.quick {
        6
    } else {
        cfg.train.trainer.steps
    });
    if opts.quick {
        cfg.train.task.window = 3;
        cfg.train.trainer.checkpoint_every = 3;
        cfg.train.trainer.validate_every = 3;
        cfg.train.task.validation_windows = 1;
    }
    if resume {
        log(&format!(
            "      resuming the run found there ({} steps)",
            cfg.train.trainer.steps
        ));
    }
    let options = RunOptions {
        resume,
        progress: !opts.quick,
        session_steps: None,
    };
    let outcome = train_multilevel(&cfg, &data_dir, &run_dir, &options, &mut |line| {
        log(&format!("      {line}"))
    })
    .map_err(|e| PipelineError::Stage {
        stage: "training".into(),
        source: Box::new(e),
    })?;
    log(&format!(
        "      {} steps ({:.1} ms/step this session), validation {}",
        outcome.steps,
        outcome.mean_step_ms,
        weft_train::metrics::describe(&outcome.validation)
    ));
    seconds[1] = t.elapsed().as_secs_f64();

    // 3. Evaluation.
    let t = begin(
        log,
        3,
        "evaluating on the test split (unseen garments, shape and motion)",
    );
    let dataset = weft_data::Dataset::open(&data_dir).map_err(stage("opening the dataset"))?;
    let eval_opts = EvalOptions {
        fps_frames: if opts.quick { 4 } else { 32 },
        command: format!(
            "weft eval {} --data {} --split test",
            run_dir.display(),
            data_dir.display()
        ),
        ..EvalOptions::default()
    };
    let mut line = |s: &str| log(&format!("      {s}"));
    let (evaluation, eval_html) = evaluate_run(
        &run_dir,
        &data_dir,
        &eval_opts,
        &weft_models::hood::RolloutOptions::default(),
        false,
        &mut line,
    )?;
    let r = &evaluation.report;
    let model_mm = r.model().map_or(f64::NAN, |m| m.overall.e_verts_mm.mean);
    let lbs_mm = r
        .method(LBS_NAME)
        .map_or(f64::NAN, |m| m.overall.e_verts_mm.mean);
    log(&format!(
        "      E_verts: model {model_mm:.2} mm, LBS only {lbs_mm:.2} mm ({})",
        r.reduction_vs_lbs().map_or("–".to_owned(), |x| format!(
            "{:.1} % {}",
            100.0 * x.abs(),
            if x >= 0.0 { "lower" } else { "higher" }
        ))
    ));
    seconds[2] = t.elapsed().as_secs_f64();

    // 4. Animation of an unseen garment on an unseen motion and shape.
    let t = begin(
        log,
        4,
        "animating an unseen garment on an unseen body shape and motion",
    );
    let anim_dir = out.join("animation");
    std::fs::create_dir_all(&anim_dir).map_err(|source| PipelineError::Io {
        path: anim_dir.clone(),
        source,
    })?;
    let body = dataset.body_model()?;
    let betas64: Vec<f64> = UNSEEN_BETAS.iter().map(|&b| f64::from(b)).collect();
    let (kind, seed, vertices) = UNSEEN_GARMENT;
    let vertices = if opts.quick { 320 } else { vertices };
    let generated = FitBody::new(&body, &betas64)
        .and_then(|fit| fit.generate(kind, &Style::from_seed(kind, seed), vertices))
        .map_err(stage("generating the unseen garment"))?;
    let garment_path = anim_dir.join("garment.obj");
    weft_garment::obj::write_obj(&garment_path, &generated)
        .map_err(stage("writing the garment"))?;
    let uvs: Vec<[[f32; 2]; 3]> = generated
        .corner_uvs
        .iter()
        .map(|t| t.map(|uv| uv.map(|x| x as f32)))
        .collect();
    let garment = generated.mesh;
    let frames = if opts.quick { 6 } else { 60 };
    let motion = MotionSpec::parse(UNSEEN_MOTION, frames, 7, 30.0)?.load(&body, &UNSEEN_BETAS)?;
    let predictor = Predictor::load(&run_dir)?;
    let animated = animate(&predictor, &garment, &body, &UNSEEN_BETAS, &motion)?;
    let posed = PosedSequence::new(&body, &UNSEEN_BETAS, motion.poses(), motion.trans())
        .map_err(stage("posing the body"))?;
    let body_frames: Vec<Vec<[f32; 3]>> = (0..posed.len())
        .filter_map(|t| posed.mesh(t))
        .map(|m| m.positions.iter().map(|p| p.map(|x| x as f32)).collect())
        .collect();
    let glb = anim_dir.join("animation.glb");
    write_animation(
        ExportFormat::Glb,
        &garment,
        Some(&uvs),
        &animated,
        motion.fps(),
        Some((body.faces(), &body_frames)),
        &glb,
    )?;
    let pc2 = anim_dir.join("garment.pc2");
    write_animation(
        ExportFormat::Pc2,
        &garment,
        None,
        &animated,
        motion.fps(),
        None,
        &pc2,
    )?;
    let shown: Vec<usize> = (0..6).map(|k| k * (animated.len() - 1) / 5).collect();
    let garment_pos: Vec<Vec<[f64; 3]>> = shown
        .iter()
        .map(|&t| animated[t].iter().map(|p| p.map(f64::from)).collect())
        .collect();
    let bodies: Vec<weft_mesh::TriMesh> = shown.iter().filter_map(|&t| posed.mesh(t)).collect();
    let scenes: Vec<Vec<SceneMesh<'_>>> = garment_pos
        .iter()
        .zip(&bodies)
        .map(|(g, b)| {
            vec![
                SceneMesh::from_parts("garment", g, &garment.faces, Paint::Solid(GARMENT_COLOR)),
                SceneMesh::new("body", b, Paint::Solid(BODY_COLOR)),
            ]
        })
        .collect();
    let labels: Vec<String> = shown.iter().map(|t| format!("frame {t}")).collect();
    let mut ropts = RenderOptions::new(320, 320);
    ropts.view = View::ThreeQuarter;
    ropts.title = Some(format!(
        "unseen {} ({} vertices), shape (betas) {:?}, motion {}",
        kind.name(),
        garment.vertex_count(),
        UNSEEN_BETAS,
        UNSEEN_MOTION
    ));
    let sheet = render_sequence(&scenes, &labels, &ropts, Some(3))?.image;
    let sheet_path = anim_dir.join("animation.png");
    sheet.write_png(&sheet_path)?;
    let check = check_animation(&garment, &animated, &posed)?;
    log(&format!(
        "      {} frames of {} vertices: {}, {}, {}\n      {check}",
        animated.len(),
        garment.vertex_count(),
        glb.display(),
        pc2.display(),
        sheet_path.display(),
    ));
    seconds[3] = t.elapsed().as_secs_f64();

    // 5. Attribution of one vertex of a test sequence (eq. 9).
    let t = begin(log, 5, "attribution of one vertex (seed 000 eq. 9)");
    let samples = if opts.quick { 4 } else { DEFAULT_SAMPLES };
    let config = weft_models::multilevel::predictor::read_run_config(&run_dir)?;
    let checkpoint = latest_checkpoint(&run_dir)?;
    let explainer =
        Predictor::from_checkpoint(config, &checkpoint, &weft_nn::backend::cpu_autodiff())?;
    let record = dataset
        .records_in(Split::Test)
        .first()
        .copied()
        .cloned()
        .ok_or_else(|| PipelineError::Invalid("the dataset has no test sequence".into()))?;
    let seq = dataset.load(&record)?;
    let frame = seq.poses.len() / 2;
    // The lowest vertex (a hem): where garments swing most.
    let vertex = seq
        .garment
        .positions
        .iter()
        .enumerate()
        .min_by(|a, b| a.1[1].total_cmp(&b.1[1]))
        .map_or(0, |(i, _)| i);
    let clip = Clip {
        betas: &record.betas,
        poses: &seq.poses,
        trans: &seq.trans,
        fps: record.fps,
    };
    let a = explain_vertex(
        explainer.model(),
        &seq.garment,
        &body,
        &clip,
        vertex,
        frame,
        samples,
    )?;
    let attr = attribution_map(
        &a.predicted,
        &a.scores,
        vertex,
        720,
        &format!(
            "attribution of vertex {vertex}, frame {frame}, {}",
            record.id
        ),
    )?;
    let attr_path = out.join("attribution.png");
    attr.write_png(&attr_path)?;
    let gap = a.attribution.completeness_gap();
    log(&format!(
        "      {} (N_s = {samples}; attributions sum to f(X) − f(0) within {gap:.2e} m)",
        attr_path.display()
    ));
    seconds[4] = t.elapsed().as_secs_f64();

    // The report.
    let mut html = Report::new("weft demo");
    html.paragraph(format!(
        "A Multilevel model (seed 000, cpu preset) trained on the {} dataset in {}, evaluated on its test split (garments, body shape and motion clips unseen in training) against the LBS-only baseline (the body's skinning weights transferred to the garment).",
        if opts.quick { "micro" } else { "tiny" },
        data_dir.display()
    ));
    error_and_speed_tables(r, &mut html);
    for (file, caption) in [
        (
            run_dir.join("report").join("comparison.png"),
            "Ground truth, model and LBS only on test frames; colour: vertex error (mm).",
        ),
        (
            run_dir.join("report").join("per_frame.png"),
            "Mean vertex error per frame.",
        ),
        (run_dir.join("curves.png"), "Training curves."),
        (
            sheet_path.clone(),
            &format!("An unseen garment on an unseen body shape and motion; {check}."),
        ),
        (
            attr_path.clone(),
            "Attribution (eq. 9): which vertices' normal features move the marked vertex.",
        ),
    ] {
        if let Ok(bytes) = std::fs::read(&file) {
            html.png(bytes, caption)?;
        }
    }
    html.heading("Files");
    html.code(format!(
        "dataset:     {}\nrun:         {}\nevaluation:  {}\nanimation:   {} (glTF with the body), {} (PC2 point cache), {}\nattribution: {}",
        data_dir.display(),
        run_dir.display(),
        eval_html.display(),
        glb.display(),
        pc2.display(),
        garment_path.display(),
        attr_path.display()
    ));
    html.heading("Timings");
    html.table(
        ["stage", "seconds"],
        [
            "dataset",
            "training",
            "evaluation",
            "animation",
            "attribution",
        ]
        .iter()
        .zip(seconds)
        .map(|(s, x)| vec![s.to_string(), format!("{x:.1}")]),
    );
    let report_path = out.join("report.html");
    html.write(&report_path)?;
    Ok(DemoSummary {
        report: report_path,
        model_mm,
        lbs_mm,
        animation: check,
        seconds,
    })
}
