//! Training GarFitNet (seed 001 ch. 4) on a fit dataset (`weft data generate --preset
//! garfit-tiny`: garments made for one body, simulated on bodies of other weights).
//!
//! - Before the first step: α's factor model is fitted on the training garment–body
//!   pairs (rest pose, §4.2.1), and three z-score normalisers on the training frames: the
//!   coarse regressor's features, the refinement's features (read from the smoothed
//!   simulated garments, the coarse output's target) and the GarFit parameters. All four
//!   are saved as `garfit.json` in the run directory.
//! - Two stages (thesis-reference G4): the coarse regressor alone on Laplacian-smoothed
//!   simulated garments for the first `coarse_fraction` of the steps; then it is frozen,
//!   its predictions of every frame are cached, and the refinement network trains on the
//!   residual to the simulated garment (the thesis trains on coarse *predictions*).
//! - An item is `frames` frames (≥ 2: batch normalisation of the GarFit vector needs more
//!   than one row, G7), drawn in a seeded order, as one disjoint graph. Loss eq. 4.8 for
//!   both networks.
//! - Validation: every validation frame, one at a time, with running statistics: the
//!   coarse and refined mean per-vertex distance to the simulated garment (cm).

pub mod config;

use std::collections::BTreeMap;
use std::path::Path;

use burn::module::Module;
use burn::tensor::{Device, Tensor, TensorData};
use weft_body::BodyModel;
use weft_data::{Dataset, Split};
use weft_mesh::rng::SplitMix64;
use weft_models::garfitnet::predictor::{
    coarse_correction, coarse_garment, refine_correction, refined_garment,
};
use weft_models::garfitnet::{
    coarse_target, fit_sample, BodyFrame, FactorAnalysis, FitPair, GarFit, GarFitConfig,
    GarFitStats, PairFit, STATS_FILE,
};
use weft_nn::NormalizerFit;

pub use config::{GarFitRun, GarFitTraining};

use crate::error::{Result, TrainError};
use crate::task::{LossTerm, Metrics, StepEnd, TrainTask};

/// The validation metric the schedule watches: the current stage's output error, cm.
pub const MEAN_ERROR_CM: &str = "mean_error_cm";
/// The coarse garment's mean per-vertex error, cm.
pub const COARSE_ERROR_CM: &str = "coarse_error_cm";
/// The refined garment's mean per-vertex error, cm (refinement stage only).
pub const REFINED_ERROR_CM: &str = "refined_error_cm";

/// The loss of each stage (eq. 4.8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Term {
    /// The coarse regressor's, on smoothed garments.
    Coarse,
    /// The refinement's, on the residual to the simulated garment.
    Refine,
}

impl LossTerm for Term {
    fn name(self) -> &'static str {
        match self {
            Term::Coarse => "coarse",
            Term::Refine => "refine",
        }
    }
}

/// Where training is: the coarse regressor first, then the refinement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    /// The coarse regressor trains.
    #[default]
    Coarse,
    /// The coarse regressor is frozen; the refinement trains.
    Refine,
}

/// One simulated frame of a pair.
pub struct FitFrame {
    /// The index of its pair.
    pub pair: usize,
    /// The posed body.
    pub body: BodyFrame,
    /// The simulated garment (m).
    pub truth: Vec<[f64; 3]>,
    /// The smoothed simulated garment: the coarse regressor's target (m).
    pub smoothed: Vec<[f64; 3]>,
}

/// The pairs and frames of one split.
pub struct FitSplit {
    /// Garment–body pairs, keyed in `keys` by `(garment id, body id)`.
    pub pairs: Vec<FitPair>,
    /// `(garment id, body id)` of each pair.
    pub keys: Vec<(String, String)>,
    /// `(sequence id, first frame, frame count)` of each sequence, in `frames`.
    pub sequences: Vec<(String, usize, usize)>,
    /// Every frame of every sequence.
    pub frames: Vec<FitFrame>,
}

/// The rest-pose garments of a split's pairs, before α is known.
struct Loaded {
    keys: Vec<(String, String)>,
    garments: Vec<(Vec<f64>, weft_mesh::TriMesh)>,
    sequences: Vec<(usize, weft_data::Sequence)>,
}

