//! Mesh validation: what is wrong with a mesh a user supplied, and whether weft can use it.
//!
//! [`check`] is the strict gate every reader runs: it fails on what would make later code
//! index out of bounds or compute NaN (an empty mesh, a non-finite coordinate, an index
//! out of range). [`validate`] lists everything it finds, including defects the mesh is
//! still usable with (degenerate, duplicate and non-manifold faces, isolated vertices),
//! and [`summarize`] folds that list into one line per kind for a report.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;

use crate::error::MeshError;
use crate::mesh::TriMesh;
use crate::vec3::{cross, dot, sub};

/// A face is degenerate when its area is at most this fraction of the squared bounding-box
/// diagonal (or when it repeats a vertex).
///
/// Relative, so the test means the same for a mesh in metres or millimetres. At 1e-12 a
/// garment 1 m across flags only faces under about 1.7 µm on a side, while rounding
/// error in the area of a healthy face (relative 1e-16 of the squared diagonal) stays far
/// below it.
pub const DEGENERATE_AREA_TOLERANCE: f64 = 1e-12;

/// Whether a finding makes a mesh unusable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Severity {
    /// The mesh is usable; the report should still mention it.
    Warning,
    /// Reading fails: later code would index out of bounds or compute NaN.
    Error,
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Severity::Warning => "warning",
            Severity::Error => "error",
        })
    }
}

/// One defect of a mesh. Indices are 0-based.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Finding {
    /// No vertices or no faces.
    Empty {
        /// Number of vertices.
        vertices: usize,
        /// Number of faces.
        faces: usize,
    },
    /// A vertex with a NaN or infinite coordinate.
    NonFinite {
        /// The vertex.
        vertex: usize,
    },
    /// A face naming a vertex that does not exist.
    IndexOutOfRange {
        /// The face.
        face: usize,
        /// The offending index.
        index: u32,
        /// Number of vertices of the mesh.
        vertex_count: usize,
    },
    /// A face that repeats a vertex or has (relatively) zero area; see
    /// [`DEGENERATE_AREA_TOLERANCE`].
    DegenerateFace {
        /// The face.
        face: usize,
    },
    /// A face on the same three vertices as an earlier one, in any order or orientation.
    DuplicateFace {
        /// The later face.
        face: usize,
        /// The first face on these vertices.
        first: usize,
    },
    /// An edge shared by more than two faces.
    NonManifoldEdge {
        /// The edge, `edge[0] < edge[1]`.
        edge: [u32; 2],
        /// Number of faces sharing it.
        faces: usize,
    },
    /// A vertex no face uses.
    IsolatedVertex {
        /// The vertex.
        vertex: usize,
    },
}

/// The kind of a [`Finding`], without its data: what [`summarize`] groups by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum FindingKind {
    /// [`Finding::Empty`].
    Empty,
    /// [`Finding::NonFinite`].
    NonFinite,
    /// [`Finding::IndexOutOfRange`].
    IndexOutOfRange,
    /// [`Finding::DegenerateFace`].
    DegenerateFace,
    /// [`Finding::DuplicateFace`].
    DuplicateFace,
    /// [`Finding::NonManifoldEdge`].
    NonManifoldEdge,
    /// [`Finding::IsolatedVertex`].
    IsolatedVertex,
}

impl FindingKind {
    /// Errors fail reading; warnings leave the mesh usable.
    pub fn severity(self) -> Severity {
        match self {
            FindingKind::Empty | FindingKind::NonFinite | FindingKind::IndexOutOfRange => {
                Severity::Error
            }
            _ => Severity::Warning,
        }
    }

    /// What `count` findings of this kind are called, e.g. "3 degenerate faces".
    pub fn noun(self, count: usize) -> &'static str {
        let one = count == 1;
        match self {
            FindingKind::Empty => "empty mesh",
            FindingKind::NonFinite if one => "non-finite vertex",
            FindingKind::NonFinite => "non-finite vertices",
            FindingKind::IndexOutOfRange if one => "out-of-range index",
            FindingKind::IndexOutOfRange => "out-of-range indices",
            FindingKind::DegenerateFace if one => "degenerate face",
            FindingKind::DegenerateFace => "degenerate faces",
            FindingKind::DuplicateFace if one => "duplicate face",
            FindingKind::DuplicateFace => "duplicate faces",
            FindingKind::NonManifoldEdge if one => "non-manifold edge",
            FindingKind::NonManifoldEdge => "non-manifold edges",
            FindingKind::IsolatedVertex if one => "isolated vertex",
            FindingKind::IsolatedVertex => "isolated vertices",
        }
    }
}

