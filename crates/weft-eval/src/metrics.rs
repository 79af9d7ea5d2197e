//! The error measures of seed 000 §4 and the physical checks weft adds, as plain functions
//! on `f32` vertex arrays (the precision of datasets and network outputs).
//!
//! - `E_verts`: distance between predicted and simulated vertex, in millimetres.
//! - `E_norm`: angle between predicted and simulated vertex normals, in degrees; normals
//!   are weft-mesh's area-weighted vertex normals of each mesh.
//! - collision rate: the share of garment vertices inside the posed body (negative
//!   signed distance from weft-body's query), the failure people see first;
//! - edge strain: `|l / l₀ − 1|` per edge against the rest garment, mean and max, which
//!   catches predictions that are close on average but stretch cloth locally.
//!
//! [`FrameMetrics`] accumulates all of them over frames, sequences and garment kinds with
//! the one-pass [`Accumulator`](crate::stats::Accumulator), so a whole test split is
//! evaluated without keeping every error in memory.

use serde::{Deserialize, Serialize};
use weft_body::query::BodySurface;
use weft_mesh::TriMesh;

use crate::error::EvalError;
use crate::stats::{Accumulator, Summary};

/// Metres to millimetres.
const MM: f64 = 1000.0;

fn check_len(what: &'static str, expected: usize, found: usize) -> Result<(), EvalError> {
    if expected == found {
        Ok(())
    } else {
        Err(EvalError::Count {
            what,
            expected,
            found,
        })
    }
}

fn f64x3(p: [f32; 3]) -> [f64; 3] {
    p.map(f64::from)
}

/// Per-vertex distance between `predicted` and `truth`, in millimetres.
pub fn vertex_errors_mm(predicted: &[[f32; 3]], truth: &[[f32; 3]]) -> Result<Vec<f64>, EvalError> {
    check_len(
        "predicted vertices vs ground-truth vertices",
        truth.len(),
        predicted.len(),
    )?;
    Ok(predicted
        .iter()
        .zip(truth)
        .map(|(&p, &q)| weft_mesh::vec3::norm(weft_mesh::vec3::sub(f64x3(p), f64x3(q))) * MM)
        .collect())
}

/// Area-weighted unit vertex normals of `faces` at `positions` (weft-mesh's definition).
pub fn vertex_normals(faces: &[[u32; 3]], positions: &[[f32; 3]]) -> Vec<[f64; 3]> {
    TriMesh::new(
        positions.iter().map(|&p| f64x3(p)).collect(),
        faces.to_vec(),
    )
    .vertex_normals()
}

/// Per-vertex angle between the normals of `predicted` and `truth` (same faces), in
/// degrees. A vertex whose normal is undefined in either mesh (no incident face of
/// non-zero area) gets `NaN`, which the accumulators leave out and count.
pub fn normal_errors_deg(
    faces: &[[u32; 3]],
    predicted: &[[f32; 3]],
    truth: &[[f32; 3]],
) -> Result<Vec<f64>, EvalError> {
    check_len(
        "predicted vertices vs ground-truth vertices",
        truth.len(),
        predicted.len(),
    )?;
    check_faces(faces, truth.len())?;
    let a = vertex_normals(faces, predicted);
    let b = vertex_normals(faces, truth);
    Ok(a.iter()
        .zip(&b)
        .map(|(&n, &m)| {
            let (ln, lm) = (weft_mesh::vec3::norm(n), weft_mesh::vec3::norm(m));
            if ln < 0.5 || lm < 0.5 {
                return f64::NAN;
            }
            weft_mesh::vec3::dot(n, m)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees()
        })
        .collect())
}

fn check_faces(faces: &[[u32; 3]], vertices: usize) -> Result<(), EvalError> {
    if let Some((f, i)) = faces
        .iter()
        .enumerate()
        .find_map(|(f, t)| t.iter().find(|&&i| i as usize >= vertices).map(|&i| (f, i)))
    {
        return Err(EvalError::Invalid(format!(
            "face {f} names vertex {i}, but the garment has {vertices} vertices"
        )));
    }
    Ok(())
}