fn load(set: &Dataset, split: Split) -> Result<Loaded> {
    let mut keys: Vec<(String, String)> = Vec::new();
    let mut garments = Vec::new();
    let mut sequences = Vec::new();
    for record in set.records_in(split) {
        if !record.has_frames() {
            continue;
        }
        let seq = set.load(record)?;
        let key = (record.garment_id.clone(), record.body_id.clone());
        let pair = match keys.iter().position(|k| *k == key) {
            Some(p) => p,
            None => {
                keys.push(key);
                let betas = record.betas.iter().map(|&b| f64::from(b)).collect();
                garments.push((betas, seq.garment.clone()));
                keys.len() - 1
            }
        };
        sequences.push((pair, seq));
    }
    Ok(Loaded {
        keys,
        garments,
        sequences,
    })
}

/// α of pair `i` (its β and rest-pose garment).
type AlphaOf<'a> = dyn Fn(usize, &[f64], &weft_mesh::TriMesh) -> Result<Vec<f64>> + 'a;

impl FitSplit {
    /// The split's pairs with α from `alpha` and every frame posed and smoothed.
    fn build(
        body: &BodyModel,
        loaded: Loaded,
        alpha: &AlphaOf<'_>,
        config: &GarFitConfig,
    ) -> Result<Self> {
        let (rounds, anchor) = (config.smoothing_rounds, config.anchor);
        let mut pairs = Vec::with_capacity(loaded.garments.len());
        for (i, (betas, garment)) in loaded.garments.into_iter().enumerate() {
            let a = alpha(i, &betas, &garment)?;
            pairs.push(FitPair::new(body, &betas, garment, a, anchor)?);
        }
        let mut frames = Vec::new();
        let mut sequences = Vec::new();
        for (p, seq) in loaded.sequences {
            let first = frames.len();
            for (t, positions) in seq.positions.iter().enumerate() {
                let truth: Vec<[f64; 3]> = positions.iter().map(|q| q.map(f64::from)).collect();
                let trans = seq.trans[t].map(f64::from);
                frames.push(FitFrame {
                    pair: p,
                    body: pairs[p].body_frame(body, &seq.poses[t], trans)?,
                    smoothed: coarse_target(&pairs[p].garment, &truth, rounds),
                    truth,
                });
            }
            sequences.push((seq.record.id.clone(), first, frames.len() - first));
        }
        Ok(FitSplit {
            pairs,
            keys: loaded.keys,
            sequences,
            frames,
        })
    }
}

/// Loads the training split, fits α's factor model and the normalisers on it, and loads
/// `others` with α from that model. Returns the statistics and the splits in order
/// (training first).
pub fn load_fit_data(
    set: &Dataset,
    config: &GarFitConfig,
    others: &[Split],
) -> Result<(GarFitStats, Vec<FitSplit>)> {
    let body = set.body_model()?;
    let train = load(set, Split::Train)?;
    if train.sequences.is_empty() {
        return Err(TrainError::config(
            "data",
            format!("{}: no finished training sequences", set.dir().display()),
            "a fit dataset (weft data generate --preset garfit-tiny)",
        ));
    }
    let samples = train
        .garments
        .iter()
        .map(|(betas, g)| Ok(fit_sample(&body, betas, g, config.distance_cap)?))
        .collect::<Result<Vec<_>>>()?;
    let fit = FactorAnalysis::fit(&samples, &config.fit)?;
    let alphas = fit.alpha(&samples)?;
    let train = FitSplit::build(&body, train, &|i, _, _| Ok(alphas[i].clone()), config)?;
    if let Some(pair) = train.pairs.first() {
        config.check_widths(pair)?;
    }
    let stats = fit_normalizers(&train, fit, config.distance_cap)?;
    let mut splits = vec![train];
    for &split in others {
        let loaded = load(set, split)?;
        let alpha = |_: usize, betas: &[f64], g: &weft_mesh::TriMesh| -> Result<Vec<f64>> {
            Ok(stats.alpha(&body, betas, g)?)
        };
        splits.push(FitSplit::build(&body, loaded, &alpha, config)?);
    }
    Ok((stats, splits))
}

