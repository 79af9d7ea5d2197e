//! Character datasets for seed 001's case 1 (DenseGATs, MultiResGNet): dressed
//! characters as one mesh, posed many ways, with a ground-truth nonlinear deformation
//! of every pose that a network learns to recover from linear blend skinning.
//!
//! * [`config`]: what to build (TOML; presets `tiny` and `paper`).
//! * [`dressed`]: a body and tight garment layers as one skinned mesh.
//! * [`poses`]: random poses in the joint limits and clip frames.
//! * [`file`]: one safetensors file per character.
//! * [`manifest`]: `characters.json` and the loader ([`CharacterSet`]).
//! * [`generate`]: the resumable build (`weft data characters`).
//!
//! See docs/characters.md.

pub mod config;
pub mod dressed;
pub mod file;
pub mod generate;
pub mod manifest;
pub mod poses;

pub use config::{CharacterConfig, CharacterSplit, TruthSource, CHARACTER_PRESETS};
pub use dressed::{dress, DressedCharacter};
pub use file::CharacterData;
pub use generate::{build_characters, CharacterReport};
pub use manifest::{CharacterManifest, CharacterRecord, CharacterSet, CHARACTER_MANIFEST};