/// Signed distance of each garment vertex to the posed body (metres, negative inside).
pub fn body_signed_distances(
    body: &BodySurface,
    garment: &[[f32; 3]],
) -> Result<Vec<f64>, EvalError> {
    let points: Vec<[f64; 3]> = garment.iter().map(|&p| f64x3(p)).collect();
    Ok(body.signed_distances(&points)?)
}

/// Number of garment vertices inside the posed body (signed distance below `-tolerance`,
/// metres; 0 counts every vertex behind the surface).
pub fn vertices_inside(
    body: &BodySurface,
    garment: &[[f32; 3]],
    tolerance: f64,
) -> Result<usize, EvalError> {
    Ok(body_signed_distances(body, garment)?
        .into_iter()
        .filter(|&d| d < -tolerance)
        .count())
}

/// Rest lengths of `edges` on the rest garment, for [`edge_strains`].
pub fn edge_lengths(edges: &[[u32; 2]], positions: &[[f32; 3]]) -> Result<Vec<f64>, EvalError> {
    edges
        .iter()
        .map(|&[a, b]| {
            let (pa, pb) = (positions.get(a as usize), positions.get(b as usize));
            match (pa, pb) {
                (Some(&pa), Some(&pb)) => Ok(weft_mesh::vec3::norm(weft_mesh::vec3::sub(
                    f64x3(pa),
                    f64x3(pb),
                ))),
                _ => Err(EvalError::Invalid(format!(
                    "edge [{a}, {b}] names a vertex beyond the garment's {}",
                    positions.len()
                ))),
            }
        })
        .collect()
}

/// `|l / l₀ − 1|` for each edge with rest length `rest[e] > 0` (others are `NaN`).
pub fn edge_strains(
    edges: &[[u32; 2]],
    rest: &[f64],
    positions: &[[f32; 3]],
) -> Result<Vec<f64>, EvalError> {
    check_len("rest edge lengths vs edges", edges.len(), rest.len())?;
    let l = edge_lengths(edges, positions)?;
    Ok(l.iter()
        .zip(rest)
        .map(|(&l, &l0)| {
            if l0 > 0.0 {
                (l / l0 - 1.0).abs()
            } else {
                f64::NAN
            }
        })
        .collect())
}

/// Everything that is fixed for one garment while its frames are evaluated.
#[derive(Clone, Debug)]
pub struct GarmentTopology {
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
    /// Undirected edges.
    pub edges: Vec<[u32; 2]>,
    /// Rest length of each edge (metres).
    pub rest_lengths: Vec<f64>,
}

impl GarmentTopology {
    /// The topology and rest edge lengths of a rest garment.
    pub fn new(rest: &TriMesh) -> Result<Self, EvalError> {
        let edges = rest.edges();
        let pos: Vec<[f32; 3]> = rest.positions.iter().map(|p| p.map(|x| x as f32)).collect();
        let rest_lengths = edge_lengths(&edges, &pos)?;
        Ok(GarmentTopology {
            faces: rest.faces.clone(),
            edges,
            rest_lengths,
        })
    }

    /// Number of vertices the faces and edges refer to at most.
    fn check(&self, vertices: usize) -> Result<(), EvalError> {
        check_faces(&self.faces, vertices)
    }
}

/// Accumulated metrics of one method over many frames.
#[derive(Clone, Debug, Default)]
pub struct FrameMetrics {
    verts: Accumulator,
    norm: Accumulator,
    undefined_normals: u64,
    strain: Accumulator,
    inside: u64,
    collision_checked: u64,
    frames: u64,
    nonfinite: u64,
    potential_gap: Accumulator,
}