fn fit_normalizers(train: &FitSplit, fit: FactorAnalysis, cap: f64) -> Result<GarFitStats> {
    let first = &train.pairs[0];
    let mut coarse = NormalizerFit::new(first.coarse_width())?;
    let mut refine = NormalizerFit::new(first.refine_width())?;
    let mut garfit = NormalizerFit::new(first.garfit_width())?;
    for f in &train.frames {
        let pair = &train.pairs[f.pair];
        coarse.observe(&pair.coarse_features(&f.body))?;
        refine.observe(&pair.refine_features(&f.body, &f.smoothed))?;
        garfit.observe(&pair.garfit(&f.body))?;
    }
    let pairs = train
        .keys
        .iter()
        .zip(&train.pairs)
        .map(|((garment, body), pair)| PairFit {
            garment: garment.clone(),
            body: body.clone(),
            betas: pair.betas.clone(),
            alpha: pair.alpha.clone(),
        })
        .collect();
    Ok(GarFitStats {
        fit,
        distance_cap: cap,
        coarse: coarse.finish()?,
        refine: refine.finish()?,
        garfit: garfit.finish()?,
        pairs,
    })
}

/// Writes `stats` into the run directory `dir` atomically.
pub fn save_stats(dir: &Path, stats: &GarFitStats) -> Result<()> {
    crate::run::save_json(dir, STATS_FILE, stats)
}

/// The mean distance between two garments, cm.
pub fn mean_error_cm(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| ((0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>()).sqrt())
        .sum();
    100.0 * sum / a.len().max(1) as f64
}

/// GarFitNet's training task; see the module documentation.
pub struct GarFitTask {
    training: GarFitTraining,
    stats: GarFitStats,
    device: Device,
    train: FitSplit,
    validation: FitSplit,
    stage: Stage,
    /// Frame indices of every item, in a seeded order.
    groups: Vec<Vec<usize>>,
    /// The frozen coarse regressor's garment of every training frame (refinement stage),
    /// or why it could not be made (reported by the next refinement step).
    coarse_train: std::result::Result<Vec<Vec<[f64; 3]>>, String>,
}

impl GarFitTask {
    /// The task over `train` and `validation` with the statistics fitted on `train`.
    pub fn new(
        training: &GarFitTraining,
        stats: GarFitStats,
        train: FitSplit,
        validation: FitSplit,
        seed: u64,
        device: &Device,
    ) -> Result<Self> {
        training.validate_values()?;
        let mut order: Vec<usize> = (0..train.frames.len()).collect();
        let mut rng = SplitMix64::new(seed ^ 0x4741_5246_4954_2121);
        for i in (1..order.len()).rev() {
            order.swap(i, rng.below(i + 1));
        }
        // Every item holds `frames` frames: a last short group would put one frame's
        // GarFit vector alone through batch normalisation (G7).
        let groups = order
            .chunks_exact(training.frames.min(order.len()).max(1))
            .map(<[_]>::to_vec)
            .collect();
        Ok(GarFitTask {
            training: training.clone(),
            stats,
            device: device.clone(),
            train,
            validation,
            stage: Stage::Coarse,
            groups,
            coarse_train: Ok(Vec::new()),
        })
    }

    /// Training sequences and pairs.
    pub fn describe(&self) -> (usize, usize, usize) {
        (
            self.train.sequences.len(),
            self.train.pairs.len(),
            self.train.frames.len(),
        )
    }

    fn tensor(&self, rows: Vec<f32>) -> Tensor<2> {
        let n = rows.len() / 3;
        Tensor::from_data(TensorData::new(rows, [n, 3]), &self.device)
    }

    /// The coarse garment of every frame of `split` under `model` (one frame at a time).
    fn coarse_all(&self, model: &GarFit, split: &FitSplit) -> Result<Vec<Vec<[f64; 3]>>> {
        split
            .frames
            .iter()
            .map(|f| {
                let pair = &split.pairs[f.pair];
                Ok(coarse_garment(
                    model,
                    &self.stats,
                    pair,
                    &f.body,
                    &self.device,
                )?)
            })
            .collect()
    }
}

impl TrainTask for GarFitTask {
    type Model = GarFit;
    type Term = Term;
    type Stage = Stage;

    fn item_count(&self) -> usize {
        self.groups.len()
    }

    fn terms(&self, stage: &Stage) -> Vec<(Term, f64)> {
        match stage {
            Stage::Coarse => vec![(Term::Coarse, 1.0)],
            Stage::Refine => vec![(Term::Refine, 1.0)],
        }
    }

