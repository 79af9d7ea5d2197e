//! A real garment–body–motion case for the model tests: a skirt generated on weft's
//! default body, a procedural walk.

#![allow(dead_code)]

use weft_body::BodyModel;
use weft_garment::{FitBody, GarmentKind, Style};
use weft_mesh::TriMesh;
use weft_motion::{generate, MotionKind, ProceduralParams};

/// One test case.
pub struct Case {
    pub body: BodyModel,
    pub betas: Vec<f32>,
    pub garment: TriMesh,
    pub poses: Vec<weft_body::Pose>,
    pub trans: Vec<[f32; 3]>,
    pub fps: f64,
}

/// A `kind` garment of about `vertices` vertices on the default body at `betas`, and a
/// `frames`-frame walk at 30 fps.
pub fn case_with(kind: GarmentKind, vertices: usize, betas: &[f32], frames: usize) -> Case {
    let body = weft_body::default_body().expect("default body");
    let betas64: Vec<f64> = betas.iter().map(|&b| f64::from(b)).collect();
    let fit = FitBody::new(&body, &betas64).expect("fit body");
    let garment = fit
        .generate(kind, &Style::from_seed(kind, 1), vertices)
        .expect("garment")
        .mesh;
    let mut params = ProceduralParams::new(MotionKind::parse("walk").expect("walk"));
    params.frames = frames;
    let motion = generate(&params).expect("walk");
    let poses = motion.poses().to_vec();
    Case {
        body,
        betas: betas.to_vec(),
        garment,
        poses,
        trans: motion.trans().to_vec(),
        fps: motion.fps(),
    }
}

/// The default case: a 600-vertex skirt, 8 frames of walking, mean shape.
pub fn case() -> Case {
    case_with(GarmentKind::Skirt, 600, &[], 8)
}

/// Host data of a float tensor.
pub fn host<const D: usize>(t: burn::tensor::Tensor<D>) -> Vec<f32> {
    t.into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .expect("f32 data")
}

/// Serialises parameter initialisation: the flex device's seeded generator is shared by
/// the whole process, so tests running in parallel would interleave their draws.
static INIT: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// A model of `cfg` initialised from `seed` on the CPU (with autodiff if asked).
pub fn model(
    cfg: &weft_models::multilevel::MultilevelConfig,
    seed: u64,
    autodiff: bool,
) -> weft_models::multilevel::Multilevel {
    let _guard = INIT.lock().unwrap_or_else(|e| e.into_inner());
    let device = if autodiff {
        weft_nn::backend::cpu_autodiff()
    } else {
        weft_nn::backend::cpu()
    };
    weft_models::multilevel::Multilevel::new(cfg, &weft_nn::backend::seeded(&device, seed))
        .expect("model")
}
