//! Per-face cone volume about a bone-tied apex: the volume term of the elastic skin.
//!
//! Each face `f = (a, b, c)` spans, with an apex `p_f` inside the limb, the tetrahedron
//! `V_f = (a − p)·((b − p) × (c − p)) / 6`; `E = Σ_f ½ κ_f (V_f − V̄_f)²` keeps each at its
//! rest value. Summed over a ring of faces around a joint this is the volume of the limb
//! section, so collapsing the inside of a bent elbow (skin moving towards the joint
//! centre while its area shrinks) costs energy, and the skin bulges instead. Unlike one
//! `(V − V̄)²` per closed component its Hessian is local (9×9 per face, no dense rank-one
//! coupling of a whole component), so it fits the block-sparse Newton solver, and it is
//! defined for open garment panels as well as closed bodies. The apexes are data, set per
//! pose by the owner; they do not depend on the positions.
//!
//! Derivatives: `∇_a V = (v × w)/6`, `∇_b V = (w × u)/6`, `∇_c V = (u × v)/6` with
//! `u, v, w = a − p, b − p, c − p`; the second derivatives are skew blocks,
//! `∂²V/∂a∂b = −[w]×/6`, `∂²V/∂b∂c = −[u]×/6`, `∂²V/∂c∂a = −[v]×/6` (and their
//! transposes), zero on the diagonal. `∇²E = κ(∇V∇Vᵀ + (V − V̄)∇²V)`; the surrogate keeps
//! the Gauss–Newton part `κ∇V∇Vᵀ`.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use rayon::prelude::*;

use crate::energy::{Energy, HessianKind};
use crate::error::{check_count, check_eval, check_nonneg, check_vertex, Output, SimError};
use crate::math::{finite3, project_psd9, skew, v3};
use crate::sparse::{BlockCsr, GatherCache};

/// Per-face cone volumes about apexes, held at their rest values.
#[derive(Clone, Debug)]
pub struct ConeVolume {
    vertex_count: usize,
    faces: Vec<[u32; 3]>,
    /// `κ_f` (N/m⁴ for an energy in J).
    stiffness: Vec<f64>,
    rest_volume: Vec<f64>,
    apex: Vec<[f64; 3]>,
    /// Where the faces' Newton blocks go in the last matrix assembled into.
    gather: GatherCache<3>,
}

/// `(V, ∇V)` of a face with corners `x` about `p`.
fn cone(x: [Vector3<f64>; 3], p: Vector3<f64>) -> (f64, [Vector3<f64>; 3]) {
    let [u, v, w] = x.map(|q| q - p);
    let g = [v.cross(&w) / 6.0, w.cross(&u) / 6.0, u.cross(&v) / 6.0];
    (u.dot(&g[0]), g)
}

impl ConeVolume {
    /// Faces of a mesh at rest positions `rest`, with one stiffness `κ_f >= 0` and one
    /// apex each; the rest volumes are the cone volumes there.
    pub fn new(
        rest: &[[f64; 3]],
        faces: Vec<[u32; 3]>,
        stiffness: Vec<f64>,
        apex: Vec<[f64; 3]>,
    ) -> Result<Self, SimError> {
        check_count("volume stiffness", "face", faces.len(), stiffness.len())?;
        for (fi, f) in faces.iter().enumerate() {
            for &v in f {
                check_vertex("face", fi, v, rest.len())?;
            }
            check_nonneg(
                || format!("face {fi} volume stiffness"),
                stiffness[fi],
                false,
            )?;
        }
        if let Some(v) = rest.iter().position(|p| !finite3(*p)) {
            return Err(SimError::InvalidVector {
                what: format!("rest position of vertex {v}"),
                message: "not finite",
            });
        }
        let mut e = ConeVolume {
            vertex_count: rest.len(),
            rest_volume: vec![0.0; faces.len()],
            faces,
            stiffness,
            apex: Vec::new(),
            gather: GatherCache::default(),
        };
        e.set_apexes(apex)?;
        e.rest_volume = e.volumes(rest)?;
        Ok(e)
    }

    /// Replaces the apexes (one per face; each pose).
    pub fn set_apexes(&mut self, apex: Vec<[f64; 3]>) -> Result<(), SimError> {
        check_count("apex", "face", self.faces.len(), apex.len())?;
        if let Some(f) = apex.iter().position(|p| !finite3(*p)) {
            return Err(SimError::InvalidVector {
                what: format!("apex of face {f}"),
                message: "not finite",
            });
        }
        self.apex = apex;
        Ok(())
    }

