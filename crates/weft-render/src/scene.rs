//! What is drawn: meshes with a paint each (a solid colour, or per-vertex scalars through
//! a colour map), checked and prepared for the rasteriser.
//!
//! Preparation is where bad data becomes visible instead of fatal. A vertex with a
//! non-finite position (a network diverged, a simulation exploded) cannot be projected,
//! so it is drawn at the mean of its finite neighbours, spreading inwards over patches of
//! bad vertices, and every face touching it is drawn in [`ERROR_COLOR`](crate::ERROR_COLOR);
//! a vertex with a non-finite scalar keeps its place and its faces are drawn in the
//! error colour too. Only faces whose vertices have no finite neighbour at all (a whole
//! component gone bad) are skipped. Every case is counted in [`MeshStats`], so callers
//! can report what the picture shows.

use weft_mesh::TriMesh;

use crate::colormap::{Colormap, ScalarRange};
use crate::error::RenderError;
use crate::image::Rgb;
use crate::math::{is_finite, V3};
use crate::shading::{vertex_normals, Shading};

/// The default colour of a garment without a colour map: a muted blue.
pub const GARMENT_COLOR: Rgb = [86, 140, 200];

/// The default colour of a body under a garment: a light neutral grey, so the garment
/// and its colour map stand out.
pub const BODY_COLOR: Rgb = [206, 202, 196];

/// How a mesh is coloured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Paint<'a> {
    /// One colour for the whole mesh.
    Solid(Rgb),
    /// One scalar per vertex through a colour map.
    Scalars(ScalarPaint<'a>),
}

/// Per-vertex scalars through a colour map, e.g. vertex error in millimetres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScalarPaint<'a> {
    /// One value per vertex; non-finite values are drawn in the error colour.
    pub values: &'a [f64],
    /// The colour map.
    pub colormap: Colormap,
    /// Which values map to the ends of the colour map.
    pub range: ScalarRange,
    /// What the values are, with unit, for the legend: "vertex error (mm)".
    pub label: &'a str,
}

/// One mesh of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneMesh<'a> {
    /// Name used in errors and statistics ("garment", a file name).
    pub name: String,
    /// Vertex positions in metres; may contain non-finite values.
    pub positions: &'a [[f64; 3]],
    /// Triangles as indices into `positions`.
    pub faces: &'a [[u32; 3]],
    /// Colouring.
    pub paint: Paint<'a>,
    /// Flat or smooth normals.
    pub shading: Shading,
}

impl<'a> SceneMesh<'a> {
    /// `mesh` named `name`, painted `paint`, smooth-shaded.
    pub fn new(name: impl Into<String>, mesh: &'a TriMesh, paint: Paint<'a>) -> Self {
        Self::from_parts(name, &mesh.positions, &mesh.faces, paint)
    }

    /// A mesh from separate positions and faces: a frame of a sequence shares the
    /// template's faces.
    pub fn from_parts(
        name: impl Into<String>,
        positions: &'a [[f64; 3]],
        faces: &'a [[u32; 3]],
        paint: Paint<'a>,
    ) -> Self {
        SceneMesh {
            name: name.into(),
            positions,
            faces,
            paint,
            shading: Shading::Smooth,
        }
    }

    /// The same mesh with `shading`.
    pub fn with_shading(mut self, shading: Shading) -> Self {
        self.shading = shading;
        self
    }

    /// The scalar paint, if any.
    pub fn scalars(&self) -> Option<&ScalarPaint<'a>> {
        match &self.paint {
            Paint::Scalars(s) => Some(s),
            Paint::Solid(_) => None,
        }
    }
}

/// What drawing one mesh found in its data.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MeshStats {
    /// The mesh's name.
    pub name: String,
    /// Vertices whose position is not finite (drawn at their neighbours' mean, faces in
    /// the error colour).
    pub nonfinite_positions: usize,
    /// Vertices whose scalar is not finite (their faces drawn in the error colour).
    pub nonfinite_scalars: usize,
    /// Faces drawn in the error colour.
    pub error_faces: usize,
    /// Faces not drawn because no vertex position could be recovered for them.
    pub skipped_faces: usize,
}

impl MeshStats {
    /// Whether anything was wrong with the mesh's data.
    pub fn has_problems(&self) -> bool {
        self.nonfinite_positions + self.nonfinite_scalars + self.skipped_faces > 0
    }
}

/// How a face is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FaceKind {
    /// Paint and lighting.
    Normal,
    /// The error colour: a corner's position or scalar was not finite.
    Error,
    /// Not at all: a corner has no usable position.
    Skip,
}