impl FrameMetrics {
    /// Nothing accumulated yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one frame: `predicted` against `truth` on `topology`, and, when `body` (the
    /// body posed at this frame) is given, the collision check of `predicted`.
    ///
    /// A non-finite predicted coordinate is an error of the method, not of the input:
    /// the vertex is counted in [`MetricsSummary::nonfinite_vertices`] and its errors are
    /// left out of the means (so one diverged vertex cannot turn the table into NaN,
    /// and the count says it happened).
    pub fn push_frame(
        &mut self,
        topology: &GarmentTopology,
        predicted: &[[f32; 3]],
        truth: &[[f32; 3]],
        body: Option<&BodySurface>,
    ) -> Result<(), EvalError> {
        topology.check(truth.len())?;
        if let Some(i) = truth.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(EvalError::Invalid(format!(
                "ground-truth vertex {i} is not finite; the dataset is damaged"
            )));
        }
        let bad = predicted
            .iter()
            .filter(|p| p.iter().any(|x| !x.is_finite()))
            .count();
        self.nonfinite += bad as u64;
        self.verts.extend(vertex_errors_mm(predicted, truth)?);
        let normals = normal_errors_deg(&topology.faces, predicted, truth)?;
        self.undefined_normals += normals.iter().filter(|x| x.is_nan()).count() as u64;
        self.norm.extend(normals);
        self.strain.extend(edge_strains(
            &topology.edges,
            &topology.rest_lengths,
            predicted,
        )?);
        if let Some(body) = body {
            let finite: Vec<[f32; 3]> = predicted
                .iter()
                .copied()
                .filter(|p| p.iter().all(|x| x.is_finite()))
                .collect();
            self.inside += vertices_inside(body, &finite, 0.0)? as u64;
            self.collision_checked += finite.len() as u64;
        }
        self.frames += 1;
        Ok(())
    }

    /// Adds the steps' potential gaps (J) a [`weft_models::StepJudge`] found.
    pub fn push_potential_gaps(&mut self, gaps: &[f64]) {
        self.potential_gap.extend(gaps.iter().copied());
    }

    /// Adds everything `other` accumulated.
    pub fn merge(&mut self, other: &FrameMetrics) {
        self.verts.merge(&other.verts);
        self.norm.merge(&other.norm);
        self.undefined_normals += other.undefined_normals;
        self.strain.merge(&other.strain);
        self.inside += other.inside;
        self.collision_checked += other.collision_checked;
        self.frames += other.frames;
        self.nonfinite += other.nonfinite;
        self.potential_gap.merge(&other.potential_gap);
    }

    /// Frames added so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// The figures.
    pub fn summary(&self) -> MetricsSummary {
        MetricsSummary {
            e_verts_mm: self.verts.summary(),
            e_norm_deg: self.norm.summary(),
            edge_strain: self.strain.summary(),
            collision_rate: if self.collision_checked > 0 {
                Some(self.inside as f64 / self.collision_checked as f64)
            } else {
                None
            },
            frames: self.frames,
            nonfinite_vertices: self.nonfinite,
            undefined_normals: self.undefined_normals,
            potential_gap_j: (self.potential_gap.count() > 0).then(|| self.potential_gap.summary()),
        }
    }
}

