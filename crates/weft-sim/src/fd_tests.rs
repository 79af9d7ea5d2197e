//! Every energy against central finite differences on random small configurations:
//! gradients against differences of the value, Hessians against differences of the
//! gradient, symmetry, and positive semi-definiteness of the projected Hessians.
//!
//! Tolerances (relative to the largest entry of the reference, step `h = 10⁻⁶ m`):
//! gradients 10⁻⁶, Hessians 10⁻⁵. Central differences have error `O(h²)` plus rounding
//! `O(ε_mach · |E| / h)`, about 10⁻¹⁰ relative here, so these bounds have room for
//! ill-conditioned random samples but catch any wrong term.

use nalgebra::DMatrix;
use proptest::prelude::*;
use weft_mesh::primitives::grid;
use weft_mesh::rng::SplitMix64;
use weft_mesh::{Topology, TriMesh};

use crate::*;

const H: f64 = 1e-6;
const GRAD_RTOL: f64 = 1e-6;
const HESS_RTOL: f64 = 1e-5;

/// Test-data draws over weft-mesh's SplitMix64, so each proptest case is one `u64`.
struct Rng(SplitMix64);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(SplitMix64::new(seed))
    }
    /// Uniform in `[a, b)`.
    fn uniform(&mut self, a: f64, b: f64) -> f64 {
        self.0.uniform(a, b)
    }
    fn vec3(&mut self, s: f64) -> [f64; 3] {
        [
            self.uniform(-s, s),
            self.uniform(-s, s),
            self.uniform(-s, s),
        ]
    }
    fn unit(&mut self) -> [f64; 3] {
        loop {
            let v = self.vec3(1.0);
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 0.1 && l <= 1.0 {
                return v.map(|c| c / l);
            }
        }
    }
}

fn perturbed(x: &[[f64; 3]], rng: &mut Rng, s: f64) -> Vec<[f64; 3]> {
    x.iter()
        .map(|p| {
            let d = rng.vec3(s);
            [p[0] + d[0], p[1] + d[1], p[2] + d[2]]
        })
        .collect()
}

fn max_abs(v: impl IntoIterator<Item = f64>) -> f64 {
    v.into_iter().fold(0.0, |m, x| m.max(x.abs()))
}

fn fd_gradient(e: &dyn Energy, x: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut g = vec![[0.0; 3]; x.len()];
    let mut y = x.to_vec();
    for i in 0..x.len() {
        for k in 0..3 {
            y[i][k] = x[i][k] + H;
            let ep = e.value(&y).unwrap();
            y[i][k] = x[i][k] - H;
            let em = e.value(&y).unwrap();
            y[i][k] = x[i][k];
            g[i][k] = (ep - em) / (2.0 * H);
        }
    }
    g
}

fn fd_hessian(e: &dyn Energy, x: &[[f64; 3]]) -> DMatrix<f64> {
    let n = 3 * x.len();
    let mut h = DMatrix::zeros(n, n);
    let mut y = x.to_vec();
    for i in 0..x.len() {
        for k in 0..3 {
            y[i][k] = x[i][k] + H;
            let gp = gradient_of(e, &y).unwrap().1;
            y[i][k] = x[i][k] - H;
            let gm = gradient_of(e, &y).unwrap().1;
            y[i][k] = x[i][k];
            for r in 0..n {
                h[(r, 3 * i + k)] = (gp[r / 3][r % 3] - gm[r / 3][r % 3]) / (2.0 * H);
            }
        }
    }
    h
}

