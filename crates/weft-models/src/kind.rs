//! [`ModelKind`]: the learned systems weft knows by name, so a run directory, a config
//! file and the command line can say which one they mean.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// A learned garment deformation system, named as in config files and on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// Seed 000's Multilevel model.
    Multilevel,
    /// HOOD: a hierarchical graph network trained by the incremental potential.
    Hood,
    /// The thesis' dense graph attention networks.
    DenseGats,
    /// The thesis' multi-resolution graph network.
    MultiResGnet,
    /// The thesis' garment fitting network.
    GarFitNet,
}

impl ModelKind {
    /// Every kind, in the order help texts list them.
    pub const ALL: [ModelKind; 5] = [
        ModelKind::Multilevel,
        ModelKind::Hood,
        ModelKind::DenseGats,
        ModelKind::MultiResGnet,
        ModelKind::GarFitNet,
    ];

    /// The name in config files and on the command line (`multilevel`, `hood`, …).
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Multilevel => "multilevel",
            ModelKind::Hood => "hood",
            ModelKind::DenseGats => "densegats",
            ModelKind::MultiResGnet => "multiresgnet",
            ModelKind::GarFitNet => "garfitnet",
        }
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A model name that is not one of [`ModelKind::ALL`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown model `{found}`; expected one of: {}", names())]
pub struct UnknownModelKind {
    /// The name given.
    pub found: String,
}

fn names() -> String {
    ModelKind::ALL.map(ModelKind::name).join(", ")
}

impl FromStr for ModelKind {
    type Err = UnknownModelKind;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ModelKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| UnknownModelKind {
                found: s.to_string(),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_match_serde() {
        for kind in ModelKind::ALL {
            assert_eq!(kind.name().parse::<ModelKind>(), Ok(kind));
            assert_eq!(kind.to_string(), kind.name());
            let v = toml::Value::try_from(kind).unwrap();
            assert_eq!(v.as_str(), Some(kind.name()));
            assert_eq!(v.try_into::<ModelKind>().unwrap(), kind);
        }
        let e = "multi".parse::<ModelKind>().unwrap_err().to_string();
        assert!(
            e.contains("`multi`") && e.contains("multilevel, hood, densegats"),
            "{e}"
        );
    }
}
