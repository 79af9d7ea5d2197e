//! Gradient checks of every loss term through burn against central differences, and the
//! two physics paths (custom operation, reference surrogate) against each other.

use std::sync::Arc;

use burn::tensor::{DType, Device, Tensor, TensorData};
use weft_mesh::primitives::grid;
use weft_mesh::TriMesh;
use weft_nn::backend::cpu_autodiff;
use weft_sim::Sphere;

use super::*;

/// The collision threshold ε (m) and garment density (kg/m²) of the tests.
const EPS: f64 = weft_sim::collision::HOOD_COLLISION_EPS;
const DENSITY: f64 = 0.15;

/// A small deterministic generator (xorshift) for test data.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// The rest garment: a 4 × 3 grid (20 vertices) of 0.1 m cells.
fn garment() -> TriMesh {
    grid(4, 3, 0.1)
}

/// `T` frames of the garment, each vertex moved by up to ±`amp` m.
fn frames(mesh: &TriMesh, t: usize, amp: f64, seed: u64) -> Vec<f64> {
    let mut rng = Rng(seed);
    (0..t)
        .flat_map(|_| mesh.positions.clone())
        .flat_map(|p| p.map(|c| c + amp * rng.uniform()))
        .collect::<Vec<_>>()
}

fn tensor3(values: &[f64], t: usize, n: usize, device: &Device, dtype: DType) -> Tensor<3> {
    Tensor::from_data(TensorData::new(values.to_vec(), [t, n, 3]), (device, dtype))
}

fn host<const D: usize>(t: Tensor<D>) -> Vec<f64> {
    t.into_data()
        .convert::<f64>()
        .try_into_vec::<f64>()
        .unwrap()
}

/// Checks the gradient burn computes for `loss` at `x` against central differences of
/// the same forward pass in f64.
fn check_gradient(
    name: &str,
    x: &[f64],
    t: usize,
    n: usize,
    loss: impl Fn(Tensor<3>) -> Tensor<1>,
    tol: f64,
) {
    let device = cpu_autodiff();
    let xt = tensor3(x, t, n, &device, DType::F64).require_grad();
    let value = loss(xt.clone());
    let grads = value.backward();
    let g = host(xt.grad(&grads).expect("gradient"));
    let eval = |v: &[f64]| host(loss(tensor3(v, t, n, &device, DType::F64)))[0];
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for i in 0..x.len() {
        let mut p = x.to_vec();
        p[i] += h;
        let fp = eval(&p);
        p[i] -= 2.0 * h;
        let fm = eval(&p);
        let fd = (fp - fm) / (2.0 * h);
        let err = (fd - g[i]).abs() / (1.0 + fd.abs().max(g[i].abs()));
        worst = worst.max(err);
    }
    assert!(worst < tol, "{name}: worst relative gradient error {worst}");
}

