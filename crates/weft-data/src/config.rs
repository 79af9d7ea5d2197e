//! Dataset configs: what to simulate, as TOML.
//!
//! A config names, per split, the garments (kind, vertex count, style seed), the body
//! shapes (explicit β vectors and/or a number drawn from a seeded normal) and the
//! motions (procedural, or AMASS `.npz` / `.bvh` files with a frame window), plus the
//! frame rate, simulator sub-steps, material and seed shared by all. Every field has a
//! default in code, so a config file only states what it changes; `weft data generate
//! --print-config` writes a preset in full for editing.
//!
//! Presets ([`PRESET_NAMES`]): [`DataConfig::tiny`] (generates in minutes on two cores,
//! for tests and demos), [`DataConfig::small`], [`DataConfig::paper`] (the proportions
//! of seed 000 §4 and supplement §3), and GarFitNet's fit data (seed 001 ch. 4: one
//! garment on bodies of different weight, [`DataConfig::garment_body`]):
//! [`DataConfig::garfit_tiny`] (minutes here) and [`DataConfig::garfit_paper`] (the
//! thesis's proportions).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use weft_garment::GarmentKind;
use weft_motion::MotionKind;

use crate::error::DataError;
use crate::split::Split;

/// The manifest and config layout version this crate writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// A whole dataset config.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DataConfig {
    /// Seed of everything drawn: garment styles without their own seed, random body
    /// shapes, procedural motions without their own seed.
    pub seed: u64,
    /// Frame rate of every sequence (motions are resampled to it).
    pub fps: f64,
    /// Frames of a procedural motion that states no `frames`.
    pub frames: usize,
    /// Simulator sub-steps per frame.
    pub substeps: usize,
    /// Frames simulated before the first stored frame: a third in the rest pose, the rest
    /// blending from it to the motion's first pose, so the garment starts settled. Silk
    /// needs most of the default 90: after 10, a tiny test skirt started 30 mm from its
    /// cut shape where it hangs 65 mm from it, and fell over the first 15 stored frames,
    /// a transient no pose-driven model can predict (docs/datasets.md).
    pub warmup_frames: usize,
    /// Material preset of garments that name none (silk, cotton, jersey, denim, leather,
    /// hood).
    pub material: String,
    /// A body model in the SMPL `.npz` layout; absent: weft's default body.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body: Option<PathBuf>,
    /// Standard deviation of randomly drawn β components.
    pub beta_sigma: f64,
    /// How many leading β components a random body draws (the rest are 0); seed 000
    /// varies the first two.
    pub beta_components: usize,
    /// Random β components stay within ±this (a truncated normal; seed 000: [−2, 2]).
    pub beta_limit: f64,
    /// Fit data (GarFitNet, seed 001 ch. 4): the β every garment is made for (missing
    /// components are 0). Each garment's pattern is built once on this body (the
    /// `garments/<id>.obj` written), and on each body of a sequence it starts as the
    /// pattern really sits there (`weft_garment::prepare::fit_onto`: resized, then draped
    /// with the pattern as rest shape: tight on a fuller body, loose on a slimmer one).
    /// Absent: every garment is made anew for each body it is simulated on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub garment_body: Option<Vec<f64>>,
    /// The training split.
    pub train: SplitConfig,
    /// The validation split.
    pub validation: SplitConfig,
    /// The test split.
    pub test: SplitConfig,
}

/// What one split holds.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SplitConfig {
    /// Explicit body shapes (β vectors; missing components are 0).
    pub betas: Vec<Vec<f64>>,
    /// More body shapes drawn from a normal seeded by the dataset seed and the split.
    pub random_bodies: usize,
    /// How many motions each garment–body pair is simulated with, assigned round-robin so
    /// every motion is used about equally; 0: every motion with every pair.
    pub motions_per_pair: usize,
    /// The garments.
    pub garments: Vec<GarmentSpec>,
    /// The motions.
    pub motions: Vec<MotionSpec>,
}

/// One garment: a procedural template fitted to each body it is simulated on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GarmentSpec {
    /// skirt, dress, tshirt, tank, longsleeve, shorts, pants or jumpsuit.
    pub kind: String,
    /// Target vertex count (the generator lands within ±15 %).
    pub vertices: usize,
    /// Style seed; absent: derived from the dataset seed and the garment's position.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Material preset; absent: the config's `material`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Skirt or dress length, `mini`, `knee` or `maxi` (short, regular, long); absent:
    /// the style seed's. Only for skirts and dresses.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<String>,
}

/// The skirt and dress lengths a [`GarmentSpec::length`] names.
pub const LENGTH_NAMES: [&str; 3] = ["mini", "knee", "maxi"];

