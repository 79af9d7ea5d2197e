//! What a character dataset holds, as TOML: how many characters per split, what they
//! wear, which poses, and where the ground truth comes from.
//!
//! Two presets: [`CharacterConfig::tiny`] (builds here in minutes, for tests and the
//! tiny tables) and [`CharacterConfig::paper`] (seed 001's proportions: 150 characters
//! split 125 / 5 / 20 as DenseGATs' §3.2.3.1, with MultiResGNet's 250 poses per
//! character of §3.3.3.1 — 150 random and 100 from clips; the 8 500 poses of §3.2.3.1
//! would be 1.3 M nonlinear solves).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use weft_garment::GarmentKind;
use weft_motion::MotionKind;
use weft_sim::ElasticSkinParams;

use crate::error::DataError;

/// Where a character's ground-truth deformation comes from (thesis-reference D1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TruthSource {
    /// weft's elastic skinning solve (`weft_sim::ElasticSkin`): membrane, bending and
    /// volume with vertices tied to their bones. Works for every body, garments too.
    #[default]
    Elastic,
    /// The full SMPL model with its pose correctives `B_p(θ)` (the thesis's own SMPL
    /// experiment, §3.3.3.1): needs a body file with `posedirs`; the character is the
    /// body alone.
    PoseCorrectives,
}

/// How many characters each split gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CharacterSplit {
    /// Training characters.
    pub train: usize,
    /// Validation characters.
    pub validation: usize,
    /// Test characters.
    pub test: usize,
}

impl CharacterSplit {
    /// Characters in all splits.
    pub fn total(&self) -> usize {
        self.train + self.validation + self.test
    }
}

/// A whole character dataset config.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CharacterConfig {
    /// Seed of every draw: shapes, outfits, random poses, clip variations.
    pub seed: u64,
    /// A body model in the SMPL `.npz` layout; absent: weft's default body.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body: Option<PathBuf>,
    /// Characters per split; no character is in two splits (each has its own shape and
    /// outfit).
    pub characters: CharacterSplit,
    /// Standard deviation of the drawn β components.
    pub beta_sigma: f64,
    /// How many leading β components are drawn (the rest are 0).
    pub beta_components: usize,
    /// β components stay within ±this.
    pub beta_limit: f64,
    /// Tops a character may wear (one drawn per character; empty: none): tshirt, tank,
    /// longsleeve.
    pub tops: Vec<String>,
    /// Bottoms a character may wear (one drawn per character; empty: none): shorts, pants.
    pub bottoms: Vec<String>,
    /// Target vertices of each garment layer.
    pub garment_vertices: usize,
    /// Distance of the tight garment layer from the skin (m).
    pub layer_offset: f64,
    /// Poses per character drawn uniformly inside the joint limits.
    pub random_poses: usize,
    /// The joint-limit boxes scaled by this about their centre for random poses (1: the
    /// full anatomical range; smaller keeps random poses from folding limbs into the
    /// torso).
    pub pose_range: f64,
    /// Procedural clips each character performs (walk, run, jump, dance, kick,
    /// raise-arms, twist, bow); each a fresh seeded variation per character.
    pub motions: Vec<String>,
    /// Frames taken from each clip, evenly spaced over one 2-second clip.
    pub frames_per_motion: usize,
    /// Where the ground truth comes from.
    pub truth: TruthSource,
    /// The elastic-skinning solve of `truth = "elastic"` (`[elastic]`; every field
    /// defaults to weft_sim's documented value).
    pub elastic: ElasticSkinParams,
}

impl Default for CharacterConfig {
    fn default() -> Self {
        Self::tiny()
    }
}

/// The preset names [`CharacterConfig::preset`] knows.
pub const CHARACTER_PRESETS: [&str; 2] = ["tiny", "paper"];

impl CharacterConfig {
    /// The preset called `name`.
    pub fn preset(name: &str) -> Result<Self, DataError> {
        match name {
            "tiny" => Ok(Self::tiny()),
            "paper" => Ok(Self::paper()),
            _ => Err(DataError::config(
                "preset",
                format!("{name:?}; expected one of {}", CHARACTER_PRESETS.join(", ")),
            )),
        }
    }

