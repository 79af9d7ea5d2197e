//! Dihedral-angle bending (discrete shells, Grinspun et al. 2003; `L_bending` of seed 004
//! eq. 5, which cites them as [19]).
//!
//! Per hinge (an interior edge with its two faces, [`weft_mesh::Hinge`]):
//! `E_e = k_e · w_e · (θ_e − θ̄_e)²` with the signed dihedral angle `θ_e` (zero when the
//! two faces are coplanar), a rest angle `θ̄_e`, a per-edge stiffness `k_e`
//! (heterogeneous garments) and a constant weight `w_e` from the rest shape:
//!
//! * [`BendingScale::Hood`] (default): `w = |ē|² / (8 (Ā₁ + Ā₂))`. This is HOOD's
//!   implementation (their `bending_energy.py`, from SNUG eq. 10:
//!   `k · |e|²/(4(A₁+A₂)) · θ²/2`) so HOOD's `k_bending` values mean the same here. HOOD
//!   takes `|e|` at the current state; we take the rest length, which changes the energy
//!   only at second order in the (small) stretch and keeps the Hessian short.
//! * [`BendingScale::DiscreteShells`]: `w = 3|ē|² / (Ā₁ + Ā₂)`, Grinspun et al.'s
//!   `|ē| / h̄_e` with `h̄_e` a third of the average triangle height.
//!
//! HOOD bends towards a flat rest (`θ̄ = 0`, [`RestAngle::Flat`], the default: garments are
//! sewn from flat panels); [`RestAngle::FromRest`] keeps the rest mesh's angles.
//!
//! The angle and its derivatives: with the hinge laid out as `x0 → x1` (the edge, in the
//! winding of the first face), `x2` opposite in the first face and `x3` in the second,
//! `e = x1 − x0`, `n₀ = e × (x2 − x0)`, `n₁ = (x3 − x0) × e`,
//! `θ = atan2((n₀ × n₁)·ê, n₀·n₁)`. The gradient is the classic one (Bridson et al. 2003,
//! "Simulation of clothing with folds and wrinkles", the `u₁..u₄` vectors):
//! `∇₂θ = −|e| n₀/|n₀|²`, `∇₃θ = −|e| n₁/|n₁|²`, and the edge vertices get the
//! combinations that make the four sum to zero. The exact Hessian of `θ` is obtained by
//! differentiating these four vectors (each is a scalar times `n/|n|²`, and
//! `d(n/|n|²) = (I − 2n̂n̂ᵀ) dn / |n|²`), then
//! `∇²E = 2kw(∇θ∇θᵀ + (θ − θ̄)∇²θ)`, indefinite away from the rest angle;
//! [`HessianKind::Projected`] clamps each hinge's 12×12 block. [`HessianKind::Surrogate`]
//! (Newton's default) is the Gauss–Newton part `2kw∇θ∇θᵀ` bounded above by a sum over
//! the hinge's two triangles, so it needs no block between the two wing vertices.
//!
//! A hinge whose current triangles are degenerate (no normal) contributes nothing until
//! they open again; a hinge folded through ±π is measured with the difference
//! `θ − θ̄` wrapped into (−π, π] so the energy stays continuous there.

use std::sync::Arc;

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use rayon::prelude::*;
use weft_mesh::{Hinge, Topology, TriMesh};

use crate::energy::{Energy, HessianKind};
use crate::error::{check_count, check_eval, check_nonneg, check_vertex, Output, SimError};
use crate::math::{axpy3, project_psd12, skew, v3};
use crate::sparse::{BlockCsr, GatherCache};

/// How the per-hinge weight `w_e` is computed from the rest shape (in TOML: `hood`,
/// `discrete_shells`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BendingScale {
    /// `|ē|² / (8(Ā₁ + Ā₂))`, HOOD's (and SNUG's) scaling.
    #[default]
    Hood,
    /// `3|ē|² / (Ā₁ + Ā₂)`, Grinspun et al. 2003.
    DiscreteShells,
}