/// The length called `name` ([`LENGTH_NAMES`]).
pub fn parse_length(name: &str) -> Option<weft_garment::SkirtLength> {
    use weft_garment::SkirtLength;
    match name {
        "mini" => Some(SkirtLength::Mini),
        "knee" => Some(SkirtLength::Knee),
        "maxi" => Some(SkirtLength::Maxi),
        _ => None,
    }
}

/// One motion: procedural (`kind`) or read from a file (`file`), never both.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MotionSpec {
    /// A procedural motion: walk, run, jump, dance, kick, raise-arms, twist or bow.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    /// An AMASS-style `.npz` or a `.bvh` file (relative paths: from the config file).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    /// Seed of a procedural motion's variations; absent: derived from the dataset seed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Forward speed (walk, run; m/s) or tempo factor (others); absent: the kind's
    /// default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
    /// Amplitude factor of a procedural motion (1: natural).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<f64>,
    /// First frame of a file's motion (after resampling to the dataset's fps).
    #[serde(skip_serializing_if = "is_zero")]
    pub start: usize,
    /// Frames to take; absent: the config's `frames` for procedural motions, the rest of
    /// the file for files.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames: Option<usize>,
}

fn is_zero(x: &usize) -> bool {
    *x == 0
}

impl Default for DataConfig {
    fn default() -> Self {
        DataConfig {
            seed: 0,
            fps: 30.0,
            frames: 40,
            substeps: 2,
            warmup_frames: 90,
            material: "silk".into(),
            body: None,
            beta_sigma: 1.0,
            beta_components: 2,
            beta_limit: 2.0,
            garment_body: None,
            train: SplitConfig::default(),
            validation: SplitConfig::default(),
            test: SplitConfig::default(),
        }
    }
}

/// Names of the presets, for the CLI's help and errors.
pub const PRESET_NAMES: [&str; 5] = ["tiny", "small", "paper", "garfit-tiny", "garfit-paper"];

/// The eight procedural motion kinds, each in the training split of `tiny` and `small`.
const MOTION_KINDS: [&str; 8] = [
    "walk",
    "dance",
    "kick",
    "run",
    "jump",
    "bow",
    "raise-arms",
    "twist",
];

/// The five motions of GarFitNet's dataset (seed 001 §4.4.1: dancing, walking, jumping,
/// raising hands, front kicking).
const GARFIT_MOTIONS: [&str; 5] = ["walk", "jump", "dance", "raise-arms", "kick"];

fn garment(kind: &str, vertices: usize, seed: u64) -> GarmentSpec {
    GarmentSpec {
        kind: kind.into(),
        vertices,
        seed: Some(seed),
        material: None,
        length: None,
    }
}

/// A skirt or dress of `length` (mini, knee, maxi).
fn garment_of_length(kind: &str, length: &str, vertices: usize, seed: u64) -> GarmentSpec {
    GarmentSpec {
        length: Some(length.into()),
        ..garment(kind, vertices, seed)
    }
}

/// Garments with style seeds `first..first + count`, kinds and sizes taken in turn by seed.
fn garment_cycle(kinds: &[&str], sizes: &[usize], first: u64, count: u64) -> Vec<GarmentSpec> {
    (first..first + count)
        .map(|i| {
            garment(
                kinds[i as usize % kinds.len()],
                sizes[i as usize % sizes.len()],
                i,
            )
        })
        .collect()
}

fn motion(kind: &str, seed: u64, frames: Option<usize>) -> MotionSpec {
    MotionSpec {
        kind: Some(kind.into()),
        seed: Some(seed),
        frames,
        ..MotionSpec::default()
    }
}

/// The fit presets' warm-up frames: each garment starts draped on its body
/// ([`DataConfig::garment_body`], `fit_onto`), so the warm-up only brings the pose in.
const GARFIT_WARMUP_FRAMES: usize = 10;

impl DataConfig {
    /// The preset called `name` ([`PRESET_NAMES`]).
    pub fn preset(name: &str) -> Result<Self, DataError> {
        match name {
            "tiny" => Ok(Self::tiny()),
            "small" => Ok(Self::small()),
            "paper" => Ok(Self::paper()),
            "garfit-tiny" => Ok(Self::garfit_tiny()),
            "garfit-paper" => Ok(Self::garfit_paper()),
            _ => Err(DataError::config(
                "preset",
                format!("{name:?}; expected one of {}", PRESET_NAMES.join(", ")),
            )),
        }
    }

