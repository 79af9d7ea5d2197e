//! Any bytes as a run's config.toml: reading it the three ways weft does (the run header
//! of `weft_models::run::read_run_config`, the `[model]` table of a Multilevel predictor,
//! the preset-plus-overlay of `weft train --config` / `--resume`) never panics and holds at
//! most `linear_bound` bytes while it reads; a configuration that resolves writes back to
//! a config.toml that resolves to the same.
//!
//! The readers take a run directory, so the input is written to a file in a directory of
//! this process's own under the temp dir (tmpfs on Linux) first.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use weft_fuzz::{bounded, linear_bound};
use weft_models::multilevel::predictor::read_run_config as read_multilevel;
use weft_models::run::read_run_config;
use weft_train::MultilevelRun;

fn run_dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let base = if std::path::Path::new("/dev/shm").is_dir() {
            PathBuf::from("/dev/shm")
        } else {
            std::env::temp_dir()
        };
        let dir = base.join(format!("weft-fuzz-run-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary run directory");
        dir
    })
}

fuzz_target!(|data: &[u8]| {
    let dir = run_dir();
    let path = dir.join("config.toml");
    std::fs::write(&path, data).expect("writing the input");
    let ((header, model, run), _) = bounded(data.len(), linear_bound(data.len()), || {
        (
            read_run_config(dir).map(|(h, _)| h),
            read_multilevel(dir),
            MultilevelRun::from_run_dir(dir),
        )
    });
    for e in [header.as_ref().err().map(|e| e.to_string()), model.as_ref().err().map(|e| e.to_string())]
        .into_iter()
        .flatten()
    {
        assert!(e.contains("config.toml"), "an error that does not name the file: {e}");
    }
    if let Ok(model) = &model {
        model.validate().expect("a [model] that reads validates");
    }
    let Ok(run) = run else {
        return;
    };
    let text = run.to_toml().expect("a resolved configuration writes");
    std::fs::write(&path, &text).expect("writing the config back");
    let back = MultilevelRun::from_run_dir(dir).expect("a written configuration resolves");
    assert_eq!(back, run, "{text}");
});
