//! One sequence per safetensors file.
//!
//! Tensors (all little-endian, row-major):
//!
//! | name             | dtype | shape     | what                                          |
//! |------------------|-------|-----------|-----------------------------------------------|
//! | `positions`      | f32   | [T, N, 3] | simulated garment vertices per frame (m)      |
//! | `poses`          | f32   | [T, 72]   | SMPL axis-angle pose per frame (24 joints)    |
//! | `trans`          | f32   | [T, 3]    | root translation per frame (m)                |
//! | `betas`          | f32   | [B]       | body shape β                                  |
//! | `rest_positions` | f32   | [N, 3]    | the garment fitted to this body, rest pose    |
//! | `faces`          | u32   | [F, 3]    | its triangles                                 |
//! | `corner_uvs`     | f32   | [F, 3, 2] | UV of each face corner (m): the flat pattern  |
//!
//! `rest_positions`: the garment on this sequence's body in its rest pose, where
//! frame 0's warm-up starts. Without the config's `garment_body` it is the garment made
//! for this body (also its rest shape). With `garment_body` (fit data, GarFitNet) it is
//! the garment's pattern, made for that body, fitted onto this one
//! (`weft_garment::prepare::fit_onto`: stretched tight on a fuller body, loose on a
//! slimmer one), while the simulator's rest shape stays the pattern
//! (`garments/<id>.obj`, same vertex order and faces). That fitted garment is what fit
//! data's fit parameter α, garment–body association and joint distances are computed
//! from.
//!
//! The header's `__metadata__` holds one key, `sequence`, the sequence id, so a shard
//! moved out of its directory still says what it is. safetensors orders tensors by
//! dtype and name, and one metadata key serialises one way, so the same data always
//! gives the same bytes.
//!
//! The manifest records each shard's SHA-256 ([`sha256_hex`] of the bytes [`write`]
//! wrote); [`check`] and [`read_checked`] compare a file against it, so a shard changed
//! after it was written (a value edited, a bit flipped on disk) is found even when its
//! header and shapes are intact.
//!
//! Why safetensors: Python (numpy, torch) reads it without weft, it is a flat header plus
//! raw arrays (no pickle, no code), and a half-written file fails the header's length
//! check, which is what resuming relies on.

use std::collections::HashMap;
use std::path::Path;

use safetensors::tensor::Dtype;
use sha2::{Digest, Sha256};

use crate::error::DataError;
use crate::tensors::{f32_tensor, f32s, faces as read_faces, parse, tensor, triples, u32_tensor};

/// SMPL pose values per frame (24 joints × 3).
pub const POSE_VALUES: usize = 72;

/// The tensors of one shard.
#[derive(Clone, Debug, PartialEq)]
pub struct ShardData {
    /// `[T][N]` garment vertex positions.
    pub positions: Vec<Vec<[f32; 3]>>,
    /// `[T]` poses (stored flat as `[T, 72]`).
    pub poses: Vec<weft_body::Pose>,
    /// `[T]` root translations.
    pub trans: Vec<[f32; 3]>,
    /// `[B]` shape β.
    pub betas: Vec<f32>,
    /// `[N]` the garment on this body in its rest pose: made for it, or with
    /// `garment_body` the pattern fitted onto it (module docs).
    pub rest_positions: Vec<[f32; 3]>,
    /// `[F]` triangles.
    pub faces: Vec<[u32; 3]>,
    /// `[F]` corner UVs.
    pub corner_uvs: Vec<[[f32; 2]; 3]>,
}

/// The shape a shard must have: what the manifest says about it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardShape {
    /// Frames T.
    pub frames: usize,
    /// Garment vertices N.
    pub vertices: usize,
    /// Garment faces F.
    pub faces: usize,
    /// Shape components B.
    pub betas: usize,
}

impl ShardData {
    /// Its shape (T from `poses`, N from `rest_positions`).
    pub fn shape(&self) -> ShardShape {
        ShardShape {
            frames: self.poses.len(),
            vertices: self.rest_positions.len(),
            faces: self.faces.len(),
            betas: self.betas.len(),
        }
    }
}