    fn losses(&mut self, model: &GarFit, item: usize, terms: &[Term]) -> Result<Vec<Tensor<1>>> {
        let frames = &self.groups[item];
        let mut out = Vec::with_capacity(terms.len());
        for term in terms {
            let loss = match term {
                Term::Coarse => {
                    let inputs: Vec<(&FitPair, &BodyFrame)> = frames
                        .iter()
                        .map(|&i| {
                            (
                                &self.train.pairs[self.train.frames[i].pair],
                                &self.train.frames[i].body,
                            )
                        })
                        .collect();
                    let mut targets = Vec::new();
                    for &i in frames {
                        let f = &self.train.frames[i];
                        targets
                            .extend(self.train.pairs[f.pair].coarse_targets(&f.body, &f.smoothed));
                    }
                    coarse_correction(model, &self.stats, &inputs, &self.device)?
                        .loss(self.tensor(targets))
                }
                Term::Refine => {
                    let cached = self.coarse_train.as_ref().map_err(|e| {
                        TrainError::config(
                            "stage",
                            "refine",
                            &format!("the frozen coarse regressor's garments ({e})"),
                        )
                    })?;
                    if cached.len() != self.train.frames.len() {
                        return Err(TrainError::config(
                            "stage",
                            "refine",
                            "the coarse garments cached on entering the stage",
                        ));
                    }
                    let mut inputs = Vec::with_capacity(frames.len());
                    let mut targets = Vec::new();
                    for &i in frames {
                        let f = &self.train.frames[i];
                        let pair = &self.train.pairs[f.pair];
                        let coarse = &cached[i];
                        inputs.push((pair, &f.body, coarse.as_slice()));
                        targets.extend(pair.refine_targets(coarse, &f.truth));
                    }
                    refine_correction(model, &self.stats, &inputs, &self.device)?
                        .loss(self.tensor(targets))
                }
            };
            out.push(loss);
        }
        Ok(out)
    }

    fn validate(&mut self, model: &GarFit) -> Result<Metrics> {
        let coarse = self.coarse_all(model, &self.validation)?;
        let n = self.validation.frames.len().max(1) as f64;
        let coarse_error: f64 = self
            .validation
            .frames
            .iter()
            .zip(&coarse)
            .map(|(f, c)| mean_error_cm(c, &f.truth))
            .sum::<f64>()
            / n;
        let mut metrics = BTreeMap::from([(COARSE_ERROR_CM.to_string(), coarse_error)]);
        let primary = if self.stage == Stage::Refine {
            let mut sum = 0.0;
            for (f, c) in self.validation.frames.iter().zip(&coarse) {
                let pair = &self.validation.pairs[f.pair];
                let refined = refined_garment(model, &self.stats, pair, &f.body, c, &self.device)?;
                sum += mean_error_cm(&refined, &f.truth);
            }
            let refined = sum / n;
            metrics.insert(REFINED_ERROR_CM.to_string(), refined);
            refined
        } else {
            coarse_error
        };
        metrics.insert(MEAN_ERROR_CM.to_string(), primary);
        Ok(metrics)
    }

    fn primary_metric(&self) -> &'static str {
        MEAN_ERROR_CM
    }

    fn stage_name(&self, stage: &Stage) -> String {
        match stage {
            Stage::Coarse => "coarse".into(),
            Stage::Refine => "refine".into(),
        }
    }

    fn advance(&self, stage: &mut Stage, end: &StepEnd<'_, Term>) -> bool {
        if *stage == Stage::Coarse && end.step >= self.training.coarse_steps(end.total) {
            *stage = Stage::Refine;
            return true;
        }
        false
    }

    fn enter_stage(&mut self, model: GarFit, stage: &Stage) -> GarFit {
        self.stage = *stage;
        if *stage == Stage::Coarse {
            return model;
        }
        let GarFit { coarse, network } = model;
        let model = GarFit {
            coarse: coarse.no_grad(),
            network,
        };
        let frozen = model.valid();
        // A failure here surfaces as the refinement term's error on the next step.
        self.coarse_train = self
            .coarse_all(&frozen, &self.train)
            .map_err(|e| e.to_string());
        model
    }
}
