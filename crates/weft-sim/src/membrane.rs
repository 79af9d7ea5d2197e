//! Rest frames of triangles and the shared machinery of every membrane energy: energies
//! that depend on a triangle only through its deformation gradient `F` (3×2).
//!
//! The deformation gradient maps the rest triangle, laid out in 2D, onto the deformed
//! one: `F = D_s D_m⁻¹` with `D_s = [x1 − x0, x2 − x0]` (3×2) and `D_m` the 2×2 rest edge
//! matrix, either from the rest triangle in a local orthonormal frame of its plane
//! (HOOD's `Dm_inv`, seed 004 §3.3) or from the UV (sewing pattern) coordinates (seed 000
//! supplement eq. 8, where the columns of `F` are `W^u`, `W^v`). `F` is linear in the
//! positions, `F = Σ_a x_a g_aᵀ` with three constant 2-vectors `g_a`, so a density's
//! derivatives in `F` map to the vertices as
//!
//! * `∂E/∂x_a = A · P g_a` with `P = ∂ψ/∂F`,
//! * `∂²E/∂x_a∂x_b[k, l] = A · Σ_{j,m} K[(k, j), (l, m)] g_a[j] g_b[m]` with `K = ∂²ψ/∂F²`,
//!
//! where `A` is the rest area. StVK stretching and the seed 000 stretch and shear terms
//! are all written as a density plus this one code path.

use nalgebra::{Matrix3x2, SMatrix, Vector3};
use rayon::prelude::*;
use weft_mesh::TriMesh;

use crate::energy::HessianKind;
use crate::error::{check_count, check_eval, check_len, check_vertex, Output, SimError};
use crate::math::{finite3, project_psd6, project_psd9, v3};
use crate::sparse::{BlockCsr, GatherCache};

/// `∂²ψ/∂F²` as a 6×6 matrix, entry `(k + 3j, l + 3m)` = `∂²ψ/∂F_kj ∂F_lm`.
pub(crate) type FHessian = SMatrix<f64, 6, 6>;

/// Rest frames of all faces of a garment: per face the three `g_a` and the rest area.
#[derive(Clone, Debug, PartialEq)]
pub struct RestFrames {
    vertex_count: usize,
    faces: Vec<[u32; 3]>,
    g: Vec<[[f64; 2]; 3]>,
    area: Vec<f64>,
    /// Where the faces' Newton blocks go in the last matrix assembled into.
    gather: GatherCache<3>,
}

/// Relative area below which a rest triangle has no usable frame.
const DEGENERATE_RELATIVE_AREA: f64 = 1e-12;

impl RestFrames {
    /// Rest frames from the rest positions of `mesh`: each triangle laid out in an
    /// orthonormal frame of its own plane (first axis along `x1 − x0`).
    pub fn from_rest_mesh(mesh: &TriMesh) -> Result<Self, SimError> {
        let n = mesh.vertex_count();
        let mut dms = Vec::with_capacity(mesh.faces.len());
        for (fi, f) in mesh.faces.iter().enumerate() {
            for &v in f {
                check_vertex("face", fi, v, n)?;
            }
            let [p0, p1, p2] = f.map(|i| mesh.positions[i as usize]);
            if !(finite3(p0) && finite3(p1) && finite3(p2)) {
                return Err(SimError::InvalidVector {
                    what: format!("face {fi} rest positions"),
                    message: "not finite",
                });
            }
            let (e1, e2) = (v3(p1) - v3(p0), v3(p2) - v3(p0));
            let l1 = e1.norm();
            let normal = e1.cross(&e2);
            let scale = e1.norm_squared().max(e2.norm_squared());
            if l1 == 0.0 || normal.norm() <= 2.0 * DEGENERATE_RELATIVE_AREA * scale {
                return Err(SimError::DegenerateTriangle {
                    face: fi,
                    area: 0.5 * normal.norm(),
                });
            }
            let t = e1 / l1;
            let b = normal.cross(&e1).normalize();
            dms.push([[l1, e2.dot(&t)], [0.0, e2.dot(&b)]]);
        }
        Self::from_edge_matrices(n, mesh.faces.clone(), &dms)
    }

