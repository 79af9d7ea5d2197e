//! A trained GarFitNet run opened for inference, and the statistics a run keeps beside
//! its checkpoints (`garfit.json`): the factor model of α and the three normalisers.
//!
//! Per frame: the body is posed, the coarse regressor moves the garment with it
//! (`M_coarse`, eq. 4.6), and the refinement network adds the fit-dependent folds (eq.
//! 4.7–4.10). Both networks take one frame at a time here, with batch normalisation's
//! running statistics.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use weft_body::BodyModel;
use weft_mesh::{Graph, TriMesh};
use weft_nn::{FeatureNormalizer, GraphBatch};

use super::fit::{fit_sample, FactorAnalysis};
use super::model::{GarFit, GarFitConfig};
use super::network::Correction;
use super::pair::{BodyFrame, FitPair};
use crate::deformer::{Clip, Deformer, Frames};
use crate::error::ModelError;
use crate::kind::ModelKind;
use crate::refine::predictor::load_record;
use crate::run::{latest_checkpoint, model_config, RunLayout};

/// The statistics file of a GarFitNet run.
pub const STATS_FILE: &str = "garfit.json";

/// What a GarFitNet run fits on its training pairs before the first step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GarFitStats {
    /// The factor model of α (§4.2.1).
    pub fit: FactorAnalysis,
    /// Garment–body distances are capped here (m), as when `fit` was fitted.
    pub distance_cap: f64,
    /// The coarse regressor's node features.
    pub coarse: FeatureNormalizer,
    /// The refinement network's node features.
    pub refine: FeatureNormalizer,
    /// The GarFit parameters `(β, θ, α)`.
    pub garfit: FeatureNormalizer,
    /// α of every training pair, to read the factors as Fig. 4.3 does (the first orders
    /// the pairs from tight to loose).
    #[serde(default)]
    pub pairs: Vec<PairFit>,
}

/// One training pair's fit parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairFit {
    /// The garment's id in the dataset.
    pub garment: String,
    /// The body's id in the dataset.
    pub body: String,
    /// The body's shape.
    pub betas: Vec<f64>,
    /// α.
    pub alpha: Vec<f64>,
}

impl GarFitStats {
    /// α of `garment` (rest pose, on the body of shape `betas`): the factor model's
    /// posterior mean of its garment–body distances.
    pub fn alpha(
        &self,
        model: &BodyModel,
        betas: &[f64],
        garment: &TriMesh,
    ) -> Result<Vec<f64>, ModelError> {
        let sample = fit_sample(model, betas, garment, self.distance_cap)?;
        let mut alpha = self.fit.alpha(&[sample])?;
        Ok(alpha.pop().unwrap_or_default())
    }

    /// Reads `dir/garfit.json`; errors name the file.
    pub fn read(dir: &Path) -> Result<Self, ModelError> {
        let path = dir.join(STATS_FILE);
        let run = |message: String| ModelError::Run {
            path: path.clone(),
            message,
        };
        let stats: GarFitStats = crate::run::read_json(&path, "GarFitNet's statistics")?;
        for n in [&stats.coarse, &stats.refine, &stats.garfit] {
            n.validate().map_err(|e| run(e.to_string()))?;
        }
        Ok(stats)
    }
}

/// `rows` (row-major, `width` columns) normalised by `normalizer`, as a tensor.
pub fn normalized(
    normalizer: &FeatureNormalizer,
    mut rows: Vec<f32>,
    width: usize,
    device: &Device,
) -> Result<Tensor<2>, ModelError> {
    normalizer.apply(&mut rows)?;
    let n = rows.len() / width.max(1);
    Ok(Tensor::from_data(TensorData::new(rows, [n, width]), device))
}

/// A tensor's values, row-major.
pub fn values(t: Tensor<2>) -> Result<Vec<f32>, ModelError> {
    t.into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .map_err(|e| ModelError::Config(format!("network output: {e:?}")))
}

/// The coarse regressor's corrections of several frames, as one disjoint graph.
pub fn coarse_correction(
    model: &GarFit,
    stats: &GarFitStats,
    frames: &[(&FitPair, &BodyFrame)],
    device: &Device,
) -> Result<Correction, ModelError> {
    let mut rows = Vec::new();
    let mut width = 0;
    for (pair, frame) in frames {
        rows.extend(pair.coarse_features(frame));
        width = pair.coarse_width();
    }
    let graphs: Vec<&Graph> = frames.iter().map(|(p, _)| p.graph()).collect();
    let batch = GraphBatch::new(&graphs)?;
    model
        .coarse
        .forward(normalized(&stats.coarse, rows, width, device)?, &batch)
}

/// The refinement's corrections of several frames (each with its coarse garment), as one
/// disjoint graph.
pub fn refine_correction(
    model: &GarFit,
    stats: &GarFitStats,
    frames: &[(&FitPair, &BodyFrame, &[[f64; 3]])],
    device: &Device,
) -> Result<Correction, ModelError> {
    let (mut rows, mut garfit) = (Vec::new(), Vec::new());
    let (mut width, mut garfit_width) = (0, 0);
    for (pair, frame, coarse) in frames {
        rows.extend(pair.refine_features(frame, coarse));
        garfit.extend(pair.garfit(frame));
        width = pair.refine_width();
        garfit_width = pair.garfit_width();
    }
    let graphs: Vec<&Graph> = frames.iter().map(|(p, _, _)| p.graph()).collect();
    let batch = GraphBatch::new(&graphs)?;
    model.network.forward(
        normalized(&stats.refine, rows, width, device)?,
        normalized(&stats.garfit, garfit, garfit_width, device)?,
        &batch,
    )
}

