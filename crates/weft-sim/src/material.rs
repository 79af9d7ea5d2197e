//! Cloth materials: density, Young's modulus and Poisson's ratio (mapped to the Lamé
//! parameters of the StVK membrane), thickness, bending stiffness and the garment–body
//! friction coefficient, with named presets.
//!
//! The membrane is a thin sheet in plane stress, so the 2D Lamé parameters are
//! `μ = E / (2(1 + ν))` and `λ = E ν / (1 − ν²)` (not the 3D `λ = Eν/((1+ν)(1−2ν))`,
//! which diverges at `ν = ½`; the plane-stress map holds for `0 <= ν < 1`, see
//! [`Material::validate`]); the stretching energy multiplies the density by the
//! thickness (HOOD's convention), so `E · thickness` is the membrane stiffness in N/m.
//! Values and their sources are in `docs/physics.md`: HOOD's default material is exact
//! (taken from their code); the fabric presets are approximate, order-of-magnitude
//! values within the ranges reported for fabric measurements, not measurements of a
//! particular fabric.

use crate::error::{check_nonneg, SimError};
use crate::stretch::StretchParams;

/// A homogeneous cloth material. A TOML table sets any of its fields; the others keep
/// the defaults of [`Material::hood`] stated on each field (the presets stay the way to
/// name a fabric: `Material::preset("silk")`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Material {
    /// Preset name. In a file: one of [`PRESET_NAMES`] (any case) or `custom`; the name
    /// only labels the material, the values are the fields'. Default: `hood`.
    #[serde(deserialize_with = "known_name")]
    pub name: StaticName,
    /// Area density, kg/m². Default: 0.20022.
    pub density: f64,
    /// Young's modulus, Pa. Default: about 70 079 (from HOOD's `μ`, `λ`).
    pub young_modulus: f64,
    /// Poisson's ratio, in [0, 1) (unitless; the membrane's plane-stress ratio, see
    /// [`Material::validate`]). Default: about 0.4847 (from HOOD's `μ`, `λ`).
    pub poisson_ratio: f64,
    /// Shell thickness, m. Default: 4.7·10⁻⁴ (0.47 mm).
    pub thickness: f64,
    /// Bending stiffness `k_b` of the dihedral energy in HOOD's scaling
    /// ([`crate::BendingScale::Hood`]), N·m. For a bending rigidity `B` (N·m, e.g. from
    /// the Kawabata B value), `k_b ≈ 4B` on regular meshes (the cylinder calibration in
    /// `docs/physics.md`). Default: 3.9626·10⁻⁵.
    pub bending_stiffness: f64,
    /// Garment–body friction coefficient μ (unitless). Default: 0.5.
    pub friction: f64,
}

/// `&'static str` under another name: serde borrows fields spelled `&str` from the input,
/// which a `'static` name cannot be; [`known_name`] maps file names to static ones.
type StaticName = &'static str;

/// HOOD's material ([`Material::hood`]), the default of every field in a file.
impl Default for Material {
    fn default() -> Self {
        Material::hood()
    }
}

/// The name a file gives a material: a preset's (case-insensitive) or `custom`. Names
/// are `&'static str` so materials stay `Copy`; an unknown one is refused, not leaked.
fn known_name<'de, D: serde::Deserializer<'de>>(d: D) -> Result<&'static str, D::Error> {
    let name = <std::borrow::Cow<'de, str> as serde::Deserialize>::deserialize(d)?;
    PRESET_NAMES
        .iter()
        .chain(&["custom"])
        .find(|n| n.eq_ignore_ascii_case(&name))
        .copied()
        .ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown material name `{name}`; expected one of {} or custom",
                PRESET_NAMES.join(", ")
            ))
        })
}

/// Names of the presets, in [`Material::presets`] order.
pub const PRESET_NAMES: [&str; 6] = ["hood", "silk", "cotton", "jersey", "denim", "leather"];

impl Material {
    /// HOOD's default (validation) material, from their code: `ρ = 0.20022 kg/m²`,
    /// `μ = 23 600 Pa`, `λ = 44 400 Pa`, `k_bending = 3.9626·10⁻⁵`, thickness 0.47 mm,
    /// friction 0.5. `E` and `ν` are the plane-stress inverse of `μ`, `λ`.
    pub fn hood() -> Self {
        Self::from_lame(
            "hood",
            0.20022,
            23_600.0,
            44_400.0,
            4.7e-4,
            3.962_577_833_333_332_5e-5,
            0.5,
        )
    }

