//! Seed 001's case 1 end to end through the real binary: `weft data characters` builds a
//! character dataset with the elastic-skin truth, `weft train --model densegats` trains
//! on it, `weft eval` tables it against LBS and DQS, `weft animate` runs the run on a
//! character mesh; and the errors a user meets on the way.

use std::path::Path;

mod common;
use common::{s, scratch, stderr, stdout, weft};

/// Three undressed characters (one per split), three poses each: the smallest dataset
/// that exercises every split.
const MICRO: &str = r#"
tops = []
bottoms = []
random_poses = 2
motions = ["walk"]
frames_per_motion = 1
beta_components = 1

[characters]
train = 1
validation = 1
test = 1
"#;

fn build(dir: &Path, config: &Path) -> std::process::Output {
    weft(&["data", "characters", "--config", s(config), "--out", s(dir)])
}

#[test]
fn characters_train_evaluate_and_animate() {
    let root = scratch("characters-e2e");
    let config = root.join("micro.toml");
    std::fs::write(&config, MICRO).unwrap();
    let data = root.join("chars");
    let o = build(&data, &config);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("3 characters built"), "{}", stdout(&o));
    let manifest = std::fs::read_to_string(data.join("characters.json")).unwrap();
    assert!(
        manifest.contains("\"c002\"") && manifest.contains("\"test\""),
        "{manifest}"
    );
    let first = std::fs::read(data.join("c000.safetensors")).unwrap();

    // Resuming keeps finished characters; a damaged file is rebuilt, byte for byte.
    let mut broken = first.clone();
    let last = broken.len() - 1;
    broken[last] ^= 0xff;
    std::fs::write(data.join("c000.safetensors"), &broken).unwrap();
    let o = build(&data, &config);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("1 characters built") && stdout(&o).contains("2 kept"),
        "{}",
        stdout(&o)
    );
    assert_eq!(std::fs::read(data.join("c000.safetensors")).unwrap(), first);

    // Another config over the same directory is refused.
    let other = root.join("other.toml");
    std::fs::write(
        &other,
        MICRO.replace("random_poses = 2", "random_poses = 3"),
    )
    .unwrap();
    let o = build(&data, &other);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("another config"), "{}", stderr(&o));

    let run = root.join("run");
    let o = weft(&[
        "train",
        "--model",
        "densegats",
        "--data",
        s(&data),
        "--out",
        s(&run),
        "--steps",
        "3",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(run.join("normalizer.json").is_file());
    assert!(stdout(&o).contains("mean_error_cm"), "{}", stdout(&o));

    let table = root.join("table");
    let o = weft(&["eval", s(&run), "--data", s(&data), "--out", s(&table)]);
    assert!(o.status.success(), "{}", stderr(&o));
    for picture in ["characters", "elbows", "knees", "shoulders", "hips"] {
        let path = table.join(format!("{picture}.png"));
        assert!(std::fs::metadata(&path).unwrap().len() > 1000, "{path:?}");
    }
    let md = std::fs::read_to_string(table.join("characters.md")).unwrap();
    for row in [
        "LBS (8 influences)",
        "DQS (8 influences)",
        "| run |",
        "c002",
        "| method | elbows | knees | shoulders | hips |",
    ] {
        assert!(md.contains(row), "{row} missing:\n{md}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(table.join("characters.json")).unwrap())
            .unwrap();
    let methods = json["methods"].as_array().unwrap();
    assert_eq!(methods.len(), 3);
    // LBS's errors sit at the joints: every region's mean exceeds its whole-mesh mean.
    let lbs = &methods[0];
    assert!(
        lbs["regions_cm"]
            .as_array()
            .unwrap()
            .iter()
            .all(|r| r.as_f64().unwrap() > lbs["mean_cm"].as_f64().unwrap()),
        "{lbs}"
    );
    for m in methods {
        let mean = m["mean_cm"].as_f64().unwrap();
        assert!(mean.is_finite() && mean > 0.0, "{m}");
        assert!(m["max_cm"].as_f64().unwrap() >= mean);
        assert_eq!(m["regions_cm"].as_array().unwrap().len(), 4, "{m}");
    }

    // Any character mesh on the body: here a t-shirt alone, bound at its shape.
    let shirt = root.join("shirt.obj");
    common::garment(&shirt, "tshirt", 400, 1);
    let out = root.join("walk.pc2");
    let o = weft(&[
        "animate",
        s(&run),
        "--character",
        s(&shirt),
        "--motion",
        "walk",
        "--frames",
        "2",
        "--format",
        "pc2",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::metadata(&out).unwrap().len() > 0);

    // A run of another model kind is not a refinement run; a garment dataset is not a
    // character dataset.
    let o = weft(&["eval", s(&run), "--data", s(&root)]);
    assert!(!o.status.success());
}

#[test]
fn bad_character_configs_name_the_field() {
    let root = scratch("characters-bad");
    let config = root.join("bad.toml");
    std::fs::write(&config, "tops = [\"skirt\"]\n").unwrap();
    let o = build(&root.join("out"), &config);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("tops[0]"), "{}", stderr(&o));
    std::fs::write(&config, "pose_range = 2.0\n").unwrap();
    let o = build(&root.join("out"), &config);
    assert!(stderr(&o).contains("pose_range"), "{}", stderr(&o));
    let o = weft(&["data", "characters", "--print-config", "--preset", "paper"]);
    assert!(o.status.success());
    assert!(stdout(&o).contains("random_poses = 150"), "{}", stdout(&o));
    let o = weft(&[
        "train",
        "--model",
        "densegats",
        "--data",
        s(&root),
        "--out",
        s(&root.join("r")),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("characters.json"), "{}", stderr(&o));
}
