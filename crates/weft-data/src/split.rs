//! The three splits of seed 000 §4: train, validation and test, which share no garment,
//! no body shape and no motion, so the test numbers measure generalisation to unseen
//! garments, shapes and motions.

use std::fmt;

use serde::{Deserialize, Serialize};

/// A dataset split.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// Fits the network's parameters.
    Train,
    /// Chooses hyper-parameters and stopping points.
    Validation,
    /// Reported numbers only.
    Test,
}

impl Split {
    /// All splits, in manifest order.
    pub const ALL: [Split; 3] = [Split::Train, Split::Validation, Split::Test];

    /// The lowercase name used in configs, manifests and ids.
    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Validation => "validation",
            Split::Test => "test",
        }
    }
}

impl fmt::Display for Split {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serde_names_are_lowercase() {
        for s in Split::ALL {
            let json = serde_json::to_string(&s).unwrap();
            assert_eq!(json, format!("\"{}\"", s.name()));
            let back: Split = serde_json::from_str(&json).unwrap();
            assert_eq!(back, s);
        }
    }
}
