//! What every scene writer takes: named meshes moving through frames, with the
//! garment's texture coordinates when its template has them.

use std::collections::HashMap;

use super::error::ExportError;
use super::obj_sequence::check_faces;
use super::Frames;

/// Texture coordinates of each triangle's three corners, in face order (OBJ `f v/vt`, as
/// [`LoadReport::corner_uvs`](crate::io::LoadReport::corner_uvs) reads them). Per corner
/// rather than per vertex because a garment's pattern has seams: one vertex on a seam
/// has a different UV in each panel.
pub type CornerUvs = [[[f32; 2]; 3]];

/// One mesh of a scene: a triangle mesh whose vertices move through `frames`.
#[derive(Clone, Copy, Debug)]
pub struct AnimatedMesh<'a> {
    /// Node, prim and mesh name, e.g. `garment` or `body`.
    pub name: &'a str,
    /// Triangles as 0-based indices into each frame's vertices.
    pub faces: &'a [[u32; 3]],
    /// Texture coordinates per triangle corner, one entry per face, or none.
    pub uvs: Option<&'a CornerUvs>,
    /// The vertex positions per frame. One frame makes a static mesh; every animated
    /// mesh of a scene needs the same frame count.
    pub frames: &'a Frames,
    /// Base colour (linear RGBA) of its material.
    pub color: [f32; 4],
}

/// The colour weft gives a garment.
pub const GARMENT_COLOR: [f32; 4] = [0.72, 0.22, 0.18, 1.0];
/// The colour weft gives a body.
pub const BODY_COLOR: [f32; 4] = [0.62, 0.62, 0.62, 1.0];

/// Fails unless there is one UV triple per face and every UV is finite.
pub fn check_uvs(faces: &[[u32; 3]], uvs: &CornerUvs) -> Result<(), ExportError> {
    if uvs.len() != faces.len() {
        return Err(ExportError::UvCount {
            uvs: uvs.len(),
            faces: faces.len(),
        });
    }
    for (face, corners) in uvs.iter().enumerate() {
        if let Some(corner) = corners
            .iter()
            .position(|uv| !uv.iter().all(|c| c.is_finite()))
        {
            return Err(ExportError::NonFiniteUv { face, corner });
        }
    }
    Ok(())
}

/// Checks a scene before anything is written and returns its frame count: at least one
/// mesh, every mesh with frames, finite positions, faces and UVs that fit, and the same
/// frame count for every animated mesh (a mesh with one frame is static).
pub(crate) fn check_scene(meshes: &[AnimatedMesh<'_>]) -> Result<usize, ExportError> {
    if meshes.is_empty() {
        return Err(ExportError::NoFrames);
    }
    // The shared frame count of the animated meshes.
    let mut animated: Option<(usize, &str)> = None;
    for m in meshes {
        if m.frames.is_empty() {
            return Err(ExportError::NoFrames);
        }
        m.frames.check_finite()?;
        check_faces(m.faces, m.frames.vertex_count())?;
        if let Some(uvs) = m.uvs {
            check_uvs(m.faces, uvs)?;
        }
        let t = m.frames.frame_count();
        if t > 1 {
            match animated {
                None => animated = Some((t, m.name)),
                Some((expected, first)) if expected != t => {
                    return Err(ExportError::FrameCountMismatch {
                        mesh: m.name.to_owned(),
                        found: t,
                        first: first.to_owned(),
                        expected,
                    })
                }
                Some(_) => {}
            }
        }
    }
    Ok(animated.map_or(1, |(t, _)| t))
}

/// Corner UVs as the formats store them: each distinct UV once, and per triangle corner
/// an index into them (OBJ's `vt` list, USD's indexed `primvars:st`).
#[derive(Clone, Debug, PartialEq)]
pub struct IndexedUvs {
    /// The distinct UVs, in order of first use.
    pub values: Vec<[f32; 2]>,
    /// Per triangle, the index of each corner's UV in `values`.
    pub corners: Vec<[u32; 3]>,
}

impl IndexedUvs {
    /// Shares equal UVs (equal bits) between corners.
    pub fn new(uvs: &CornerUvs) -> Self {
        let mut index: HashMap<[u32; 2], u32> = HashMap::new();
        let mut values = Vec::new();
        let corners = uvs
            .iter()
            .map(|tri| {
                tri.map(|uv| {
                    *index.entry(uv.map(f32::to_bits)).or_insert_with(|| {
                        values.push(uv);
                        (values.len() - 1) as u32
                    })
                })
            })
            .collect();
        IndexedUvs { values, corners }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_uvs_are_shared_and_checked() {
        let uvs = [
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        ];
        let indexed = IndexedUvs::new(&uvs);
        assert_eq!(
            indexed.values,
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
        );
        assert_eq!(indexed.corners, vec![[0, 1, 2], [0, 2, 3]]);
        let faces = [[0, 1, 2], [0, 2, 3]];
        check_uvs(&faces, &uvs).unwrap();
        assert_eq!(
            check_uvs(&faces[..1], &uvs).unwrap_err().to_string(),
            "the template has 2 UV triangles but 1 faces; expected one UV per face corner"
        );
        let bad = [uvs[0], [[0.0, 0.0], [f32::NAN, 1.0], [0.0, 1.0]]];
        assert_eq!(
            check_uvs(&faces, &bad).unwrap_err().to_string(),
            "face 1, corner 1: the texture coordinate is not finite"
        );
    }
}