    /// Six characters (4 / 1 / 1) in t-shirts or long sleeves over shorts or pants, 24
    /// random poses and 2 frames of each of five clips per character.
    pub fn tiny() -> Self {
        CharacterConfig {
            seed: 0,
            body: None,
            characters: CharacterSplit {
                train: 4,
                validation: 1,
                test: 1,
            },
            beta_sigma: 1.0,
            beta_components: 2,
            beta_limit: 2.0,
            tops: vec!["tshirt".into(), "longsleeve".into()],
            bottoms: vec!["shorts".into(), "pants".into()],
            garment_vertices: 600,
            layer_offset: 0.006,
            random_poses: 24,
            pose_range: 0.8,
            motions: ["walk", "run", "jump", "dance", "kick"]
                .map(String::from)
                .to_vec(),
            frames_per_motion: 2,
            truth: TruthSource::Elastic,
            elastic: ElasticSkinParams::default(),
        }
    }

    /// Seed 001's proportions (see the module documentation).
    pub fn paper() -> Self {
        CharacterConfig {
            characters: CharacterSplit {
                train: 125,
                validation: 5,
                test: 20,
            },
            beta_components: 10,
            tops: vec!["tshirt".into(), "longsleeve".into(), "tank".into()],
            garment_vertices: 2500,
            random_poses: 150,
            frames_per_motion: 20,
            ..Self::tiny()
        }
    }

    /// Reads a config file (a relative body path is taken from the file's directory) and
    /// validates it.
    pub fn load(path: &Path) -> Result<Self, DataError> {
        let text = weft_mesh::io::read_input_to_string(path)
            .map_err(|e| DataError::io(path, "cannot read the character config", e))?;
        let mut config: CharacterConfig =
            toml::from_str(&text).map_err(|e| DataError::ConfigSyntax {
                path: path.to_path_buf(),
                message: e.message().trim_end().replace('\n', "; "),
            })?;
        if let (Some(b), Some(dir)) = (&mut config.body, path.parent()) {
            if b.is_relative() && !dir.as_os_str().is_empty() {
                *b = dir.join(&*b);
            }
        }
        config.validate()?;
        Ok(config)
    }

    /// The tops, parsed.
    pub fn top_kinds(&self) -> Result<Vec<GarmentKind>, DataError> {
        kinds(
            "tops",
            &self.tops,
            &[
                GarmentKind::TShirt,
                GarmentKind::Tank,
                GarmentKind::LongSleeve,
            ],
        )
    }

    /// The bottoms, parsed.
    pub fn bottom_kinds(&self) -> Result<Vec<GarmentKind>, DataError> {
        kinds(
            "bottoms",
            &self.bottoms,
            &[GarmentKind::Shorts, GarmentKind::Pants],
        )
    }

    /// The clips, parsed.
    pub fn motion_kinds(&self) -> Result<Vec<MotionKind>, DataError> {
        self.motions
            .iter()
            .enumerate()
            .map(|(i, m)| {
                MotionKind::parse(m).ok_or_else(|| {
                    DataError::config(
                        format!("motions[{i}]"),
                        format!("{m:?} is not a procedural motion (walk, run, jump, dance, kick, raise-arms, twist, bow)"),
                    )
                })
            })
            .collect()
    }

    /// Poses per character.
    pub fn poses_per_character(&self) -> usize {
        self.random_poses + self.motions.len() * self.frames_per_motion
    }