    /// A dataset small enough to generate in under five minutes on two cores and still
    /// worth training on: skirts, dresses and t-shirts of 500–850 vertices on five train
    /// shapes (the mean body and four spread over β₁, β₂ ∈ [−2, 2], where the unseen
    /// shapes are drawn: trained on three, the `cpu` model put 1.58 % of the test split's
    /// vertices inside its fuller unseen body, on five 0.68–0.88 %, docs/multilevel.md), each
    /// pair simulated on three of the eight procedural motion kinds; for
    /// validation an unseen dress, shape and walk, and for test two unseen garments (kinds
    /// seen in training) on an unseen shape and two unseen motion clips (a twist and a
    /// larger dance, other seeds than training's). As in seed 000 §4, where test poses
    /// come from CMU sequences no training pair used but of the same kinds of motion, the
    /// splits share no clip, not no kind. Timings: docs/benchmarks.md ("Datasets").
    pub fn tiny() -> Self {
        DataConfig {
            frames: 40,
            train: SplitConfig {
                betas: vec![
                    vec![0.0, 0.0],
                    vec![1.5, -0.5],
                    vec![-1.0, 1.0],
                    vec![1.0, 1.8],
                    vec![-1.5, -1.5],
                ],
                random_bodies: 0,
                motions_per_pair: 3,
                garments: vec![
                    garment("skirt", 600, 1),
                    garment("dress", 800, 2),
                    garment("tshirt", 700, 3),
                    garment("skirt", 800, 4),
                    garment("tshirt", 550, 5),
                ],
                motions: MOTION_KINDS
                    .iter()
                    .zip(1..)
                    .map(|(k, seed)| motion(k, seed, None))
                    .collect(),
            },
            validation: SplitConfig {
                betas: vec![],
                random_bodies: 1,
                motions_per_pair: 0,
                garments: vec![garment("dress", 650, 6)],
                motions: vec![MotionSpec {
                    speed: Some(1.6),
                    ..motion("walk", 11, None)
                }],
            },
            test: SplitConfig {
                betas: vec![],
                random_bodies: 1,
                motions_per_pair: 0,
                garments: vec![garment("skirt", 700, 7), garment("tshirt", 750, 8)],
                motions: vec![
                    motion("twist", 12, None),
                    MotionSpec {
                        amplitude: Some(1.1),
                        ..motion("dance", 13, None)
                    },
                ],
            },
            ..DataConfig::default()
        }
    }

    /// Between [`tiny`](Self::tiny) and [`paper`](Self::paper), to see what more data
    /// buys on this machine (generates in minutes here; docs/benchmarks.md, "Datasets"):
    /// the same three garment kinds as tiny, six of each (500–1 000 vertices, other
    /// styles than tiny's), six train shapes, sixteen motion clips (two of each kind),
    /// each pair on three of them: 324 train sequences of 40 frames, 7.2× tiny's.
    /// Validation: two unseen garments on an unseen shape and two clips; test: one
    /// unseen garment of each kind on two unseen shapes and three clips no training pair
    /// used (a twist, a larger dance and a faster walk).
    pub fn small() -> Self {
        let garments = |first, count| {
            garment_cycle(
                &["skirt", "dress", "tshirt"],
                &[500, 650, 800, 1000, 700, 900],
                first,
                count,
            )
        };
        DataConfig {
            frames: 40,
            train: SplitConfig {
                betas: vec![
                    vec![0.0, 0.0],
                    vec![1.5, -0.5],
                    vec![-1.0, 1.0],
                    vec![-1.8, -1.2],
                    vec![0.8, 1.6],
                    vec![2.0, 0.4],
                ],
                random_bodies: 0,
                motions_per_pair: 3,
                garments: garments(100, 18),
                motions: MOTION_KINDS
                    .iter()
                    .zip(100..)
                    .flat_map(|(k, seed)| [motion(k, seed, None), motion(k, seed + 50, None)])
                    .collect(),
            },
            validation: SplitConfig {
                betas: vec![],
                random_bodies: 1,
                motions_per_pair: 0,
                garments: garments(118, 2),
                motions: vec![motion("kick", 160, None), motion("walk", 161, None)],
            },
            test: SplitConfig {
                betas: vec![],
                random_bodies: 2,
                motions_per_pair: 0,
                garments: garments(120, 3),
                motions: vec![
                    motion("twist", 170, None),
                    MotionSpec {
                        amplitude: Some(1.1),
                        ..motion("dance", 171, None)
                    },
                    MotionSpec {
                        speed: Some(1.6),
                        ..motion("walk", 172, None)
                    },
                ],
            },
            ..DataConfig::default()
        }
    }