/// The shard's bytes.
pub fn encode(sequence_id: &str, data: &ShardData) -> Result<Vec<u8>, DataError> {
    let s = data.shape();
    let (t, n, f) = (s.frames, s.vertices, s.faces);
    if data.positions.len() != t || data.trans.len() != t {
        return Err(DataError::Simulation {
            id: sequence_id.to_string(),
            message: format!(
                "{} position frames and {} translations for {t} poses; expected one of each per frame",
                data.positions.len(),
                data.trans.len()
            ),
        });
    }
    if let Some(bad) = data.positions.iter().position(|p| p.len() != n) {
        return Err(DataError::Simulation {
            id: sequence_id.to_string(),
            message: format!(
                "frame {bad} has {} vertices; the garment has {n}",
                data.positions[bad].len()
            ),
        });
    }
    if data.corner_uvs.len() != f {
        return Err(DataError::Simulation {
            id: sequence_id.to_string(),
            message: format!("{} corner UV rows for {f} faces", data.corner_uvs.len()),
        });
    }
    let tensors = [
        (
            "positions",
            f32_tensor(vec![t, n, 3], data.positions.iter().flatten().flatten()),
        ),
        (
            "poses",
            f32_tensor(vec![t, POSE_VALUES], data.poses.iter().flatten().flatten()),
        ),
        ("trans", f32_tensor(vec![t, 3], data.trans.iter().flatten())),
        ("betas", f32_tensor(vec![s.betas], data.betas.iter())),
        (
            "rest_positions",
            f32_tensor(vec![n, 3], data.rest_positions.iter().flatten()),
        ),
        ("faces", u32_tensor(vec![f, 3], data.faces.iter().flatten())),
        (
            "corner_uvs",
            f32_tensor(vec![f, 3, 2], data.corner_uvs.iter().flatten().flatten()),
        ),
    ];
    let metadata = HashMap::from([("sequence".to_string(), sequence_id.to_string())]);
    safetensors::tensor::serialize(tensors.iter().map(|(k, v)| (*k, v)), Some(metadata)).map_err(
        |e| DataError::Simulation {
            id: sequence_id.to_string(),
            message: format!("cannot encode the shard: {e}"),
        },
    )
}

/// SHA-256 of `bytes` as 64 lowercase hex digits: the shard digest the manifest records
/// (`"sha256"` of a sequence record).
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Whether `text` is what [`sha256_hex`] gives: 64 lowercase hex digits.
pub fn is_sha256_hex(text: &str) -> bool {
    text.len() == 64
        && text
            .bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
}

/// Writes a shard atomically (temporary file, then rename): a killed run leaves either
/// the old file, no file, or a stray temporary file, never a torn shard. Returns the
/// SHA-256 of the bytes written ([`sha256_hex`]), for the manifest.
pub fn write(path: &Path, sequence_id: &str, data: &ShardData) -> Result<String, DataError> {
    let bytes = encode(sequence_id, data)?;
    weft_mesh::io::write_atomic(path, |w| w.write_all(&bytes))
        .map_err(|e| DataError::io(path, "cannot write the shard", e))?;
    Ok(sha256_hex(&bytes))
}

/// Reads a shard and checks every tensor against `expected`; errors name the file, the
/// tensor and the expected dtype and shape. The bytes are not compared with a digest:
/// see [`read_checked`].
pub fn read(path: &Path, expected: ShardShape) -> Result<ShardData, DataError> {
    read_checked(path, expected, None)
}

/// [`read`], after checking that the file's SHA-256 is `sha256` (when given; what the
/// manifest recorded): a changed file is [`DataError::Digest`].
pub fn read_checked(
    path: &Path,
    expected: ShardShape,
    sha256: Option<&str>,
) -> Result<ShardData, DataError> {
    let bytes = weft_mesh::io::read_input(path)
        .map_err(|e| DataError::io(path, "cannot read the shard", e))?;
    check_digest(path, &bytes, sha256)?;
    decode(path, &bytes, expected)
}

/// Checks a shard's SHA-256 against `sha256` (when given), then its header and tensor
/// shapes without converting the arrays: what a resumed run does to decide whether a
/// shard is finished and unchanged. Returns the file's SHA-256, so a record from before
/// digests were kept can have it recorded.
pub fn check(path: &Path, expected: ShardShape, sha256: Option<&str>) -> Result<String, DataError> {
    let bytes = weft_mesh::io::read_input(path)
        .map_err(|e| DataError::io(path, "cannot read the shard", e))?;
    let found = check_digest(path, &bytes, sha256)?;
    let st = parse(path, &bytes)?;
    for (name, dtype, shape) in layout(expected) {
        tensor(path, &st, name, dtype, &shape)?;
    }
    Ok(found)
}

/// The SHA-256 of `bytes`, after checking it is `expected` when one is given.
fn check_digest(path: &Path, bytes: &[u8], expected: Option<&str>) -> Result<String, DataError> {
    let found = sha256_hex(bytes);
    match expected {
        Some(e) if e != found => Err(DataError::Digest {
            path: path.to_path_buf(),
            expected: e.to_string(),
            found,
        }),
        _ => Ok(found),
    }
}

