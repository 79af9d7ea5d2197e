//! Every width and depth of the Multilevel model (seed 000 §3.2–3.3, supplement §1), with
//! the two presets: `paper` (the published widths) and `cpu` (narrow, so the tiny dataset
//! trains in minutes on a two-core machine).
//!
//! The config is a burn `Config`: serde (TOML in a run directory, JSON through burn), and
//! every field has its default in code, so a config file names only what it changes.

use burn::config::Config;

use crate::error::ModelError;

/// How M^mp goes between resolutions (seed 000 Table 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoolingKind {
    /// Structure-preserving pooling and neighbour-weighted unpooling (§3.3, the paper's).
    #[default]
    Structure,
    /// Single level: the same GAT blocks in cascade on the full graph, no pooling.
    None,
    /// TopKPool (Gao & Ji) with unpooling by index.
    TopK,
    /// SAGPool (Lee et al.) with unpooling by index.
    Sag,
    /// ASAP (Ranjan et al.) with unpooling by index.
    Asap,
}

impl PoolingKind {
    /// Every kind, paper's first.
    pub const ALL: [PoolingKind; 5] = [
        PoolingKind::Structure,
        PoolingKind::None,
        PoolingKind::TopK,
        PoolingKind::Sag,
        PoolingKind::Asap,
    ];

    /// The name used in configs and tables.
    pub fn name(self) -> &'static str {
        match self {
            PoolingKind::Structure => "structure",
            PoolingKind::None => "none",
            PoolingKind::TopK => "top_k",
            PoolingKind::Sag => "sag",
            PoolingKind::Asap => "asap",
        }
    }

    /// The name in tables and pictures (Table 1's row names).
    pub fn label(self) -> &'static str {
        match self {
            PoolingKind::Structure => "Multilevel (structure-preserving)",
            PoolingKind::None => "Single-level",
            PoolingKind::TopK => "TopKPool",
            PoolingKind::Sag => "SAGPool",
            PoolingKind::Asap => "ASAP",
        }
    }
}