    /// Seed 000's proportions (§4; supplement §3): 55 / 5 / 10 garments (dresses and
    /// jumpsuits, as in CLOTH3D, plus skirts), nine train shapes (β₁, β₂ each at four
    /// evenly spaced points of [−2, 2], and the zero shape), three validation and four
    /// random test shapes, and about 50 000 / 3 000 / 8 000 poses: every garment–shape
    /// pair is simulated on one motion (100 frames in train, 200 in validation and test).
    pub fn paper() -> Self {
        let garments = |first, count| {
            garment_cycle(
                &["dress", "jumpsuit", "dress", "skirt"],
                &[2000, 3000, 4000, 6000, 2500],
                first,
                count,
            )
        };
        let grid = [-2.0, -2.0 / 3.0, 2.0 / 3.0, 2.0];
        let mut train_betas = vec![vec![0.0, 0.0]];
        for b in grid {
            train_betas.push(vec![b, 0.0]);
        }
        for b in grid {
            train_betas.push(vec![0.0, b]);
        }
        let train_motions = ["walk", "run", "jump", "dance", "kick"]
            .iter()
            .enumerate()
            .flat_map(|(i, k)| {
                let i = i as u64;
                [motion(k, 100 + i, Some(100)), motion(k, 200 + i, Some(100))]
            })
            .collect();
        DataConfig {
            frames: 100,
            train: SplitConfig {
                betas: train_betas,
                random_bodies: 0,
                motions_per_pair: 1,
                garments: garments(0, 55),
                motions: train_motions,
            },
            validation: SplitConfig {
                betas: vec![],
                random_bodies: 3,
                motions_per_pair: 1,
                garments: garments(55, 5),
                motions: vec![motion("bow", 300, Some(200))],
            },
            test: SplitConfig {
                betas: vec![],
                random_bodies: 4,
                motions_per_pair: 1,
                garments: garments(60, 10),
                motions: vec![
                    motion("raise-arms", 400, Some(200)),
                    motion("twist", 401, Some(200)),
                ],
            },
            ..DataConfig::default()
        }
    }

    /// GarFitNet's fit data at a size that generates here in minutes (seed 001 ch. 4,
    /// `weft data generate --preset garfit-tiny`; timings in docs/benchmarks.md,
    /// "Datasets"). One garment fits bodies of different weight differently, so every
    /// garment is made once for the zero shape (`garment_body`) and started on each body
    /// as it really sits there (tight on a heavier body, loose on a thinner one); β₄
    /// (index 3) is the default body's weight component. Silk, 40 frames.
    ///
    /// * train: four garments of about 600 vertices, a skirt at each length (mini, knee,
    ///   maxi) and a knee dress, on four weights β₄ ∈ {−1.8, −0.6, 0.6, 1.8}, with the
    ///   thesis's five motions (walk, jump, dance, raise-arms, kick), two per pair: 32
    ///   sequences.
    /// * validation: an unseen knee skirt on β₄ = 0.9 with an unseen walk clip.
    /// * test: three unseen skirts (mini, knee, maxi: new style seeds) on a thin (β₄ =
    ///   −1.2), regular (0) and fat (1.2) body, each with an unseen walk (another seed
    ///   and 1.4 m/s) and an unseen jump (another seed, amplitude 1.1): 18 sequences, as
    ///   the thesis tests three new garments on three new bodies. The regular test body
    ///   is the body the garments are made for, but no training body.
    pub fn garfit_tiny() -> Self {
        let weight = |w: f64| vec![0.0, 0.0, 0.0, w];
        DataConfig {
            frames: 40,
            material: "silk".into(),
            garment_body: Some(vec![0.0]),
            warmup_frames: GARFIT_WARMUP_FRAMES,
            train: SplitConfig {
                betas: [-1.8, -0.6, 0.6, 1.8].map(weight).to_vec(),
                random_bodies: 0,
                motions_per_pair: 2,
                garments: vec![
                    garment_of_length("skirt", "mini", 600, 1401),
                    garment_of_length("skirt", "knee", 600, 1402),
                    garment_of_length("skirt", "maxi", 600, 1403),
                    garment_of_length("dress", "knee", 600, 1404),
                ],
                motions: GARFIT_MOTIONS
                    .iter()
                    .zip(1411..)
                    .map(|(k, seed)| motion(k, seed, None))
                    .collect(),
            },
            validation: SplitConfig {
                betas: vec![weight(0.9)],
                random_bodies: 0,
                motions_per_pair: 0,
                garments: vec![garment_of_length("skirt", "knee", 600, 1421)],
                motions: vec![motion("walk", 1422, None)],
            },
            test: SplitConfig {
                betas: [-1.2, 0.0, 1.2].map(weight).to_vec(),
                random_bodies: 0,
                motions_per_pair: 0,
                garments: vec![
                    garment_of_length("skirt", "mini", 600, 1431),
                    garment_of_length("skirt", "knee", 600, 1432),
                    garment_of_length("skirt", "maxi", 600, 1433),
                ],
                motions: vec![
                    MotionSpec {
                        speed: Some(1.4),
                        ..motion("walk", 1441, None)
                    },
                    MotionSpec {
                        amplitude: Some(1.1),
                        ..motion("jump", 1442, None)
                    },
                ],
            },
            ..DataConfig::default()
        }
    }

