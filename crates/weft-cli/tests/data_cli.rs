//! End-to-end tests of `weft data …` through the real binary.
//!
//! Simulating is slow in the test profile, so the datasets `info` and `merge` read are
//! made with weft-data's library and a cheap stand-in simulator; the one test that runs
//! `weft data generate` with the real simulator is ignored (run it with `--ignored`).

use weft_data::manifest::Job;
use weft_data::{
    generate, DataConfig, Dataset, GarmentSpec, GenerateOptions, MotionSpec, SequenceSimulator,
    Silent, SimInput, SimOutcome,
};

mod common;
use common::{s, scratch, stderr, stdout, weft};

/// The rest garment moved with the root, one frame per motion frame; diverges at frame 1
/// on bodies with β₀ = 1.
struct StandIn;

impl SequenceSimulator for StandIn {
    fn simulate(
        &self,
        input: &SimInput<'_>,
        on_frame: &mut dyn FnMut(),
    ) -> Result<SimOutcome, String> {
        let mut frames = Vec::new();
        for t in 0..input.motion.frame_count() {
            if input.betas[0] == 1.0 && t == 1 {
                return Ok(SimOutcome::Diverged {
                    frame: 1,
                    message: "a vertex moved at 1e9 m/s".into(),
                    frames,
                    stats: serde_json::json!([]),
                });
            }
            let tr = input.motion.trans()[t];
            frames.push(
                input
                    .garment
                    .positions
                    .iter()
                    .map(|p| std::array::from_fn(|k| (p[k] + f64::from(tr[k])) as f32))
                    .collect(),
            );
            on_frame();
        }
        Ok(SimOutcome::Finished {
            frames,
            stats: serde_json::json!([]),
        })
    }
}

fn small_config() -> DataConfig {
    let g = |kind: &str, seed| GarmentSpec {
        kind: kind.into(),
        vertices: 300,
        seed: Some(seed),
        material: None,
        length: None,
    };
    let m = |kind: &str, seed| MotionSpec {
        kind: Some(kind.into()),
        seed: Some(seed),
        frames: Some(2),
        ..MotionSpec::default()
    };
    let mut c = DataConfig::tiny();
    c.train.garments = vec![g("skirt", 1)];
    c.train.betas = vec![vec![0.0], vec![1.0]];
    c.train.motions = vec![m("walk", 1)];
    c.validation.garments = vec![g("skirt", 2)];
    c.validation.motions = vec![m("kick", 2)];
    c.test.garments = vec![g("tshirt", 3)];
    c.test.motions = vec![m("twist", 3)];
    c
}