    /// Light silk (e.g. crêpe de Chine, habotai).
    pub fn silk() -> Self {
        Material {
            name: "silk",
            density: 0.06,
            young_modulus: 2.0e6,
            poisson_ratio: 0.3,
            thickness: 1.5e-4,
            bending_stiffness: 8.0e-6,
            friction: 0.3,
        }
    }

    /// Cotton shirting / poplin.
    pub fn cotton() -> Self {
        Material {
            name: "cotton",
            density: 0.15,
            young_modulus: 3.0e6,
            poisson_ratio: 0.3,
            thickness: 3.5e-4,
            bending_stiffness: 3.1e-5,
            friction: 0.5,
        }
    }

    /// Cotton jersey (weft knit): stretchy, soft.
    pub fn jersey() -> Self {
        Material {
            name: "jersey",
            density: 0.20,
            young_modulus: 4.0e5,
            poisson_ratio: 0.4,
            thickness: 6.0e-4,
            bending_stiffness: 1.6e-5,
            friction: 0.5,
        }
    }

    /// Denim (12–14 oz twill).
    pub fn denim() -> Self {
        Material {
            name: "denim",
            density: 0.40,
            young_modulus: 6.0e6,
            poisson_ratio: 0.25,
            thickness: 7.0e-4,
            bending_stiffness: 3.9e-4,
            friction: 0.6,
        }
    }

    /// Garment leather (lamb/cow nappa, about 1 mm).
    pub fn leather() -> Self {
        Material {
            name: "leather",
            density: 0.9,
            young_modulus: 2.0e7,
            poisson_ratio: 0.35,
            thickness: 1.1e-3,
            bending_stiffness: 2.0e-3,
            friction: 0.6,
        }
    }

    /// All presets, in [`PRESET_NAMES`] order.
    pub fn presets() -> [Material; 6] {
        [
            Self::hood(),
            Self::silk(),
            Self::cotton(),
            Self::jersey(),
            Self::denim(),
            Self::leather(),
        ]
    }

    /// The preset called `name` (case-insensitive).
    pub fn preset(name: &str) -> Result<Self, SimError> {
        Self::presets()
            .into_iter()
            .find(|m| m.name.eq_ignore_ascii_case(name))
            .ok_or_else(|| SimError::UnknownMaterial {
                name: name.to_string(),
                known: PRESET_NAMES.join(", "),
            })
    }

    /// A material from Lamé parameters (plane stress) instead of `E`, `ν`.
    pub fn from_lame(
        name: &'static str,
        density: f64,
        mu: f64,
        lambda: f64,
        thickness: f64,
        bending_stiffness: f64,
        friction: f64,
    ) -> Self {
        let (young_modulus, poisson_ratio) = young_poisson(mu, lambda);
        Material {
            name,
            density,
            young_modulus,
            poisson_ratio,
            thickness,
            bending_stiffness,
            friction,
        }
    }

    /// Checks every value: positive density, modulus and thickness, `0 <= ν < 1`,
    /// non-negative bending and friction, all finite.
    ///
    /// `ν` is the plane-stress ratio of the membrane: `0 <= ν < 1` is exactly `μ > 0`,
    /// `λ >= 0` ([`lame_plane_stress`]; `ν = λ/(λ + 2μ)`), where the StVK membrane energy
    /// is positive definite. `ν >= ½` (`λ >= 2μ`) has no isotropic 3D solid behind it, but
    /// woven fabrics measure in-plane ratios above ½, and HOOD's training materials
    /// (`μ` down to 15 909 Pa, `λ` up to 93 334 Pa, [`crate::hood_material`]) reach
    /// `ν ≈ 0.75`.
    pub fn validate(&self) -> Result<(), SimError> {
        let name = self.name;
        check_nonneg(|| format!("{name} density"), self.density, true)?;
        check_nonneg(
            || format!("{name} Young's modulus"),
            self.young_modulus,
            true,
        )?;
        check_nonneg(|| format!("{name} thickness"), self.thickness, true)?;
        check_nonneg(
            || format!("{name} bending stiffness"),
            self.bending_stiffness,
            false,
        )?;
        check_nonneg(|| format!("{name} friction"), self.friction, false)?;
        if !(self.poisson_ratio >= 0.0 && self.poisson_ratio < 1.0) {
            return Err(SimError::InvalidParameter {
                what: format!("{name} Poisson's ratio"),
                value: self.poisson_ratio,
                expected: "expected 0 <= ν < 1",
            });
        }
        Ok(())
    }

