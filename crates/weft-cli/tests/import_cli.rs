//! Issue 18 item 3, end to end through the binary: simulations made outside weft's
//! dataset generator (here by `weft simulate`, standing in for Marvelous Designer or
//! Houdini: a PC2 cache, an OBJ sequence and an .npy, with the motion as AMASS .npz and
//! BVH) are imported with `weft data import`, verified, trained on by Multilevel and
//! evaluated.

use std::path::Path;

mod common;
use common::{garment, s, scratch, stderr, stdout, weft};

/// `weft simulate` of `g` on `motion` (3 frames) into `out`, with an OBJ sequence.
fn simulate(g: &Path, motion: &Path, out: &Path) {
    let o = weft(&[
        "simulate",
        "--garment",
        s(g),
        "--motion",
        s(motion),
        "--frames",
        "3",
        "--warmup",
        "2",
        "--substeps",
        "2",
        "--material",
        "silk",
        "--out",
        s(out),
        "--obj",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn imported_simulations_train_and_evaluate_multilevel() {
    let dir = scratch("import");
    let (walk, kick) = (dir.join("walk.npz"), dir.join("kick.bvh"));
    for (kind, path) in [("walk", &walk), ("kick", &kick)] {
        let o = weft(&[
            "motion",
            "generate",
            "--kind",
            kind,
            "--frames",
            "6",
            "--out",
            s(path),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    for seed in 1..=3 {
        let g = dir.join(format!("skirt{seed}.obj"));
        garment(&g, "skirt", 300, seed);
        let motion = if seed == 2 { &kick } else { &walk };
        simulate(&g, motion, &dir.join(format!("sim{seed}")));
    }
    let spec = dir.join("import.toml");
    std::fs::write(
        &spec,
        r#"fps = 30
[[garments]]
id = "skirt1"
template = "skirt1.obj"
kind = "skirt"
[[garments]]
id = "skirt2"
template = "skirt2.obj"
kind = "skirt"
[[garments]]
id = "skirt3"
template = "skirt3.obj"
kind = "skirt"

[[sequences]]
garment = "skirt1"
cache = "sim1/frames.pc2"
motion = "walk.npz"
split = "train"
[[sequences]]
garment = "skirt1"
cache = "sim1/obj"
motion = "walk.npz"
split = "train"
[[sequences]]
garment = "skirt2"
cache = "sim2/frames.npy"
motion = "kick.bvh"
split = "validation"
[[sequences]]
garment = "skirt3"
cache = "sim3/frames.pc2"
motion = "walk.npz"
split = "test"
"#,
    )
    .unwrap();
    let data = dir.join("data");
    let o = weft(&["data", "import", s(&spec), "--out", s(&data)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).starts_with("imported 4 sequences (2 train, 1 validation, 1 test; 12 frames)"),
        "{}",
        stdout(&o)
    );
    let o = weft(&["data", "info", s(&data), "--verify"]);
    assert!(o.status.success(), "{}", stderr(&o));

    let run = dir.join("run");
    let o = weft(&[
        "train",
        "--data",
        s(&data),
        "--out",
        s(&run),
        "--steps",
        "2",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("trained 2 steps"), "{}", stdout(&o));
    let o = weft(&["eval", s(&run), "--data", s(&data), "--json", "--no-timing"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(r["split"], "test");
    assert_eq!(r["frames"].as_u64(), Some(3));
    let lbs = r["methods"][1]["overall"]["e_verts_mm"]["mean"]
        .as_f64()
        .unwrap();
    assert!(lbs.is_finite() && lbs > 0.0, "{r}");

    // A second import into the same directory is refused, naming it.
    let o = weft(&["data", "import", s(&spec), "--out", s(&data)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("not an empty directory"),
        "{}",
        stderr(&o)
    );
}
