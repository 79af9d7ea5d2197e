//! Checkpoint inputs found by fuzzing (docs/fuzzing.md, target `read_checkpoint`): each
//! must give an error naming the file, never a panic.

use std::path::Path;

use burn::module::Module;
use burn::nn::LinearConfig;
use weft_train::run::{load_model_record, load_optimizer_record};
use weft_train::{OptimizerConfig, TrainError};

/// A model record in which one tensor's `param_id` key is misspelt (`pargm_id`, the
/// fuzzer's one-byte change), so that tensor carries no parameter id. As an optimiser
/// record, burn-optim 0.22.1 panics on it ("Optimizer record tensors should carry a
/// parameter id"); `load_optimizer_record` reports a damaged record instead.
#[test]
fn an_optimizer_record_without_parameter_ids_is_an_error() {
    let device = weft_nn::backend::cpu();
    let linear = LinearConfig::new(2, 3).init(&device);
    let mut bytes = linear.clone().into_record().into_bytes().unwrap().to_vec();
    let at = bytes
        .windows(8)
        .position(|w| w == b"param_id")
        .expect("a record names its parameter ids");
    bytes[at + 3] = b'g';
    let path = Path::new("run/checkpoints/step-000001.optim.bpk");
    let optim = OptimizerConfig::default().init(None);
    let e = match load_optimizer_record(optim, bytes.clone(), path) {
        Err(e) => e,
        Ok(_) => panic!("a damaged optimiser record loads"),
    };
    assert!(matches!(e, TrainError::Record { .. }), "{e:?}");
    let message = format!("{e}: {}", std::error::Error::source(&e).unwrap());
    assert!(
        message.starts_with(&path.display().to_string()),
        "{message}"
    );
    assert!(message.contains("damaged"), "{message}");

    // As a model record the same bytes load (a missing id is made up), and the
    // untouched optimiser state of a fresh optimiser round-trips.
    let model = load_model_record(linear, bytes, path).expect("a model record without ids");
    assert_eq!(model.num_params(), 9);
    let optim = OptimizerConfig::default().init(None);
    let fresh = optim.into_bytes().unwrap().to_vec();
    load_optimizer_record(OptimizerConfig::default().init(None), fresh, path).unwrap();
}