/// Every width and depth of the model; see the module documentation. Defaults are the
/// `cpu` preset.
#[derive(Config, Debug, PartialEq)]
pub struct MultilevelConfig {
    /// The preset this config started from (`paper`, `cpu`, or `custom`).
    #[config(default = "String::from(\"cpu\")")]
    pub preset: String,
    /// Body joints `S` (24 for SMPL-format bodies): heads of the last E^gg block, columns
    /// of the skinning weights.
    #[config(default = 24)]
    pub joints: usize,
    /// `F`: channels per joint of the garment–body encoding, output width of E^gs, E^bs
    /// and E^t1.
    #[config(default = 32)]
    pub feature_width: usize,
    /// Channels per head of the E^gg GAT blocks before the style-fusion block
    /// (paper: [32, 64, 128]).
    #[config(default = "vec![16, 32, 32]")]
    pub gg_widths: Vec<usize>,
    /// Heads of those blocks (averaged; paper: S = 24).
    #[config(default = 4)]
    pub gg_heads: usize,
    /// Hidden widths of E^gs before its `F`-wide output (paper: [256, 256]).
    #[config(default = "vec![64, 64]")]
    pub gs_hidden: Vec<usize>,
    /// Hidden widths of E^bs before its `F`-wide output (paper: [512, 256]).
    #[config(default = "vec![64, 32]")]
    pub bs_hidden: Vec<usize>,
    /// Nyström landmarks `N*`: length of the garment style descriptor.
    #[config(default = 32)]
    pub nystrom_landmarks: usize,
    /// Body vertices sampled (evenly by index) for the joint–vertex distances of E^bs and
    /// the velocities of E^t2.
    #[config(default = 128)]
    pub body_samples: usize,
    /// Frames `m` of the pose and velocity histories.
    #[config(default = 5)]
    pub history: usize,
    /// LSTM layers of E^t1 (hidden width `F`).
    #[config(default = 2)]
    pub t1_layers: usize,
    /// LSTM layers of E^t2 (hidden width `F·S`).
    #[config(default = 2)]
    pub t2_layers: usize,
    /// Submodules of M^mp whose blend shapes add up (paper: 2; step 2 of training
    /// updates only the last).
    #[config(default = 2)]
    pub mp_submodules: usize,
    /// Pooling levels of each submodule (paper: 2).
    #[config(default = 2)]
    pub mp_levels: usize,
    /// Channels per head of the M^mp GAT blocks (paper: 32).
    #[config(default = 16)]
    pub mp_channels: usize,
    /// Heads of the M^mp GAT blocks, concatenated (paper: 4).
    #[config(default = 4)]
    pub mp_heads: usize,
    /// Heads of the final blend-shape GAT block, averaged (paper: 4).
    #[config(default = 4)]
    pub out_heads: usize,
    /// How M^mp changes resolution.
    #[config(default = "PoolingKind::Structure")]
    pub pooling: PoolingKind,
    /// Fraction of nodes a learned pooling keeps per level.
    #[config(default = 0.5)]
    pub pool_ratio: f64,
    /// LeakyReLU slope of every attention logit.
    #[config(default = 0.2)]
    pub negative_slope: f64,
    /// Add `ln(w_transfer + ε)` (body weights transferred to the garment) to the
    /// skinning-weight logits, so the untrained model skins like the LBS baseline.
    #[config(default = true)]
    pub weight_prior: bool,
    /// Take that prior from the transfer diffused over the garment
    /// (weft_body::features::diffusion): loose cloth — a skirt's hem between the legs —
    /// starts as a blend of the nearby bones instead of following the nearest thigh.
    #[config(default = true)]
    pub weight_diffusion: bool,
    /// Initial gain of the learned skinning-weight logits (small: start near the prior).
    #[config(default = 0.01)]
    pub weight_gain: f64,
    /// Initial gain of the blend shapes, metres per unit of the final GAT output (small:
    /// start near zero offsets).
    #[config(default = 0.01)]
    pub blend_gain: f64,
    /// Give M^mp the body contact of every garment vertex and frame (multilevel::contact;
    /// not in seed 000, so off in `paper`): scaled signed distance to the posed body and
    /// the body normal in the rest frame, added to the embedding of each submodule. With
    /// the collision term trained from step 1 it took the tiny test split's collisions
    /// from 3.3 % to 0.2 % at the same vertex error (docs/multilevel.md).
    #[config(default = true)]
    pub body_contact: bool,
    /// Metres at which the contact distance saturates (`h / radius` clamped to ±1).
    #[config(default = 0.1)]
    pub contact_radius: f64,
    /// Drape every garment on its body's rest pose with this material (a preset name of
    /// weft_sim::Material) before building its inputs (weft_garment::prepare::drape; not
    /// in seed 000): the template `T` the network deforms and skins is then the garment
    /// as it hangs, not as it was cut. `None` or [`NO_DRAPE`]: the garment as given (the
    /// default; the `cpu` preset drapes in silk).
    #[config(default = "None")]
    pub drape: Option<String>,
}

/// The `drape` value that turns the drape off in a config file (TOML has no `None`, and
/// a missing key takes the preset's value).
pub const NO_DRAPE: &str = "none";

/// Names [`MultilevelConfig::preset`] accepts.
pub const PRESETS: [&str; 2] = ["paper", "cpu"];

impl MultilevelConfig {
    /// The published widths (supplement §1): E^gg [32, 64, 128] + 128 with 24 heads,
    /// E^gs [256, 256, 128], E^bs [512, 256, 128], E^t1 2×128, E^t2 2×(128·24), M^mp two
    /// submodules, two levels, 32 channels × 4 heads, output 3 channels × 4 heads.
    pub fn paper() -> Self {
        MultilevelConfig::new()
            .with_preset("paper".into())
            .with_feature_width(128)
            .with_gg_widths(vec![32, 64, 128])
            .with_gg_heads(24)
            .with_gs_hidden(vec![256, 256])
            .with_bs_hidden(vec![512, 256])
            .with_nystrom_landmarks(64)
            .with_body_samples(512)
            .with_history(5)
            .with_mp_channels(32)
            .with_body_contact(false)
    }

    /// Narrow widths for CPU training on the tiny dataset (the defaults): E^gg [16, 32, 32]
    /// with 4 heads, F = 32, M^mp 16 channels × 4 heads, and the body contact input. Half these widths (F = 16,
    /// M^mp 8 channels) underfit the tiny dataset: the training error fell only from 66 to
    /// 56 mm in 3 000 steps (docs/multilevel.md has the measurements). The template is
    /// draped in silk (`drape`, the defaults otherwise): on settled ground truth the test
    /// error fell from 34–36 % to 41–42 % below LBS (docs/multilevel.md, "Settled ground
    /// truth").
    pub fn cpu() -> Self {
        MultilevelConfig::new().with_drape(Some("silk".into()))
    }