/// Checks value/gradient consistency, the gradient and the exact Hessian against finite
/// differences, symmetry, and the projected Hessian (PSD; equal to the exact one when
/// `exact_is_psd`). Returns the relative errors `(gradient, hessian)`.
fn check(e: &dyn Energy, x: &[[f64; 3]], exact_is_psd: bool) -> (f64, f64) {
    let v = e.value(x).unwrap();
    let (v2, g) = gradient_of(e, x).unwrap();
    assert!(
        (v - v2).abs() <= 1e-12 * v.abs().max(1e-300),
        "{}: value {v} vs {v2}",
        e.name()
    );
    let fg = fd_gradient(e, x);
    let scale = max_abs(fg.iter().flatten().copied()).max(1e-300);
    let gerr = max_abs(
        g.iter()
            .flatten()
            .zip(fg.iter().flatten())
            .map(|(a, b)| a - b),
    ) / scale;
    assert!(
        gerr <= GRAD_RTOL,
        "{}: gradient error {gerr:e} (scale {scale:e})",
        e.name()
    );

    let exact = hessian_of(e, x, HessianKind::Exact).unwrap().to_dense();
    let fh = fd_hessian(e, x);
    let hscale = max_abs(fh.iter().copied()).max(1e-300);
    let herr = max_abs((&exact - &fh).iter().copied()) / hscale;
    assert!(
        herr <= HESS_RTOL,
        "{}: Hessian error {herr:e} (scale {hscale:e})",
        e.name()
    );
    let asym = max_abs((&exact - exact.transpose()).iter().copied()) / hscale;
    assert!(asym <= 1e-12, "{}: Hessian asymmetry {asym:e}", e.name());

    let proj = hessian_of(e, x, HessianKind::Projected).unwrap().to_dense();
    let min_eig = proj.clone().symmetric_eigen().eigenvalues.min();
    assert!(
        min_eig >= -1e-9 * hscale,
        "{}: projected Hessian eigenvalue {min_eig:e}",
        e.name()
    );
    if exact_is_psd {
        let d = max_abs((&proj - &exact).iter().copied()) / hscale;
        assert!(
            d <= 1e-10,
            "{}: projection changed a PSD Hessian by {d:e}",
            e.name()
        );
    }
    if std::env::var_os("WEFT_FD_REPORT").is_some() {
        eprintln!("fd {}: gradient {gerr:.2e}, Hessian {herr:.2e}", e.name());
    }
    (gerr, herr)
}

/// A 3×3 vertex grid (8 faces, 8 hinges... and boundary) with a perturbed rest shape.
fn rest_mesh(rng: &mut Rng) -> TriMesh {
    let mut m = grid(3, 3, 0.5);
    m.positions = perturbed(&m.positions, rng, 0.1);
    m
}

fn min_area(m: &TriMesh, x: &[[f64; 3]]) -> f64 {
    TriMesh::new(x.to_vec(), m.faces.clone())
        .face_areas()
        .into_iter()
        .fold(f64::INFINITY, f64::min)
}