    /// The cone volume of each face at `x`, m³.
    pub fn volumes(&self, x: &[[f64; 3]]) -> Result<Vec<f64>, SimError> {
        check_eval(self.vertex_count, x, Output::Value)?;
        Ok((0..self.faces.len()).map(|f| self.face(f, x).0).collect())
    }

    fn face(&self, f: usize, x: &[[f64; 3]]) -> (f64, [Vector3<f64>; 3]) {
        cone(self.faces[f].map(|v| v3(x[v as usize])), v3(self.apex[f]))
    }

    /// The 9×9 Hessian of face `f` of the given kind.
    fn face_hessian(&self, f: usize, x: &[[f64; 3]], kind: HessianKind) -> SMatrix<f64, 9, 9> {
        let k = self.stiffness[f];
        let (vol, g) = self.face(f, x);
        let gv = SVector::<f64, 9>::from_iterator(g.iter().flat_map(|c| c.iter().copied()));
        let mut h = gv * gv.transpose() * k;
        if kind == HessianKind::Surrogate {
            return h;
        }
        let [u, v, w] = self.faces[f].map(|i| v3(x[i as usize]) - v3(self.apex[f]));
        let r = k * (vol - self.rest_volume[f]) / 6.0;
        // (a, b, −[w]×), (b, c, −[u]×), (c, a, −[v]×), each with its transpose.
        for (a, b, s) in [(0, 1, skew(&w)), (1, 2, skew(&u)), (2, 0, skew(&v))] {
            let m: Matrix3<f64> = -s * r;
            let mut blk = h.fixed_view_mut::<3, 3>(3 * a, 3 * b);
            blk += m;
            let mut blk = h.fixed_view_mut::<3, 3>(3 * b, 3 * a);
            blk += m.transpose();
        }
        match kind {
            HessianKind::Projected => project_psd9(&h),
            _ => h,
        }
    }
}

impl Energy for ConeVolume {
    fn name(&self) -> &'static str {
        "cone volume"
    }
    fn vertex_count(&self) -> usize {
        self.vertex_count
    }
    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Value)?;
        Ok((0..self.faces.len())
            .into_par_iter()
            .with_min_len(512)
            .map(|f| 0.5 * self.stiffness[f] * (self.face(f, x).0 - self.rest_volume[f]).powi(2))
            .sum())
    }
    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Gradient(grad.len()))?;
        let mut e = 0.0;
        for (f, face) in self.faces.iter().enumerate() {
            let (vol, g) = self.face(f, x);
            let d = vol - self.rest_volume[f];
            e += 0.5 * self.stiffness[f] * d * d;
            let s = scale * self.stiffness[f] * d;
            for (gc, &v) in g.iter().zip(face) {
                let out = &mut grad[v as usize];
                for k in 0..3 {
                    out[k] += s * gc[k];
                }
            }
        }
        Ok(e)
    }
    fn add_hessian(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        kind: HessianKind,
        hess: &mut BlockCsr,
    ) -> Result<(), SimError> {
        check_eval(self.vertex_count, x, Output::Hessian(hess.block_rows()))?;
        let blocks: Vec<_> = (0..self.faces.len())
            .into_par_iter()
            .with_min_len(256)
            .map(|f| self.face_hessian(f, x, kind))
            .collect();
        let gather = self.gather.get(hess, self.faces.len(), |f| self.faces[f])?;
        hess.add_gathered(&gather, scale, |f, a, b| {
            blocks[f].fixed_view::<3, 3>(3 * a, 3 * b).into_owned()
        })
    }
    fn for_each_stencil(&self, _kind: HessianKind, f: &mut dyn FnMut(&[u32])) {
        for face in &self.faces {
            f(face);
        }
    }
}

/// `Σ_f V_f` of `faces` about one point `center`: for the ring of faces round a joint,
/// the volume of that limb section (what LBS loses at a bent elbow), m³.
pub fn cone_volume_sum(positions: &[[f64; 3]], faces: &[[u32; 3]], center: [f64; 3]) -> f64 {
    faces
        .iter()
        .map(|f| cone(f.map(|v| v3(positions[v as usize])), v3(center)).0)
        .sum()
}