    /// Rest frames from per-corner UV coordinates (`uvs[f][c]` for corner `c` of face
    /// `f`), which allows seams. The UVs must be the flat pattern in metres: they define
    /// rest lengths and rest areas.
    pub fn from_corner_uvs(
        vertex_count: usize,
        faces: Vec<[u32; 3]>,
        uvs: &[[[f64; 2]; 3]],
    ) -> Result<Self, SimError> {
        check_count("uv", "face", faces.len(), uvs.len())?;
        let mut dms = Vec::with_capacity(faces.len());
        for (fi, (f, uv)) in faces.iter().zip(uvs).enumerate() {
            for &v in f {
                check_vertex("face", fi, v, vertex_count)?;
            }
            if uv.iter().flatten().any(|c| !c.is_finite()) {
                return Err(SimError::InvalidVector {
                    what: format!("face {fi} uv"),
                    message: "not finite",
                });
            }
            let d1 = [uv[1][0] - uv[0][0], uv[1][1] - uv[0][1]];
            let d2 = [uv[2][0] - uv[0][0], uv[2][1] - uv[0][1]];
            // Columns are the UV edges (seed 000 supplement eq. 8).
            dms.push([[d1[0], d2[0]], [d1[1], d2[1]]]);
        }
        Self::from_edge_matrices(vertex_count, faces, &dms)
    }

    /// Rest frames from per-vertex UV coordinates (no seams).
    pub fn from_vertex_uvs(
        vertex_count: usize,
        faces: Vec<[u32; 3]>,
        uv: &[[f64; 2]],
    ) -> Result<Self, SimError> {
        check_len("uv", vertex_count, uv.len())?;
        let mut corner = Vec::with_capacity(faces.len());
        for (fi, f) in faces.iter().enumerate() {
            for &v in f {
                check_vertex("face", fi, v, vertex_count)?;
            }
            corner.push(f.map(|v| uv[v as usize]));
        }
        Self::from_corner_uvs(vertex_count, faces, &corner)
    }

    /// From 2×2 rest edge matrices `D_m` (row-major, columns are the rest edges).
    fn from_edge_matrices(
        vertex_count: usize,
        faces: Vec<[u32; 3]>,
        dms: &[[[f64; 2]; 2]],
    ) -> Result<Self, SimError> {
        let mut g = Vec::with_capacity(faces.len());
        let mut area = Vec::with_capacity(faces.len());
        for (fi, dm) in dms.iter().enumerate() {
            let det = dm[0][0] * dm[1][1] - dm[0][1] * dm[1][0];
            let scale =
                (dm[0][0].powi(2) + dm[1][0].powi(2)).max(dm[0][1].powi(2) + dm[1][1].powi(2));
            if !det.is_finite()
                || det.abs() <= 2.0 * DEGENERATE_RELATIVE_AREA * scale
                || scale == 0.0
            {
                return Err(SimError::DegenerateTriangle {
                    face: fi,
                    area: 0.5 * det.abs(),
                });
            }
            // D_m⁻¹ = [[d, −b], [−c, a]] / det.
            let inv = [
                [dm[1][1] / det, -dm[0][1] / det],
                [-dm[1][0] / det, dm[0][0] / det],
            ];
            let g1 = inv[0];
            let g2 = inv[1];
            g.push([[-g1[0] - g2[0], -g1[1] - g2[1]], g1, g2]);
            area.push(0.5 * det.abs());
        }
        Ok(RestFrames {
            vertex_count,
            faces,
            g,
            area,
            gather: GatherCache::default(),
        })
    }

    /// Number of vertices of the garment.
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// The faces.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Rest area of each face (m², or UV units² for UV frames).
    pub fn areas(&self) -> &[f64] {
        &self.area
    }

    /// The deformation gradient `F` (3×2) of face `f` at positions `x` (`f` and the
    /// length of `x` are checked by the callers).
    pub fn deformation_gradient(&self, f: usize, x: &[[f64; 3]]) -> Matrix3x2<f64> {
        let mut m = Matrix3x2::zeros();
        for (a, &v) in self.faces[f].iter().enumerate() {
            let p = v3(x[v as usize]);
            let g = self.g[f][a];
            m.column_mut(0).axpy(g[0], &p, 1.0);
            m.column_mut(1).axpy(g[1], &p, 1.0);
        }
        m
    }

    /// Adds `s · A_f · P g_a` to the gradient of the three vertices of face `f`.
    pub(crate) fn scatter_gradient(
        &self,
        f: usize,
        p: &Matrix3x2<f64>,
        s: f64,
        grad: &mut [[f64; 3]],
    ) {
        let w = s * self.area[f];
        for (a, &v) in self.faces[f].iter().enumerate() {
            let g = self.g[f][a];
            let d: Vector3<f64> = (p.column(0) * g[0] + p.column(1) * g[1]) * w;
            let out = &mut grad[v as usize];
            out[0] += d.x;
            out[1] += d.y;
            out[2] += d.z;
        }
    }

    /// The 9×9 vertex-space Hessian of face `f`, `A_f · Gᵀ K G`, from the F-space
    /// Hessian `K`.
    /// Face `f`'s rest-frame shape gradients `g_a` (`F = Σ_a x_a g_aᵀ`) and its rest area.
    pub(crate) fn shape(&self, f: usize) -> (&[[f64; 2]; 3], f64) {
        (&self.g[f], self.area[f])
    }