fn random_params(rng: &mut Rng, faces: usize) -> Vec<StretchParams> {
    (0..faces)
        .map(|_| StretchParams {
            mu: rng.uniform(1.5e4, 6.4e4),
            lambda: rng.uniform(3.5e3, 9.3e4),
            thickness: 4.7e-4,
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn stretch_derivatives(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let rest = rest_mesh(&mut rng);
        let x = perturbed(&rest.positions, &mut rng, 0.15);
        let frames = RestFrames::from_rest_mesh(&rest).unwrap();
        let e = Stretch::new(frames, random_params(&mut rng, rest.face_count())).unwrap();
        check(&e, &x, false);
    }

    #[test]
    fn stretch_from_uvs_derivatives(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let rest = rest_mesh(&mut rng);
        // UVs: the flat grid, scaled (a garment pattern in metres).
        let uv: Vec<[f64; 2]> = grid(3, 3, 0.5).positions.iter().map(|p| [1.1 * p[0], 0.9 * p[2]]).collect();
        let frames = RestFrames::from_vertex_uvs(9, rest.faces.clone(), &uv).unwrap();
        let x = perturbed(&rest.positions, &mut rng, 0.15);
        let e = Stretch::new(frames, random_params(&mut rng, rest.face_count())).unwrap();
        check(&e, &x, false);
    }

    #[test]
    fn bending_derivatives(seed in any::<u64>(), shells in any::<bool>(), from_rest in any::<bool>()) {
        let mut rng = Rng::new(seed);
        let rest = rest_mesh(&mut rng);
        let x = perturbed(&rest.positions, &mut rng, 0.2);
        prop_assume!(min_area(&rest, &x) > 0.02);
        let hinges = Topology::new(&rest).hinges(&rest);
        let k: Vec<f64> = (0..hinges.len()).map(|_| rng.uniform(1e-5, 1e-3)).collect();
        let scale = if shells { BendingScale::DiscreteShells } else { BendingScale::Hood };
        let angle = if from_rest { RestAngle::FromRest } else { RestAngle::Flat };
        let e = Bending::new(&rest, &hinges, &k, scale, angle).unwrap();
        let angles = e.dihedral_angles(&x).unwrap();
        prop_assume!(angles.iter().all(|a| a.abs() < 2.8));
        check(&e, &x, false);
    }

    #[test]
    fn single_hinge_at_large_angles(seed in any::<u64>()) {
        // One hinge folded anywhere in (−2.8, 2.8) rad.
        let mut rng = Rng::new(seed);
        let rest = TriMesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 0.8, 0.0], [0.6, -0.9, 0.0]],
            vec![[0, 1, 2], [1, 0, 3]],
        );
        let phi = rng.uniform(-2.8, 2.8);
        let (c, s) = (phi.cos(), phi.sin());
        let mut x = rest.positions.clone();
        x[3] = [0.6, -0.9 * c, -0.9 * s];
        let x = perturbed(&x, &mut rng, 0.05);
        let e = Bending::uniform(&rest, 1e-3, BendingScale::DiscreteShells, RestAngle::Flat).unwrap();
        prop_assume!(e.dihedral_angles(&x).unwrap()[0].abs() < 2.9);
        check(&e, &x, false);
    }

    #[test]
    fn cone_volume_derivatives(seed in any::<u64>()) {
        // Apexes anywhere round the grid (on either side of a face), rest volumes from
        // the rest shape, stiffnesses over two orders of magnitude.
        let mut rng = Rng::new(seed);
        let rest = rest_mesh(&mut rng);
        let x = perturbed(&rest.positions, &mut rng, 0.2);
        let apex: Vec<[f64; 3]> = (0..rest.face_count()).map(|_| rng.vec3(0.6)).collect();
        let k: Vec<f64> = (0..rest.face_count()).map(|_| rng.uniform(1e2, 1e4)).collect();
        let e = ConeVolume::new(&rest.positions, rest.faces.clone(), k, apex).unwrap();
        check(&e, &x, false);
    }

    #[test]
    fn button_derivatives(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let rest = rest_mesh(&mut rng);
        let x = perturbed(&rest.positions, &mut rng, 0.2);
        let n = rest.vertex_count() as u32;
        let pairs: Vec<[u32; 2]> = (0..4u32).map(|p| [p, (p + 3 + (seed % 2) as u32) % n]).collect();
        let k: Vec<f64> = pairs.iter().map(|_| rng.uniform(1.0, 100.0)).collect();
        let e = Buttons::new(rest.vertex_count(), pairs, k).unwrap();
        check(&e, &x, true);
    }

    #[test]
    fn gravity_and_inertia_derivatives(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let rest = rest_mesh(&mut rng);
        let dens: Vec<f64> = (0..rest.face_count()).map(|_| rng.uniform(0.05, 0.7)).collect();
        let m = lumped_masses(&rest, &dens).unwrap();
        let x = perturbed(&rest.positions, &mut rng, 0.2);
        let g = Gravity::new(m.clone(), STANDARD_GRAVITY).unwrap();
        check(&g, &x, true);
        let target = perturbed(&rest.positions, &mut rng, 0.2);
        let i = Inertia::new(m, 1.0 / 30.0, target).unwrap();
        check(&i, &x, true);
    }

    #[test]
    fn collision_derivatives(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let x: Vec<[f64; 3]> = (0..6).map(|_| rng.vec3(0.5)).collect();
        let eps = 2e-3;
        let contacts: Vec<VertexContact> = (0..6u32)
            .map(|v| {
                let n = rng.unit();
                // Signed distance in (−5ε, 3ε): inside, in the band, or outside.
                let d = rng.uniform(-5.0 * eps, 3.0 * eps);
                let p = x[v as usize];
                VertexContact { vertex: v, contact: BodyContact { point: std::array::from_fn(|k| p[k] - d * n[k]), normal: n } }
            })
            .collect();
        // Away from d = ε, where the penalty's third derivative jumps (finite differences
        // of the gradient straddling it are only first-order accurate) and where eq. 4
        // has its kink.
        prop_assume!(contacts.iter().all(|c| (c.contact.signed_distance(x[c.vertex as usize]) - eps).abs() > 1e-4));
        // And with one vertex at least ε/2 into the band: central differences of the
        // cubic are off by up to `k_c H²` (5·10⁻⁷ N), and with every vertex shallower
        // the largest gradient component can be a few tenths of a newton, so the relative
        // error passes 10⁻⁶ (seed 8478337286043000365: 0.28 N, 1.5·10⁻⁶).
        prop_assume!(contacts.iter().any(|c| c.contact.signed_distance(x[c.vertex as usize]) < 0.5 * eps));
        let c = CubicCollision::new(6, 5e5, eps, contacts.clone()).unwrap();
        check(&c, &x, true);
        let l = LinearCollision::new(6, eps, contacts).unwrap();
        check(&l, &x, true);
    }

    #[test]
    fn friction_derivatives(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let x: Vec<[f64; 3]> = (0..5).map(|_| rng.vec3(0.5)).collect();
        // A slip length large enough that the finite differences' truncation error on
        // the mollifier (relative h²/ε²) stays far below the tolerance.
        let eps = 1e-2;
        let contacts: Vec<FrictionContact> = (0..5u32)
            .map(|v| {
                // Tangential slip from 0.1 ε to 5 ε (both branches of the mollifier),
                // kept 10⁻³ ε away from y = ε where the fourth derivative jumps.
                let mut slip = eps * rng.uniform(0.1, 5.0);
                if (slip - eps).abs() < 1e-3 * eps {
                    slip = 2.0 * eps;
                }
                let n = nalgebra::Vector3::from(rng.unit());
                let t = n.cross(&nalgebra::Vector3::from(rng.unit())).normalize();
                let off = rng.uniform(-0.1, 0.1);
                let a = nalgebra::Vector3::from(x[v as usize]) - t * slip - n * off;
                FrictionContact {
                    vertex: v,
                    anchor: [a.x, a.y, a.z],
                    normal: [n.x, n.y, n.z],
                    normal_force: rng.uniform(0.0, 2.0),
                    mu: rng.uniform(0.1, 1.0),
                }
            })
            .collect();
        let f = Friction::new(5, eps, contacts).unwrap();
        check(&f, &x, true);
    }

    #[test]
    fn multilevel_membrane_derivatives(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let rest = rest_mesh(&mut rng);
        let x = perturbed(&rest.positions, &mut rng, 0.15);
        let uv: Vec<[f64; 2]> = grid(3, 3, 0.5).positions.iter().map(|p| [p[0], p[2]]).collect();
        let frames = RestFrames::from_vertex_uvs(9, rest.faces.clone(), &uv).unwrap();
        check(&UvStretch::new(frames.clone()), &x, false);
        check(&UvShear::new(frames), &x, false);
    }

    #[test]
    fn full_potential_derivatives(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let rest = rest_mesh(&mut rng);
        let x = perturbed(&rest.positions, &mut rng, 0.1);
        prop_assume!(min_area(&rest, &x) > 0.02);
        let p = full_potential(&rest, &x, &mut rng);
        prop_assume!(p.bending().unwrap().dihedral_angles(&x).unwrap().iter().all(|a| a.abs() < 2.8));
        check(&p, &x, false);
        let sum: f64 = p.breakdown(&x).unwrap().iter().map(|(_, w, v)| w * v).sum();
        let v = p.value(&x).unwrap();
        prop_assert!((sum - v).abs() <= 1e-12 * v.abs().max(1.0));
    }
}

