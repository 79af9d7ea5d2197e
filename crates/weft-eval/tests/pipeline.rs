//! The evaluation pipeline on a real garment, body and motion with an (untrained)
//! Multilevel model: scoring against a known ground truth, the report files, the
//! attribution of one vertex, and animation export.

use std::path::PathBuf;

use weft_data::{SequenceRecord, Split};
use weft_eval::evaluate::{write_report, EvalOptions, Evaluator};
use weft_eval::explain::explain_vertex;
use weft_eval::LBS_NAME;
use weft_garment::{FitBody, GarmentKind, Style};
use weft_mesh::TriMesh;
use weft_models::multilevel::{Multilevel, MultilevelConfig, Predictor};
use weft_models::{Clip, Deformer, Frames, ModelError, SkinningBaseline, StepJudge, DQS_NAME};
use weft_motion::{generate, MotionKind, ProceduralParams};

struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("weft-eval-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

struct Case {
    body: weft_body::BodyModel,
    garment: TriMesh,
    poses: Vec<weft_body::Pose>,
    trans: Vec<[f32; 3]>,
}

fn case(frames: usize) -> Case {
    let body = weft_body::default_body().unwrap();
    let fit = FitBody::new(&body, &[]).unwrap();
    let garment = fit
        .generate(
            GarmentKind::Skirt,
            &Style::from_seed(GarmentKind::Skirt, 2),
            400,
        )
        .unwrap()
        .mesh;
    let mut p = ProceduralParams::new(MotionKind::parse("walk").unwrap());
    p.frames = frames;
    let motion = generate(&p).unwrap();
    Case {
        body,
        garment,
        poses: motion.poses().to_vec(),
        trans: motion.trans().to_vec(),
    }
}

impl Case {
    fn clip(&self) -> Clip<'_> {
        Clip {
            betas: &[],
            poses: &self.poses,
            trans: &self.trans,
            fps: 30.0,
        }
    }

    /// The sequence of this case whose simulated frames are `positions`.
    fn sequence(&self, frames: usize, positions: Frames) -> weft_data::Sequence {
        weft_data::Sequence {
            record: record(self, frames),
            garment: self.garment.clone(),
            corner_uvs: vec![],
            poses: self.poses.clone(),
            trans: self.trans.clone(),
            positions,
        }
    }
}

fn record(c: &Case, frames: usize) -> SequenceRecord {
    SequenceRecord {
        id: "test-skirt-b0-walk".into(),
        index: 0,
        split: Split::Test,
        shard: String::new(),
        stats: String::new(),
        garment_id: "skirt".into(),
        garment_kind: "skirt".into(),
        vertices: c.garment.vertex_count(),
        faces: c.garment.faces.len(),
        body_id: "b0".into(),
        betas: vec![],
        motion_id: "walk".into(),
        frame_range: [0, frames],
        material: "cotton".into(),
        fps: 30.0,
        frames,
        sha256: None,
        status: weft_data::Status::Done,
        diverged_at: None,
        message: None,
    }
}

fn predictor(autodiff: bool) -> Predictor {
    let device = if autodiff {
        weft_nn::backend::cpu_autodiff()
    } else {
        weft_nn::backend::cpu()
    };
    let cfg = MultilevelConfig::new();
    Predictor::from_model(Multilevel::new(&cfg, &weft_nn::backend::seeded(&device, 5)).unwrap())
}