    /// GarFitNet's dataset at the thesis's proportions (seed 001 §4.4.1; meant for a
    /// cluster, not generated here): eight body weights (β₄ = ±0.5, ±1, ±1.5, ±2) × six
    /// garments (a skirt and a dress at each of the three lengths, 3 500–4 000 vertices,
    /// as the thesis's six garments of 3 178–4 002) = 48 garment–body pairs, every pair
    /// on the five motions (dance, walk, jump, raise-arms, kick) of 305 frames: 1 525
    /// poses per pair, the thesis's count. All garments are made for the zero shape and
    /// fitted onto each body (`garment_body`), silk. Validation: an unseen dress on β₄ =
    /// 0.75 with an unseen walk; test: three unseen garments (a mini skirt, a knee dress,
    /// a maxi skirt) on a thin (β₄ = −1.25), regular (0) and fat (1.25) body, with an
    /// unseen walk and an unseen jump (the thesis's Table 4.2 motion) of 305 frames.
    pub fn garfit_paper() -> Self {
        let weight = |w: f64| vec![0.0, 0.0, 0.0, w];
        let mut garments = Vec::new();
        for (i, length) in ["mini", "knee", "maxi"].iter().enumerate() {
            let i = i as u64;
            garments.push(garment_of_length(
                "skirt",
                length,
                3500 + 200 * i as usize,
                1500 + 2 * i,
            ));
            garments.push(garment_of_length(
                "dress",
                length,
                3600 + 200 * i as usize,
                1501 + 2 * i,
            ));
        }
        DataConfig {
            frames: 305,
            material: "silk".into(),
            garment_body: Some(vec![0.0]),
            warmup_frames: GARFIT_WARMUP_FRAMES,
            train: SplitConfig {
                betas: [-2.0, -1.5, -1.0, -0.5, 0.5, 1.0, 1.5, 2.0]
                    .map(weight)
                    .to_vec(),
                random_bodies: 0,
                motions_per_pair: 0,
                garments,
                motions: GARFIT_MOTIONS
                    .iter()
                    .zip(1510..)
                    .map(|(k, seed)| motion(k, seed, None))
                    .collect(),
            },
            validation: SplitConfig {
                betas: vec![weight(0.75)],
                random_bodies: 0,
                motions_per_pair: 0,
                garments: vec![garment_of_length("dress", "knee", 3800, 1520)],
                motions: vec![motion("walk", 1521, None)],
            },
            test: SplitConfig {
                betas: [-1.25, 0.0, 1.25].map(weight).to_vec(),
                random_bodies: 0,
                motions_per_pair: 0,
                garments: vec![
                    garment_of_length("skirt", "mini", 3400, 1530),
                    garment_of_length("dress", "knee", 3900, 1531),
                    garment_of_length("skirt", "maxi", 4000, 1532),
                ],
                motions: vec![
                    MotionSpec {
                        speed: Some(1.4),
                        ..motion("walk", 1540, None)
                    },
                    MotionSpec {
                        amplitude: Some(1.1),
                        ..motion("jump", 1541, None)
                    },
                ],
            },
            ..DataConfig::default()
        }
    }

    /// Reads a config file; relative motion file paths are taken from the file's
    /// directory. The result is [`validate`](Self::validate)d.
    pub fn load(path: &Path) -> Result<Self, DataError> {
        let text = weft_mesh::io::read_input_to_string(path)
            .map_err(|e| DataError::io(path, "cannot read the dataset config", e))?;
        let mut config = Self::from_toml(&text).map_err(|e| match e {
            DataError::ConfigSyntax { message, .. } => DataError::ConfigSyntax {
                path: path.to_path_buf(),
                message,
            },
            other => other,
        })?;
        if let Some(dir) = path.parent() {
            let rebase = |p: &mut PathBuf| {
                if p.is_relative() && !dir.as_os_str().is_empty() {
                    *p = dir.join(&*p);
                }
            };
            for split in [&mut config.train, &mut config.validation, &mut config.test] {
                for m in &mut split.motions {
                    if let Some(f) = &mut m.file {
                        rebase(f);
                    }
                }
            }
            if let Some(b) = &mut config.body {
                rebase(b);
            }
        }
        config.validate()?;
        Ok(config)
    }