#[test]
fn supervised_terms_match_central_differences() {
    let mesh = garment();
    let (t, n) = (2, mesh.vertex_count());
    let topo = GarmentTopology::new(&mesh).unwrap();
    let device = cpu_autodiff();
    let window = topo.window(t, &device).unwrap();
    let gt_frames: Vec<Vec<[f32; 3]>> = frames(&mesh, t, 0.02, 7)
        .chunks(3 * n)
        .map(|f| {
            f.chunks(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
                .collect()
        })
        .collect();
    let targets = Targets::new(&topo, &mesh.faces, &gt_frames, &device).unwrap();
    let x = frames(&mesh, t, 0.02, 99);
    let gt = targets.positions.clone().cast(DType::F64);
    check_gradient(
        "vertex",
        &x,
        t,
        n,
        |p| vertex_loss(p, gt.clone()).unwrap(),
        1e-6,
    );
    let lengths = targets.edge_lengths.clone().cast(DType::F64);
    check_gradient(
        "edge",
        &x,
        t,
        n,
        |p| edge_loss(p, &topo, &window, lengths.clone()).unwrap(),
        1e-6,
    );
    let normals = targets.normals.clone().cast(DType::F64);
    check_gradient(
        "normal",
        &x,
        t,
        n,
        |p| normal_loss(p, &topo, &window, normals.clone()).unwrap(),
        1e-5,
    );
}

#[test]
fn supervised_terms_vanish_on_the_ground_truth_and_match_host_values() {
    let mesh = garment();
    let (t, n) = (3, mesh.vertex_count());
    let topo = GarmentTopology::new(&mesh).unwrap();
    let device = cpu_autodiff();
    let window = topo.window(t, &device).unwrap();
    let x = frames(&mesh, t, 0.03, 5);
    let gt_frames: Vec<Vec<[f32; 3]>> = x
        .chunks(3 * n)
        .map(|f| {
            f.chunks(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
                .collect()
        })
        .collect();
    let targets = Targets::new(&topo, &mesh.faces, &gt_frames, &device).unwrap();
    let p = targets.positions.clone().require_grad();
    let v = vertex_loss(p.clone(), targets.positions.clone()).unwrap();
    let e = edge_loss(p.clone(), &topo, &window, targets.edge_lengths.clone()).unwrap();
    let nl = normal_loss(p.clone(), &topo, &window, targets.normals.clone()).unwrap();
    for (name, l) in [("vertex", &v), ("edge", &e), ("normal", &nl)] {
        let value = host(l.clone())[0];
        assert!(
            value.abs() < 1e-6,
            "{name} loss {value} on the ground truth"
        );
    }
    // Zero loss, finite (zero) gradient: the sqrt guard works.
    let grads = (v + e + nl).backward();
    assert!(host(p.grad(&grads).unwrap()).iter().all(|g| g.is_finite()));

    // A uniform offset of 3 mm along x: vertex loss 3 mm, edge and normal loss zero.
    let shifted: Vec<f32> = gt_frames
        .iter()
        .flatten()
        .flat_map(|q| [q[0] + 0.003, q[1], q[2]])
        .collect();
    let s = Tensor::<3>::from_data(TensorData::new(shifted, [t, n, 3]), (&device, DType::F32));
    let value = host(vertex_loss(s.clone(), targets.positions.clone()).unwrap())[0];
    assert!((value - 0.003).abs() < 1e-6, "{value}");
    let value = host(edge_loss(s, &topo, &window, targets.edge_lengths.clone()).unwrap())[0];
    assert!(value.abs() < 1e-10);
    assert!(Targets::new(&topo, &mesh.faces, &gt_frames[..1], &device).is_ok());
    assert!(Targets::new(&topo, &mesh.faces, &[vec![[0.0; 3]; 2]], &device).is_err());
}

/// The physics terms with the custom operation and the reference path, both against
/// central differences of the energy, and against each other.
#[test]
fn physics_terms_match_central_differences_on_both_paths() {
    let mesh = garment();
    let (t, n) = (2, mesh.vertex_count());
    let x = frames(&mesh, t, 0.03, 11);
    let xs: Vec<[f64; 3]> = x.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    // A sphere under the middle of the grid, touching some vertices: contacts in both
    // frames, some below ε.
    let body = Sphere {
        center: [0.2, -0.3, 0.15],
        radius: 0.3,
    };
    let collision = collision_energies(&[body, body], &xs, n, EPS, 0.05).unwrap();
    assert!(collision.value(&xs).unwrap() > 0.0, "the sphere must touch");
    let gravity = gravity_energy(&mesh, t, DENSITY).unwrap();
    let (stretch, shear) = membrane_energies(&rest_frames(&mesh, None).unwrap(), t).unwrap();
    for energy in [collision, gravity, stretch, shear] {
        let energy = Arc::new(energy);
        for imp in [PhysicsImpl::Auto, PhysicsImpl::Reference] {
            let e = energy.clone();
            check_gradient(
                &format!("{} {imp:?}", energy.name()),
                &x,
                t,
                n,
                move |p| physics_loss(p, &e, imp).unwrap(),
                1e-6,
            );
        }
        // Same value and gradient in f32 from both paths.
        let device = cpu_autodiff();
        let run = |imp| {
            let p = tensor3(&x, t, n, &device, DType::F32).require_grad();
            let l = physics_loss(p.clone(), &energy, imp).unwrap();
            let v = host(l.clone())[0];
            let g = host(p.grad(&l.backward()).unwrap());
            (v, g)
        };
        let (va, ga) = run(PhysicsImpl::Auto);
        let (vr, gr) = run(PhysicsImpl::Reference);
        assert!((va - vr).abs() <= 1e-5 * (1.0 + va.abs()), "{va} vs {vr}");
        for (a, b) in ga.iter().zip(&gr) {
            assert!((a - b).abs() <= 1e-5 * (1.0 + a.abs()), "{a} vs {b}");
        }
        // The mean over frames: the value is the per-frame energy averaged.
        let per_frame: f64 = xs
            .chunks(n)
            .map(|f| {
                let one = FrameEnergies::shared(energy_frame(&energy), 1).unwrap();
                one.value(f).unwrap()
            })
            .sum::<f64>()
            / t as f64;
        if energy.name() != "linear collision" {
            assert!((energy.value(&xs).unwrap() - per_frame).abs() < 1e-12);
        }
    }
}

fn energy_frame(e: &FrameEnergies) -> Arc<dyn weft_sim::Energy + Send + Sync> {
    e.frame(0).unwrap().clone()
}

#[test]
fn physics_loss_rejects_wrong_shapes_and_turns_non_finite_input_into_nan() {
    let mesh = garment();
    let n = mesh.vertex_count();
    let gravity = Arc::new(gravity_energy(&mesh, 2, DENSITY).unwrap());
    let device = cpu_autodiff();
    let wrong = Tensor::<3>::zeros([1, n, 3], (&device, DType::F32));
    assert!(matches!(
        physics_loss(wrong, &gravity, PhysicsImpl::Auto),
        Err(crate::TrainError::Shape { .. })
    ));
    let (stretch, _) = membrane_energies(&rest_frames(&mesh, None).unwrap(), 1).unwrap();
    let mut x = frames(&mesh, 1, 0.0, 1);
    x[4] = f64::NAN;
    let p = tensor3(&x, 1, n, &device, DType::F32);
    let v = host(physics_loss(p, &Arc::new(stretch), PhysicsImpl::Auto).unwrap())[0];
    assert!(v.is_nan());
    assert!(FrameEnergies::per_frame(Vec::new()).is_err());
}

#[test]
fn vertex_error_in_millimetres() {
    let a = vec![vec![[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0]]];
    let b = vec![vec![[0.0f32, 0.002, 0.0], [1.0, 0.0, 0.004]]];
    assert!((mean_vertex_error_mm(&a, &b).unwrap() - 3.0).abs() < 1e-4);
    assert!(mean_vertex_error_mm(&a, &[]).is_err());
}
