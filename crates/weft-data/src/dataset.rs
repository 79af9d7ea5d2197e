//! The loader: open a dataset directory, list its sequences by split, read a sequence's
//! shard, read a garment.

use std::path::{Path, PathBuf};

use weft_mesh::TriMesh;

use crate::error::DataError;
use crate::manifest::{partial_manifests, Manifest, SequenceRecord, MANIFEST_FILE};
use crate::shard::{self, ShardShape};
use crate::split::Split;

/// A generated dataset on disk (see [`crate::manifest`] for the layout).
#[derive(Clone, Debug)]
pub struct Dataset {
    dir: PathBuf,
    manifest: Manifest,
}

/// One sequence, loaded.
#[derive(Clone, Debug, PartialEq)]
pub struct Sequence {
    /// Its manifest record.
    pub record: SequenceRecord,
    /// The garment fitted to this sequence's body, in rest pose: the template whose
    /// vertices `positions` moves (same vertex order; f32 values widened to f64). With
    /// the config's `garment_body` (fit data) it is the pattern fitted onto this body
    /// (tight on a fuller body, loose on a slimmer one) and the simulator's rest shape
    /// was the pattern, [`Dataset::garment`].
    pub garment: TriMesh,
    /// UV of each face corner (m), the flat pattern of the seed 000 stretch/shear losses
    /// and of rest frames; one row per face of `garment`.
    pub corner_uvs: Vec<[[f32; 2]; 3]>,
    /// SMPL pose per frame: 24 axis-angle rotations.
    pub poses: Vec<weft_body::Pose>,
    /// Root translation per frame (m).
    pub trans: Vec<[f32; 3]>,
    /// Simulated garment vertex positions per frame (m).
    pub positions: Vec<Vec<[f32; 3]>>,
}

impl Dataset {
    /// Reads and validates `dir/manifest.json`. A directory holding only the partial
    /// manifests of `--shard i/n` jobs is refused with the merge command to run.
    pub fn open(dir: &Path) -> Result<Self, DataError> {
        let path = dir.join(MANIFEST_FILE);
        if !path.exists() {
            let parts = partial_manifests(dir)?;
            if !parts.is_empty() {
                return Err(DataError::Conflict {
                    path: dir.to_path_buf(),
                    message: format!(
                        "{} partial manifests of --shard jobs but no {MANIFEST_FILE}; run `weft data merge {}` first",
                        parts.len(),
                        dir.display()
                    ),
                });
            }
        }
        let manifest = Manifest::read(&path)?;
        Ok(Dataset {
            dir: dir.to_path_buf(),
            manifest,
        })
    }

    /// The dataset directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The whole manifest (config echo, garments, bodies, motions).
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// Every sequence record, in plan order, whatever its status.
    pub fn records(&self) -> &[SequenceRecord] {
        &self.manifest.sequences
    }

    /// The loadable records of one split: done, or diverged with at least one finished
    /// frame ([`SequenceRecord::has_frames`]).
    pub fn records_in(&self, split: Split) -> Vec<&SequenceRecord> {
        self.manifest
            .sequences
            .iter()
            .filter(|r| r.split == split && r.has_frames())
            .collect()
    }

    /// The record with this id.
    pub fn record(&self, id: &str) -> Result<&SequenceRecord, DataError> {
        self.manifest
            .sequences
            .iter()
            .find(|r| r.id == id)
            .ok_or_else(|| DataError::UnknownId {
                kind: "sequence",
                id: id.to_string(),
                dir: self.dir.clone(),
            })
    }

    /// Reads a sequence's shard, checking every tensor's dtype and shape against the
    /// record. The bytes are not compared with the recorded SHA-256 (training reads
    /// shards again every epoch); [`load_verified`](Self::load_verified) does that.
    pub fn load(&self, record: &SequenceRecord) -> Result<Sequence, DataError> {
        self.load_checked(record, None)
    }

    /// [`load`](Self::load), after checking that the shard's SHA-256 is the one the
    /// manifest recorded (when it recorded one, see [`SequenceRecord::sha256`]): a shard
    /// changed since it was written is [`DataError::Digest`]. What `weft data info
    /// --verify` does.
    pub fn load_verified(&self, record: &SequenceRecord) -> Result<Sequence, DataError> {
        self.load_checked(record, record.sha256.as_deref())
    }

    fn load_checked(
        &self,
        record: &SequenceRecord,
        sha256: Option<&str>,
    ) -> Result<Sequence, DataError> {
        if !record.has_frames() {
            return Err(DataError::NotGenerated {
                id: record.id.clone(),
                status: record.status.name().to_string(),
            });
        }
        let path = self.dir.join(&record.shard);
        let data = shard::read_checked(&path, shape_of(record), sha256)?;
        let garment = TriMesh::new(
            data.rest_positions
                .iter()
                .map(|p| p.map(f64::from))
                .collect(),
            data.faces,
        );
        Ok(Sequence {
            record: record.clone(),
            garment,
            corner_uvs: data.corner_uvs,
            poses: data.poses,
            trans: data.trans,
            positions: data.positions,
        })
    }

    /// The garment template fitted to the zero shape (`garments/<id>.obj`). Each
    /// sequence's own fit to its body is [`Sequence::garment`] (same kind, style and
    /// target vertex count; the vertex count can differ by a few percent between
    /// shapes). With the config's `garment_body` (fit data) it is the garment's pattern,
    /// made for that body: the rest shape of every sequence of the garment, same vertex
    /// order and faces as their [`Sequence::garment`], which is the pattern fitted onto
    /// each body.
    pub fn garment(&self, garment_id: &str) -> Result<TriMesh, DataError> {
        let g = self
            .manifest
            .garments
            .iter()
            .find(|g| g.id == garment_id)
            .ok_or_else(|| DataError::UnknownId {
                kind: "garment",
                id: garment_id.to_string(),
                dir: self.dir.clone(),
            })?;
        weft_mesh::read_mesh(&self.dir.join(&g.file)).map_err(|e| DataError::Mesh(Box::new(e)))
    }

    /// The body model the shapes belong to: weft's default body, or the SMPL `.npz`
    /// the config named.
    pub fn body_model(&self) -> Result<weft_body::BodyModel, DataError> {
        weft_body::BodyModel::load_or_default(self.manifest.body_file()).map_err(|source| {
            DataError::Body {
                what: "model".into(),
                source: Box::new(source),
            }
        })
    }
}

/// What a record's shard must hold.
pub(crate) fn shape_of(record: &SequenceRecord) -> ShardShape {
    ShardShape {
        frames: record.frames,
        vertices: record.vertices,
        faces: record.faces,
        betas: record.betas.len(),
    }
}
