//! HOOD through the real binary: `weft train --model hood` with no dataset (a tiny
//! config: one 300-vertex skirt on one body, a walk, rollouts of two steps), the same
//! curve from the same seed, resume, `weft animate` with a material, a material map and
//! buttons, and the errors of bad input.

use std::path::Path;

use weft_mesh::export::npy::write_npy;

mod common;
use common::{garment, s, scratch, stderr, stdout, weft};

/// A config small enough for a debug build: one garment, one shape, a 12-frame walk,
/// a two-level network of width 8. Three items a step and replay always: step 3's last
/// item goes on with the rollout step 1's first left, so the resume below needs the
/// kept rollouts from step 2's checkpoint.
const TINY: &str = r#"
[model]
latent = 8
hidden_layers = 1
levels = 2
schedule = "0,1 | 1"

[train]
garments = ["skirt"]
styles = 1
shapes = 1
garment_vertices = 300
motions = ["walk"]
motion_frames = 12
max_rollout = 2
rollout_every = 2
validation_scenes = 1
validation_frames = 5
checkpoint_every = 2
validate_every = 2
batch = 3
replay = 1.0
"#;

fn train(config: &Path, run: &Path, steps: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "train",
        "--model",
        "hood",
        "--config",
        s(config),
        "--out",
        s(run),
        "--steps",
        steps,
        "--quiet",
    ];
    args.extend_from_slice(extra);
    weft(&args)
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

fn losses(run: &Path) -> Vec<String> {
    std::fs::read_to_string(run.join("metrics.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            format!("{} {}", v["loss"], v["terms"])
        })
        .collect()
}

