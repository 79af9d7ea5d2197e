//! The supervised loss terms of seed 000 (supplement eq. 1–3) as plain burn tensor code
//! over a window of predicted frames `x` (`[T, N, 3]`) and the simulated ground truth:
//!
//! - eq. 1, vertex: `(1/N) Σ_i ‖x_i − x_i^GT‖₂`, the mean per-vertex distance (averaged
//!   over the frames too);
//! - eq. 2, edge: `‖E − E^GT‖₂²` over the edge lengths; written here as the mean over
//!   edges and frames, so the term does not grow with the mesh resolution (the weight
//!   `k_e` absorbs the constant);
//! - eq. 3, normal: `(1/N) Σ_i (1 − n_i · n_i^GT)` with area-weighted unit vertex
//!   normals, the normals weft-mesh computes ([`TriMesh::vertex_normals`]).
//!
//! The ground-truth side (edge lengths, normals) is computed once per window on the
//! host in f64 ([`Targets`]); only the prediction side is differentiated. The weights
//! `k_v, k_e, k_n` are applied by the caller ([`crate::tasks::multilevel::TermWeights`]).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use burn::tensor::{DType, Device, Int, Tensor, TensorData};
use weft_mesh::vec3::{norm, sub};
use weft_mesh::TriMesh;
use weft_nn::adjacency::index_tensor;
use weft_nn::{sparse_matmul, SparseImpl, SparseMatrix};

use crate::error::{Result, TrainError};

/// Guards `sqrt` at zero (its derivative is infinite there): a prediction equal to the
/// ground truth must give a zero gradient, not NaN. Squared metres, far below any error
/// that matters (1 µm² = 1e-12).
const SQRT_GUARD: f64 = 1e-16;

/// The garment's edges and faces, with index tensors per window length cached.
#[derive(Debug)]
pub struct GarmentTopology {
    vertex_count: usize,
    edges: Vec<[u32; 2]>,
    faces: Vec<[u32; 3]>,
    windows: Mutex<HashMap<usize, Arc<WindowIndex>>>,
}

/// Index tensors of a window of `T` frames: rows of the flattened `[T·N, 3]` positions.
#[derive(Debug)]
pub struct WindowIndex {
    frames: usize,
    edge_a: Tensor<1, Int>,
    edge_b: Tensor<1, Int>,
    corners: [Tensor<1, Int>; 3],
    /// Vertex–face incidence, block diagonal over frames: `[T·N, T·F]`.
    incidence: Arc<SparseMatrix>,
}

impl GarmentTopology {
    /// The topology of the rest garment `mesh`.
    pub fn new(mesh: &TriMesh) -> Result<Self> {
        if mesh.faces.is_empty() {
            return Err(TrainError::Shape {
                what: "garment".into(),
                expected: "at least one face".into(),
                found: "none".into(),
            });
        }
        Ok(GarmentTopology {
            vertex_count: mesh.vertex_count(),
            edges: mesh.edges(),
            faces: mesh.faces.clone(),
            windows: Mutex::new(HashMap::new()),
        })
    }

