//! The demo pipeline end to end with the micro configuration and the stand-in simulator
//! (LBS plus a smooth sag: cheap, deterministic, and not what the baseline predicts), so
//! CI runs every stage — data, training, evaluation, animation, attribution, report —
//! in seconds; `weft demo` runs the same code with the real simulator.

use std::path::PathBuf;

use weft_data::Silent;
use weft_pipeline::demo::{run_demo, DemoOptions};
use weft_pipeline::stand_in::StandInSimulator;

#[test]
fn quick_demo_runs_every_stage_and_resumes() {
    let out = std::env::temp_dir().join(format!("weft-pipeline-demo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    // 4 steps, not the quick default of 6: the second run below, with no count given,
    // must finish the run it finds rather than refuse it as another.
    let opts = DemoOptions {
        out: out.clone(),
        quick: true,
        steps: Some(4),
    };
    let mut lines = Vec::new();
    let s = run_demo(&opts, &StandInSimulator, &Silent, &mut |l| {
        lines.push(l.to_owned())
    })
    .unwrap();
    assert!(s.report.is_file());
    assert!(s.model_mm.is_finite() && s.lbs_mm > 5.0, "{s:?}");
    let a = s.animation;
    assert!(
        (0.0..=1.0).contains(&a.inside) && a.deepest_mm >= 0.0 && a.strain_max >= a.strain_mean,
        "{s:?}"
    );
    assert!(a.frames > 0 && a.nonfinite == 0, "{s:?}");
    assert!(lines.iter().any(|l| l.contains("inside the body")));
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
        assert!(
            f.is_file(),
            "{} missing; log:\n{}",
            f.display(),
            lines.join("\n")
        );
    }
    assert!(lines.iter().any(|l| l.starts_with("[5/5]")));
    // A second run, with no step count, reuses the data and the finished training.
    let again_opts = DemoOptions {
        steps: None,
        ..opts.clone()
    };
    let mut again = Vec::new();
    run_demo(&again_opts, &StandInSimulator, &Silent, &mut |l| {
        again.push(l.to_owned())
    })
    .unwrap();
    assert!(
        again.iter().any(|l| l.contains("0 simulated")),
        "{}",
        again.join("\n")
    );
    assert!(
        again
            .iter()
            .any(|l| l.contains("resuming the run found there (4 steps)")),
        "{}",
        again.join("\n")
    );
    // An explicit count that differs is a different run, refused naming the field.
    let other = DemoOptions {
        steps: Some(5),
        ..opts.clone()
    };
    let err = run_demo(&other, &StandInSimulator, &Silent, &mut |_| {}).unwrap_err();
    let cause = std::error::Error::source(&err).map_or(String::new(), |c| c.to_string());
    assert!(cause.contains("steps"), "{err}: {cause}");
    let _ = std::fs::remove_dir_all(&out);
}