/// Every term at once, with weights.
fn full_potential(rest: &TriMesh, x: &[[f64; 3]], rng: &mut Rng) -> IncrementalPotential {
    let n = rest.vertex_count();
    let mat = Material::cotton();
    let masses = lumped_masses(rest, &vec![mat.density; rest.face_count()]).unwrap();
    let contacts: Vec<VertexContact> = (0..n as u32)
        .step_by(2)
        .map(|v| {
            let nrm = rng.unit();
            let mut d = rng.uniform(-4e-3, 4e-3);
            if (d - 2e-3).abs() < 1e-4 {
                d = 0.0; // away from the threshold, see collision_derivatives
            }
            let p = x[v as usize];
            VertexContact {
                vertex: v,
                contact: BodyContact {
                    point: std::array::from_fn(|k| p[k] - d * nrm[k]),
                    normal: nrm,
                },
            }
        })
        .collect();
    let fr: Vec<FrictionContact> = contacts
        .iter()
        .map(|c| FrictionContact {
            vertex: c.vertex,
            anchor: perturbed(&[x[c.vertex as usize]], rng, 1e-3)[0],
            normal: c.contact.normal,
            normal_force: 0.05,
            mu: 0.5,
        })
        .collect();
    let frames = RestFrames::from_rest_mesh(rest).unwrap();
    IncrementalPotential::new(n)
        .with(
            1.0,
            Term::Stretch(Stretch::uniform(rest, mat.stretch_params()).unwrap()),
        )
        .unwrap()
        .with(
            1.0,
            Term::Bending(
                Bending::uniform(rest, 1e-3, BendingScale::Hood, RestAngle::FromRest).unwrap(),
            ),
        )
        .unwrap()
        .with(
            1.0,
            Term::Gravity(Gravity::new(masses.clone(), STANDARD_GRAVITY).unwrap()),
        )
        .unwrap()
        .with(
            1.0,
            Term::Inertia(Inertia::new(masses, 1.0 / 30.0, perturbed(x, rng, 0.01)).unwrap()),
        )
        .unwrap()
        .with(
            1.0,
            Term::Collision(CubicCollision::new(n, 5e5, 2e-3, contacts).unwrap()),
        )
        .unwrap()
        // Slip (< 1.8 mm) stays inside the mollifier's 1 cm: no branch change under FD.
        .with(0.5, Term::Friction(Friction::new(n, 1e-2, fr).unwrap()))
        .unwrap()
        .with(2.0, Term::UvShear(UvShear::new(frames)))
        .unwrap()
}