impl Finding {
    /// The kind of this finding.
    pub fn kind(&self) -> FindingKind {
        match self {
            Finding::Empty { .. } => FindingKind::Empty,
            Finding::NonFinite { .. } => FindingKind::NonFinite,
            Finding::IndexOutOfRange { .. } => FindingKind::IndexOutOfRange,
            Finding::DegenerateFace { .. } => FindingKind::DegenerateFace,
            Finding::DuplicateFace { .. } => FindingKind::DuplicateFace,
            Finding::NonManifoldEdge { .. } => FindingKind::NonManifoldEdge,
            Finding::IsolatedVertex { .. } => FindingKind::IsolatedVertex,
        }
    }

    /// Errors fail reading; warnings leave the mesh usable.
    pub fn severity(&self) -> Severity {
        self.kind().severity()
    }

    /// The element the finding is about, e.g. "face 17", "edge [2, 5]", "mesh".
    pub fn location(&self) -> String {
        match self {
            Finding::Empty { .. } => "mesh".to_owned(),
            Finding::NonFinite { vertex } | Finding::IsolatedVertex { vertex } => {
                format!("vertex {vertex}")
            }
            Finding::IndexOutOfRange { face, .. }
            | Finding::DegenerateFace { face }
            | Finding::DuplicateFace { face, .. } => format!("face {face}"),
            Finding::NonManifoldEdge { edge, .. } => format!("edge [{}, {}]", edge[0], edge[1]),
        }
    }

    /// The strict error for this finding, when it is an error.
    fn to_error(&self, path: &Path) -> Option<MeshError> {
        let path = path.to_path_buf();
        let (element, index) = match *self {
            Finding::Empty { vertices, faces } => {
                return Some(MeshError::Empty {
                    path,
                    vertices,
                    faces,
                })
            }
            Finding::NonFinite { vertex } => ("vertex", vertex),
            Finding::IndexOutOfRange { face, .. } => ("face", face),
            _ => return None,
        };
        Some(MeshError::Invalid {
            path,
            element,
            index,
            message: self.problem(),
        })
    }

    /// What is wrong and what was expected, without the location.
    fn problem(&self) -> String {
        match self {
            Finding::Empty { vertices, faces } => format!(
                "empty ({vertices} vertices, {faces} faces); expected at least one triangle"
            ),
            Finding::NonFinite { .. } => {
                "has a NaN or infinite coordinate; expected finite x, y, z".to_owned()
            }
            Finding::IndexOutOfRange {
                index,
                vertex_count,
                ..
            } => format!(
                "names vertex {index}, but the mesh has {vertex_count} vertices; \
                 expected indices below {vertex_count}"
            ),
            Finding::DegenerateFace { .. } => "is degenerate (a repeated vertex or zero area); \
                 expected three distinct corners spanning an area"
                .to_owned(),
            Finding::DuplicateFace { first, .. } => {
                format!("repeats the vertices of face {first}; expected each triangle once")
            }
            Finding::NonManifoldEdge { faces, .. } => {
                format!("is shared by {faces} faces; expected at most two")
            }
            Finding::IsolatedVertex { .. } => {
                "is used by no face; expected every vertex on a face".to_owned()
            }
        }
    }
}

impl fmt::Display for Finding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Finding::Empty { .. } => write!(f, "mesh is {}", self.problem()),
            _ => write!(f, "{} {}", self.location(), self.problem()),
        }
    }
}

/// The strict gate: `Err` on the first hard error (empty mesh, non-finite coordinate,
/// index out of range), naming `path` and the element. Linear time; every reader runs it.
pub fn check(mesh: &TriMesh, path: &Path) -> Result<(), MeshError> {
    match first_error(mesh) {
        Some(finding) => Err(finding
            .to_error(path)
            .unwrap_or_else(|| MeshError::Invalid {
                path: path.to_path_buf(),
                element: "mesh",
                index: 0,
                message: finding.problem(),
            })),
        None => Ok(()),
    }
}