    /// Vertices `N`.
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Unique edges.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Index tensors for windows of `frames` frames on `device` (built once per length).
    pub fn window(&self, frames: usize, device: &Device) -> Result<Arc<WindowIndex>> {
        let mut cache = self
            .windows
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(w) = cache.get(&frames) {
            return Ok(w.clone());
        }
        let n = self.vertex_count as u32;
        let f = self.faces.len() as u32;
        let offset = |t: usize| t as u32 * n;
        let rows = |pick: &dyn Fn([u32; 2]) -> u32| -> Vec<u32> {
            (0..frames)
                .flat_map(|t| self.edges.iter().map(move |&e| (t, e)))
                .map(|(t, e)| offset(t) + pick(e))
                .collect()
        };
        let edge_a = index_tensor(&rows(&|e| e[0]), device);
        let edge_b = index_tensor(&rows(&|e| e[1]), device);
        let corner = |k: usize| -> Tensor<1, Int> {
            let idx: Vec<u32> = (0..frames)
                .flat_map(|t| self.faces.iter().map(move |face| offset(t) + face[k]))
                .collect();
            index_tensor(&idx, device)
        };
        let corners = [corner(0), corner(1), corner(2)];
        let triplets = (0..frames).flat_map(|t| {
            self.faces.iter().enumerate().flat_map(move |(fi, face)| {
                face.map(|v| (offset(t) + v, t as u32 * f + fi as u32, 1.0))
            })
        });
        let incidence = Arc::new(SparseMatrix::from_triplets(
            frames * self.vertex_count,
            frames * self.faces.len(),
            triplets,
        )?);
        let w = Arc::new(WindowIndex {
            frames,
            edge_a,
            edge_b,
            corners,
            incidence,
        });
        cache.insert(frames, w.clone());
        Ok(w)
    }
}

/// The ground truth of a window, ready for the losses: positions `[T, N, 3]`, edge
/// lengths `[T·E]` and unit vertex normals `[T·N, 3]`.
#[derive(Clone, Debug)]
pub struct Targets {
    /// Ground-truth positions.
    pub positions: Tensor<3>,
    /// Ground-truth edge lengths, frame-major.
    pub edge_lengths: Tensor<1>,
    /// Ground-truth unit vertex normals, frame-major.
    pub normals: Tensor<2>,
}

impl Targets {
    /// From `frames[t][i]` (f32, as datasets store them) of the garment `topology`.
    pub fn new(
        topology: &GarmentTopology,
        faces: &[[u32; 3]],
        frames: &[Vec<[f32; 3]>],
        device: &Device,
    ) -> Result<Self> {
        let (t, n) = (frames.len(), topology.vertex_count);
        if t == 0 {
            return Err(TrainError::Shape {
                what: "ground-truth window".into(),
                expected: "at least one frame".into(),
                found: "none".into(),
            });
        }
        let mut positions = Vec::with_capacity(t * n * 3);
        let mut lengths = Vec::with_capacity(t * topology.edges.len());
        let mut normals = Vec::with_capacity(t * n * 3);
        for (k, frame) in frames.iter().enumerate() {
            if frame.len() != n {
                return Err(TrainError::Shape {
                    what: format!("ground-truth frame {k}"),
                    expected: format!("{n} vertices"),
                    found: frame.len().to_string(),
                });
            }
            let mesh = TriMesh::new(
                frame.iter().map(|p| p.map(f64::from)).collect(),
                faces.to_vec(),
            );
            positions.extend(frame.iter().flatten().copied());
            lengths.extend(topology.edges.iter().map(|&[a, b]| {
                norm(sub(mesh.positions[a as usize], mesh.positions[b as usize])) as f32
            }));
            normals.extend(
                mesh.vertex_normals()
                    .into_iter()
                    .flat_map(|v| v.map(|c| c as f32)),
            );
        }
        let f32s = |v: Vec<f32>, shape: Vec<usize>| TensorData::new(v, shape);
        Ok(Targets {
            positions: Tensor::from_data(f32s(positions, vec![t, n, 3]), (device, DType::F32)),
            edge_lengths: Tensor::from_data(
                f32s(lengths, vec![t * topology.edges.len()]),
                (device, DType::F32),
            ),
            normals: Tensor::from_data(f32s(normals, vec![t * n, 3]), (device, DType::F32)),
        })
    }
}

fn check_window(what: &str, x: &Tensor<3>, w: &WindowIndex, n: usize) -> Result<()> {
    let dims = x.dims();
    if dims != [w.frames, n, 3] {
        return Err(TrainError::Shape {
            what: format!("{what} loss prediction"),
            expected: format!("[{}, {n}, 3]", w.frames),
            found: format!("{dims:?}"),
        });
    }
    Ok(())
}