#[test]
fn stretch_is_zero_and_psd_at_rest() {
    let mut rng = Rng::new(7);
    let rest = rest_mesh(&mut rng);
    let e = Stretch::uniform(&rest, Material::hood().stretch_params()).unwrap();
    let (v, g) = gradient_of(&e, &rest.positions).unwrap();
    assert!(v.abs() < 1e-20);
    assert!(max_abs(g.iter().flatten().copied()) < 1e-10);
    // Rigid motions leave it zero too.
    let (c, s) = (0.6f64.cos(), 0.6f64.sin());
    let moved: Vec<[f64; 3]> = rest
        .positions
        .iter()
        .map(|p| [c * p[0] - s * p[2] + 1.0, p[1] - 2.0, s * p[0] + c * p[2]])
        .collect();
    assert!(e.value(&moved).unwrap().abs() < 1e-18);
    let h = hessian_of(&e, &rest.positions, HessianKind::Exact)
        .unwrap()
        .to_dense();
    let scale = max_abs(h.iter().copied());
    assert!(h.symmetric_eigen().eigenvalues.min() > -1e-9 * scale);
}

#[test]
fn stvk_is_indefinite_under_compression_and_projection_fixes_it() {
    let rest = TriMesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        vec![[0, 1, 2]],
    );
    let e = Stretch::uniform(&rest, Material::hood().stretch_params()).unwrap();
    let squashed: Vec<[f64; 3]> = rest.positions.iter().map(|p| p.map(|c| 0.5 * c)).collect();
    let exact = hessian_of(&e, &squashed, HessianKind::Exact)
        .unwrap()
        .to_dense();
    assert!(exact.symmetric_eigen().eigenvalues.min() < 0.0);
    let proj = hessian_of(&e, &squashed, HessianKind::Projected)
        .unwrap()
        .to_dense();
    assert!(proj.symmetric_eigen().eigenvalues.min() > -1e-9);
}