/// The first hard error, in the order empty, non-finite, out of range.
fn first_error(mesh: &TriMesh) -> Option<Finding> {
    let n = mesh.positions.len();
    if n == 0 || mesh.faces.is_empty() {
        return Some(Finding::Empty {
            vertices: n,
            faces: mesh.faces.len(),
        });
    }
    if let Some(vertex) = mesh
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Some(Finding::NonFinite { vertex });
    }
    mesh.faces.iter().enumerate().find_map(|(face, f)| {
        f.iter()
            .find(|&&i| i as usize >= n)
            .map(|&index| Finding::IndexOutOfRange {
                face,
                index,
                vertex_count: n,
            })
    })
}

/// Every finding, errors first, then by kind in [`FindingKind`] order and by element.
///
/// Faces with an out-of-range index are left out of the geometric and topological tests;
/// faces touching a non-finite vertex are left out of the area test.
pub fn validate(mesh: &TriMesh) -> Vec<Finding> {
    let n = mesh.positions.len();
    let mut out = Vec::new();
    if n == 0 || mesh.faces.is_empty() {
        out.push(Finding::Empty {
            vertices: n,
            faces: mesh.faces.len(),
        });
    }
    let finite: Vec<bool> = mesh
        .positions
        .iter()
        .map(|p| p.iter().all(|c| c.is_finite()))
        .collect();
    out.extend(
        finite
            .iter()
            .enumerate()
            .filter(|(_, &ok)| !ok)
            .map(|(vertex, _)| Finding::NonFinite { vertex }),
    );
    let mut in_range = vec![true; mesh.faces.len()];
    for (face, f) in mesh.faces.iter().enumerate() {
        for &index in f {
            if index as usize >= n {
                in_range[face] = false;
                out.push(Finding::IndexOutOfRange {
                    face,
                    index,
                    vertex_count: n,
                });
            }
        }
    }

    // Degenerate: a repeated vertex, or (relatively) zero area. Edges are divided by the
    // diagonal first, so neither huge nor tiny coordinates overflow the test.
    let diag = mesh
        .bounding_box()
        .map(|b| {
            let d = sub(b.max, b.min);
            d[0].hypot(d[1]).hypot(d[2])
        })
        .unwrap_or(0.0);
    // |cross| is twice the area. Without a usable diagonal (all vertices coincide, or the
    // box is infinite) only an exactly zero area counts.
    let (unit, max_cross) = if diag > 0.0 && diag.is_finite() {
        (diag, 2.0 * DEGENERATE_AREA_TOLERANCE)
    } else {
        (1.0, 0.0)
    };
    let scaled = |v: [f64; 3]| [v[0] / unit, v[1] / unit, v[2] / unit];
    let mut repeats = vec![false; mesh.faces.len()];
    for (face, &[a, b, c]) in mesh.faces.iter().enumerate() {
        if !in_range[face] {
            continue;
        }
        repeats[face] = a == b || b == c || a == c;
        let degenerate = repeats[face] || {
            let [pa, pb, pc] = [a, b, c].map(|i| mesh.positions[i as usize]);
            let x = cross(scaled(sub(pb, pa)), scaled(sub(pc, pa)));
            let corners_finite = [a, b, c].iter().all(|&i| finite[i as usize]);
            corners_finite && dot(x, x).sqrt() <= max_cross
        };
        if degenerate {
            out.push(Finding::DegenerateFace { face });
        }
    }

    // Duplicate: the same vertex set as an earlier face.
    let mut first_with: HashMap<[u32; 3], usize> = HashMap::with_capacity(mesh.faces.len());
    let mut duplicate = vec![false; mesh.faces.len()];
    for (face, f) in mesh.faces.iter().enumerate() {
        if !in_range[face] || repeats[face] {
            continue;
        }
        let mut key = *f;
        key.sort_unstable();
        match first_with.get(&key) {
            Some(&first) => {
                duplicate[face] = true;
                out.push(Finding::DuplicateFace { face, first });
            }
            None => {
                first_with.insert(key, face);
            }
        }
    }

    // Non-manifold: an edge of more than two faces (duplicates and repeats left out, so a
    // duplicated face is reported once, as a duplicate).
    let mut keys: Vec<[u32; 2]> = Vec::with_capacity(3 * mesh.faces.len());
    for (face, f) in mesh.faces.iter().enumerate() {
        if in_range[face] && !repeats[face] && !duplicate[face] {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                keys.push([a.min(b), a.max(b)]);
            }
        }
    }
    keys.sort_unstable();
    for run in keys.chunk_by(|a, b| a == b) {
        if run.len() > 2 {
            out.push(Finding::NonManifoldEdge {
                edge: run[0],
                faces: run.len(),
            });
        }
    }

    // Isolated: on no face with in-range indices.
    let mut used = vec![false; n];
    for (face, f) in mesh.faces.iter().enumerate() {
        if in_range[face] {
            for &i in f {
                used[i as usize] = true;
            }
        }
    }
    out.extend(
        used.iter()
            .enumerate()
            .filter(|(_, &u)| !u)
            .map(|(vertex, _)| Finding::IsolatedVertex { vertex }),
    );
    out
}