    /// Plane-stress Lamé parameters `(μ, λ)`, Pa.
    pub fn lame(&self) -> (f64, f64) {
        lame_plane_stress(self.young_modulus, self.poisson_ratio)
    }

    /// The StVK parameters of one face.
    pub fn stretch_params(&self) -> StretchParams {
        let (mu, lambda) = self.lame();
        StretchParams {
            mu,
            lambda,
            thickness: self.thickness,
        }
    }
}

/// Plane-stress Lamé parameters: `μ = E/(2(1+ν))`, `λ = Eν/(1−ν²)`.
pub fn lame_plane_stress(young_modulus: f64, poisson_ratio: f64) -> (f64, f64) {
    let (e, nu) = (young_modulus, poisson_ratio);
    (e / (2.0 * (1.0 + nu)), e * nu / (1.0 - nu * nu))
}

/// The inverse of [`lame_plane_stress`]: `ν = r/(2 + r)` with `r = λ/μ`, `E = 2μ(1+ν)`.
pub fn young_poisson(mu: f64, lambda: f64) -> (f64, f64) {
    let r = lambda / mu;
    let nu = r / (2.0 + r);
    (2.0 * mu * (1.0 + nu), nu)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid_and_named() {
        for (m, n) in Material::presets().iter().zip(PRESET_NAMES) {
            m.validate().unwrap();
            assert_eq!(m.name, n);
            assert_eq!(Material::preset(&n.to_uppercase()).unwrap(), *m);
        }
        assert!(matches!(
            Material::preset("tweed"),
            Err(SimError::UnknownMaterial { .. })
        ));
    }

    #[test]
    fn materials_round_trip_through_toml_and_partial_tables_take_defaults() {
        for m in Material::presets() {
            let text = toml::to_string(&m).unwrap();
            assert_eq!(toml::from_str::<Material>(&text).unwrap(), m, "{text}");
        }
        let m: Material = toml::from_str("name = \"Custom\"\ndensity = 0.3\n").unwrap();
        assert_eq!(
            m,
            Material {
                name: "custom",
                density: 0.3,
                ..Material::hood()
            }
        );
        assert_eq!(toml::from_str::<Material>("").unwrap(), Material::default());
        let e = toml::from_str::<Material>("densty = 0.3")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown field `densty`"), "{e}");
        let e = toml::from_str::<Material>("name = \"tweed\"")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown material name `tweed`"), "{e}");
    }

    #[test]
    fn hood_material_round_trips_its_lame_parameters() {
        let (mu, lambda) = Material::hood().lame();
        assert!((mu - 23_600.0).abs() < 1e-8 && (lambda - 44_400.0).abs() < 1e-8);
    }

    /// The corner of HOOD's training range with the largest `λ/μ` (ν ≈ 0.75 in plane
    /// stress) is a valid material and keeps its Lamé parameters.
    #[test]
    fn hoods_softest_corner_is_valid() {
        let (mu, lambda) = (15_909.0, 93_333.74);
        let m = Material::from_lame("custom", 0.2, mu, lambda, 4.7e-4, 1e-6, 0.5);
        m.validate().unwrap();
        assert!(m.poisson_ratio > 0.74 && m.poisson_ratio < 0.75, "{m:?}");
        let (mu2, lambda2) = m.lame();
        assert!((mu2 - mu).abs() < 1e-9 * mu && (lambda2 - lambda).abs() < 1e-9 * lambda);
    }

    #[test]
    fn bad_values_are_rejected() {
        let mut m = Material::cotton();
        m.poisson_ratio = 1.0;
        assert!(m.validate().is_err());
        m.poisson_ratio = -0.1;
        assert!(m.validate().is_err());
        m = Material::cotton();
        m.density = 0.0;
        assert!(m.validate().is_err());
        m = Material::cotton();
        m.young_modulus = f64::NAN;
        assert!(m.validate().is_err());
    }
}