#[test]
fn scores_a_known_truth_and_writes_the_report() {
    let frames = 6;
    let c = case(frames);
    // Ground truth: the LBS baseline moved 1 cm along +X, so the baseline's error is
    // exactly 10 mm everywhere and its normals are exact.
    let lbs = SkinningBaseline::LBS
        .animate(&c.garment, &c.body, &c.clip())
        .unwrap();
    let truth: Vec<Vec<[f32; 3]>> = lbs
        .iter()
        .map(|f| f.iter().map(|p| [p[0] + 0.01, p[1], p[2]]).collect())
        .collect();
    let seq = c.sequence(frames, truth);
    let p = predictor(false);
    let opts = EvalOptions {
        fps_batches: vec![1, 4],
        fps_frames: 4,
        command: "weft eval RUN --data DATA".into(),
        ..EvalOptions::default()
    };
    let methods: [&dyn Deformer; 3] = [&p, &SkinningBaseline::LBS, &SkinningBaseline::DQS];
    let mut ev = Evaluator::new(&methods, &c.body, &opts).unwrap();
    let means = ev.add(seq).unwrap();
    let (model_mm, lbs_mm, dqs_mm) = (means[0], means[1], means[2]);
    assert!((lbs_mm - 10.0).abs() < 0.01, "{lbs_mm}");
    assert!(model_mm.is_finite());
    // DQS differs from LBS where the walk bends the hips, by less than the offset.
    assert!(dqs_mm > 5.0 && (dqs_mm - lbs_mm).abs() > 1e-4, "{dqs_mm}");
    // A diverged sequence: the frames before the divergence are scored.
    let mut cut = c.sequence(frames, lbs[..2].to_vec());
    ev.add(cut.clone()).unwrap();
    cut.positions.clear();
    assert!(ev.add(cut).is_err());
    let eval = ev.finish("RUN", "DATA");
    let r = &eval.report;
    assert_eq!((r.sequences, r.frames), (2, frames as u64 + 2));
    let base = r.method(LBS_NAME).unwrap();
    // 6 frames at 10 mm and 2 exact frames.
    let want = 10.0 * frames as f64 / (frames + 2) as f64;
    assert!((base.overall.e_verts_mm.mean - want).abs() < 0.01);
    assert!(base.overall.e_norm_deg.mean < 0.01);
    assert!(base.per_kind.contains_key("skirt"));
    assert!(base.overall.collision_rate.is_some());
    // Each sequence's share of vertices inside the body, per method; over the two
    // sequences (same vertex count) they make up each method's overall share.
    assert_eq!(r.per_sequence.len(), 2);
    for (i, m) in r.methods.iter().enumerate() {
        let [a, b] = [&r.per_sequence[0], &r.per_sequence[1]]
            .map(|q| q.collision_rate[i].expect("collisions were checked"));
        let overall = m.overall.collision_rate.unwrap();
        let weighted = (a * frames as f64 + b * 2.0) / (frames + 2) as f64;
        assert!(
            (weighted - overall).abs() < 1e-12,
            "{}: {weighted} vs {overall}",
            m.name
        );
    }
    let names: Vec<&str> = r.methods.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, [p.name().as_str(), LBS_NAME, DQS_NAME]);
    assert_eq!(r.methods[0].model.as_deref(), Some("multilevel"));
    assert_eq!(r.methods[0].variant["pooling"], "structure");
    assert_eq!(r.methods[2].variant["skinning"], "dqs");
    // Only the model has something to time apart from animating.
    assert_eq!(r.methods[0].fps.len(), 2);
    assert!(r.methods[0]
        .fps
        .iter()
        .all(|f| f.network_fps > 0.0 && f.frames >= 4));
    assert!(r.methods[1].fps.is_empty() && r.methods[2].fps.is_empty());
    // Two methods of one name cannot be told apart in a report.
    let twice: [&dyn Deformer; 2] = [&SkinningBaseline::LBS, &SkinningBaseline::LBS];
    assert!(Evaluator::new(&twice, &c.body, &opts).is_err());
    assert!(Evaluator::new(&[], &c.body, &opts).is_err());

    let dir = TempDir::new("report");
    let html = write_report(&eval, &dir.0).unwrap();
    for f in [
        "eval.json",
        "eval.md",
        "eval.html",
        "comparison.png",
        "error_map.png",
        "per_frame.png",
    ] {
        assert!(dir.0.join(f).is_file(), "{f} missing");
    }
    let md = std::fs::read_to_string(dir.0.join("eval.md")).unwrap();
    assert!(md.contains("## Per sequence") && md.contains("LBS only: E_verts (mm) / inside"));
    let text = std::fs::read_to_string(html).unwrap();
    assert!(text.contains("LBS only") && text.contains("DQS only"));
    assert!(text.contains("Per sequence"));
    assert!(text.contains("data:image/png;base64"));
}

#[test]
fn attribution_of_one_vertex_is_complete() {
    let c = case(3);
    let p = predictor(true);
    let clip = c.clip();
    let a = explain_vertex(p.model(), &c.garment, &c.body, &clip, 17, 2, 8).unwrap();
    assert_eq!(a.scores.len(), c.garment.vertex_count());
    assert_eq!(a.attribution.cols, 6 + 24);
    let change = a.attribution.output - a.attribution.baseline_output;
    let gap = a.attribution.completeness_gap();
    // Eq. 9 with 8 nodes on a real network: the sum of attributions accounts for the
    // change of the output to within a few percent.
    assert!(
        gap.abs() <= 0.05 * change.abs().max(1e-3),
        "gap {gap}, change {change}"
    );
    assert!(explain_vertex(p.model(), &c.garment, &c.body, &clip, 100_000, 0, 4).is_err());
}

/// Scores every step of a sequence by its frame count, after checking it was told the
/// sequence's material: the plumbing, not the physics (HOOD's judge has its own tests).
struct CountingJudge;

impl StepJudge for CountingJudge {
    fn potential_gaps(
        &self,
        _garment: &TriMesh,
        _body: &weft_body::BodyModel,
        _clip: &Clip,
        material: &str,
        frames: &Frames,
    ) -> Result<Vec<f64>, ModelError> {
        assert_eq!(material, "cotton");
        Ok(vec![frames.len() as f64; frames.len().saturating_sub(2)])
    }
}

#[test]
fn a_judge_scores_every_methods_steps() {
    let frames = 6;
    let c = case(frames);
    let truth = SkinningBaseline::LBS
        .animate(&c.garment, &c.body, &c.clip())
        .unwrap();
    let seq = c.sequence(frames, truth);
    let opts = EvalOptions {
        fps_batches: vec![],
        ..EvalOptions::default()
    };
    let methods: [&dyn Deformer; 2] = [&SkinningBaseline::LBS, &SkinningBaseline::DQS];
    let column = "step potential above its minimum (J)";
    // Without a judge, no figure and no column.
    let mut plain = Evaluator::new(&methods, &c.body, &opts).unwrap();
    plain.add(seq.clone()).unwrap();
    let r = plain.finish("RUN", "DATA").report;
    assert!(r
        .methods
        .iter()
        .all(|m| m.overall.potential_gap_j.is_none()));
    assert!(!r.table().0.iter().any(|h| h == column));
    let mut judged = Evaluator::new(&methods, &c.body, &opts)
        .unwrap()
        .judged_by(&CountingJudge);
    judged.add(seq).unwrap();
    let r = judged.finish("RUN", "DATA").report;
    for m in &r.methods {
        let g = m
            .overall
            .potential_gap_j
            .expect("the judge scored the steps");
        assert_eq!((g.count, g.mean), (frames as u64 - 2, frames as f64));
    }
    let (header, rows) = r.table();
    assert_eq!(header.last().map(String::as_str), Some(column));
    assert!(
        rows[0].last().unwrap().starts_with("6.0000"),
        "{:?}",
        rows[0]
    );
}