    /// Parses TOML text (not yet validated).
    pub fn from_toml(text: &str) -> Result<Self, DataError> {
        toml::from_str(text).map_err(|e| {
            // toml's Display draws the offending line over several lines; errors here are
            // one line: position, then the reader's message.
            let at = e.span().map(|span| {
                let before = &text[..span.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
                format!("line {line}, column {column}: ")
            });
            DataError::ConfigSyntax {
                path: PathBuf::from("<config>"),
                message: format!(
                    "{}{}",
                    at.unwrap_or_default(),
                    e.message().trim_end().replace('\n', "; ")
                ),
            }
        })
    }

    /// The config as TOML, every field written out.
    pub fn to_toml(&self) -> Result<String, DataError> {
        toml::to_string(self).map_err(|e| DataError::config("<config>", e.to_string()))
    }

    /// The split's config.
    pub fn split(&self, split: Split) -> &SplitConfig {
        match split {
            Split::Train => &self.train,
            Split::Validation => &self.validation,
            Split::Test => &self.test,
        }
    }

    /// Checks every value's range and that each split has something to simulate. Split
    /// overlap is checked on the resolved plan ([`crate::plan::Plan::new`]), where
    /// derived seeds and drawn shapes are known.
    pub fn validate(&self) -> Result<(), DataError> {
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= weft_motion::MAX_FPS) {
            return Err(DataError::config(
                "fps",
                format!(
                    "{}; expected a frame rate above 0 and at most {}",
                    self.fps,
                    weft_motion::MAX_FPS
                ),
            ));
        }
        if self.frames == 0 {
            return Err(DataError::config("frames", "0; expected at least 1 frame"));
        }
        if !(1..=weft_sim::MAX_SUBSTEPS).contains(&self.substeps) {
            return Err(DataError::config(
                "substeps",
                format!(
                    "{}; expected 1 to {}",
                    self.substeps,
                    weft_sim::MAX_SUBSTEPS
                ),
            ));
        }
        if self.warmup_frames > weft_sim::MAX_WARMUP_FRAMES {
            return Err(DataError::config(
                "warmup_frames",
                format!(
                    "{}; expected at most {}",
                    self.warmup_frames,
                    weft_sim::MAX_WARMUP_FRAMES
                ),
            ));
        }
        check_material("material", &self.material)?;
        if !(self.beta_sigma.is_finite() && self.beta_sigma >= 0.0) {
            return Err(DataError::config(
                "beta_sigma",
                format!("{}; expected a finite value ≥ 0", self.beta_sigma),
            ));
        }
        if !(self.beta_limit.is_finite() && self.beta_limit > 0.0) {
            return Err(DataError::config(
                "beta_limit",
                format!("{}; expected a finite value above 0", self.beta_limit),
            ));
        }
        if let Some(b) = &self.garment_body {
            if let Some(j) = b.iter().position(|x| !x.is_finite()) {
                return Err(DataError::config(
                    format!("garment_body[{j}]"),
                    "not a finite number; expected the β the garments are made for",
                ));
            }
        }
        for split in Split::ALL {
            self.validate_split(split)?;
        }
        Ok(())
    }

    fn validate_split(&self, split: Split) -> Result<(), DataError> {
        let s = self.split(split);
        let name = split.name();
        if s.garments.is_empty() {
            return Err(DataError::config(
                format!("{name}.garments"),
                "empty; expected at least one garment per split",
            ));
        }
        if s.motions.is_empty() {
            return Err(DataError::config(
                format!("{name}.motions"),
                "empty; expected at least one motion per split",
            ));
        }
        if s.betas.is_empty() && s.random_bodies == 0 {
            return Err(DataError::config(
                format!("{name}.betas"),
                "no body shapes (betas empty and random_bodies = 0); expected at least one",
            ));
        }
        for (i, b) in s.betas.iter().enumerate() {
            if let Some(j) = b.iter().position(|x| !x.is_finite()) {
                return Err(DataError::config(
                    format!("{name}.betas[{i}][{j}]"),
                    "not a finite number",
                ));
            }
        }
        for (i, g) in s.garments.iter().enumerate() {
            let field = format!("{name}.garments[{i}]");
            GarmentKind::parse(&g.kind).map_err(|_| {
                DataError::config(
                    format!("{field}.kind"),
                    format!(
                        "{:?}; expected one of {}",
                        g.kind,
                        GarmentKind::NAMES.join(", ")
                    ),
                )
            })?;
            let (lo, hi) = (weft_garment::MIN_VERTICES, weft_garment::MAX_VERTICES);
            if !(lo..=hi).contains(&g.vertices) {
                return Err(DataError::config(
                    format!("{field}.vertices"),
                    format!("{}; expected {lo} to {hi}", g.vertices),
                ));
            }
            if let Some(m) = &g.material {
                check_material(&format!("{field}.material"), m)?;
            }
            if let Some(length) = &g.length {
                if parse_length(length).is_none() {
                    return Err(DataError::config(
                        format!("{field}.length"),
                        format!(
                            "{length:?}; expected one of {} (short, regular, long)",
                            LENGTH_NAMES.join(", ")
                        ),
                    ));
                }
                if !matches!(g.kind.as_str(), "skirt" | "dress") {
                    return Err(DataError::config(
                        format!("{field}.length"),
                        format!(
                            "given for a {}; expected only on a skirt or a dress",
                            g.kind
                        ),
                    ));
                }
            }
        }
        for (i, m) in s.motions.iter().enumerate() {
            let field = format!("{name}.motions[{i}]");
            match (&m.kind, &m.file) {
                (Some(_), Some(_)) | (None, None) => {
                    return Err(DataError::config(
                        field,
                        "expected exactly one of `kind` (procedural) or `file` (.npz/.bvh)",
                    ))
                }
                (Some(k), None) => {
                    if MotionKind::parse(k).is_none() {
                        let names: Vec<&str> = MotionKind::ALL.iter().map(|k| k.name()).collect();
                        return Err(DataError::config(
                            format!("{field}.kind"),
                            format!("{k:?}; expected one of {}", names.join(", ")),
                        ));
                    }
                    if m.start != 0 {
                        return Err(DataError::config(
                            format!("{field}.start"),
                            "only file motions take a start frame",
                        ));
                    }
                }
                (None, Some(_)) => {
                    if m.seed.is_some() || m.speed.is_some() || m.amplitude.is_some() {
                        return Err(DataError::config(
                            field,
                            "seed, speed and amplitude apply to procedural motions only",
                        ));
                    }
                }
            }
            if m.frames == Some(0) {
                return Err(DataError::config(
                    format!("{field}.frames"),
                    "0; expected at least 1 frame",
                ));
            }
        }
        Ok(())
    }
}