/// The rest angle of each hinge (in TOML: `flat`, `from_rest`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RestAngle {
    /// `θ̄ = 0`: bending towards flat (HOOD).
    #[default]
    Flat,
    /// `θ̄` = the dihedral angle of the rest mesh.
    FromRest,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct HingeData {
    /// `[x0, x1, x2, x3]`: edge in the first face's winding, then the opposite vertices.
    verts: [u32; 4],
    /// `k_e · w_e`.
    coefficient: f64,
    rest_angle: f64,
}

/// Dihedral-angle bending energy of a garment. The hinges are shared (`Arc`), so a clone
/// is cheap: a [`crate::ClothModel`] hands one to every step's potential.
#[derive(Clone, Debug)]
pub struct Bending {
    vertex_count: usize,
    hinges: Arc<[HingeData]>,
    /// Where the hinges' blocks go in the last matrix assembled into, shared by the
    /// clones that every step's potential holds: whole hinges (exact and projected
    /// Hessians) and their two wings (the surrogate).
    gather: Arc<GatherCache<4>>,
    wings_gather: Arc<GatherCache<3>>,
}

type V12 = SVector<f64, 12>;
type M12 = SMatrix<f64, 12, 12>;
type J = SMatrix<f64, 3, 12>;

/// Orders a hinge's vertices as `[x0, x1, x2, x3]` with `x0 → x1` in the winding of the
/// first face.
fn hinge_vertices(mesh: &TriMesh, h: &Hinge) -> [u32; 4] {
    let f0 = mesh.faces[h.faces[0] as usize];
    let [a, b] = h.edge;
    let forward = (0..3).any(|k| f0[k] == a && f0[(k + 1) % 3] == b);
    if forward {
        [a, b, h.opposite[0], h.opposite[1]]
    } else {
        [b, a, h.opposite[0], h.opposite[1]]
    }
}

impl Bending {
    /// Bending over `hinges` (from [`Topology::hinges`] of `rest`) with one stiffness
    /// `k_e >= 0` per hinge (N·m).
    pub fn new(
        rest: &TriMesh,
        hinges: &[Hinge],
        stiffness: &[f64],
        scale: BendingScale,
        rest_angle: RestAngle,
    ) -> Result<Self, SimError> {
        check_count("bending stiffness", "hinge", hinges.len(), stiffness.len())?;
        let n = rest.vertex_count();
        let areas = rest.face_areas();
        let mut out = Vec::with_capacity(hinges.len());
        for (i, (h, &k)) in hinges.iter().zip(stiffness).enumerate() {
            check_nonneg(|| format!("hinge {i} bending stiffness"), k, false)?;
            for v in h.edge.iter().chain(&h.opposite) {
                check_vertex("hinge", i, *v, n)?;
            }
            for &f in &h.faces {
                if f as usize >= rest.faces.len() {
                    return Err(SimError::InvalidParameter {
                        what: format!("hinge {i} face"),
                        value: f as f64,
                        expected: "expected a face index below the face count",
                    });
                }
            }
            let verts = hinge_vertices(rest, h);
            let p = verts.map(|v| v3(rest.positions[v as usize]));
            let l2 = (p[1] - p[0]).norm_squared();
            let a = areas[h.faces[0] as usize] + areas[h.faces[1] as usize];
            if !(a > 0.0 && a.is_finite() && l2.is_finite()) {
                return Err(SimError::DegenerateTriangle {
                    face: h.faces[0] as usize,
                    area: a,
                });
            }
            let w = match scale {
                BendingScale::Hood => l2 / (8.0 * a),
                BendingScale::DiscreteShells => 3.0 * l2 / a,
            };
            let theta_bar = match rest_angle {
                RestAngle::Flat => 0.0,
                RestAngle::FromRest => dihedral(&p).unwrap_or(0.0),
            };
            out.push(HingeData {
                verts,
                coefficient: k * w,
                rest_angle: theta_bar,
            });
        }
        Ok(Bending {
            vertex_count: n,
            hinges: out.into(),
            gather: Arc::default(),
            wings_gather: Arc::default(),
        })
    }