/// A mesh checked and made drawable.
pub(crate) struct Prepared<'m> {
    pub(crate) mesh: &'m SceneMesh<'m>,
    /// Positions with non-finite ones replaced where possible.
    pub(crate) positions: Vec<V3>,
    pub(crate) normals: Vec<V3>,
    pub(crate) face_kind: Vec<FaceKind>,
    pub(crate) stats: MeshStats,
}

/// Checks every mesh (face indices in range, one scalar per vertex) and prepares it.
pub(crate) fn prepare<'m>(meshes: &'m [SceneMesh<'m>]) -> Result<Vec<Prepared<'m>>, RenderError> {
    meshes.iter().map(prepare_one).collect()
}

fn prepare_one<'m>(mesh: &'m SceneMesh<'m>) -> Result<Prepared<'m>, RenderError> {
    let n = mesh.positions.len();
    for (fi, f) in mesh.faces.iter().enumerate() {
        if let Some(&bad) = f.iter().find(|&&i| i as usize >= n) {
            return Err(RenderError::FaceIndex {
                mesh: mesh.name.clone(),
                face: fi,
                index: bad,
                vertices: n,
            });
        }
    }
    let mut stats = MeshStats {
        name: mesh.name.clone(),
        ..MeshStats::default()
    };
    let mut scalar_bad = vec![false; n];
    if let Some(s) = mesh.scalars() {
        if s.values.len() != n {
            return Err(RenderError::ScalarCount {
                mesh: mesh.name.clone(),
                values: s.values.len(),
                vertices: n,
            });
        }
        for (b, v) in scalar_bad.iter_mut().zip(s.values) {
            *b = !v.is_finite();
        }
        stats.nonfinite_scalars = scalar_bad.iter().filter(|&&b| b).count();
    }
    let mut positions: Vec<V3> = mesh.positions.to_vec();
    let bad_position: Vec<bool> = positions.iter().map(|&p| !is_finite(p)).collect();
    stats.nonfinite_positions = bad_position.iter().filter(|&&b| b).count();
    let placed = if stats.nonfinite_positions > 0 {
        fill_from_neighbours(&mut positions, mesh.faces, &bad_position)
    } else {
        vec![true; n]
    };
    let face_kind: Vec<FaceKind> = mesh
        .faces
        .iter()
        .map(|f| {
            let f = f.map(|i| i as usize);
            if f.iter().any(|&i| !placed[i]) {
                FaceKind::Skip
            } else if f.iter().any(|&i| bad_position[i] || scalar_bad[i]) {
                FaceKind::Error
            } else {
                FaceKind::Normal
            }
        })
        .collect();
    stats.error_faces = face_kind.iter().filter(|&&k| k == FaceKind::Error).count();
    stats.skipped_faces = face_kind.iter().filter(|&&k| k == FaceKind::Skip).count();
    let normals = vertex_normals(&positions, mesh.faces);
    Ok(Prepared {
        mesh,
        positions,
        normals,
        face_kind,
        stats,
    })
}

/// Replaces the positions marked `bad` by the mean of their already-placed face
/// neighbours, ring by ring inwards, until no more can be placed. Returns which
/// vertices have a usable position. Deterministic: each ring uses only earlier rings.
fn fill_from_neighbours(positions: &mut [V3], faces: &[[u32; 3]], bad: &[bool]) -> Vec<bool> {
    let mut placed: Vec<bool> = bad.iter().map(|&b| !b).collect();
    loop {
        let mut sum = vec![[0.0; 3]; positions.len()];
        let mut count = vec![0u32; positions.len()];
        for f in faces {
            for &i in f {
                let i = i as usize;
                if placed[i] {
                    continue;
                }
                for &j in f {
                    let j = j as usize;
                    if placed[j] {
                        for k in 0..3 {
                            sum[i][k] += positions[j][k];
                        }
                        count[i] += 1;
                    }
                }
            }
        }
        let mut progress = false;
        for i in 0..positions.len() {
            if count[i] > 0 {
                let c = f64::from(count[i]);
                positions[i] = sum[i].map(|s| s / c);
                placed[i] = true;
                progress = true;
            }
        }
        if !progress {
            return placed;
        }
    }
}

/// Positions of the vertices of drawn (not skipped) faces, over all meshes: what the
/// camera has to frame.
pub(crate) fn drawn_points<'a, I>(prepared: I) -> Vec<V3>
where
    I: IntoIterator<Item = &'a Prepared<'a>>,
{
    let mut out = Vec::new();
    for p in prepared {
        let mut used = vec![false; p.positions.len()];
        for (f, kind) in p.mesh.faces.iter().zip(&p.face_kind) {
            if *kind != FaceKind::Skip {
                for &i in f {
                    used[i as usize] = true;
                }
            }
        }
        out.extend(
            p.positions
                .iter()
                .zip(&used)
                .filter(|(_, &u)| u)
                .map(|(q, _)| *q),
        );
    }
    out
}

/// The resolved colour range of each mesh's scalars (`None` for solid paint), computed
/// over the given frames together, so a sequence shares one colour scale. `frames[f][m]`
/// is mesh `m` of frame `f`; meshes are matched by index.
pub(crate) fn shared_ranges(frames: &[&[SceneMesh<'_>]]) -> Vec<Option<(f64, f64)>> {
    let count = frames.iter().map(|f| f.len()).max().unwrap_or(0);
    (0..count)
        .map(|m| {
            let first = frames
                .iter()
                .find_map(|f| f.get(m).and_then(|x| x.scalars()))?;
            let values = frames
                .iter()
                .filter_map(|f| f.get(m).and_then(|x| x.scalars()))
                .flat_map(|s| s.values.iter().copied());
            Some(first.range.resolve(values, first.colormap))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives::grid;

    fn solid(m: &TriMesh) -> SceneMesh<'_> {
        SceneMesh::new("g", m, Paint::Solid(GARMENT_COLOR))
    }

    #[test]
    fn bad_indices_and_counts_are_errors_naming_the_mesh() {
        let mut m = grid(2, 2, 1.0);
        m.faces.push([0, 1, 9]);
        let meshes = [solid(&m)];
        let e = prepare(&meshes).err().expect("error");
        assert_eq!(
            e.to_string(),
            "g: face 2 refers to vertex 9, but the mesh has 4 vertices"
        );
        let m = grid(2, 2, 1.0);
        let v = [0.0; 3];
        let meshes = [SceneMesh::new(
            "garment",
            &m,
            Paint::Scalars(ScalarPaint {
                values: &v,
                colormap: Colormap::Viridis,
                range: ScalarRange::Auto,
                label: "",
            }),
        )];
        let e = prepare(&meshes).err().expect("error");
        assert_eq!(
            e.to_string(),
            "garment: 3 scalar values for 4 vertices; expected one value per vertex"
        );
    }

    #[test]
    fn nonfinite_positions_are_placed_from_neighbours_and_counted() {
        let mut m = grid(5, 5, 1.0);
        m.positions[12] = [f64::NAN, 0.0, 0.0];
        m.positions[13][1] = f64::INFINITY;
        let meshes = [solid(&m)];
        let p = prepare(&meshes).unwrap();
        let s = &p[0].stats;
        assert_eq!((s.nonfinite_positions, s.skipped_faces), (2, 0));
        assert!(s.error_faces > 0 && s.has_problems());
        assert!(p[0].positions.iter().all(|&q| is_finite(q)));
        // The centre vertex lands inside the grid.
        let c = p[0].positions[12];
        assert!(
            c[0] > 1.0 && c[0] < 3.5 && c[2] > 1.0 && c[2] < 3.5,
            "{c:?}"
        );
        let points = drawn_points(&p);
        assert_eq!(points.len(), 25);
        assert!(points.iter().all(|&q| is_finite(q)));
    }

    #[test]
    fn an_all_bad_component_is_skipped() {
        let mut m = grid(2, 2, 1.0);
        for p in &mut m.positions {
            p[0] = f64::NAN;
        }
        let meshes = [solid(&m)];
        let p = prepare(&meshes).unwrap();
        assert_eq!(p[0].stats.skipped_faces, 2);
        assert!(drawn_points(&p).is_empty());
    }

    #[test]
    fn ranges_are_shared_across_frames() {
        let m = grid(2, 2, 1.0);
        let a = [0.0, 1.0, 2.0, f64::NAN];
        let b = [5.0, 1.0, 2.0, 3.0];
        let paint = |v| {
            Paint::Scalars(ScalarPaint {
                values: v,
                colormap: Colormap::Viridis,
                range: ScalarRange::Auto,
                label: "",
            })
        };
        let f0 = [SceneMesh::new("g", &m, paint(&a)), solid(&m)];
        let f1 = [SceneMesh::new("g", &m, paint(&b)), solid(&m)];
        let r = shared_ranges(&[&f0, &f1]);
        assert_eq!(r, vec![Some((0.0, 5.0)), None]);
    }
}