    /// Checks every value; errors name the field.
    pub fn validate(&self) -> Result<(), DataError> {
        if self.characters.train == 0 {
            return Err(DataError::config(
                "characters.train",
                "0; at least one training character is needed",
            ));
        }
        if self.poses_per_character() == 0 {
            return Err(DataError::config(
                "random_poses",
                "no poses: set random_poses or motions with frames_per_motion",
            ));
        }
        let positive = |field: &str, v: f64, hi: f64| {
            if v.is_finite() && v > 0.0 && v <= hi {
                Ok(())
            } else {
                Err(DataError::config(
                    field,
                    format!("{v}; expected above 0 and at most {hi}"),
                ))
            }
        };
        positive("pose_range", self.pose_range, 1.0)?;
        self.elastic
            .check()
            .map_err(|e| DataError::config("elastic", e.to_string()))?;
        positive("layer_offset", self.layer_offset, 0.05)?;
        positive("beta_limit", self.beta_limit, 5.0)?;
        if !(self.beta_sigma.is_finite() && self.beta_sigma >= 0.0) {
            return Err(DataError::config(
                "beta_sigma",
                format!("{}; expected a non-negative number", self.beta_sigma),
            ));
        }
        self.top_kinds()?;
        self.bottom_kinds()?;
        self.motion_kinds()?;
        let dressed = !(self.tops.is_empty() && self.bottoms.is_empty());
        if dressed
            && !(weft_garment::MIN_VERTICES..=weft_garment::MAX_VERTICES)
                .contains(&self.garment_vertices)
        {
            return Err(DataError::config(
                "garment_vertices",
                format!(
                    "{}; expected {} to {}",
                    self.garment_vertices,
                    weft_garment::MIN_VERTICES,
                    weft_garment::MAX_VERTICES
                ),
            ));
        }
        if self.truth == TruthSource::PoseCorrectives && dressed {
            return Err(DataError::config(
                "truth",
                "pose_correctives describes the SMPL body alone; set tops = [] and bottoms = []",
            ));
        }
        Ok(())
    }

    /// The config as TOML (what `weft data characters --print-config` writes).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }
}

fn kinds(
    field: &str,
    names: &[String],
    allowed: &[GarmentKind],
) -> Result<Vec<GarmentKind>, DataError> {
    names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let bad = || {
                DataError::config(
                    format!("{field}[{i}]"),
                    format!(
                        "{n:?}; expected one of {}",
                        allowed
                            .iter()
                            .map(|k| k.name())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            };
            let k = GarmentKind::parse(n).map_err(|_| bad())?;
            if allowed.contains(&k) {
                Ok(k)
            } else {
                Err(bad())
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_round_trip() {
        for name in CHARACTER_PRESETS {
            let c = CharacterConfig::preset(name).unwrap();
            c.validate().unwrap();
            let back: CharacterConfig = toml::from_str(&c.to_toml()).unwrap();
            assert_eq!(back, c);
        }
        assert_eq!(CharacterConfig::paper().poses_per_character(), 250);
        assert_eq!(CharacterConfig::paper().characters.total(), 150);
    }

    #[test]
    fn bad_values_name_their_field() {
        let mut c = CharacterConfig::tiny();
        c.tops = vec!["skirt".into()];
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("tops[0]") && e.contains("skirt"), "{e}");
        let mut c = CharacterConfig::tiny();
        c.motions = vec!["moonwalk".into()];
        assert!(c.validate().unwrap_err().to_string().contains("motions[0]"));
        let mut c = CharacterConfig::tiny();
        c.truth = TruthSource::PoseCorrectives;
        assert!(c.validate().unwrap_err().to_string().contains("truth"));
        c.tops.clear();
        c.bottoms.clear();
        c.validate().unwrap();
        let mut c = CharacterConfig::tiny();
        c.pose_range = 1.5;
        assert!(c.validate().unwrap_err().to_string().contains("pose_range"));
        let mut c = CharacterConfig::tiny();
        c.elastic.bending_stiffness = -1.0;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("elastic") && e.contains("bending"), "{e}");
    }

    #[test]
    fn elastic_parameters_come_from_the_file_and_default_per_field() {
        let c: CharacterConfig = toml::from_str("[elastic]\nbending_stiffness = 1.0\n").unwrap();
        assert_eq!(c.elastic.bending_stiffness, 1.0);
        assert_eq!(
            c.elastic.volume_stiffness,
            ElasticSkinParams::default().volume_stiffness
        );
        assert!(toml::from_str::<CharacterConfig>("[elastic]\nstiffness = 1.0\n").is_err());
        // A dataset config written before `[elastic]` existed reads as the defaults.
        let old: CharacterConfig = toml::from_str("seed = 0\n").unwrap();
        assert_eq!(old.elastic, ElasticSkinParams::default());
    }
}
