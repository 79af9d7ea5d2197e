//! `characters.json`: what a character dataset holds, and the loader training and
//! evaluation open it with ([`CharacterSet`]).
//!
//! Only finished characters are recorded, each with the SHA-256 of its file, so a
//! resumed build keeps exactly the characters whose files are intact.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::config::CharacterConfig;
use super::file::{self, CharacterData};
use crate::error::DataError;
use crate::split::Split;

/// The manifest's file name in a character dataset directory.
pub const CHARACTER_MANIFEST: &str = "characters.json";

/// The layout version of [`CharacterManifest`].
pub const CHARACTER_FORMAT: u32 = 1;

/// One finished character.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CharacterRecord {
    /// `c000`, `c001`, … in plan order.
    pub id: String,
    /// Its split.
    pub split: Split,
    /// Its shape.
    pub betas: Vec<f64>,
    /// The garment layers it wears.
    pub outfit: Vec<String>,
    /// Vertices of the whole character mesh.
    pub vertices: usize,
    /// Vertices of its body part.
    pub body_vertices: usize,
    /// Poses in its file.
    pub poses: usize,
    /// The file, relative to the dataset directory.
    pub file: String,
    /// SHA-256 of the file's bytes.
    pub sha256: String,
    /// Seconds the ground truth took.
    pub seconds: f64,
}

/// The whole manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CharacterManifest {
    /// [`CHARACTER_FORMAT`] of the writer.
    pub format_version: u32,
    /// The config the dataset was built from.
    pub config: CharacterConfig,
    /// Finished characters, in plan order.
    pub characters: Vec<CharacterRecord>,
}

impl CharacterManifest {
    /// Reads `dir/characters.json`.
    pub fn load(dir: &Path) -> Result<Self, DataError> {
        let path = dir.join(CHARACTER_MANIFEST);
        let text = weft_mesh::io::read_input_to_string(&path)
            .map_err(|e| DataError::io(&path, "cannot read the character manifest (is this a character dataset? build one with `weft data characters`)", e))?;
        let m: CharacterManifest =
            serde_json::from_str(&text).map_err(|e| DataError::Manifest {
                path: path.clone(),
                message: e.to_string(),
            })?;
        if m.format_version != CHARACTER_FORMAT {
            return Err(DataError::Manifest {
                path,
                message: format!(
                    "format_version {}; this build reads {CHARACTER_FORMAT}",
                    m.format_version
                ),
            });
        }
        Ok(m)
    }

    /// Writes `dir/characters.json` atomically.
    pub fn save(&self, dir: &Path) -> Result<(), DataError> {
        let path = dir.join(CHARACTER_MANIFEST);
        let text = serde_json::to_string_pretty(self).map_err(|e| DataError::Manifest {
            path: path.clone(),
            message: e.to_string(),
        })?;
        weft_mesh::io::write_atomic(&path, |w| w.write_all(text.as_bytes()))
            .map_err(|e| DataError::io(&path, "cannot write the character manifest", e))
    }
}

/// A character dataset on disk.
#[derive(Clone, Debug)]
pub struct CharacterSet {
    root: PathBuf,
    manifest: CharacterManifest,
}

impl CharacterSet {
    /// Opens the dataset in `dir`.
    pub fn open(dir: &Path) -> Result<Self, DataError> {
        Ok(CharacterSet {
            root: dir.to_path_buf(),
            manifest: CharacterManifest::load(dir)?,
        })
    }

    /// Its directory.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Its manifest.
    pub fn manifest(&self) -> &CharacterManifest {
        &self.manifest
    }

    /// The finished characters of `split`, in plan order.
    pub fn records(&self, split: Split) -> Vec<&CharacterRecord> {
        self.manifest
            .characters
            .iter()
            .filter(|r| r.split == split)
            .collect()
    }

    /// Reads a character's file, checking its digest and that it matches its record.
    pub fn load(&self, record: &CharacterRecord) -> Result<CharacterData, DataError> {
        let path = self.root.join(&record.file);
        let d = file::read(&path, Some(&record.sha256))?;
        if d.vertex_count() != record.vertices || d.poses.len() != record.poses {
            return Err(DataError::Manifest {
                path: self.root.join(CHARACTER_MANIFEST),
                message: format!(
                    "{}: the file holds {} vertices and {} poses; the record says {} and {}",
                    record.id,
                    d.vertex_count(),
                    d.poses.len(),
                    record.vertices,
                    record.poses
                ),
            });
        }
        Ok(d)
    }
}
