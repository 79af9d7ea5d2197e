//! Garment kinds and their seeded style parameters.

use weft_mesh::rng::SplitMix64;

use crate::skirt::SkirtLength;
use crate::GarmentError;

/// Mixed into every style seed ("WEFTGARM"), so a garment's draws differ from other
/// streams seeded with the same number.
const STYLE_SALT: u64 = 0x5745_4654_4741_524d;

/// The procedural garment kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GarmentKind {
    /// A skirt from the waist (one tube: waist and hem).
    Skirt,
    /// A dress: bodice and skirt in one tube, strapless, with straps or with short sleeves.
    Dress,
    /// A t-shirt with short sleeves.
    TShirt,
    /// A tank top (narrow straps, no sleeves).
    Tank,
    /// A top with long sleeves.
    LongSleeve,
    /// Shorts (legs to mid-thigh).
    Shorts,
    /// Pants (legs to the ankle).
    Pants,
    /// A jumpsuit: t-shirt top and pants in one piece.
    Jumpsuit,
}

impl GarmentKind {
    /// Every kind, in CLI order.
    pub const ALL: [GarmentKind; 8] = [
        GarmentKind::Skirt,
        GarmentKind::Dress,
        GarmentKind::TShirt,
        GarmentKind::Tank,
        GarmentKind::LongSleeve,
        GarmentKind::Shorts,
        GarmentKind::Pants,
        GarmentKind::Jumpsuit,
    ];
    /// The CLI names of [`Self::ALL`].
    pub const NAMES: [&'static str; 8] = [
        "skirt",
        "dress",
        "tshirt",
        "tank",
        "longsleeve",
        "shorts",
        "pants",
        "jumpsuit",
    ];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        let i = Self::ALL.iter().position(|&k| k == self).unwrap_or(0);
        Self::NAMES[i]
    }

    /// Parses a CLI name.
    pub fn parse(name: &str) -> Result<Self, GarmentError> {
        Self::NAMES
            .iter()
            .position(|&n| n == name)
            .map(|i| Self::ALL[i])
            .ok_or_else(|| GarmentError::UnknownKind(name.to_string()))
    }
}

/// What a dress has above the bodice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DressTop {
    /// No straps: the bodice ends under the arms (two boundary loops).
    Strapless,
    /// Narrow straps (four loops: neck, two armholes, hem).
    Straps,
    /// Shoulder panels and short sleeves (four loops: neck, two cuffs, hem).
    Sleeves,
}

/// Style parameters of a garment. [`Style::from_seed`] draws them; any field can be
/// overridden afterwards (the CLI does for length, flare and the dress top).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    /// Distance between body and garment (m): 1–3 cm for fitted kinds, more for loose.
    pub ease: f64,
    /// Skirt/dress flare, 0 (straight) to 1 (wide A-line).
    pub flare: f64,
    /// Skirt/dress length.
    pub length: SkirtLength,
    /// Dress top.
    pub dress_top: DressTop,
    /// Hem waviness, relative radius (0 to 0.05).
    pub wave: f64,
    /// Lobes of the hem waviness around the hem.
    pub lobes: f64,
}

impl Style {
    /// Style drawn from `seed`: the same seed always gives the same style.
    pub fn from_seed(kind: GarmentKind, seed: u64) -> Self {
        let mut r = SplitMix64::new(seed ^ STYLE_SALT);
        let (lo, hi) = match kind {
            GarmentKind::Tank | GarmentKind::Pants | GarmentKind::Shorts => (0.012, 0.025),
            GarmentKind::Skirt | GarmentKind::Dress => (0.015, 0.03),
            _ => (0.02, 0.04),
        };
        let ease = r.uniform(lo, hi);
        let flare = r.uniform(0.1, 0.9);
        let length =
            [SkirtLength::Mini, SkirtLength::Knee, SkirtLength::Maxi][(r.next_u64() % 3) as usize];
        let dress_top =
            [DressTop::Strapless, DressTop::Straps, DressTop::Sleeves][(r.next_u64() % 3) as usize];
        let wave = r.uniform(0.0, 0.04);
        let lobes = (3 + r.next_u64() % 6) as f64;
        Style {
            ease,
            flare,
            length,
            dress_top,
            wave,
            lobes,
        }
    }

    /// Rejects values outside the documented ranges.
    pub fn check(&self) -> Result<(), GarmentError> {
        let range = |name, value: f64, lo: f64, hi: f64, range| {
            if value.is_finite() && (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(GarmentError::Style { name, value, range })
            }
        };
        range("ease", self.ease, 0.003, 0.15, "0.003..=0.15 m")?;
        range("flare", self.flare, 0.0, 1.0, "0..=1")?;
        range("wave", self.wave, 0.0, 0.1, "0..=0.1")?;
        range("lobes", self.lobes, 0.0, 32.0, "0..=32")
    }
}
