//! A run directory written the way weft-train writes it loads into a [`Predictor`] that
//! animates exactly like the model it was saved from; mismatched runs are refused by name.

mod common;

use std::path::{Path, PathBuf};

use burn::module::Module;
use common::{case, host, model};
use weft_models::multilevel::{
    FrameInputs, GarmentInput, MultilevelConfig, Predictor, RUN_FORMAT_VERSION,
};
use weft_models::Clip;

struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("weft-models-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("checkpoints")).unwrap();
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn write_config(run: &Path, version: i64, preset: &str, cfg: &MultilevelConfig) {
    let model: toml::Table = toml::from_str(&cfg.to_toml().unwrap()).unwrap();
    let mut t = toml::Table::new();
    t.insert("format_version".into(), toml::Value::Integer(version));
    t.insert("preset".into(), toml::Value::String(preset.into()));
    t.insert("model".into(), toml::Value::Table(model));
    std::fs::write(run.join("config.toml"), toml::to_string(&t).unwrap()).unwrap();
}

#[test]
fn predictor_round_trip_and_mismatches() {
    let c = case();
    let cfg = MultilevelConfig::new().with_mp_submodules(1);
    let net = model(&cfg, 11, false);
    let dir = TempDir::new("predictor");
    let run = dir.0.as_path();
    net.clone()
        .save_file(run.join("checkpoints/step-000001.bpk"))
        .unwrap();
    std::fs::write(run.join("checkpoints/latest"), "step-000001.bpk\n").unwrap();
    write_config(run, RUN_FORMAT_VERSION, "cpu", &cfg);

    let predictor = Predictor::load(run).expect("load the run");
    assert_eq!(predictor.config(), &cfg);
    let frames = predictor
        .animate(
            &c.garment,
            &c.body,
            &Clip {
                betas: &c.betas,
                poses: &c.poses,
                trans: &c.trans,
                fps: c.fps,
            },
        )
        .unwrap();
    assert_eq!(frames.len(), c.poses.len());
    let g = GarmentInput::new(&c.garment, &c.body, &c.betas, &cfg).unwrap();
    let f = FrameInputs::new(
        &c.body,
        &g,
        &Clip {
            betas: &c.betas,
            poses: &c.poses,
            trans: &c.trans,
            fps: c.fps,
        },
        0..c.poses.len(),
        &cfg,
    )
    .unwrap();
    let want = host(
        net.forward(&net.encode_pair(&g).unwrap(), &g, &f)
            .unwrap()
            .vertices,
    );
    let got: Vec<f32> = frames.iter().flatten().flatten().copied().collect();
    assert_eq!(got.len(), want.len());
    let worst = got
        .iter()
        .zip(&want)
        .fold(0.0f32, |a, (x, y)| a.max((x - y).abs()));
    assert!(worst < 1e-6, "loaded model differs by {worst}");

    // A run written before `body_contact` existed: its [model] table lacks the key, and
    // its model had no contact input.
    let older = cfg.clone().with_body_contact(false);
    model(&older, 12, false)
        .save_file(run.join("checkpoints/step-000001.bpk"))
        .unwrap();
    write_config(run, RUN_FORMAT_VERSION, "cpu", &older);
    let text = std::fs::read_to_string(run.join("config.toml")).unwrap();
    let text: String = text
        .lines()
        .filter(|l| !l.starts_with("body_contact"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(run.join("config.toml"), text).unwrap();
    let loaded = Predictor::load(run).expect("a run from before body_contact");
    assert!(!loaded.config().body_contact);

    // Another format version.
    write_config(run, RUN_FORMAT_VERSION + 1, "cpu", &cfg);
    let m = Predictor::load(run).unwrap_err().to_string();
    assert!(
        m.contains("format_version") && m.contains("config.toml"),
        "{m}"
    );
    // The preset line disagrees with the [model] table.
    write_config(run, RUN_FORMAT_VERSION, "paper", &cfg);
    let m = Predictor::load(run).unwrap_err().to_string();
    assert!(m.contains("preset"), "{m}");
    // A checkpoint of another model configuration.
    let wider = cfg
        .clone()
        .with_feature_width(8)
        .with_preset("custom".into());
    write_config(run, RUN_FORMAT_VERSION, "custom", &wider);
    let m = Predictor::load(run).unwrap_err().to_string();
    assert!(
        m.contains("step-000001.bpk") && m.contains("does not fit"),
        "{m}"
    );
    // No checkpoint.
    std::fs::remove_file(run.join("checkpoints/latest")).unwrap();
    let m = Predictor::load(run).unwrap_err().to_string();
    assert!(m.contains("latest"), "{m}");
}