/// Eq. 1 without `k_v`: the mean per-vertex distance between `x` and `gt` (`[T, N, 3]`).
pub fn vertex_loss(x: Tensor<3>, gt: Tensor<3>) -> Result<Tensor<1>> {
    if x.dims() != gt.dims() {
        return Err(TrainError::Shape {
            what: "vertex loss ground truth".into(),
            expected: format!("{:?}", x.dims()),
            found: format!("{:?}", gt.dims()),
        });
    }
    let d = (x - gt)
        .powi_scalar(2)
        .sum_dim(2)
        .add_scalar(SQRT_GUARD)
        .sqrt();
    Ok(d.mean())
}

/// Eq. 2 without `k_e`: the mean squared difference of edge lengths.
pub fn edge_loss(
    x: Tensor<3>,
    topology: &GarmentTopology,
    window: &WindowIndex,
    gt_lengths: Tensor<1>,
) -> Result<Tensor<1>> {
    check_window("edge", &x, window, topology.vertex_count)?;
    let flat: Tensor<2> = x.reshape([window.frames * topology.vertex_count, 3]);
    let e = flat.clone().select(0, window.edge_b.clone()) - flat.select(0, window.edge_a.clone());
    let lengths: Tensor<1> = e
        .powi_scalar(2)
        .sum_dim(1)
        .add_scalar(SQRT_GUARD)
        .sqrt()
        .flatten(0, 1);
    Ok((lengths - gt_lengths).powi_scalar(2).mean())
}

/// Area-weighted unit vertex normals of the predicted frames, `[T·N, 3]`.
pub fn vertex_normals(
    x: Tensor<3>,
    topology: &GarmentTopology,
    window: &WindowIndex,
) -> Result<Tensor<2>> {
    check_window("normal", &x, window, topology.vertex_count)?;
    let flat: Tensor<2> = x.reshape([window.frames * topology.vertex_count, 3]);
    let [c0, c1, c2] = window.corners.clone();
    let p0 = flat.clone().select(0, c0);
    let e1 = flat.clone().select(0, c1) - p0.clone();
    let e2 = flat.select(0, c2) - p0;
    let face = e1.cross(e2, 1);
    let summed = sparse_matmul(&window.incidence, face, SparseImpl::Auto)?;
    let len = summed
        .clone()
        .powi_scalar(2)
        .sum_dim(1)
        .add_scalar(SQRT_GUARD * SQRT_GUARD)
        .sqrt();
    Ok(summed / len)
}

/// Eq. 3 without `k_n`: `mean(1 − n · n^GT)` over vertices and frames.
pub fn normal_loss(
    x: Tensor<3>,
    topology: &GarmentTopology,
    window: &WindowIndex,
    gt_normals: Tensor<2>,
) -> Result<Tensor<1>> {
    let n = vertex_normals(x, topology, window)?;
    let cos = (n * gt_normals).sum_dim(1);
    Ok(cos.neg().add_scalar(1.0).mean())
}

/// The mean per-vertex distance in millimetres between two frame sequences (host
/// metric for validation, E_verts of seed 000 §4).
pub fn mean_vertex_error_mm(pred: &[Vec<[f32; 3]>], gt: &[Vec<[f32; 3]>]) -> Result<f64> {
    if pred.len() != gt.len() || pred.iter().zip(gt).any(|(a, b)| a.len() != b.len()) {
        return Err(TrainError::Shape {
            what: "vertex error".into(),
            expected: format!("{} frames like the ground truth", gt.len()),
            found: format!("{} frames", pred.len()),
        });
    }
    let (mut sum, mut count) = (0.0, 0usize);
    for (a, b) in pred.iter().zip(gt) {
        for (p, q) in a.iter().zip(b) {
            sum += norm(sub(p.map(f64::from), q.map(f64::from)));
            count += 1;
        }
    }
    Ok(if count == 0 {
        0.0
    } else {
        1000.0 * sum / count as f64
    })
}