    /// The material the template is draped in: `None` when `drape` is unset or
    /// [`NO_DRAPE`].
    pub fn drape_material(&self) -> Option<&str> {
        self.drape.as_deref().filter(|m| *m != NO_DRAPE)
    }

    /// A preset by name (`paper` or `cpu`).
    pub fn preset(name: &str) -> Result<Self, ModelError> {
        match name {
            "paper" => Ok(Self::paper()),
            "cpu" => Ok(Self::cpu()),
            other => Err(ModelError::mismatch(
                "model preset",
                format!("one of {}", PRESETS.join(", ")),
                format!("{other:?}"),
            )),
        }
    }

    /// `F·S`: width of the garment–body encoding per node.
    pub fn fused_width(&self) -> usize {
        self.feature_width * self.joints
    }

    /// Node features of the garment graph: position, normal, distance to each joint.
    pub fn node_features(&self) -> usize {
        6 + self.joints
    }

    /// Width of the M^mp GAT blocks (heads concatenated).
    pub fn mp_width(&self) -> usize {
        self.mp_channels * self.mp_heads
    }

    /// Checks every value; the model and its inputs call this before building anything.
    pub fn validate(&self) -> Result<(), ModelError> {
        let positive = [
            ("joints", self.joints),
            ("feature_width", self.feature_width),
            ("gg_heads", self.gg_heads),
            ("nystrom_landmarks", self.nystrom_landmarks),
            ("body_samples", self.body_samples),
            ("history", self.history),
            ("t1_layers", self.t1_layers),
            ("t2_layers", self.t2_layers),
            ("mp_submodules", self.mp_submodules),
            ("mp_channels", self.mp_channels),
            ("mp_heads", self.mp_heads),
            ("out_heads", self.out_heads),
        ];
        for (name, v) in positive {
            if v == 0 {
                return Err(ModelError::Config(format!(
                    "{name} must be positive, got 0"
                )));
            }
        }
        for (name, widths) in [
            ("gg_widths", &self.gg_widths),
            ("gs_hidden", &self.gs_hidden),
            ("bs_hidden", &self.bs_hidden),
        ] {
            if widths.contains(&0) {
                return Err(ModelError::Config(format!(
                    "{name} must hold positive widths, got {widths:?}"
                )));
            }
        }
        if !(self.pool_ratio > 0.0 && self.pool_ratio <= 1.0) {
            return Err(ModelError::Config(format!(
                "pool_ratio must be in (0, 1], got {}",
                self.pool_ratio
            )));
        }
        for (name, v) in [
            ("negative_slope", self.negative_slope),
            ("weight_gain", self.weight_gain),
            ("blend_gain", self.blend_gain),
        ] {
            if !v.is_finite() || v < 0.0 {
                return Err(ModelError::Config(format!(
                    "{name} must be finite and non-negative, got {v}"
                )));
            }
        }
        if let Some(name) = self.drape_material() {
            weft_sim::Material::preset(name).map_err(|e| {
                ModelError::Config(format!("drape must name a material preset: {e}"))
            })?;
        }
        if !(self.contact_radius.is_finite() && self.contact_radius > 0.0) {
            return Err(ModelError::Config(format!(
                "contact_radius must be a positive number of metres, got {}",
                self.contact_radius
            )));
        }
        Ok(())
    }

    /// The config as TOML.
    pub fn to_toml(&self) -> Result<String, ModelError> {
        toml::to_string(self).map_err(|e| ModelError::Config(format!("to TOML: {e}")))
    }

    /// A config from a run's `[model]` TOML ([`Self::from_table`]).
    pub fn from_toml(text: &str) -> Result<Self, ModelError> {
        let table = weft_config::parse_table(text).map_err(|message| ModelError::RunToml {
            path: "<model config>".into(),
            message,
        })?;
        Self::from_table(&table, "<model config>")
    }

    /// A config from a parsed TOML table (the `[model]` table of a run's config.toml,
    /// read from `origin`): the `cpu` preset with the table laid over it by the one
    /// configuration path (weft-config), so an unknown key is refused by name. A table
    /// without `drape` is of a run that did not drape (weft writes the whole table, and
    /// runs from before the `cpu` preset draped have no such key), so it stays off.
    pub fn from_table(table: &toml::Table, origin: &str) -> Result<Self, ModelError> {
        let base = Self::cpu().with_drape(None);
        let cfg = weft_config::overlay(&base, table, origin, "model")?;
        cfg.validate()?;
        Ok(cfg)
    }
}