#[test]
fn hood_trains_resumes_and_animates() {
    let dir = scratch("hood");
    let config = dir.join("tiny.toml");
    std::fs::write(&config, TINY).unwrap();
    let run = dir.join("run");
    let o = train(&config, &run, "3", &[]);
    let (out, err) = (stdout(&o), stderr(&o));
    assert!(o.status.success(), "{err}");
    assert!(out.contains("trained 3 steps"), "{out}");
    assert!(out.contains("stage rollout 2"), "{out}");
    assert!(
        out.contains("potential") && out.contains("inside_percent"),
        "{out}"
    );
    assert!(err.contains("1 garments x 1 motions"), "{err}");
    for f in ["config.toml", "hood.json", "checkpoints/latest"] {
        assert!(run.join(f).exists(), "{f} missing");
    }
    let log = std::fs::read_to_string(run.join("metrics.jsonl")).unwrap();
    for term in [
        "stretching",
        "bending",
        "gravity",
        "inertia",
        "collision",
        "friction",
    ] {
        assert!(log.contains(term), "{term} not logged");
    }

    // The same seed gives the same curve; a run resumed after 2 steps ends where the
    // uninterrupted one did.
    let again = dir.join("again");
    assert!(train(&config, &again, "3", &[]).status.success());
    assert_eq!(losses(&run), losses(&again));
    // A kill after step 2: the run as it was then (step 3's checkpoint not yet written).
    let resumed = dir.join("resumed");
    copy_dir(&run, &resumed);
    let cp = resumed.join("checkpoints");
    for f in [
        "step-000003.bpk",
        "step-000003.optim.bpk",
        "step-000003.state.json",
    ] {
        std::fs::remove_file(cp.join(f)).unwrap();
    }
    std::fs::write(cp.join("latest"), "step-000002.bpk").unwrap();
    let o = weft(&[
        "train",
        "--model",
        "hood",
        "--out",
        s(&resumed),
        "--resume",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(losses(&run), losses(&resumed));

    // Animate an unseen garment on an unseen walk.
    let skirt = dir.join("skirt.obj");
    garment(&skirt, "skirt", 320, 7);
    let anim_run = |run: &Path, extra: &[&str], out: &Path| {
        let mut args = vec![
            "animate",
            s(run),
            "--garment",
            s(&skirt),
            "--motion",
            "walk",
            "--seed",
            "5",
            "--frames",
            "6",
            "--format",
            "pc2",
            "--out",
            s(out),
        ];
        args.extend_from_slice(extra);
        weft(&args)
    };
    let anim = |extra: &[&str], out: &Path| anim_run(&run, extra, out);
    let plain = dir.join("plain.pc2");
    let o = anim(&[], &plain);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("6 frames"), "{}", stdout(&o));
    let silk = dir.join("silk.pc2");
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let o = anim(&["--material", "silk", "--json"], &silk);
    assert!(o.status.success(), "{}", stderr(&o));
    // Silk is stiffer than any material of HOOD's ranges: said, in the report too,
    // and read as the nearest one inside.
    let e = stderr(&o);
    assert!(
        e.contains("warning: --material silk: μ 245.") && e.contains("nearest material inside"),
        "{e}"
    );
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let outside = report["materials_outside"].as_array().unwrap();
    assert_eq!(outside.len(), 1, "{report}");
    assert!(
        outside[0].as_str().unwrap().starts_with("silk: μ"),
        "{report}"
    );
    // The material enters the network: the frames differ.
    assert_ne!(
        std::fs::read(&plain).unwrap(),
        std::fs::read(&silk).unwrap()
    );

    // A 120 fps motion: the network steps at its 1/30 s, every motion frame comes back.
    let o = anim(&["--fps", "120"], &dir.join("fast.pc2"));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("6 frames"), "{}", stdout(&o));

    // A two-material map, buttons and unbuttoning.
    let n = weft_mesh::load_mesh(&skirt).unwrap().mesh.vertex_count();
    let map = dir.join("map.npy");
    let halves: Vec<i64> = (0..n as i64).map(|i| i % 2).collect();
    write_npy(&map, &[n], &halves).unwrap();
    let pairs = dir.join("buttons.json");
    std::fs::write(&pairs, "[[0, 5], [10, 15]]").unwrap();
    let o = anim(
        &[
            "--material",
            "denim,silk",
            "--material-map",
            s(&map),
            "--buttons",
            s(&pairs),
            "--unbutton-at",
            "3",
        ],
        &dir.join("mixed.pc2"),
    );
    assert!(o.status.success(), "{}", stderr(&o));

    // Run-time corrections other than the run's own projection (the cpu preset's 5 %,
    // 5 %, 2 mm): reported, and they change the frames.
    let corrected = dir.join("corrected.pc2");
    let o = anim(
        &["--strain-limit", "10", "--push-out", "4", "--json"],
        &corrected,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(
        report["materials_outside"],
        serde_json::json!([]),
        "{report}"
    );
    let c = &report["rollout_corrections"];
    assert!(
        c["edges_limited"].is_u64() && c["vertices_projected"].is_u64(),
        "{report}"
    );
    assert!(report["pushed_out_vertices"].is_null(), "{report}");
    assert_ne!(
        std::fs::read(&plain).unwrap(),
        std::fs::read(&corrected).unwrap()
    );

    // Newton iterations of the step's potential after each network step: other frames.
    let refined = dir.join("refined.pc2");
    let o = anim(&["--refine", "2"], &refined);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(
        std::fs::read(&plain).unwrap(),
        std::fs::read(&refined).unwrap()
    );
    // The run's objective in place of its network: other frames again.
    let objective = dir.join("objective.pc2");
    let o = anim(&["--objective"], &objective);
    assert!(o.status.success(), "{}", stderr(&o));
    for other in [&plain, &refined] {
        assert_ne!(
            std::fs::read(other).unwrap(),
            std::fs::read(&objective).unwrap()
        );
    }

    // The run's step ends in a projection (the cpu preset's `[model] project_*`): a
    // rollout reports it by default; --no-projection gives the network's steps alone,
    // which a copy of the run without the projection gives by default.
    let o = anim(&["--json"], &dir.join("own.pc2"));
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(
        report["rollout_corrections"]["edges_limited"].is_u64(),
        "{report}"
    );
    let alone = dir.join("alone.pc2");
    let o = anim(&["--no-projection"], &alone);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(
        std::fs::read(&plain).unwrap(),
        std::fs::read(&alone).unwrap()
    );
    let unprojected = dir.join("unprojected");
    copy_dir(&run, &unprojected);
    let text = std::fs::read_to_string(unprojected.join("config.toml")).unwrap();
    assert!(text.contains("project_margin = 0.002"), "{text}");
    let text: String = text
        .lines()
        .filter(|l| !l.starts_with("project_"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(unprojected.join("config.toml"), text).unwrap();
    let own = dir.join("unprojected.pc2");
    let o = anim_run(&unprojected, &["--json"], &own);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(report["rollout_corrections"].is_null(), "{report}");
    assert_eq!(std::fs::read(&alone).unwrap(), std::fs::read(&own).unwrap());

    // Bad input: named, non-zero, nothing written.
    let short = dir.join("short.npy");
    write_npy(&short, &[3], &[0i64, 1, 0]).unwrap();
    let far = dir.join("far.json");
    std::fs::write(&far, format!("[[0, {n}]]")).unwrap();
    for (extra, needle) in [
        (
            vec!["--material", "denim,silk", "--material-map", s(&short)],
            "one per garment vertex",
        ),
        (vec!["--material", "denim,silk"], "needs --material-map"),
        (vec!["--buttons", s(&far)], "button pair 0"),
        (vec!["--strain-limit=-1"], "--strain-limit -1"),
        (
            vec!["--compression-limit", "100"],
            "--compression-limit 100",
        ),
    ] {
        let out = dir.join("bad.pc2");
        let o = anim(&extra, &out);
        assert!(!o.status.success(), "{extra:?} was accepted");
        assert!(stderr(&o).contains(needle), "{extra:?}: {}", stderr(&o));
        assert!(!out.exists(), "{extra:?} wrote a file");
    }
    // A run whose [model] holds an unknown key: named, as every run's config is read.
    let badkey = dir.join("badkey");
    copy_dir(&run, &badkey);
    let text = std::fs::read_to_string(badkey.join("config.toml")).unwrap();
    std::fs::write(
        badkey.join("config.toml"),
        text.replace("[model]\n", "[model]\nlatnet = 32\n"),
    )
    .unwrap();
    let k = dir.join("k.pc2");
    let o = weft(&[
        "animate",
        s(&badkey),
        "--garment",
        s(&skirt),
        "--motion",
        "walk",
        "--frames",
        "3",
        "--format",
        "pc2",
        "--out",
        s(&k),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("model.latnet"), "{}", stderr(&o));
    assert!(!k.exists());
    let o = weft(&[
        "train",
        "--model",
        "hood",
        "--data",
        s(&dir),
        "--out",
        s(&dir.join("x")),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("not a dataset"), "{}", stderr(&o));
}
