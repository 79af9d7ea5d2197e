//! Any bytes as a checkpoint: loading them the ways weft does never panics and holds at
//! most `linear_bound` bytes while it loads:
//!
//! - as a model record into a (tiny) Multilevel model, as `weft train --resume` does
//!   (`weft_train::run::load_model_record`, from `RunDir::load`);
//! - as a model record from a file, as inference does (`Predictor::from_checkpoint`);
//! - as an optimiser record into the trainer's default optimiser (Adamax), as `--resume`
//!   does (`weft_train::run::load_optimizer_record`).
//!
//! A record that loads one way loads the other. burn-optim 0.22.1 panics on some damaged
//! optimiser records; `load_optimizer_record` catches those and reports an error, so the
//! harness lets panics raised in burn-optim's sources unwind to it (any other panic, or
//! one that escapes, aborts).
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use burn::optim::ModuleOptimizer;
use libfuzzer_sys::fuzz_target;
use weft_fuzz::{allow_caught_panics_from, bounded, linear_bound, tiny_multilevel};
use weft_models::multilevel::{Multilevel, Predictor};
use weft_train::run::{load_model_record, load_optimizer_record};
use weft_train::TrainConfig;

struct Fixture {
    model: Multilevel,
    optim: ModuleOptimizer,
    file: PathBuf,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        allow_caught_panics_from(&["/burn-optim-0.22.1/src/"]);
        let device = weft_nn::backend::cpu();
        let model = Multilevel::new(&tiny_multilevel(), &device).expect("the tiny model builds");
        let cfg = TrainConfig::preset("cpu").expect("the cpu preset");
        let optim = cfg.optimizer.init(cfg.grad_clip_norm);
        let base = if std::path::Path::new("/dev/shm").is_dir() {
            PathBuf::from("/dev/shm")
        } else {
            std::env::temp_dir()
        };
        let file = base.join(format!("weft-fuzz-checkpoint-{}.bpk", std::process::id()));
        Fixture { model, optim, file }
    })
}

fuzz_target!(|data: &[u8]| {
    let f = fixture();
    std::fs::write(&f.file, data).expect("writing the input");
    let ((from_bytes, from_file, optim), _) = bounded(data.len(), linear_bound(data.len()), || {
        let from_bytes = load_model_record(f.model.clone(), data.to_vec(), &f.file);
        let from_file =
            Predictor::from_checkpoint(tiny_multilevel(), &f.file, &weft_nn::backend::cpu());
        let optim = load_optimizer_record(f.optim.clone(), data.to_vec(), &f.file);
        (from_bytes.map(|_| ()), from_file.map(|_| ()), optim.map(|_| ()))
    });
    for e in [from_bytes.as_ref().err().map(|e| e.to_string()), from_file.as_ref().err().map(|e| e.to_string()), optim.as_ref().err().map(|e| e.to_string())]
        .into_iter()
        .flatten()
    {
        assert!(e.contains("weft-fuzz-checkpoint"), "an error that does not name the file: {e}");
    }
    assert_eq!(
        from_bytes.is_ok(),
        from_file.is_ok(),
        "bytes: {from_bytes:?}, file: {from_file:?}"
    );
});