    /// The same stiffness on every hinge of `rest`.
    pub fn uniform(
        rest: &TriMesh,
        stiffness: f64,
        scale: BendingScale,
        rest_angle: RestAngle,
    ) -> Result<Self, SimError> {
        for (fi, f) in rest.faces.iter().enumerate() {
            for &v in f {
                check_vertex("face", fi, v, rest.vertex_count())?;
            }
        }
        let hinges = Topology::new(rest).hinges(rest);
        let k = vec![stiffness; hinges.len()];
        Self::new(rest, &hinges, &k, scale, rest_angle)
    }

    /// Number of hinges.
    pub fn hinge_count(&self) -> usize {
        self.hinges.len()
    }

    /// The signed dihedral angle of every hinge at `x` (0 for a degenerate hinge).
    pub fn dihedral_angles(&self, x: &[[f64; 3]]) -> Result<Vec<f64>, SimError> {
        check_eval(self.vertex_count, x, Output::Value)?;
        Ok(self
            .hinges
            .iter()
            .map(|h| dihedral(&h.verts.map(|v| v3(x[v as usize]))).unwrap_or(0.0))
            .collect())
    }
}

/// `θ − θ̄` wrapped into (−π, π].
fn wrapped(theta: f64, rest: f64) -> f64 {
    let mut d = theta - rest;
    let tau = std::f64::consts::TAU;
    if d > std::f64::consts::PI {
        d -= tau;
    } else if d <= -std::f64::consts::PI {
        d += tau;
    }
    d
}

/// Normals, edge and their squared lengths, `None` when degenerate.
struct Geometry {
    e: Vector3<f64>,
    f: Vector3<f64>,
    q: Vector3<f64>,
    n0: Vector3<f64>,
    n1: Vector3<f64>,
    l: f64,
    a0: f64,
    a1: f64,
}

impl Geometry {
    /// The signed dihedral angle. Computed on demand: Newton's surrogate matrix needs
    /// only `∇θ`, and `atan2` was 5 % of a simulated frame.
    fn theta(&self) -> f64 {
        (self.n0.cross(&self.n1).dot(&self.e) / self.l).atan2(self.n0.dot(&self.n1))
    }
}

fn geometry(p: &[Vector3<f64>; 4]) -> Option<Geometry> {
    let e = p[1] - p[0];
    let f = p[2] - p[0];
    let q = p[3] - p[0];
    let n0 = e.cross(&f);
    let n1 = q.cross(&e);
    let l2 = e.norm_squared();
    let (a0, a1) = (n0.norm_squared(), n1.norm_squared());
    let tiny = 1e-24 * l2 * l2;
    if !(l2 > 0.0 && a0 > tiny && a1 > tiny && l2.is_finite() && a0.is_finite() && a1.is_finite()) {
        return None;
    }
    let l = l2.sqrt();
    Some(Geometry {
        e,
        f,
        q,
        n0,
        n1,
        l,
        a0,
        a1,
    })
}

/// The signed dihedral angle of `[x0, x1, x2, x3]`.
fn dihedral(p: &[Vector3<f64>; 4]) -> Option<f64> {
    geometry(p).map(|g| g.theta())
}

/// The edge-vertex coefficients `c00, c01, c10, c11`.
fn coefficients(g: &Geometry, p: &[Vector3<f64>; 4]) -> [f64; 4] {
    let e = &g.e;
    [
        (p[2] - p[1]).dot(e) / g.l,
        (p[3] - p[1]).dot(e) / g.l,
        -g.f.dot(e) / g.l,
        -g.q.dot(e) / g.l,
    ]
}

/// `∇θ` (12-vector).
fn angle_gradient(g: &Geometry, p: &[Vector3<f64>; 4]) -> V12 {
    let m0 = g.n0 / g.a0;
    let m1 = g.n1 / g.a1;
    let [c00, c01, c10, c11] = coefficients(g, p);
    let blocks = [
        -(m0 * c00 + m1 * c01),
        -(m0 * c10 + m1 * c11),
        -(m0 * g.l),
        -(m1 * g.l),
    ];
    let mut out = V12::zeros();
    for (a, b) in blocks.iter().enumerate() {
        out.fixed_rows_mut::<3>(3 * a).copy_from(b);
    }
    out
}

