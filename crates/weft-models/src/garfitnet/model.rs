//! The whole of GarFitNet as one trained model: the coarse regressor (§4.2.2) and the
//! refinement network (§4.3) with the settings of the fit parameter α (§4.2.1) and of the
//! coarse targets, so a run directory holds everything inference needs.

use burn::config::Config;
use burn::module::Module;
use burn::tensor::Device;

use super::coarse::{CoarseRegressor, CoarseRegressorConfig};
use super::fit::FactorAnalysisConfig;
use super::network::{GarFitNet, GarFitNetConfig};
use super::pair::{Anchor, FitPair};
use crate::error::ModelError;

/// Configuration of [`GarFit`] (`[model]` of a run).
#[derive(Config, Debug, PartialEq)]
pub struct GarFitConfig {
    /// The coarse regressor.
    #[config(default = "CoarseRegressorConfig::new()")]
    pub coarse: CoarseRegressorConfig,
    /// The refinement network.
    #[config(default = "GarFitNetConfig::new()")]
    pub network: GarFitNetConfig,
    /// The factor model of α (three factors, §4.2.1).
    #[config(default = "FactorAnalysisConfig::default()")]
    pub fit: FactorAnalysisConfig,
    /// Garment–body distances are capped here (m): a body vertex farther from the garment
    /// (uncovered) reads this.
    #[config(default = 0.1)]
    pub distance_cap: f64,
    /// Jacobi rounds of Laplacian smoothing that make the coarse targets (G5: 10).
    #[config(default = 10)]
    pub smoothing_rounds: usize,
    /// Where the coarse garment starts: the nearest body vertex (the thesis) or the
    /// garment vertex skinned with diffused weights.
    #[config(default = "Anchor::BodyVertex")]
    pub anchor: Anchor,
}

impl GarFitConfig {
    /// The preset `name`: `paper` (the thesis's widths as thesis-reference G2/G3/G5 reads
    /// them, the nearest-body-vertex anchor) or `cpu` (the same structure, narrower: graph
    /// blocks of 16 × 4, GarFit MLP (64, 128), branches of three local blocks of 16 × 2
    /// and one global block, output transforms (64); coarse regressor three blocks of
    /// 16 × 4), so the tiny set trains in minutes on two cores, with the skinned anchor:
    /// on garfit-tiny it lowered the test error by 4 % and took the pants-like shape out
    /// of the predicted skirts (docs/garfitnet.md).
    pub fn preset(name: &str) -> Result<Self, ModelError> {
        match name {
            "paper" => Ok(Self::new()),
            "cpu" => Ok(Self::new()
                .with_coarse(
                    CoarseRegressorConfig::new()
                        .with_blocks(3)
                        .with_channels(16)
                        .with_output_widths(vec![32]),
                )
                .with_network(
                    GarFitNetConfig::new()
                        .with_graph_channels(16)
                        .with_garfit_widths(vec![64, 128])
                        .with_branch_blocks(3)
                        .with_branch_channels(16)
                        .with_global_blocks(1)
                        .with_output_widths(vec![64]),
                )
                .with_anchor(Anchor::Skinned)),
            other => Err(ModelError::Config(format!(
                "unknown preset `{other}`; expected cpu or paper"
            ))),
        }
    }

    /// Checks the values; errors name the field.
    pub fn validate(&self) -> Result<(), ModelError> {
        ModelError::check_positive(&[
            ("fit.factors", self.fit.factors),
            ("coarse.blocks", self.coarse.blocks),
        ])?;
        if !(self.distance_cap.is_finite() && self.distance_cap > 0.0) {
            return Err(ModelError::Config(format!(
                "distance_cap = {}: expected a positive number of metres",
                self.distance_cap
            )));
        }
        if self.coarse.node_features != 6 + self.fit.factors {
            return Err(ModelError::Config(format!(
                "coarse.node_features = {}: the coarse features are a position, a normal and α, so expected 6 + fit.factors = {}",
                self.coarse.node_features,
                6 + self.fit.factors
            )));
        }
        Ok(())
    }

    /// Checks that the networks read what `pair` gives (the body model's joint and shape
    /// counts and α's factors decide the widths); errors name the field and the width
    /// expected, instead of a shape failure inside the networks.
    pub fn check_widths(&self, pair: &FitPair) -> Result<(), ModelError> {
        for (field, set, given) in [
            (
                "coarse.node_features",
                self.coarse.node_features,
                pair.coarse_width(),
            ),
            (
                "network.node_features",
                self.network.node_features,
                pair.refine_width(),
            ),
            (
                "network.garfit_features",
                self.network.garfit_features,
                pair.garfit_width(),
            ),
        ] {
            if set != given {
                return Err(ModelError::Config(format!(
                    "{field} = {set}, but this body model and fit give {given} per row (6 + joints for the node features, |β| + 3·joints + factors for the GarFit parameters)"
                )));
            }
        }
        Ok(())
    }

    /// Builds both networks; errors name the field.
    pub fn init(&self, device: &Device) -> Result<GarFit, ModelError> {
        self.validate()?;
        Ok(GarFit {
            coarse: self.coarse.init(device)?,
            network: self.network.init(device)?,
        })
    }
}

/// GarFitNet's two trained networks.
#[derive(Module, Debug)]
pub struct GarFit {
    /// The coarse regressor (trained first, then frozen).
    pub coarse: CoarseRegressor,
    /// The refinement network.
    pub network: GarFitNet,
}

#[cfg(test)]
mod tests {
    use weft_nn::backend::cpu;

    use super::*;

    #[test]
    fn presets_build_and_check_their_widths() {
        for name in ["cpu", "paper"] {
            let cfg = GarFitConfig::preset(name).unwrap();
            cfg.validate().unwrap();
        }
        assert!(GarFitConfig::preset("cpu").unwrap().init(&cpu()).is_ok());
        assert_eq!(GarFitConfig::preset("cpu").unwrap().anchor, Anchor::Skinned);
        assert_eq!(
            GarFitConfig::preset("paper").unwrap().anchor,
            Anchor::BodyVertex
        );
        let e = GarFitConfig::preset("cpu")
            .unwrap()
            .with_distance_cap(0.0)
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("distance_cap"), "{e}");
        let mut cfg = GarFitConfig::new();
        cfg.fit.factors = 2;
        let e = cfg.validate().unwrap_err().to_string();
        assert!(e.contains("coarse.node_features"), "{e}");
        assert!(GarFitConfig::preset("huge").is_err());
    }
}