/// One frame's coarse garment `M_coarse` (eq. 4.6) under `model`.
pub fn coarse_garment(
    model: &GarFit,
    stats: &GarFitStats,
    pair: &FitPair,
    frame: &BodyFrame,
    device: &Device,
) -> Result<Vec<[f64; 3]>, ModelError> {
    let delta = coarse_correction(model, stats, &[(pair, frame)], device)?;
    Ok(pair.coarse_positions(frame, &values(delta.vector())?))
}

/// One frame's refined garment from its coarse garment `coarse` under `model`.
pub fn refined_garment(
    model: &GarFit,
    stats: &GarFitStats,
    pair: &FitPair,
    frame: &BodyFrame,
    coarse: &[[f64; 3]],
    device: &Device,
) -> Result<Vec<[f64; 3]>, ModelError> {
    let delta = refine_correction(model, stats, &[(pair, frame, coarse)], device)?;
    Ok(pair.refined_positions(coarse, &values(delta.vector())?))
}

/// A trained GarFitNet run ready to run on the CPU.
pub struct GarFitPredictor {
    /// Both networks, at the run's latest checkpoint (validation mode).
    pub model: GarFit,
    /// The run's `[model]`.
    pub config: GarFitConfig,
    /// The run's statistics.
    pub stats: GarFitStats,
    device: Device,
    checkpoint: PathBuf,
}

impl GarFitPredictor {
    /// Loads the run in `dir`. Errors name the file: a run of another kind, a `[model]`
    /// that does not validate, a checkpoint that does not fit, missing statistics.
    pub fn load(dir: &Path) -> Result<Self, ModelError> {
        let config = model_config(
            dir,
            ModelKind::GarFitNet,
            &GarFitConfig::new(),
            GarFitConfig::validate,
        )?;
        let path = RunLayout::new(dir).config();
        let run_err = |message: String| ModelError::Run {
            path: path.clone(),
            message,
        };
        let device = weft_nn::backend::cpu();
        let checkpoint = latest_checkpoint(dir)?;
        let model = load_record(config.init(&device)?, &checkpoint)?;
        let stats = GarFitStats::read(dir)?;
        if stats.fit.factors() != config.fit.factors {
            return Err(run_err(format!(
                "{STATS_FILE} holds {} fit factors, [model] fit.factors = {}",
                stats.fit.factors(),
                config.fit.factors
            )));
        }
        Ok(GarFitPredictor {
            model,
            config,
            stats,
            device,
            checkpoint,
        })
    }

    /// The pair of `garment` on the body of shape `betas` (rest pose, as it sits there),
    /// with α from the run's factor model.
    pub fn pair(
        &self,
        body: &BodyModel,
        betas: &[f64],
        garment: TriMesh,
    ) -> Result<FitPair, ModelError> {
        let alpha = self.stats.alpha(body, betas, &garment)?;
        let pair = FitPair::new(body, betas, garment, alpha, self.config.anchor)?;
        self.config.check_widths(&pair)?;
        Ok(pair)
    }
}

impl GarFitPredictor {
    /// The coarse garment (`refined` false) or GarFitNet's output of every frame of `clip`
    /// (`garment` as it sits on the body of `clip.betas` in the rest pose).
    pub fn animate_stage(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        refined: bool,
    ) -> Result<Frames, ModelError> {
        clip.check()?;
        let betas: Vec<f64> = clip.betas.iter().map(|&b| f64::from(b)).collect();
        let pair = self.pair(body, &betas, garment.clone())?;
        let (model, stats, device) = (&self.model, &self.stats, &self.device);
        clip.poses
            .iter()
            .zip(clip.trans)
            .map(|(pose, trans)| {
                let frame = pair.body_frame(body, pose, trans.map(f64::from))?;
                let mut garment = coarse_garment(model, stats, &pair, &frame, device)?;
                if refined {
                    garment = refined_garment(model, stats, &pair, &frame, &garment, device)?;
                }
                Ok(garment.into_iter().map(|p| p.map(|c| c as f32)).collect())
            })
            .collect()
    }

    /// The coarse regressor alone as a [`Deformer`] (Tables 4.1–4.2's "Coarse" column).
    pub fn coarse_stage(&self) -> CoarseStage<'_> {
        CoarseStage(self)
    }

    fn variant_of(&self, output: &str) -> BTreeMap<String, String> {
        BTreeMap::from([
            ("checkpoint".into(), self.checkpoint.display().to_string()),
            ("output".into(), output.into()),
            (
                "garfit branch".into(),
                self.config.network.garfit_branch.to_string(),
            ),
            (
                "decomposed".into(),
                self.config.network.decomposed.to_string(),
            ),
        ])
    }
}

impl Deformer for GarFitPredictor {
    fn name(&self) -> String {
        "GarFitNet".into()
    }

    fn kind(&self) -> Option<ModelKind> {
        Some(ModelKind::GarFitNet)
    }

    fn variant(&self) -> BTreeMap<String, String> {
        self.variant_of("refined")
    }

    fn animate(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Frames, ModelError> {
        self.animate_stage(garment, body, clip, true)
    }
}

/// A GarFitNet run's coarse regressor as a [`Deformer`]: `M_coarse` of eq. 4.6.
pub struct CoarseStage<'a>(&'a GarFitPredictor);

impl Deformer for CoarseStage<'_> {
    fn name(&self) -> String {
        "GarFitNet coarse".into()
    }

    fn kind(&self) -> Option<ModelKind> {
        Some(ModelKind::GarFitNet)
    }

    fn variant(&self) -> BTreeMap<String, String> {
        self.0.variant_of("coarse")
    }

    fn animate(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Frames, ModelError> {
        self.0.animate_stage(garment, body, clip, false)
    }
}
