//! End-to-end tests of `weft train` and `weft config show` through the real binary.
//!
//! The dataset is made with weft-data's library and weft-eval's stand-in simulator
//! (LBS plus a sag), since the real simulator is slow in the test profile; what is
//! tested here is the command, its files and its errors.

use std::path::Path;

use weft_data::{generate, DataConfig, GarmentSpec, GenerateOptions, MotionSpec, Silent};
use weft_pipeline::stand_in::StandInSimulator;

mod common;
use common::{s, scratch, stderr, stdout, weft};

/// One training and one validation sequence of 3 frames, 300-vertex skirts.
fn dataset(dir: &Path) {
    let g = |seed| GarmentSpec {
        kind: "skirt".into(),
        vertices: 300,
        seed: Some(seed),
        material: None,
        length: None,
    };
    let m = |kind: &str, seed| MotionSpec {
        kind: Some(kind.into()),
        seed: Some(seed),
        frames: Some(3),
        ..MotionSpec::default()
    };
    let mut c = DataConfig::tiny();
    c.train.garments = vec![g(1)];
    c.train.betas = vec![vec![0.0]];
    c.train.motions = vec![m("walk", 1)];
    c.validation.garments = vec![g(2)];
    c.validation.motions = vec![m("kick", 2)];
    c.test.garments = vec![g(3)];
    c.test.motions = vec![m("twist", 3)];
    generate(
        &c,
        dir,
        &GenerateOptions::default(),
        &StandInSimulator,
        &Silent,
    )
    .expect("dataset");
}

#[test]
fn config_show_prints_every_default_as_toml() {
    for preset in ["cpu", "paper"] {
        let o = weft(&["config", "show", "--preset", preset]);
        let (out, err) = (stdout(&o), stderr(&o));
        assert!(o.status.success(), "{err}");
        for needle in [
            "format_version = 1",
            &format!("preset = \"{preset}\""),
            "[model]",
            "gg_widths = ",
            "mp_channels = ",
            "pooling = ",
            "[train]",
            "learning_rate = ",
            "steps = ",
            "window = ",
            "[train.weights]",
            "[train.schedule]",
            "supervised_window = 50",
        ] {
            assert!(out.contains(needle), "{needle:?} missing in\n{out}");
        }
    }
    let o = weft(&["config", "show", "--preset", "huge"]);
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.starts_with("error: ") && err.contains("huge"), "{err}");
}

#[test]
fn train_writes_a_run_resumes_and_refuses_mismatches() {
    let dir = scratch("run");
    let data = dir.join("data");
    dataset(&data);
    // A config file in the format `weft config show` prints, edited.
    let o = weft(&["config", "show"]);
    let shown = stdout(&o);
    let config = dir.join("short.toml");
    let edited: Vec<&str> = shown
        .lines()
        .map(|l| {
            if l.starts_with("checkpoint_every =") {
                "checkpoint_every = 2"
            } else if l.starts_with("validate_every =") {
                "validate_every = 2"
            } else {
                l
            }
        })
        .collect();
    assert!(edited.contains(&"checkpoint_every = 2") && edited.contains(&"validate_every = 2"));
    std::fs::write(&config, edited.join("\n")).unwrap();
    let run = dir.join("run");
    let args = |extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = ["train", "--data", s(&data), "--out", s(&run), "--quiet"]
            .iter()
            .map(|x| x.to_string())
            .collect();
        v.extend(extra.iter().map(|x| x.to_string()));
        v
    };
    let call = |a: Vec<String>| weft(&a.iter().map(String::as_str).collect::<Vec<_>>());

    let o = call(args(&["--config", s(&config), "--steps", "3"]));
    let (out, err) = (stdout(&o), stderr(&o));
    assert!(o.status.success(), "{err}");
    assert!(out.contains("trained 3 steps"), "{out}");
    assert!(out.contains("validation: e_verts_mm "), "{out}");
    for f in [
        "config.toml",
        "metrics.jsonl",
        "curves.png",
        "checkpoints/latest",
    ] {
        assert!(run.join(f).exists(), "{f} missing");
    }
    assert_eq!(
        std::fs::read_to_string(run.join("checkpoints/latest"))
            .unwrap()
            .trim(),
        "step-000003.bpk"
    );
    assert!(run.join("checkpoints/step-000002.optim.bpk").exists());
    let log = std::fs::read_to_string(run.join("metrics.jsonl")).unwrap();
    assert_eq!(log.lines().count(), 4, "{log}");

    // Resume of a finished run: nothing to do, success.
    let o = call(args(&["--resume"]));
    assert!(o.status.success(), "{}", stderr(&o));
    // A longer run is another configuration: named in the error.
    let o = call(args(&["--resume", "--config", s(&config), "--steps", "5"]));
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("train.steps"), "{err}");
    // Another preset.
    let o = call(args(&["--resume", "--preset", "paper"]));
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("preset"), "{err}");
    // A new run over the old one.
    let o = call(args(&["--config", s(&config), "--steps", "3"]));
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("already holds a trained run"), "{err}");
    // No dataset.
    let o = weft(&[
        "train",
        "--data",
        s(&dir.join("none")),
        "--out",
        s(&dir.join("r2")),
    ]);
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("weft data generate"), "{err}");
    assert!(!dir.join("r2").exists(), "nothing half-written");
    let _ = std::fs::remove_dir_all(&dir);
}