#[test]
fn bending_is_zero_at_flat_rest_and_grows_quadratically() {
    let rest = grid(3, 3, 0.5);
    let e = Bending::uniform(&rest, 1.0, BendingScale::DiscreteShells, RestAngle::Flat).unwrap();
    assert_eq!(e.hinge_count(), 8);
    assert_eq!(e.value(&rest.positions).unwrap(), 0.0);
    let lift = |t: f64| {
        let mut x = rest.positions.clone();
        x[8][1] = t; // corner vertex: bends the two hinges of the corner quad's neighbours
        e.value(&x).unwrap()
    };
    let r = lift(2e-3) / lift(1e-3);
    assert!((r - 4.0).abs() < 1e-3, "{r}");
}

/// On a cylinder of radius R the continuum bending energy is `∫ B/2 κ² dA` =
/// `B/2 · A / R²`. The ratio of the discrete energies (k = 1) to `A/(2R²)` is the factor
/// that converts a bending rigidity `B` into the hinge stiffness `k` for this kind of
/// mesh (recorded in docs/physics.md).
#[test]
fn cylinder_calibration_of_the_bending_scales() {
    for (scale, lo, hi) in [
        (BendingScale::Hood, 0.2, 0.3),
        (BendingScale::DiscreteShells, 5.0, 6.5),
    ] {
        let (nx, nz, h) = (41, 21, 0.01);
        let flat = grid(nx, nz, h);
        let r = 0.1;
        // Roll the grid's X axis onto a cylinder of radius r (axis along Z).
        let x: Vec<[f64; 3]> = flat
            .positions
            .iter()
            .map(|p| {
                let a = p[0] / r;
                [r * a.sin(), r * (1.0 - a.cos()), p[2]]
            })
            .collect();
        let e = Bending::uniform(&flat, 1.0, scale, RestAngle::Flat).unwrap();
        let area: f64 = flat.face_areas().iter().sum();
        let ratio = e.value(&x).unwrap() / (area / (2.0 * r * r));
        assert!(ratio > lo && ratio < hi, "{scale:?}: {ratio}");
        eprintln!("bending calibration {scale:?}: discrete / continuum (k = B) = {ratio:.4}");
    }
}

#[test]
fn errors_instead_of_panics() {
    let rest = grid(3, 3, 0.5);
    let e = Stretch::uniform(&rest, Material::cotton().stretch_params()).unwrap();
    assert!(matches!(
        e.value(&rest.positions[..4]),
        Err(SimError::VertexCount { .. })
    ));
    let mut small = vec![[0.0; 3]; 3];
    assert!(e.add_gradient(&rest.positions, 1.0, &mut small).is_err());
    let mut wrong = PatternBuilder::new(9).build();
    assert!(matches!(
        e.add_hessian(&rest.positions, 1.0, HessianKind::Exact, &mut wrong),
        Err(SimError::NotInPattern { .. })
    ));
    assert!(Stretch::new(RestFrames::from_rest_mesh(&rest).unwrap(), vec![]).is_err());
    let bad = StretchParams {
        mu: -1.0,
        lambda: 0.0,
        thickness: 1e-3,
    };
    assert!(Stretch::uniform(&rest, bad).is_err());
    assert!(Bending::uniform(&rest, f64::NAN, BendingScale::Hood, RestAngle::Flat).is_err());
    let mut p = IncrementalPotential::new(4);
    assert!(p.push(1.0, Term::Stretch(e)).is_err());
    assert!(CubicCollision::new(
        9,
        1.0,
        1e-3,
        vec![VertexContact {
            vertex: 9,
            contact: BodyContact {
                point: [0.0; 3],
                normal: [0.0, 1.0, 0.0]
            }
        }]
    )
    .is_err());
    assert!(Friction::new(9, 0.0, vec![]).is_err());
}