/// The figures of one method on one group of frames (a garment kind, or all).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MetricsSummary {
    /// `E_verts` (mm) over all vertices and frames.
    pub e_verts_mm: Summary,
    /// `E_norm` (degrees) over all vertices with a defined normal and frames.
    pub e_norm_deg: Summary,
    /// `|l/l₀ − 1|` over all edges and frames: `mean` and `max` are the mean and the
    /// maximum strain.
    pub edge_strain: Summary,
    /// Share of garment vertices inside the posed body, when bodies were given.
    pub collision_rate: Option<f64>,
    /// Frames evaluated.
    pub frames: u64,
    /// Predicted vertices with a non-finite coordinate (left out of the errors).
    pub nonfinite_vertices: u64,
    /// Vertices whose normal is undefined (no face of non-zero area) in prediction or
    /// ground truth (left out of `E_norm`).
    pub undefined_normals: u64,
    /// Per step, its incremental potential less the minimum (J), when a judge scored
    /// the steps (`weft eval` of a HOOD run).
    #[serde(default)]
    pub potential_gap_j: Option<Summary>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives;

    fn f32s(m: &TriMesh) -> Vec<[f32; 3]> {
        m.positions.iter().map(|p| p.map(|x| x as f32)).collect()
    }

    #[test]
    fn vertex_error_is_distance_in_mm() {
        let e = vertex_errors_mm(
            &[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]],
            &[[0.003, 0.004, 0.0], [1.0, 1.0, 1.0]],
        )
        .unwrap();
        assert!((e[0] - 5.0).abs() < 1e-4, "{e:?}");
        assert_eq!(e[1], 0.0);
        assert!(matches!(
            vertex_errors_mm(&[[0.0; 3]], &[]),
            Err(EvalError::Count { .. })
        ));
    }

    #[test]
    fn rotating_a_patch_tilts_every_normal_by_the_angle() {
        let plane = primitives::grid(4, 4, 1.0);
        let truth = f32s(&plane);
        let angle = 20f64.to_radians();
        let (s, c) = angle.sin_cos();
        // Rotate about the X axis: every normal turns by `angle`.
        let rotated: Vec<[f32; 3]> = plane
            .positions
            .iter()
            .map(|p| [p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]].map(|x| x as f32))
            .collect();
        let e = normal_errors_deg(&plane.faces, &rotated, &truth).unwrap();
        for x in e {
            assert!((x - 20.0).abs() < 1e-3, "{x}");
        }
        // Translation changes no normal.
        let moved: Vec<[f32; 3]> = truth.iter().map(|p| [p[0] + 0.5, p[1], p[2]]).collect();
        assert!(normal_errors_deg(&plane.faces, &moved, &truth)
            .unwrap()
            .iter()
            .all(|&x| x < 1e-3));
    }

    #[test]
    fn strain_of_a_uniform_scale() {
        let m = primitives::grid(3, 3, 1.0);
        let topo = GarmentTopology::new(&m).unwrap();
        let scaled: Vec<[f32; 3]> = f32s(&m).iter().map(|p| p.map(|x| 1.1 * x)).collect();
        for s in edge_strains(&topo.edges, &topo.rest_lengths, &scaled).unwrap() {
            assert!((s - 0.1).abs() < 1e-5, "{s}");
        }
    }

    #[test]
    fn collision_counts_vertices_inside_a_closed_body() {
        // A closed, outward-oriented octahedron with vertices at distance 1 on the axes.
        let positions = vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let faces = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        let body = BodySurface::new(&positions, &faces).unwrap();
        let points = [
            [0.0, 0.0, 0.0],
            [0.0, 0.3, 0.1],
            [0.0, 2.0, 0.0],
            [1.5, 0.0, 0.0],
        ];
        assert_eq!(vertices_inside(&body, &points, 0.0).unwrap(), 2);
    }

    #[test]
    fn accumulates_frames_and_counts_nonfinite_predictions() {
        let m = primitives::grid(3, 3, 1.0);
        let topo = GarmentTopology::new(&m).unwrap();
        let truth = f32s(&m);
        let mut pred: Vec<[f32; 3]> = truth.iter().map(|p| [p[0], p[1], p[2] + 0.002]).collect();
        let mut acc = FrameMetrics::new();
        acc.push_frame(&topo, &pred, &truth, None).unwrap();
        pred[0] = [f32::NAN, 0.0, 0.0];
        acc.push_frame(&topo, &pred, &truth, None).unwrap();
        let s = acc.summary();
        assert_eq!(s.frames, 2);
        assert_eq!(s.nonfinite_vertices, 1);
        assert_eq!(s.e_verts_mm.count, 2 * truth.len() as u64 - 1);
        assert!((s.e_verts_mm.mean - 2.0).abs() < 1e-3);
        assert!(s.e_norm_deg.mean < 1e-3);
        assert_eq!(s.collision_rate, None);
        // Damaged ground truth is an error, not a silently skipped vertex.
        let mut bad = truth.clone();
        bad[1] = [f32::INFINITY, 0.0, 0.0];
        assert!(acc.push_frame(&topo, &pred, &bad, None).is_err());
    }
}
