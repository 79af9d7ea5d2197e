//! [`BodySurface`]: a triangle mesh (normally the posed body) with its AABB tree and
//! pseudo-normals, ready for closest-point and signed-distance queries, updated per
//! frame by a refit or a rebuild.

use rayon::prelude::*;
use weft_mesh::{Aabb, TriMesh};

use super::aabb_tree::AabbTree;
use super::error::QueryError;
use super::pseudo_normal::PseudoNormals;
use weft_mesh::vec3::is_finite;

/// A triangle surface prepared for queries.
///
/// Invariants (checked by [`BodySurface::new`]): at least one face, every face index in
/// range, every position finite. Signed distances are meaningful when the surface is
/// closed and its faces are oriented outwards (the default body and SMPL are); closest
/// points and unsigned distances work on any triangle soup.
#[derive(Clone, Debug, PartialEq)]
pub struct BodySurface {
    pub(crate) positions: Vec<[f64; 3]>,
    pub(crate) faces: Vec<[u32; 3]>,
    pub(crate) tree: AabbTree,
    pub(crate) normals: PseudoNormals,
}

/// The box of one triangle.
#[inline]
fn triangle_box(positions: &[[f64; 3]], f: [u32; 3]) -> Aabb {
    let [a, b, c] = f.map(|i| positions[i as usize]);
    Aabb {
        min: std::array::from_fn(|k| a[k].min(b[k]).min(c[k])),
        max: std::array::from_fn(|k| a[k].max(b[k]).max(c[k])),
    }
}

/// Index of the first non-finite position, if any.
pub(crate) fn check_finite(points: &[[f64; 3]], what: &'static str) -> Result<(), QueryError> {
    match points.iter().position(|&p| !is_finite(p)) {
        Some(index) => Err(QueryError::NonFinite {
            what,
            index,
            position: points[index],
        }),
        None => Ok(()),
    }
}

impl BodySurface {
    /// Builds the tree and the normals of the mesh `positions`/`faces`.
    pub fn new(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<Self, QueryError> {
        if faces.is_empty() {
            return Err(QueryError::Empty {
                vertices: positions.len(),
                faces: 0,
                needed: "triangle",
            });
        }
        let n = positions.len();
        for (face, f) in faces.iter().enumerate() {
            if let Some(&vertex) = f.iter().find(|&&v| v as usize >= n) {
                return Err(QueryError::FaceOutOfRange {
                    face,
                    vertex,
                    vertex_count: n,
                });
            }
        }
        check_finite(positions, "vertex")?;
        let boxes = Self::boxes(positions, faces);
        Ok(BodySurface {
            positions: positions.to_vec(),
            faces: faces.to_vec(),
            tree: AabbTree::build(&boxes),
            normals: PseudoNormals::new(positions, faces),
        })
    }

    /// [`BodySurface::new`] on a [`TriMesh`].
    pub fn from_mesh(mesh: &TriMesh) -> Result<Self, QueryError> {
        Self::new(&mesh.positions, &mesh.faces)
    }

    fn boxes(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<Aabb> {
        faces.iter().map(|&f| triangle_box(positions, f)).collect()
    }

    fn set_positions(&mut self, positions: &[[f64; 3]]) -> Result<Vec<Aabb>, QueryError> {
        if positions.len() != self.positions.len() {
            return Err(QueryError::CountMismatch {
                expected: self.positions.len(),
                found: positions.len(),
            });
        }
        check_finite(positions, "vertex")?;
        self.positions.copy_from_slice(positions);
        self.normals.update(&self.positions, &self.faces);
        Ok(Self::boxes(&self.positions, &self.faces))
    }

    /// Moves the vertices (same count, same faces: the next frame of a posed body) and
    /// refits the tree bottom-up, keeping its topology: `O(n)`, the cheap per-frame
    /// update. Queries stay exact; they only slow down if the motion since the build
    /// was large (the boxes of a refit tree overlap more).
    pub fn refit(&mut self, positions: &[[f64; 3]]) -> Result<(), QueryError> {
        let boxes = self.set_positions(positions)?;
        // Lengths agree: one box per face, as at build time.
        let _ = self.tree.refit(&boxes);
        Ok(())
    }

    /// Moves the vertices like [`BodySurface::refit`] but builds a fresh tree
    /// (`O(n log n)`), for when the pose is far from the one the tree was built on.
    pub fn rebuild(&mut self, positions: &[[f64; 3]]) -> Result<(), QueryError> {
        let boxes = self.set_positions(positions)?;
        self.tree = AabbTree::build(&boxes);
        Ok(())
    }

    /// The vertex positions.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// The triangles.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// The AABB tree over the triangles (primitive `i` is face `i`).
    pub fn tree(&self) -> &AabbTree {
        &self.tree
    }

    /// Unit normal of each face (zero for a degenerate face).
    pub fn face_normals(&self) -> &[[f64; 3]] {
        &self.normals.face
    }

    /// Unit angle-weighted pseudo-normal of each vertex (zero for an unused vertex):
    /// the vertex normal to use for signs and for interpolated shading normals.
    pub fn vertex_normals(&self) -> Vec<[f64; 3]> {
        (0..self.positions.len() as u32)
            .into_par_iter()
            .map(|v| self.vertex_normal(v))
            .collect()
    }

    /// [`BodySurface::vertex_normals`] of one vertex (computed on first use after each
    /// update, [`PseudoNormals`]).
    pub fn vertex_normal(&self, v: u32) -> [f64; 3] {
        self.normals
            .vertex(v as usize, &self.positions, &self.faces)
    }

    /// Whether every edge has exactly two faces (a closed 2-manifold edge graph), the
    /// condition under which the sign of [`BodySurface::signed_distance`] is exact.
    pub fn is_closed(&self) -> bool {
        let mut count = vec![0u32; self.normals.edge_vertices.len()];
        for fe in &self.normals.face_edges {
            for &e in fe {
                count[e as usize] += 1;
            }
        }
        count.iter().all(|&c| c == 2)
    }
}
