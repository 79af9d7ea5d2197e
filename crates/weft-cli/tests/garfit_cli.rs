//! GarFitNet through the real binary: `weft train --model garfitnet` on a fit dataset
//! (garments made for one body, fitted onto others), `weft eval` (coarse and refined
//! rows, per-sequence scores), `weft animate --made-for`, and the errors of bad input.
//!
//! The dataset's garments are fitted with the real drape; the sequences come from the
//! stand-in simulator (LBS plus a sag), since what is tested is the commands.

use std::path::Path;

use weft_data::{generate, DataConfig, GarmentSpec, GenerateOptions, MotionSpec, Silent};
use weft_pipeline::stand_in::StandInSimulator;

mod common;
use common::{s, scratch, stderr, stdout, weft};

/// Two training pairs, one validation and one test pair, 3 frames each, 300-vertex skirts
/// made for β = 0.
fn dataset(dir: &Path) {
    let g = |seed, length: &str| GarmentSpec {
        kind: "skirt".into(),
        vertices: 300,
        seed: Some(seed),
        material: None,
        length: Some(length.into()),
    };
    let m = |kind: &str, seed| MotionSpec {
        kind: Some(kind.into()),
        seed: Some(seed),
        frames: Some(3),
        ..MotionSpec::default()
    };
    let mut c = DataConfig::garfit_tiny();
    c.warmup_frames = 2;
    c.train.garments = vec![g(1, "mini"), g(2, "knee")];
    c.train.betas = vec![vec![0.0, 0.0, 0.0, -1.0], vec![0.0, 0.0, 0.0, 1.0]];
    c.train.motions = vec![m("walk", 1)];
    c.train.motions_per_pair = 0;
    c.validation.garments = vec![g(3, "knee")];
    c.validation.motions = vec![m("kick", 2)];
    c.test.garments = vec![g(4, "maxi")];
    c.test.betas = vec![vec![0.0, 0.0, 0.0, 0.5]];
    c.test.motions = vec![m("jump", 3)];
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
fn garfitnet_trains_evaluates_and_animates() {
    let dir = scratch("garfit");
    let data = dir.join("data");
    dataset(&data);
    let run = dir.join("run");
    let o = weft(&[
        "train",
        "--model",
        "garfitnet",
        "--data",
        s(&data),
        "--out",
        s(&run),
        "--steps",
        "4",
        "--quiet",
    ]);
    let (out, err) = (stdout(&o), stderr(&o));
    assert!(o.status.success(), "{err}");
    assert!(out.contains("trained 4 steps"), "{out}");
    assert!(out.contains("stage refine"), "{out}");
    assert!(out.contains("refined_error_cm"), "{out}");
    assert!(err.contains("4 garment-body pairs"), "{err}");
    for f in ["config.toml", "garfit.json", "checkpoints/latest"] {
        assert!(run.join(f).exists(), "{f} missing");
    }
    // The same seed gives the same training curve.
    let again = dir.join("again");
    let o = weft(&[
        "train",
        "--model",
        "garfitnet",
        "--data",
        s(&data),
        "--out",
        s(&again),
        "--steps",
        "4",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let losses = |run: &Path| -> Vec<f64> {
        std::fs::read_to_string(run.join("metrics.jsonl"))
            .unwrap()
            .lines()
            .map(|l| {
                serde_json::from_str::<serde_json::Value>(l).unwrap()["loss"]
                    .as_f64()
                    .unwrap()
            })
            .collect()
    };
    assert_eq!(losses(&run), losses(&again));
    assert_eq!(losses(&run).len(), 5);

    // Evaluation: the refined and the coarse output beside the baselines, per sequence.
    let o = weft(&["eval", s(&run), "--data", s(&data), "--no-timing"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(run.join("report/eval.json")).unwrap()).unwrap();
    let names: Vec<&str> = report["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["GarFitNet", "GarFitNet coarse", "LBS only", "DQS only"]
    );
    let seqs = report["per_sequence"].as_array().unwrap();
    assert_eq!(seqs.len(), 1);
    assert_eq!(seqs[0]["e_verts_mm"].as_array().unwrap().len(), 4);
    assert_eq!(seqs[0]["body"].as_str().unwrap(), "b003");

    // The pattern, made for β = 0, fitted onto a fuller body and animated.
    let pattern = data.join("garments/g003-skirt.obj");
    let frames = dir.join("frames");
    let o = weft(&[
        "animate",
        s(&run),
        "--garment",
        s(&pattern),
        "--made-for",
        "0",
        "--betas",
        "0,0,0,1.2",
        "--motion",
        "walk",
        "--frames",
        "2",
        "--format",
        "obj",
        "--out",
        s(&frames),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_dir(&frames).unwrap().count(), 2);

    // A garment not on the body: named, nothing written.
    let away = dir.join("away.obj");
    let text = std::fs::read_to_string(&pattern).unwrap();
    let moved: String = text
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(rest) => {
                let v: Vec<f64> = rest
                    .split_whitespace()
                    .map(|x| x.parse().unwrap())
                    .collect();
                format!("v {} {} {}\n", v[0] + 3.0, v[1], v[2])
            }
            None => format!("{l}\n"),
        })
        .collect();
    std::fs::write(&away, moved).unwrap();
    let nowhere = dir.join("nowhere");
    let o = weft(&[
        "animate",
        s(&run),
        "--garment",
        s(&away),
        "--motion",
        "walk",
        "--frames",
        "2",
        "--format",
        "obj",
        "--out",
        s(&nowhere),
    ]);
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("not dressed on this body"), "{err}");
    assert!(!nowhere.exists());

    // Widths the data cannot feed: refused by field before any step.
    let wrong = dir.join("wrong.toml");
    std::fs::write(&wrong, "[model.network]\ngarfit_features = 84\n").unwrap();
    let o = weft(&[
        "train",
        "--model",
        "garfitnet",
        "--data",
        s(&data),
        "--out",
        s(&dir.join("wrong")),
        "--config",
        s(&wrong),
        "--quiet",
    ]);
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(
        err.contains("network.garfit_features = 84") && err.contains("85"),
        "{err}"
    );
    assert!(!dir.join("wrong/checkpoints").exists());

    // A run of another kind where a GarFitNet run is expected is refused by name.
    let o = weft(&[
        "train",
        "--model",
        "densegats",
        "--data",
        s(&data),
        "--out",
        s(&run),
        "--resume",
        "--quiet",
    ]);
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("garfitnet"), "{err}");
}