    pub(crate) fn element_hessian(&self, f: usize, k: &FHessian) -> SMatrix<f64, 9, 9> {
        let g = &self.g[f];
        let mut h = SMatrix::<f64, 9, 9>::zeros();
        for a in 0..3 {
            for b in 0..3 {
                for kk in 0..3 {
                    for l in 0..3 {
                        let mut acc = 0.0;
                        for j in 0..2 {
                            for m in 0..2 {
                                acc += k[(kk + 3 * j, l + 3 * m)] * g[a][j] * g[b][m];
                            }
                        }
                        h[(3 * a + kk, 3 * b + l)] = acc * self.area[f];
                    }
                }
            }
        }
        h
    }

    /// Checks that `x` has one position per vertex.
    pub(crate) fn check_positions(&self, x: &[[f64; 3]]) -> Result<(), SimError> {
        check_eval(self.vertex_count, x, Output::Value)
    }
}

/// An energy density `ψ(F)` per unit rest area of a face (parameters may vary by face).
pub(crate) trait MembraneDensity {
    /// `ψ` of face `f`.
    fn psi(&self, f: usize, fgrad: &Matrix3x2<f64>) -> f64;
    /// `ψ` and `P = ∂ψ/∂F`.
    fn psi_and_stress(&self, f: usize, fgrad: &Matrix3x2<f64>) -> (f64, Matrix3x2<f64>);
    /// `K = ∂²ψ/∂F²`.
    fn stiffness(&self, f: usize, fgrad: &Matrix3x2<f64>) -> FHessian;
    /// A PSD stand-in for `K` ([`HessianKind::Surrogate`]); by default `K` projected
    /// (6×6, cheaper than projecting the 9×9 vertex block: `K ⪰ 0` makes `GᵀKG ⪰ 0`).
    fn surrogate_stiffness(&self, f: usize, fgrad: &Matrix3x2<f64>) -> FHessian {
        project_psd6(&self.stiffness(f, fgrad))
    }
    /// Face `f`'s 9×9 block of the surrogate Newton matrix; by default `A GᵀK̃G` from
    /// [`MembraneDensity::surrogate_stiffness`]. A density with a closed form overrides
    /// it.
    fn surrogate_element(
        &self,
        frames: &RestFrames,
        f: usize,
        fgrad: &Matrix3x2<f64>,
    ) -> SMatrix<f64, 9, 9> {
        frames.element_hessian(f, &self.surrogate_stiffness(f, fgrad))
    }
}

/// `Σ_f A_f ψ_f(F_f)`.
pub(crate) fn membrane_value<D: MembraneDensity + Sync>(
    frames: &RestFrames,
    d: &D,
    x: &[[f64; 3]],
) -> Result<f64, SimError> {
    frames.check_positions(x)?;
    Ok((0..frames.faces.len())
        .into_par_iter()
        .with_min_len(256)
        .map(|f| frames.area[f] * d.psi(f, &frames.deformation_gradient(f, x)))
        .sum())
}

/// Adds `scale · ∇E` and returns `E`.
pub(crate) fn membrane_gradient<D: MembraneDensity + Sync>(
    frames: &RestFrames,
    d: &D,
    x: &[[f64; 3]],
    scale: f64,
    grad: &mut [[f64; 3]],
) -> Result<f64, SimError> {
    check_eval(frames.vertex_count, x, Output::Gradient(grad.len()))?;
    // Stresses in parallel, scatter serial (three adds per face).
    let stresses: Vec<(f64, Matrix3x2<f64>)> = (0..frames.faces.len())
        .into_par_iter()
        .with_min_len(256)
        .map(|f| d.psi_and_stress(f, &frames.deformation_gradient(f, x)))
        .collect();
    let mut e = 0.0;
    for (f, (psi, p)) in stresses.iter().enumerate() {
        e += frames.area[f] * psi;
        frames.scatter_gradient(f, p, scale, grad);
    }
    Ok(e)
}

/// Adds `scale · ∇²E` (exact or per-face projected) into `hess`.
pub(crate) fn membrane_hessian<D: MembraneDensity + Sync>(
    frames: &RestFrames,
    d: &D,
    x: &[[f64; 3]],
    scale: f64,
    kind: HessianKind,
    hess: &mut BlockCsr,
) -> Result<(), SimError> {
    check_eval(frames.vertex_count, x, Output::Hessian(hess.block_rows()))?;
    // Element matrices (and their eigen-projections, the bulk of the cost) in parallel,
    // then the parallel gather into the stored blocks.
    let blocks: Vec<SMatrix<f64, 9, 9>> = (0..frames.faces.len())
        .into_par_iter()
        .map(|f| {
            let fg = frames.deformation_gradient(f, x);
            match kind {
                HessianKind::Exact => frames.element_hessian(f, &d.stiffness(f, &fg)),
                HessianKind::Projected => {
                    project_psd9(&frames.element_hessian(f, &d.stiffness(f, &fg)))
                }
                HessianKind::Surrogate => d.surrogate_element(frames, f, &fg),
            }
        })
        .collect();
    let gather = frames
        .gather
        .get(hess, frames.faces.len(), |f| frames.faces[f])?;
    hess.add_gathered(&gather, scale, |f, a, b| {
        blocks[f].fixed_view::<3, 3>(3 * a, 3 * b).into_owned()
    })
}