fn layout(e: ShardShape) -> [(&'static str, Dtype, Vec<usize>); 7] {
    let (t, n, f) = (e.frames, e.vertices, e.faces);
    [
        ("positions", Dtype::F32, vec![t, n, 3]),
        ("poses", Dtype::F32, vec![t, POSE_VALUES]),
        ("trans", Dtype::F32, vec![t, 3]),
        ("betas", Dtype::F32, vec![e.betas]),
        ("rest_positions", Dtype::F32, vec![n, 3]),
        ("faces", Dtype::U32, vec![f, 3]),
        ("corner_uvs", Dtype::F32, vec![f, 3, 2]),
    ]
}

/// Decodes shard bytes (see [`read`]).
pub fn decode(path: &Path, bytes: &[u8], expected: ShardShape) -> Result<ShardData, DataError> {
    let st = parse(path, bytes)?;
    let [positions, poses, trans, betas, rest, faces, uvs] = layout(expected);
    let get =
        |(name, dtype, shape): (&str, Dtype, Vec<usize>)| tensor(path, &st, name, dtype, &shape);
    let positions_b = get(positions)?;
    let poses_b = get(poses)?;
    let trans_b = get(trans)?;
    let betas_b = get(betas)?;
    let rest_b = get(rest)?;
    let faces_b = get(faces)?;
    let uvs_b = get(uvs)?;
    let n = expected.vertices;
    let all = triples(positions_b);
    let positions = if n == 0 {
        vec![Vec::new(); expected.frames]
    } else {
        all.chunks_exact(n).map(<[_]>::to_vec).collect()
    };
    let pose_values: Vec<f32> = f32s(poses_b).collect();
    let poses = pose_values
        .chunks_exact(POSE_VALUES)
        .map(|c| std::array::from_fn(|j| [c[3 * j], c[3 * j + 1], c[3 * j + 2]]))
        .collect();
    let faces = read_faces(path, "faces", faces_b, n)?;
    let uv_values: Vec<f32> = f32s(uvs_b).collect();
    let corner_uvs = uv_values
        .chunks_exact(6)
        .map(|c| [[c[0], c[1]], [c[2], c[3]], [c[4], c[5]]])
        .collect();
    Ok(ShardData {
        positions,
        poses,
        trans: triples(trans_b),
        betas: f32s(betas_b).collect(),
        rest_positions: triples(rest_b),
        faces,
        corner_uvs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> ShardData {
        ShardData {
            positions: vec![
                vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]],
                vec![[0.0, -0.1, 0.0], [1.0, -0.1, 0.0], [0.0, 0.9, 0.5]],
            ],
            poses: vec![[[0.1; 3]; 24], [[0.2; 3]; 24]],
            trans: vec![[0.0, 0.9, 0.0], [0.0, 0.9, 0.1]],
            betas: vec![1.0, -0.5, 0.0],
            rest_positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]],
            faces: vec![[0, 1, 2]],
            corner_uvs: vec![[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]],
        }
    }

    #[test]
    fn round_trip_and_deterministic_bytes() {
        let d = sample();
        let a = encode("s", &d).unwrap();
        assert_eq!(a, encode("s", &d).unwrap());
        let back = decode(Path::new("s.safetensors"), &a, d.shape()).unwrap();
        assert_eq!(back, d);
    }

    #[test]
    fn wrong_shapes_name_file_tensor_and_expectation() {
        let d = sample();
        let bytes = encode("s", &d).unwrap();
        let mut e = d.shape();
        e.vertices = 4;
        let err = decode(Path::new("x.safetensors"), &bytes, e)
            .unwrap_err()
            .to_string();
        assert!(err.contains("x.safetensors"), "{err}");
        assert!(err.contains("\"positions\""), "{err}");
        assert!(err.contains("f32 [2, 4, 3]"), "{err}");
        assert!(err.contains("[2, 3, 3]"), "{err}");
    }

    #[test]
    fn truncated_shards_are_rejected() {
        let d = sample();
        let bytes = encode("s", &d).unwrap();
        for cut in [0, 7, 20, bytes.len() - 1] {
            let err = decode(Path::new("t.safetensors"), &bytes[..cut], d.shape()).unwrap_err();
            assert!(matches!(err, DataError::Shard { .. }), "cut {cut}: {err}");
        }
    }

    #[test]
    fn digests_are_of_the_bytes_written_and_catch_a_changed_value() {
        let dir = std::env::temp_dir().join(format!("weft-shard-digest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("s.safetensors");
        let d = sample();
        let digest = write(&path, "s", &d).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(digest, sha256_hex(&bytes));
        assert!(is_sha256_hex(&digest), "{digest}");
        // The SHA-256 test vector of "abc".
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(check(&path, d.shape(), Some(&digest)).unwrap(), digest);
        assert_eq!(read_checked(&path, d.shape(), Some(&digest)).unwrap(), d);
        // One position moved by 0.5 m: same header, same shapes, another digest.
        let mut moved = d.clone();
        moved.positions[1][2][0] += 0.5;
        std::fs::write(&path, encode("s", &moved).unwrap()).unwrap();
        assert_eq!(read(&path, d.shape()).unwrap(), moved);
        for err in [
            check(&path, d.shape(), Some(&digest)).unwrap_err(),
            read_checked(&path, d.shape(), Some(&digest)).unwrap_err(),
        ] {
            assert!(matches!(err, DataError::Digest { .. }), "{err}");
            let text = err.to_string();
            assert!(
                text.contains("s.safetensors") && text.contains(&digest),
                "{text}"
            );
        }
        // No digest recorded: only the header and shapes are checked.
        assert!(check(&path, d.shape(), None).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn out_of_range_faces_are_rejected() {
        let mut d = sample();
        d.faces[0][2] = 3;
        let bytes = encode("s", &d).unwrap();
        let err = decode(Path::new("f.safetensors"), &bytes, d.shape())
            .unwrap_err()
            .to_string();
        assert!(err.contains("faces"), "{err}");
    }
}
