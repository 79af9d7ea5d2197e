//! Cutting a mesh open along a path of edges: every vertex on the path is split into one
//! copy per side, so the two sides no longer share an edge. What turns a pullover into an
//! open-front jacket (weft-garment's `open_front`), whose two edges can then be buttoned
//! back together by vertex pairs (seed 004 Fig. 4).

use crate::geodesic::{GeodesicError, Geodesics};
use crate::mesh::TriMesh;
use crate::vec3::dist;

/// Why a mesh could not be cut.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CutError {
    /// A path vertex does not exist.
    #[error("cut path vertex {vertex} is out of range (the mesh has {vertex_count} vertices)")]
    OutOfRange {
        /// The vertex.
        vertex: u32,
        /// Vertices of the mesh.
        vertex_count: usize,
    },
    /// Two consecutive path vertices are not joined by an edge of the mesh.
    #[error("cut path vertices {from} and {to} are not joined by a mesh edge")]
    NotAnEdge {
        /// First vertex.
        from: u32,
        /// Second vertex.
        to: u32,
    },
    /// A vertex appears twice on the path.
    #[error("cut path visits vertex {vertex} twice")]
    Repeated {
        /// The vertex.
        vertex: u32,
    },
    /// No path of edges joins the two vertices.
    #[error("no path of mesh edges joins vertices {from} and {to}")]
    Disconnected {
        /// Start.
        from: u32,
        /// End.
        to: u32,
    },
    /// The mesh itself is unusable for distances (a face out of range, a non-finite
    /// position).
    #[error("cannot measure paths on the mesh: {0}")]
    Mesh(#[from] GeodesicError),
}

/// A mesh cut open, with the vertex pairs the cut separated.
#[derive(Clone, Debug, PartialEq)]
pub struct Cut {
    /// The cut mesh: the input's vertices (same indices) followed by the copies, and the
    /// input's faces in the same order, those on the far side of the cut renumbered to
    /// the copies.
    pub mesh: TriMesh,
    /// `[original, copy]` for every path vertex the cut split, in path order.
    pub pairs: Vec<[u32; 2]>,
}

/// Cuts `mesh` along `path`, a chain of vertices joined by mesh edges.
///
/// Around each path vertex the faces are grouped by the edges they share, crossing no
/// edge of the path; the first group keeps the vertex, every further group gets a copy at
/// the same position. An interior path vertex thus splits in two, and so does an end on
/// the mesh boundary; an end inside the mesh is where the slit stops, and stays whole.
pub fn cut_along(mesh: &TriMesh, path: &[u32]) -> Result<Cut, CutError> {
    let n = mesh.vertex_count();
    let mut on_path = vec![false; n];
    for &v in path {
        if v as usize >= n {
            return Err(CutError::OutOfRange {
                vertex: v,
                vertex_count: n,
            });
        }
        if std::mem::replace(&mut on_path[v as usize], true) {
            return Err(CutError::Repeated { vertex: v });
        }
    }
    let graph = mesh.graph();
    let cut_edges: Vec<[u32; 2]> = path.windows(2).map(|w| edge_key(w[0], w[1])).collect();
    for w in path.windows(2) {
        if !graph.neighbors(w[0] as usize).contains(&w[1]) {
            return Err(CutError::NotAnEdge {
                from: w[0],
                to: w[1],
            });
        }
    }
    let mut faces_of = vec![Vec::new(); n];
    for (f, face) in mesh.faces.iter().enumerate() {
        for &v in face {
            if on_path[v as usize] {
                faces_of[v as usize].push(f);
            }
        }
    }
    let mut out = mesh.clone();
    let mut pairs = Vec::new();
    for &v in path {
        let around = &faces_of[v as usize];
        let groups = fan_groups(mesh, v, around, &cut_edges);
        for group in groups.iter().skip(1) {
            let copy = out.positions.len() as u32;
            out.positions.push(mesh.positions[v as usize]);
            for &f in group {
                for c in &mut out.faces[f] {
                    if *c == v {
                        *c = copy;
                    }
                }
            }
            pairs.push([v, copy]);
        }
    }
    Ok(Cut { mesh: out, pairs })
}