/// Calls `f` with every face.
pub(crate) fn face_stencils(frames: &RestFrames, f: &mut dyn FnMut(&[u32])) {
    for face in &frames.faces {
        f(face);
    }
}

/// `impl Energy for $t` over its `frames: RestFrames` field and its [`MembraneDensity`]:
/// the one membrane energy impl, for StVK stretching and the UV stretch and shear losses.
macro_rules! membrane_energy {
    ($t:ty, $name:literal) => {
        impl $crate::energy::Energy for $t {
            fn name(&self) -> &'static str {
                $name
            }
            fn vertex_count(&self) -> usize {
                self.frames.vertex_count()
            }
            fn value(&self, x: &[[f64; 3]]) -> Result<f64, $crate::error::SimError> {
                $crate::membrane::membrane_value(&self.frames, self, x)
            }
            fn add_gradient(
                &self,
                x: &[[f64; 3]],
                scale: f64,
                grad: &mut [[f64; 3]],
            ) -> Result<f64, $crate::error::SimError> {
                $crate::membrane::membrane_gradient(&self.frames, self, x, scale, grad)
            }
            fn add_hessian(
                &self,
                x: &[[f64; 3]],
                scale: f64,
                kind: $crate::energy::HessianKind,
                hess: &mut $crate::sparse::BlockCsr,
            ) -> Result<(), $crate::error::SimError> {
                $crate::membrane::membrane_hessian(&self.frames, self, x, scale, kind, hess)
            }
            fn for_each_stencil(
                &self,
                _kind: $crate::energy::HessianKind,
                f: &mut dyn FnMut(&[u32]),
            ) {
                $crate::membrane::face_stencils(&self.frames, f)
            }
        }
    };
}
pub(crate) use membrane_energy;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rest_frame_gives_identity_metric_at_rest() {
        let mesh = TriMesh::new(
            vec![[0.1, 0.2, 0.3], [1.3, 0.1, -0.2], [0.4, 0.9, 0.8]],
            vec![[0, 1, 2]],
        );
        let fr = RestFrames::from_rest_mesh(&mesh).unwrap();
        let f = fr.deformation_gradient(0, &mesh.positions);
        let c = f.transpose() * f;
        assert!((c - nalgebra::Matrix2::identity()).norm() < 1e-12, "{c}");
        assert!((fr.areas()[0] - mesh.face_areas()[0]).abs() < 1e-14);
    }

    #[test]
    fn uv_frame_columns_are_the_uv_derivatives() {
        // A flat triangle whose UVs are its XZ coordinates scaled by 1/2: W^u = (2,0,0).
        let x = vec![[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]];
        let uv = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let fr = RestFrames::from_vertex_uvs(3, vec![[0, 1, 2]], &uv).unwrap();
        let f = fr.deformation_gradient(0, &x);
        assert!((f.column(0) - Vector3::new(2.0, 0.0, 0.0)).norm() < 1e-15);
        assert!((f.column(1) - Vector3::new(0.0, 0.0, 2.0)).norm() < 1e-15);
        assert_eq!(fr.areas()[0], 0.5);
    }

    #[test]
    fn degenerate_and_bad_input_are_errors() {
        let line = TriMesh::new(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            vec![[0, 1, 2]],
        );
        assert!(matches!(
            RestFrames::from_rest_mesh(&line),
            Err(SimError::DegenerateTriangle { face: 0, .. })
        ));
        let oob = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0]], vec![[0, 1, 2]]);
        assert!(matches!(
            RestFrames::from_rest_mesh(&oob),
            Err(SimError::VertexOutOfRange { vertex: 2, .. })
        ));
        let nan = TriMesh::new(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, f64::NAN, 1.0]],
            vec![[0, 1, 2]],
        );
        assert!(RestFrames::from_rest_mesh(&nan).is_err());
        assert!(RestFrames::from_vertex_uvs(
            3,
            vec![[0, 1, 2]],
            &[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]
        )
        .is_err());
        assert!(RestFrames::from_vertex_uvs(3, vec![[0, 1, 2]], &[[0.0, 0.0]]).is_err());
    }
}