fn check_material(field: &str, name: &str) -> Result<(), DataError> {
    weft_sim::Material::preset(name)
        .map(|_| ())
        .map_err(|e| DataError::config(field, e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_round_trip_through_toml() {
        for name in PRESET_NAMES {
            let c = DataConfig::preset(name).unwrap();
            c.validate().unwrap();
            let text = c.to_toml().unwrap();
            let back = DataConfig::from_toml(&text).unwrap();
            assert_eq!(back, c, "{name}");
        }
    }

    #[test]
    fn an_empty_file_is_the_defaults_and_fails_validation_by_field() {
        let c = DataConfig::from_toml("").unwrap();
        assert_eq!(c, DataConfig::default());
        let err = c.validate().unwrap_err().to_string();
        assert!(err.contains("train.garments"), "{err}");
    }

    #[test]
    fn errors_name_the_field() {
        let mut c = DataConfig::tiny();
        c.test.garments[1].kind = "cape".into();
        let err = c.validate().unwrap_err().to_string();
        assert!(err.contains("test.garments[1].kind"), "{err}");
        assert!(err.contains("skirt"), "{err}");

        let mut c = DataConfig::tiny();
        c.train.motions[0].file = Some("a.npz".into());
        let err = c.validate().unwrap_err().to_string();
        assert!(err.contains("train.motions[0]"), "{err}");

        let mut c = DataConfig::tiny();
        c.validation.garments[0].material = Some("tweed".into());
        let err = c.validate().unwrap_err().to_string();
        assert!(err.contains("validation.garments[0].material"), "{err}");

        let err = DataConfig::from_toml("fps = 30.0\nframez = 3\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("framez"), "{err}");
    }

    #[test]
    fn small_sits_between_tiny_and_paper() {
        let sequences = |c: &DataConfig| {
            let s = &c.train;
            s.garments.len() * (s.betas.len() + s.random_bodies) * s.motions_per_pair
        };
        let small = DataConfig::small();
        small.validate().unwrap();
        assert_eq!(sequences(&small), 324);
        assert!(sequences(&DataConfig::tiny()) < sequences(&small));
        // Its test split shares no clip with training, and no style with tiny's.
        let seeds =
            |s: &SplitConfig| -> Vec<u64> { s.motions.iter().filter_map(|m| m.seed).collect() };
        assert!(seeds(&small.test)
            .iter()
            .all(|m| !seeds(&small.train).contains(m)));
        let styles = |c: &DataConfig| -> Vec<u64> {
            [&c.train, &c.validation, &c.test]
                .iter()
                .flat_map(|s| s.garments.iter().filter_map(|g| g.seed))
                .collect()
        };
        assert!(styles(&small)
            .iter()
            .all(|g| !styles(&DataConfig::tiny()).contains(g)));
    }

    #[test]
    fn a_length_is_checked_by_value_and_kind_naming_the_field() {
        let mut c = DataConfig::garfit_tiny();
        c.train.garments[1].length = Some("midi".into());
        let err = c.validate().unwrap_err().to_string();
        for needle in ["train.garments[1].length", "\"midi\"", "mini, knee, maxi"] {
            assert!(err.contains(needle), "{needle:?} not in {err}");
        }
        let mut c = DataConfig::garfit_tiny();
        c.test.garments[0].kind = "tshirt".into();
        let err = c.validate().unwrap_err().to_string();
        assert!(
            err.contains("test.garments[0].length") && err.contains("skirt or a dress"),
            "{err}"
        );
        // From TOML, and a config without the field still reads (no length).
        let text = "[[train.garments]]\nkind = \"dress\"\nvertices = 600\nlength = \"maxi\"\n";
        let c = DataConfig::from_toml(text).unwrap();
        assert_eq!(c.train.garments[0].length.as_deref(), Some("maxi"));
        let c = DataConfig::from_toml("[[train.garments]]\nkind = \"dress\"\nvertices = 600\n")
            .unwrap();
        assert_eq!(c.train.garments[0].length, None);
        assert_eq!(c.garment_body, None);
        let err = DataConfig::from_toml(
            "[[train.garments]]\nkind = \"dress\"\nvertices = 600\nlenght = \"mini\"\n",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("lenght"), "{err}");
    }

    #[test]
    fn garment_body_must_be_finite_and_is_not_written_when_absent() {
        let mut c = DataConfig::garfit_tiny();
        c.garment_body = Some(vec![0.0, f64::NAN]);
        let err = c.validate().unwrap_err().to_string();
        assert!(err.contains("garment_body[1]"), "{err}");
        assert!(!DataConfig::tiny()
            .to_toml()
            .unwrap()
            .contains("garment_body"));
        assert!(!DataConfig::tiny().to_toml().unwrap().contains("length"));
        let text = DataConfig::garfit_tiny().to_toml().unwrap();
        assert!(text.contains("garment_body = [0.0]"), "{text}");
    }

    /// garfit-tiny: four garments (three skirt lengths and a dress) made on β = 0, on
    /// four train weights, five motions two per pair; three unseen skirts on three
    /// unseen bodies (thin, regular, fat) with two unseen clips in test.
    #[test]
    fn garfit_presets_hold_one_garment_on_bodies_of_different_weight() {
        let c = DataConfig::garfit_tiny();
        assert_eq!(c.garment_body, Some(vec![0.0]));
        let sequences = |s: &SplitConfig| {
            let k = if s.motions_per_pair == 0 {
                s.motions.len()
            } else {
                s.motions_per_pair
            };
            s.garments.len() * s.betas.len() * k
        };
        assert_eq!(
            [
                sequences(&c.train),
                sequences(&c.validation),
                sequences(&c.test)
            ],
            [32, 1, 18]
        );
        let lengths = |s: &SplitConfig| -> Vec<String> {
            s.garments
                .iter()
                .map(|g| format!("{} {}", g.kind, g.length.as_deref().unwrap_or("-")))
                .collect()
        };
        assert_eq!(
            lengths(&c.train),
            ["skirt mini", "skirt knee", "skirt maxi", "dress knee"]
        );
        assert_eq!(lengths(&c.test), ["skirt mini", "skirt knee", "skirt maxi"]);
        // Only the weight component varies.
        for s in [&c.train, &c.validation, &c.test] {
            assert!(s.betas.iter().all(|b| b.len() == 4 && b[..3] == [0.0; 3]));
        }
        let weights: Vec<f64> = c.test.betas.iter().map(|b| b[3]).collect();
        assert_eq!(weights, [-1.2, 0.0, 1.2]);

        let p = DataConfig::garfit_paper();
        p.validate().unwrap();
        assert_eq!(p.train.garments.len() * p.train.betas.len(), 48);
        assert_eq!(p.train.motions.len() * p.frames, 1525);
        assert!(p
            .train
            .garments
            .iter()
            .all(|g| (3500..=4000).contains(&g.vertices)));
        assert_eq!(p.test.garments.len() * p.test.betas.len(), 9);
    }

    #[test]
    fn paper_has_the_seed_000_proportions() {
        let c = DataConfig::paper();
        assert_eq!(c.train.garments.len(), 55);
        assert_eq!(c.validation.garments.len(), 5);
        assert_eq!(c.test.garments.len(), 10);
        assert_eq!(c.train.betas.len(), 9);
        assert_eq!(c.validation.random_bodies, 3);
        let poses = |s: &SplitConfig, frames: usize| {
            s.garments.len() * (s.betas.len() + s.random_bodies) * frames
        };
        assert_eq!(poses(&c.train, 100), 49_500);
        assert_eq!(poses(&c.validation, 200), 3_000);
        assert_eq!(poses(&c.test, 200), 8_000);
    }
}