#[test]
fn print_config_writes_a_preset_that_reads_back() {
    let dir = scratch("print");
    for preset in ["tiny", "small", "paper", "garfit-tiny", "garfit-paper"] {
        let o = weft(&["data", "generate", "--preset", preset, "--print-config"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = stdout(&o);
        assert!(
            text.contains("[train]") || text.contains("[[train.garments]]"),
            "{text}"
        );
        let path = dir.join(format!("{preset}.toml"));
        std::fs::write(&path, &text).unwrap();
        let back = DataConfig::load(&path).unwrap();
        assert_eq!(back, DataConfig::preset(preset).unwrap());
        // --config FILE --print-config echoes it, with --seed applied.
        let o = weft(&[
            "data",
            "generate",
            "--config",
            s(&path),
            "--seed",
            "9",
            "--print-config",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stdout(&o).contains("seed = 9"), "{}", stdout(&o));
    }
}

#[test]
fn info_shows_splits_and_diverged_sequences() {
    let dir = scratch("info");
    generate(
        &small_config(),
        &dir,
        &GenerateOptions::default(),
        &StandIn,
        &Silent,
    )
    .unwrap();
    let o = weft(&["data", "info", s(&dir)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for needle in [
        "train",
        "validation",
        "test",
        "skirt",
        "tshirt",
        "silk",
        "garment vertices:",
        "diverged: train-g000-skirt-b001-m000-walk at frame 1 (1 frames kept)",
    ] {
        assert!(text.contains(needle), "{needle:?} missing in\n{text}");
    }
    let o = weft(&["data", "info", s(&dir), "--verify"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("verified: 4 shards, 7 frames"),
        "{}",
        stdout(&o)
    );
    let o = weft(&["data", "info", s(&dir), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["splits"][0]["split"], "train");
    assert_eq!(v["splits"][0]["sequences"], 2);
    assert_eq!(v["problems"][0]["status"], "diverged");
    assert!(v["disk_bytes"].as_u64().unwrap() > 0);
}

#[test]
fn verify_fails_naming_a_shard_changed_after_it_was_written() {
    let dir = scratch("verify-changed");
    generate(
        &small_config(),
        &dir,
        &GenerateOptions::default(),
        &StandIn,
        &Silent,
    )
    .unwrap();
    let victim = Dataset::open(&dir).unwrap().records()[0].clone();
    // Move the first vertex of the first frame by 0.5 m, in place.
    let path = dir.join(&victim.shard);
    let mut bytes = std::fs::read(&path).unwrap();
    let header_len = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + header_len]).unwrap();
    let at = 8 + header_len + header["positions"]["data_offsets"][0].as_u64().unwrap() as usize;
    let x = f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) + 0.5;
    bytes[at..at + 4].copy_from_slice(&x.to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();

    let o = weft(&["data", "info", s(&dir), "--verify"]);
    assert!(!o.status.success(), "{}", stdout(&o));
    let out = stdout(&o);
    assert!(
        out.contains(&format!("broken shard: {}", victim.id))
            && out.contains(&victim.shard)
            && out.contains("changed since it was written")
            && out.contains("to repair: run `weft data generate`"),
        "{out}"
    );
    let err = stderr(&o);
    assert!(
        err.contains("1 of 4 shards")
            && err.contains(&victim.shard)
            && err.contains("weft data generate"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    // Without --verify the summary does not read the shards.
    assert!(weft(&["data", "info", s(&dir)]).status.success());
}

#[test]
fn more_beta_components_than_the_body_has_are_refused_naming_the_file() {
    let dir = scratch("beta-components");
    let mut c = small_config();
    c.beta_components = 100;
    let config = dir.join("many-betas.toml");
    std::fs::write(&config, c.to_toml().unwrap()).unwrap();
    let out = dir.join("out");
    let o = weft(&["data", "generate", "--config", s(&config), "--out", s(&out)]);
    assert!(!o.status.success(), "{}", stdout(&o));
    let err = stderr(&o);
    for needle in [
        "many-betas.toml",
        "beta_components",
        "100",
        "10 shape components",
        "0 to 10",
    ] {
        assert!(err.contains(needle), "{needle:?} not in {err}");
    }
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(!out.join("manifest.json").exists());
}

#[test]
fn merge_joins_shard_jobs() {
    let dir = scratch("merge");
    let c = small_config();
    for i in 0..2 {
        let job = Some(Job { index: i, count: 2 });
        generate(&c, &dir, &GenerateOptions { job }, &StandIn, &Silent).unwrap();
    }
    let o = weft(&["data", "info", s(&dir)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("weft data merge"), "{}", stderr(&o));
    let o = weft(&["data", "merge", s(&dir)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.join("manifest.json").is_file());
    let o = weft(&["data", "info", s(&dir)]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn bad_input_is_one_line_naming_the_problem() {
    let dir = scratch("bad");
    let cases: Vec<(Vec<String>, &str)> = {
        let bad_toml = dir.join("bad.toml");
        std::fs::write(
            &bad_toml,
            "[train]\nbetas = [[0.0]]\nmotions = [{ kind = \"walk\" }]\ngarments = [{ kind = \"cape\", vertices = 500 }]\n",
        )
        .unwrap();
        let typo = dir.join("typo.toml");
        std::fs::write(&typo, "fpz = 30\n").unwrap();
        let out = s(&dir.join("out")).to_string();
        vec![
            (
                vec![
                    "--preset".into(),
                    "huge".into(),
                    "--out".into(),
                    out.clone(),
                ],
                "tiny, small, paper, garfit-tiny, garfit-paper",
            ),
            (
                vec![
                    "--config".into(),
                    s(&bad_toml).into(),
                    "--out".into(),
                    out.clone(),
                ],
                "train.garments[0].kind",
            ),
            (
                vec![
                    "--config".into(),
                    s(&typo).into(),
                    "--out".into(),
                    out.clone(),
                ],
                "fpz",
            ),
            (
                vec![
                    "--config".into(),
                    s(&dir.join("none.toml")).into(),
                    "--out".into(),
                    out.clone(),
                ],
                "none.toml",
            ),
            (
                vec!["--shard".into(), "2/2".into(), "--out".into(), out.clone()],
                "--shard",
            ),
        ]
    };
    for (args, needle) in cases {
        let mut all = vec!["data".to_string(), "generate".to_string()];
        all.extend(args);
        let refs: Vec<&str> = all.iter().map(String::as_str).collect();
        let o = weft(&refs);
        assert!(!o.status.success(), "{all:?} succeeded");
        let err = stderr(&o);
        assert!(err.contains(needle), "{all:?}: {needle:?} not in {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
    let o = weft(&["data", "info", s(&dir.join("nothing"))]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("manifest.json"), "{}", stderr(&o));
}

/// `weft data generate` with the real simulator on a one-sequence-per-split config.
/// Slow in the test profile; run with `cargo test -p weft-cli --release -- --ignored`.
#[test]
#[ignore]
fn generate_with_the_real_simulator() {
    let dir = scratch("real");
    let mut c = small_config();
    c.train.betas = vec![vec![0.0]];
    c.warmup_frames = 3;
    let config = dir.join("data.toml");
    std::fs::write(&config, c.to_toml().unwrap()).unwrap();
    let out = dir.join("out");
    let o = weft(&["data", "generate", "--config", s(&config), "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = weft(&["data", "info", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("garment vertices:"), "{}", stdout(&o));
}