/// The faces `around` vertex `v`, in groups joined through shared edges `(v, w)` that are
/// not cut; groups ordered by their smallest face.
fn fan_groups(mesh: &TriMesh, v: u32, around: &[usize], cut_edges: &[[u32; 2]]) -> Vec<Vec<usize>> {
    let mut group: Vec<usize> = (0..around.len()).collect();
    fn root(group: &mut [usize], mut i: usize) -> usize {
        while group[i] != i {
            group[i] = group[group[i]];
            i = group[i];
        }
        i
    }
    let others = |f: usize| mesh.faces[f].into_iter().filter(move |&w| w != v);
    for i in 0..around.len() {
        for j in i + 1..around.len() {
            let shared = others(around[i]).find(|w| others(around[j]).any(|u| u == *w));
            if let Some(w) = shared {
                if !cut_edges.contains(&edge_key(v, w)) {
                    let (a, b) = (root(&mut group, i), root(&mut group, j));
                    group[a.max(b)] = a.min(b);
                }
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut index_of_root = vec![usize::MAX; around.len()];
    for (i, &f) in around.iter().enumerate() {
        let r = root(&mut group, i);
        if index_of_root[r] == usize::MAX {
            index_of_root[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[index_of_root[r]].push(f);
    }
    groups
}

fn edge_key(a: u32, b: u32) -> [u32; 2] {
    [a.min(b), a.max(b)]
}

/// The shortest chain of mesh edges (by length) from `from` to `to`, both included.
pub fn shortest_path(mesh: &TriMesh, from: u32, to: u32) -> Result<Vec<u32>, CutError> {
    let n = mesh.vertex_count();
    for v in [from, to] {
        if v as usize >= n {
            return Err(CutError::OutOfRange {
                vertex: v,
                vertex_count: n,
            });
        }
    }
    let geodesics = Geodesics::new(mesh)?;
    let d = geodesics.distances_from(from as usize);
    if !d[to as usize].is_finite() {
        return Err(CutError::Disconnected { from, to });
    }
    // Walk back from `to`, each time to the neighbour the distance came through.
    let graph = geodesics.graph();
    let mut path = vec![to];
    let mut at = to;
    while at != from {
        let step = |&w: &u32| {
            d[w as usize] + dist(mesh.positions[w as usize], mesh.positions[at as usize])
        };
        at = graph
            .neighbors(at as usize)
            .iter()
            .copied()
            .filter(|w| d[*w as usize] < d[at as usize])
            .min_by(|a, b| step(a).total_cmp(&step(b)))
            .ok_or(CutError::Disconnected { from, to })?;
        path.push(at);
    }
    path.reverse();
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::primitives::grid;
    use crate::topology::Topology;

    /// A 4×4 grid cut down its middle column from the top edge to the bottom edge
    /// falls into two pieces: every path vertex is split, no face keeps vertices of both
    /// sides, and the positions are unchanged.
    #[test]
    fn a_boundary_to_boundary_cut_splits_a_sheet() {
        let g = grid(4, 4, 1.0);
        // Vertices are row-major: column 1 from row 0 to row 3.
        let path = [1u32, 5, 9, 13];
        let cut = cut_along(&g, &path).unwrap();
        assert_eq!(cut.pairs.len(), 4);
        assert_eq!(cut.mesh.vertex_count(), 20);
        assert_eq!(cut.mesh.face_count(), g.face_count());
        for &[a, b] in &cut.pairs {
            assert_eq!(
                cut.mesh.positions[a as usize],
                cut.mesh.positions[b as usize]
            );
        }
        // Two connected pieces now, and the cut edges are boundary on both sides.
        let graph = cut.mesh.graph();
        let mut seen = [false; 20];
        let mut stack = vec![0usize];
        while let Some(v) = stack.pop() {
            if !std::mem::replace(&mut seen[v], true) {
                stack.extend(graph.neighbors(v).iter().map(|&w| w as usize));
            }
        }
        assert!(seen.iter().filter(|&&s| s).count() < 20);
        let boundary = Topology::new(&cut.mesh).boundary_edges().len();
        assert_eq!(boundary, Topology::new(&g).boundary_edges().len() + 2 * 3);
    }

    /// A slit ending inside the sheet leaves its inner end whole.
    #[test]
    fn a_slit_keeps_its_inner_end() {
        let g = grid(5, 5, 1.0);
        let path = [2u32, 7, 12];
        let cut = cut_along(&g, &path).unwrap();
        assert_eq!(
            cut.pairs.iter().map(|p| p[0]).collect::<Vec<_>>(),
            vec![2, 7]
        );
        assert!(cut_along(&g, &[2, 12]).is_err());
        assert!(cut_along(&g, &[2, 7, 2]).is_err());
        assert!(cut_along(&g, &[2, 99]).is_err());
    }

    #[test]
    fn shortest_path_follows_edges() {
        let g = grid(4, 4, 1.0);
        let p = shortest_path(&g, 1, 13).unwrap();
        assert_eq!((p[0], *p.last().unwrap(), p.len()), (1, 13, 4));
        let graph = g.graph();
        assert!(p
            .windows(2)
            .all(|w| graph.neighbors(w[0] as usize).contains(&w[1])));
    }

    #[test]
    fn shortest_path_names_a_broken_mesh_not_a_disconnection() {
        let mut g = grid(4, 4, 1.0);
        g.positions[5][0] = f64::NAN;
        assert!(matches!(
            shortest_path(&g, 1, 13),
            Err(CutError::Mesh(GeodesicError::NonFinitePosition {
                vertex: 5,
                ..
            }))
        ));
    }
}