/// The 3×12 selector of vertex `a`.
fn sel(a: usize) -> J {
    let mut s = J::zeros();
    s.fixed_view_mut::<3, 3>(0, 3 * a)
        .copy_from(&Matrix3::identity());
    s
}

/// `∇²θ` (12×12, symmetric).
fn angle_hessian(g: &Geometry, p: &[Vector3<f64>; 4]) -> M12 {
    let s = [sel(0), sel(1), sel(2), sel(3)];
    let je = s[1] - s[0];
    let jf = s[2] - s[0];
    let jq = s[3] - s[0];
    let jn0 = -skew(&g.f) * je + skew(&g.e) * jf;
    let jn1 = -skew(&g.e) * jq + skew(&g.q) * je;
    let m0 = g.n0 / g.a0;
    let m1 = g.n1 / g.a1;
    let jm0 = (Matrix3::identity() - g.n0 * g.n0.transpose() * (2.0 / g.a0)) * jn0 / g.a0;
    let jm1 = (Matrix3::identity() - g.n1 * g.n1.transpose() * (2.0 / g.a1)) * jn1 / g.a1;
    let ehat = g.e / g.l;
    let jl = ehat.transpose() * je; // 1×12
                                    // c = (d·e)/l for a difference vector d with Jacobian jd.
    let jc = |d: Vector3<f64>, jd: &J| {
        (g.e.transpose() * jd + d.transpose() * je) / g.l - jl * (d.dot(&g.e) / (g.l * g.l))
    };
    let [c00, c01, c10, c11] = coefficients(g, p);
    let jc00 = jc(p[2] - p[1], &(s[2] - s[1]));
    let jc01 = jc(p[3] - p[1], &(s[3] - s[1]));
    let jc10 = -jc(g.f, &jf);
    let jc11 = -jc(g.q, &jq);
    let rows: [J; 4] = [
        -(m0 * jc00 + jm0 * c00 + m1 * jc01 + jm1 * c01),
        -(m0 * jc10 + jm0 * c10 + m1 * jc11 + jm1 * c11),
        -(m0 * jl + jm0 * g.l),
        -(m1 * jl + jm1 * g.l),
    ];
    let mut h = M12::zeros();
    for (a, r) in rows.iter().enumerate() {
        h.fixed_view_mut::<3, 12>(3 * a, 0).copy_from(r);
    }
    (h + h.transpose()) * 0.5
}

impl Bending {
    fn local(&self, h: &HingeData, x: &[[f64; 3]]) -> [Vector3<f64>; 4] {
        h.verts.map(|v| v3(x[v as usize]))
    }
}

