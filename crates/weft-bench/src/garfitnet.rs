//! `weft bench garfitnet`: one frame of GarFitNet (seed 001 ch. 4) on the benchmark skirt
//! of about `vertices` vertices, per stage, as `weft animate` and `weft eval` run it: the
//! posed body (LBS of the whole body, its normals, the associated vertices), the coarse
//! regressor's features and network (eq. 4.5–4.6), the refinement's features (the coarse
//! garment's normals, the joint distances) and network (eq. 4.7–4.10), and the whole
//! frame. The pair's one-off preparation (association, volumetric joint distances) is
//! timed apart: a clip pays it once.
//!
//! The networks run as burn layers on the flex CPU backend (no inference form yet, unlike
//! DenseGATs and MultiResGNet). The thesis gives no timing for GarFitNet.

use std::hint::black_box;

use serde::Serialize;
use weft_body::{BodyModel, Pose};
use weft_models::garfitnet::predictor::{coarse_garment, refined_garment};
use weft_models::garfitnet::{FactorAnalysis, FitPair, GarFitConfig, GarFitStats};
use weft_nn::backend::cpu;
use weft_nn::FeatureNormalizer;

use crate::timing::try_median_ms;
use crate::{skirt, BenchError, Row};

/// What to measure.
#[derive(Clone, Debug)]
pub struct GarFitNetBench {
    /// Model preset: cpu or paper.
    pub preset: String,
    /// Vertices of the garment.
    pub vertices: usize,
    /// Timed runs per figure.
    pub reps: usize,
}

/// One frame, per stage, ms.
#[derive(Clone, Debug, Serialize)]
pub struct GarFitNetFigures {
    /// `"garfitnet"`.
    pub bench: &'static str,
    /// The preset.
    pub preset: String,
    /// Vertices of the garment.
    pub vertices: usize,
    /// Threads of the pool.
    pub threads: usize,
    /// Parameters of both networks.
    pub parameters: usize,
    /// Once per garment–body pair: association and volumetric joint distances.
    pub pair_ms: f64,
    /// The posed body: LBS, normals, the associated vertices.
    pub body_ms: f64,
    /// The coarse regressor's node features.
    pub coarse_features_ms: f64,
    /// The coarse regressor, features included.
    pub coarse_ms: f64,
    /// The refinement's node features and GarFit parameters.
    pub refine_features_ms: f64,
    /// The refinement network, features included.
    pub refine_ms: f64,
    /// Body, coarse and refinement: one frame.
    pub frame_ms: f64,
}

impl Row for GarFitNetFigures {
    fn cells(&self) -> Vec<(&'static str, String)> {
        vec![
            ("preset", self.preset.clone()),
            ("N", self.vertices.to_string()),
            ("params", self.parameters.to_string()),
            ("pair (once)", format!("{:.1}", self.pair_ms)),
            ("body", format!("{:.2}", self.body_ms)),
            ("coarse feat.", format!("{:.2}", self.coarse_features_ms)),
            ("coarse", format!("{:.1}", self.coarse_ms)),
            ("refine feat.", format!("{:.2}", self.refine_features_ms)),
            ("refine", format!("{:.1}", self.refine_ms)),
            ("frame ms", format!("{:.1}", self.frame_ms)),
        ]
    }
}

/// A normaliser that changes nothing: the cost does not depend on the statistics.
fn identity(width: usize) -> FeatureNormalizer {
    FeatureNormalizer {
        mean: vec![0.0; width],
        std: vec![1.0; width],
    }
}

impl GarFitNetBench {
    /// Runs the bench on the skirt fitted to `body`.
    pub fn run(
        &self,
        body: &BodyModel,
        progress: &mut dyn FnMut(&str),
    ) -> Result<GarFitNetFigures, BenchError> {
        let cfg = GarFitConfig::preset(&self.preset).map_err(|e| BenchError::Option {
            what: "--preset",
            message: e.to_string(),
        })?;
        progress("garment");
        let mesh = skirt(body, self.vertices)?;
        let reps = self.reps;
        let alpha = vec![0.0; cfg.fit.factors];
        let pair_ms = try_median_ms(reps.min(3), || {
            FitPair::new(body, &[], mesh.clone(), alpha.clone(), cfg.anchor).map(drop)
        })
        .map_err(BenchError::stage("the garment-body pair"))?;
        let pair = FitPair::new(body, &[], mesh, alpha, cfg.anchor)
            .map_err(BenchError::stage("the garment-body pair"))?;
        let stats = GarFitStats {
            fit: FactorAnalysis {
                mean: Vec::new(),
                loadings: Vec::new(),
                noise: Vec::new(),
                log_likelihood: Vec::new(),
            },
            distance_cap: cfg.distance_cap,
            coarse: identity(pair.coarse_width()),
            refine: identity(pair.refine_width()),
            garfit: identity(pair.garfit_width()),
            pairs: Vec::new(),
        };
        let mut pose: Pose = [[0.0; 3]; 24];
        pose[1] = [-0.5, 0.0, 0.1];
        pose[2] = [0.3, 0.0, -0.1];
        pose[18] = [0.0, -1.2, 0.0];
        progress("body");
        let body_ms = try_median_ms(reps, || {
            pair.body_frame(body, &pose, [0.0; 3])
                .map(|x| drop(black_box(x)))
        })
        .map_err(BenchError::stage("posing the body"))?;
        let frame = pair
            .body_frame(body, &pose, [0.0; 3])
            .map_err(BenchError::stage("posing the body"))?;
        let device = cpu();
        let model = cfg
            .init(&device)
            .map_err(BenchError::stage("the networks"))?;
        progress("coarse regressor");
        let coarse_features_ms = try_median_ms(reps, || {
            black_box(pair.coarse_features(&frame));
            Ok::<(), BenchError>(())
        })?;
        let coarse_of = || coarse_garment(&model, &stats, &pair, &frame, &device);
        let coarse_ms = try_median_ms(reps, || coarse_of().map(|x| drop(black_box(x))))
            .map_err(BenchError::stage("the coarse regressor"))?;
        let coarse = coarse_of().map_err(BenchError::stage("the coarse regressor"))?;
        progress("refinement");
        let refine_features_ms = try_median_ms(reps, || {
            black_box(pair.refine_features(&frame, &coarse));
            black_box(pair.garfit(&frame));
            Ok::<(), BenchError>(())
        })?;
        let refine_of =
            |coarse: &[[f64; 3]]| refined_garment(&model, &stats, &pair, &frame, coarse, &device);
        let refine_ms = try_median_ms(reps, || refine_of(&coarse).map(|x| drop(black_box(x))))
            .map_err(BenchError::stage("the refinement"))?;
        progress("frame");
        let frame_ms = try_median_ms(reps, || {
            black_box(pair.body_frame(body, &pose, [0.0; 3])?);
            refine_of(&coarse_of()?).map(|x| drop(black_box(x)))
        })
        .map_err(BenchError::stage("one frame"))?;
        Ok(GarFitNetFigures {
            bench: "garfitnet",
            preset: self.preset.clone(),
            vertices: pair.vertex_count(),
            threads: rayon::current_num_threads(),
            parameters: burn::module::Module::num_params(&model),
            pair_ms,
            body_ms,
            coarse_features_ms,
            coarse_ms,
            refine_features_ms,
            refine_ms,
            frame_ms,
        })
    }
}