/// All findings of one kind, folded: how many, and the first.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KindSummary {
    /// The kind.
    pub kind: FindingKind,
    /// How many findings of this kind.
    pub count: usize,
    /// The first of them, in [`validate`]'s order.
    pub first: Finding,
}

impl fmt::Display for KindSummary {
    /// One report line, e.g. "3 degenerate faces (first: face 17)".
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            FindingKind::Empty => write!(f, "{}", self.first),
            kind => write!(
                f,
                "{} {} (first: {})",
                self.count,
                kind.noun(self.count),
                self.first.location()
            ),
        }
    }
}

/// One [`KindSummary`] per kind present, in [`FindingKind`] order (errors first).
pub fn summarize(findings: &[Finding]) -> Vec<KindSummary> {
    let mut out: Vec<KindSummary> = Vec::new();
    for finding in findings {
        let kind = finding.kind();
        match out.iter_mut().find(|s| s.kind == kind) {
            Some(s) => s.count += 1,
            None => out.push(KindSummary {
                kind,
                count: 1,
                first: finding.clone(),
            }),
        }
    }
    out.sort_by_key(|s| s.kind);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives::{cylinder, grid};

    fn kinds(findings: &[Finding]) -> Vec<FindingKind> {
        findings.iter().map(Finding::kind).collect()
    }

    fn tri() -> TriMesh {
        TriMesh::new(
            vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]],
            vec![[0, 1, 2]],
        )
    }

    #[test]
    fn healthy_meshes_have_no_findings() {
        assert!(validate(&tri()).is_empty());
        assert!(validate(&grid(5, 4, 0.1)).is_empty());
        assert!(validate(&cylinder(4, 9, 1.0, 0.2)).is_empty());
        assert!(check(&cylinder(4, 9, 1.0, 0.2), Path::new("c.obj")).is_ok());
    }

    #[test]
    fn empty_meshes_are_errors() {
        let no_faces = TriMesh::new(vec![[0.; 3]], vec![]);
        let f = validate(&no_faces);
        assert_eq!(
            f[0],
            Finding::Empty {
                vertices: 1,
                faces: 0
            }
        );
        assert_eq!(f[0].severity(), Severity::Error);
        let e = check(&TriMesh::default(), Path::new("e.obj")).unwrap_err();
        assert!(matches!(
            e,
            MeshError::Empty {
                vertices: 0,
                faces: 0,
                ..
            }
        ));
        assert!(e.to_string().starts_with("e.obj: the mesh is empty"), "{e}");
    }

    #[test]
    fn non_finite_coordinates_are_errors() {
        let mut m = tri();
        m.positions[1][2] = f64::NAN;
        assert_eq!(validate(&m), vec![Finding::NonFinite { vertex: 1 }]);
        let e = check(&m, Path::new("n.ply")).unwrap_err().to_string();
        assert!(e.starts_with("n.ply: vertex 1: has a NaN"), "{e}");
        m.positions[1][2] = f64::INFINITY;
        assert!(check(&m, Path::new("n.ply")).is_err());
    }

    #[test]
    fn out_of_range_indices_are_errors() {
        let mut m = tri();
        m.faces.push([0, 2, 7]);
        let f = validate(&m);
        assert_eq!(
            f,
            vec![Finding::IndexOutOfRange {
                face: 1,
                index: 7,
                vertex_count: 3
            }]
        );
        assert_eq!(
            f[0].to_string(),
            "face 1 names vertex 7, but the mesh has 3 vertices; expected indices below 3"
        );
        let e = check(&m, Path::new("x.obj")).unwrap_err().to_string();
        assert!(e.starts_with("x.obj: face 1: names vertex 7"), "{e}");
    }

    #[test]
    fn degenerate_faces_are_warnings() {
        let mut m = tri();
        m.positions.push([2., 0., 0.]); // collinear with 0 and 1
        m.faces.push([0, 1, 3]); // zero area
        m.faces.push([2, 2, 1]); // repeated vertex
        let f = validate(&m);
        assert_eq!(
            f,
            vec![
                Finding::DegenerateFace { face: 1 },
                Finding::DegenerateFace { face: 2 }
            ]
        );
        assert_eq!(f[0].severity(), Severity::Warning);
        assert!(check(&m, Path::new("d.obj")).is_ok());
    }

    #[test]
    fn degeneracy_survives_extreme_scales() {
        for s in [1e-300, 1e-160, 1e160, 1e300] {
            let mut m = tri();
            for p in &mut m.positions {
                *p = p.map(|c| c * s);
            }
            assert!(validate(&m).is_empty(), "scale {s}");
        }
        let mut point = tri();
        point.positions = vec![[2.0; 3]; 3];
        assert_eq!(validate(&point), vec![Finding::DegenerateFace { face: 0 }]);
    }

    #[test]
    fn degeneracy_is_relative_to_the_mesh_size() {
        // The same slightly bent sliver is healthy in a small mesh and degenerate in a
        // mesh a million times larger.
        let sliver = |scale: f64| {
            TriMesh::new(
                vec![
                    [0., 0., 0.],
                    [1e-3, 0., 0.],
                    [2e-3, 1e-9, 0.],
                    [scale, scale, 0.],
                ],
                vec![[0, 1, 2], [0, 1, 3]],
            )
        };
        assert!(kinds(&validate(&sliver(1e-3))).is_empty());
        assert_eq!(
            kinds(&validate(&sliver(1e3))),
            vec![FindingKind::DegenerateFace]
        );
    }

    #[test]
    fn duplicate_faces_in_any_order_and_orientation() {
        let mut m = tri();
        m.faces.push([2, 0, 1]); // same orientation, rotated
        m.faces.push([0, 2, 1]); // flipped
        let f = validate(&m);
        assert_eq!(
            f,
            vec![
                Finding::DuplicateFace { face: 1, first: 0 },
                Finding::DuplicateFace { face: 2, first: 0 }
            ]
        );
        assert_eq!(
            f[1].to_string(),
            "face 2 repeats the vertices of face 0; expected each triangle once"
        );
    }

    #[test]
    fn three_faces_on_an_edge_are_non_manifold() {
        let m = TriMesh::new(
            vec![
                [0.; 3],
                [1., 0., 0.],
                [0., 1., 0.],
                [0., -1., 0.],
                [0., 0., 1.],
            ],
            vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
        );
        let f = validate(&m);
        assert_eq!(
            f,
            vec![Finding::NonManifoldEdge {
                edge: [0, 1],
                faces: 3
            }]
        );
        assert_eq!(
            f[0].to_string(),
            "edge [0, 1] is shared by 3 faces; expected at most two"
        );
    }

    #[test]
    fn isolated_vertices_are_warnings() {
        let mut m = tri();
        m.positions.push([5., 5., 5.]);
        assert_eq!(validate(&m), vec![Finding::IsolatedVertex { vertex: 3 }]);
    }

    #[test]
    fn summary_lines_count_and_name_the_first() {
        let mut m = grid(3, 3, 1.0);
        m.faces.push([0, 0, 1]);
        m.faces.push([4, 4, 5]);
        m.faces.push([3, 3, 3]);
        m.positions.push([9., 9., 9.]);
        let lines: Vec<String> = summarize(&validate(&m))
            .iter()
            .map(ToString::to_string)
            .collect();
        assert_eq!(
            lines,
            vec![
                "3 degenerate faces (first: face 8)",
                "1 isolated vertex (first: vertex 9)"
            ]
        );
        let empty = summarize(&validate(&TriMesh::default()));
        assert_eq!(
            empty[0].to_string(),
            "mesh is empty (0 vertices, 0 faces); expected at least one triangle"
        );
    }
}