impl Energy for Bending {
    fn name(&self) -> &'static str {
        "bending"
    }

    fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    fn value(&self, x: &[[f64; 3]]) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Value)?;
        Ok(self
            .hinges
            .par_iter()
            .with_min_len(256)
            .filter_map(|h| {
                let g = geometry(&self.local(h, x))?;
                Some(h.coefficient * wrapped(g.theta(), h.rest_angle).powi(2))
            })
            .sum())
    }

    fn add_gradient(
        &self,
        x: &[[f64; 3]],
        scale: f64,
        grad: &mut [[f64; 3]],
    ) -> Result<f64, SimError> {
        check_eval(self.vertex_count, x, Output::Gradient(grad.len()))?;
        // Hinge gradients in parallel, scatter serial.
        let per_hinge: Vec<Option<(f64, V12)>> = self
            .hinges
            .par_iter()
            .with_min_len(256)
            .map(|h| {
                let p = self.local(h, x);
                let g = geometry(&p)?;
                let d = wrapped(g.theta(), h.rest_angle);
                let gt = angle_gradient(&g, &p) * (2.0 * h.coefficient * d * scale);
                Some((h.coefficient * d * d, gt))
            })
            .collect();
        let mut e = 0.0;
        for (h, r) in self.hinges.iter().zip(per_hinge) {
            let Some((eh, gt)) = r else { continue };
            e += eh;
            for (a, &v) in h.verts.iter().enumerate() {
                axpy3(
                    &mut grad[v as usize],
                    1.0,
                    std::array::from_fn(|k| gt[3 * a + k]),
                );
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
        // Hinge blocks in parallel, then the parallel gather into the stored blocks. A
        // degenerate hinge (no dihedral angle) adds nothing.
        if kind == HessianKind::Surrogate {
            // Gauss–Newton `uuᵀ`, `u = √(2kw) ∇θ`, bounded above by `2(vvᵀ + wwᵀ)` with
            // `u = v + w`, `v` on (x0/2, x1/2, x2) and `w` on (x0/2, x1/2, x3): PSD, and
            // it couples no wing vertex with the other, so the matrix keeps the faces'
            // pattern (7 blocks per row of a regular mesh instead of 13; each PCG product
            // reads half the blocks). Kept as 12 numbers per hinge.
            let gather = self.wings_gather.get(hess, 2 * self.hinges.len(), |i| {
                let v = self.hinges[i / 2].verts;
                [v[0], v[1], v[2 + i % 2]]
            })?;
            let u: Vec<V12> = self
                .hinges
                .par_iter()
                .map(|h| {
                    let p = self.local(h, x);
                    geometry(&p).map_or(V12::zeros(), |g| {
                        angle_gradient(&g, &p) * (2.0 * h.coefficient).sqrt()
                    })
                })
                .collect();
            // Wing `i` of hinge `i / 2`: its own vertex in full, the edge's halves.
            let part = |i: usize, a: usize| -> Vector3<f64> {
                let u = &u[i / 2];
                if a < 2 {
                    u.fixed_rows::<3>(3 * a) * 0.5
                } else {
                    u.fixed_rows::<3>(3 * (2 + i % 2)).into_owned()
                }
            };
            return hess.add_gathered(&gather, 2.0 * scale, |i, a, b| {
                part(i, a) * part(i, b).transpose()
            });
        }
        let gather = self
            .gather
            .get(hess, self.hinges.len(), |i| self.hinges[i].verts)?;
        let m: Vec<M12> = self
            .hinges
            .par_iter()
            .map(|h| {
                let p = self.local(h, x);
                let Some(g) = geometry(&p) else {
                    return M12::zeros();
                };
                let d = wrapped(g.theta(), h.rest_angle);
                let gt = angle_gradient(&g, &p);
                let m = (gt * gt.transpose() + angle_hessian(&g, &p) * d) * (2.0 * h.coefficient);
                if kind == HessianKind::Projected {
                    project_psd12(&m)
                } else {
                    m
                }
            })
            .collect();
        hess.add_gathered(&gather, scale, |i, a, b| {
            m[i].fixed_view::<3, 3>(3 * a, 3 * b).into_owned()
        })
    }

    fn for_each_stencil(&self, kind: HessianKind, f: &mut dyn FnMut(&[u32])) {
        for h in self.hinges.iter() {
            let v = h.verts;
            if kind == HessianKind::Surrogate {
                // The two wings (see `add_hessian`).
                f(&[v[0], v[1], v[2]]);
                f(&[v[0], v[1], v[3]]);
            } else {
                f(&v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angle_sign_and_magnitude() {
        // Flat hinge, then fold x2 up by 90°.
        let p = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.0, -1.0, 0.0),
        ];
        assert!(dihedral(&p).unwrap().abs() < 1e-15);
        let mut up = p;
        up[2] = Vector3::new(0.0, 0.0, 1.0);
        assert!((dihedral(&up).unwrap().abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // Folding either wing the same way gives the same sign.
        let mut down = p;
        down[3] = Vector3::new(0.0, 0.0, 1.0);
        assert_eq!(
            dihedral(&up).unwrap().signum(),
            dihedral(&down).unwrap().signum()
        );
        let mut degenerate = p;
        degenerate[2] = Vector3::new(0.5, 0.0, 0.0);
        assert!(dihedral(&degenerate).is_none());
    }

    #[test]
    fn wrap_keeps_difference_in_range() {
        assert!((wrapped(3.0, -3.0) - (6.0 - std::f64::consts::TAU)).abs() < 1e-15);
        assert!((wrapped(-3.0, 3.0) + (6.0 - std::f64::consts::TAU)).abs() < 1e-15);
        assert_eq!(wrapped(0.5, 0.25), 0.25);
    }
}
