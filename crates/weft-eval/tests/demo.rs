//! The demo pipeline end to end with the micro configuration and a stand-in simulator
//! (LBS plus a smooth sag: cheap, deterministic, and not what the baseline predicts), so
//! CI runs every stage — data, training, evaluation, animation, attribution, report —
//! in seconds; `weft demo` runs the same code with the real simulator.

use std::path::PathBuf;

use weft_data::{SequenceSimulator, Silent, SimInput, SimOutcome};
use weft_eval::demo::{run_demo, DemoOptions};
use weft_eval::LbsBaseline;

struct Sagging;

impl SequenceSimulator for Sagging {
    fn simulate(
        &self,
        input: &SimInput<'_>,
        on_frame: &mut dyn FnMut(),
    ) -> Result<SimOutcome, String> {
        let betas: Vec<f32> = input.betas.iter().map(|&b| b as f32).collect();
        let poses = weft_eval::animate::flat_poses(input.motion);
        let frames = LbsBaseline::new(input.garment, input.body, &betas)
            .and_then(|b| b.animate(input.body, &poses, input.motion.trans()))
            .map_err(|e| e.to_string())?;
        let frames = frames
            .into_iter()
            .enumerate()
            .map(|(t, f)| {
                on_frame();
                f.into_iter()
                    .map(|p| [p[0], p[1] - 0.01 * (1.0 + (0.3 * t as f32).sin()), p[2]])
                    .collect()
            })
            .collect();
        Ok(SimOutcome::Finished {
            frames,
            stats: serde_json::Value::Null,
        })
    }
}

#[test]
fn quick_demo_runs_every_stage_and_resumes() {
    let out = std::env::temp_dir().join(format!("weft-eval-demo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let opts = DemoOptions {
        out: out.clone(),
        quick: true,
        steps: None,
    };
    let mut lines = Vec::new();
    let s = run_demo(&opts, &Sagging, &Silent, &mut |l| lines.push(l.to_owned())).unwrap();
    assert!(s.report.is_file());
    assert!(s.model_mm.is_finite() && s.lbs_mm > 5.0, "{s:?}");
    let files: [PathBuf; 7] = [
        out.join("run/report/eval.json"),
        out.join("run/report/eval.html"),
        out.join("animation/animation.glb"),
        out.join("animation/garment.pc2"),
        out.join("animation/garment.obj"),
        out.join("animation/animation.png"),
        out.join("attribution.png"),
    ];
    for f in &files {
        assert!(f.is_file(), "{} missing; log:\n{}", f.display(), lines.join("\n"));
    }
    assert!(lines.iter().any(|l| l.starts_with("[5/5]")));
    // A second run reuses the data and the finished training.
    let mut again = Vec::new();
    run_demo(&opts, &Sagging, &Silent, &mut |l| again.push(l.to_owned())).unwrap();
    assert!(again.iter().any(|l| l.contains("0 simulated")), "{}", again.join("\n"));
    assert!(again.iter().any(|l| l.contains("resuming")), "{}", again.join("\n"));
    let _ = std::fs::remove_dir_all(&out);
}
