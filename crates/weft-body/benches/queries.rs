//! Body queries against the default body (13 380 vertices, 26 756 triangles) posed by a
//! procedural walk: signed-distance queries per second for the 4 000-vertex built-in
//! garment, near-contact queries, the per-frame tree updates (build, refit, rebuild) and
//! the garment features built on them (body edges, weight transfer, volumetric joint
//! distances). Figures go to docs/body-features.md and docs/benchmarks.md.
//!
//! `cargo bench -p weft-body --bench queries`
//!
//! The garment is `weft_mesh::primitives::builtin_garment()` (a tube of radius 0.3 m,
//! 40 rings over 0.585 m) hung from 10 cm above the pelvis, a loose skirt 5–15 cm off
//! the hips and thighs. Frames are posed without root translation so that it stays
//! around the body.

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use weft_body::features::{
    transfer_weights, transfer_weights_diffused, DiffusionParams, VolumetricDistance,
    VolumetricParams,
};
use weft_body::query::{AabbTree, BodyEdgeRule, BodySurface, VertexTree};
use weft_body::{default_body, Skinning};
use weft_mesh::primitives::builtin_garment;
use weft_mesh::Aabb;
use weft_motion::{generate, MotionKind, ProceduralParams};

fn boxes(p: &[[f64; 3]], f: &[[u32; 3]]) -> Vec<Aabb> {
    f.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| p[i as usize]);
            Aabb {
                min: std::array::from_fn(|k| a[k].min(b[k]).min(c[k])),
                max: std::array::from_fn(|k| a[k].max(b[k]).max(c[k])),
            }
        })
        .collect()
}

fn queries(c: &mut Criterion) {
    let model = default_body().expect("the default body loads");
    let shaped = model.shaped(&[]).expect("mean shape");
    let faces = model.faces().to_vec();
    let mut params = ProceduralParams::new(MotionKind::Walk);
    params.frames = 30;
    let walk = generate(&params).expect("a walk");
    let pose = |k: usize| -> Vec<[f64; 3]> {
        let p: Vec<[f64; 3]> = walk.poses()[k].iter().map(|w| w.map(f64::from)).collect();
        model
            .pose_vertices(&shaped, &p, [0.0; 3], Skinning::Lbs)
            .expect("posing")
    };
    let rest = shaped.vertices.clone();
    let (frame_a, frame_b) = (pose(0), pose(15));

    let mut garment = builtin_garment();
    for q in &mut garment.positions {
        q[1] += 0.1;
    }
    let g = &garment.positions;

    // Built on the posed frame; and built on the T-pose then refit to it.
    let surface = BodySurface::new(&frame_b, &faces).expect("valid body");
    assert!(surface.is_closed(), "the default body is a closed surface");
    let mut refit = BodySurface::new(&rest, &faces).expect("valid body");
    refit.refit(&frame_b).expect("same count");

    let mut group = c.benchmark_group("signed_distance_garment_4000");
    group.sample_size(10);
    group.throughput(Throughput::Elements(g.len() as u64));
    group.bench_function("batched_rayon", |b| {
        b.iter(|| surface.signed_distances(g).expect("finite"))
    });
    group.bench_function("one_thread", |b| {
        b.iter(|| {
            g.iter()
                .map(|&x| surface.signed_distance(x).expect("finite"))
                .sum::<f64>()
        })
    });
    group.bench_function("one_thread_tree_refit_from_t_pose", |b| {
        b.iter(|| {
            g.iter()
                .map(|&x| refit.signed_distance(x).expect("finite"))
                .sum::<f64>()
        })
    });
    group.finish();

    // Near-contact points, 5 mm outside the posed surface (every 4th vertex): what the
    // collision term and the simulator's contacts ask about.
    let near: Vec<[f64; 3]> = frame_b
        .iter()
        .zip(surface.vertex_normals())
        .step_by(4)
        .map(|(v, n)| std::array::from_fn(|k| v[k] + 0.005 * n[k]))
        .collect();
    let mut group = c.benchmark_group("signed_distance_near_contact");
    group.sample_size(10);
    group.throughput(Throughput::Elements(near.len() as u64));
    group.bench_function("one_thread", |b| {
        b.iter(|| {
            near.iter()
                .map(|&x| surface.signed_distance(x).expect("finite"))
                .sum::<f64>()
        })
    });
    group.bench_function("within_2cm_one_thread", |b| {
        b.iter(|| {
            near.iter()
                .filter_map(|&x| surface.closest_point_within(x, 0.02).expect("finite"))
                .count()
        })
    });
    group.finish();

    let mut group = c.benchmark_group("body_update_13380_vertices");
    group.sample_size(10);
    let (bx_a, bx_b) = (boxes(&frame_a, &faces), boxes(&frame_b, &faces));
    group.bench_function("aabb_tree_build", |b| b.iter(|| AabbTree::build(&bx_b)));
    let mut tree = AabbTree::build(&bx_a);
    group.bench_function("aabb_tree_refit", |b| b.iter(|| tree.refit(&bx_b)));
    group.bench_function("surface_new", |b| {
        b.iter(|| BodySurface::new(&frame_b, &faces).expect("valid"))
    });
    let mut s = surface.clone();
    let mut flip = false;
    group.bench_function("surface_refit", |b| {
        b.iter(|| {
            flip = !flip;
            s.refit(if flip { &frame_a } else { &frame_b })
                .expect("same count")
        })
    });
    group.bench_function("surface_rebuild", |b| {
        b.iter(|| {
            flip = !flip;
            s.rebuild(if flip { &frame_a } else { &frame_b })
                .expect("same count")
        })
    });
    group.finish();

    let mut group = c.benchmark_group("garment_features_4000");
    group.sample_size(10);
    let vt = VertexTree::new(&frame_b).expect("valid");
    for r in [0.05, 0.15] {
        group.bench_with_input(BenchmarkId::new("body_edges_nearest", r), &r, |b, &r| {
            b.iter(|| vt.body_edges(g, r, BodyEdgeRule::Nearest).expect("valid"))
        });
    }
    let w = model.skinning_weights().expect("valid weights");
    let rest_surface = BodySurface::new(&rest, &faces).expect("valid");
    group.bench_function("transfer_weights", |b| {
        b.iter(|| transfer_weights(&rest_surface, &w, g).expect("valid"))
    });
    group.bench_function("transfer_weights_diffused", |b| {
        b.iter(|| {
            transfer_weights_diffused(&rest_surface, &w, &garment, &DiffusionParams::default())
                .expect("valid")
        })
    });
    group.finish();

    // Volumetric distances to the 24 joints: 400 garment vertices (every 10th).
    let mut group = c.benchmark_group("volumetric_joint_distances_24_joints");
    group.sample_size(10);
    let sub: Vec<[f64; 3]> = g.iter().step_by(10).copied().collect();
    group.throughput(Throughput::Elements(sub.len() as u64));
    let v = VolumetricDistance::new(
        &rest_surface,
        &shaped.joints,
        model.skeleton().parents(),
        VolumetricParams::default(),
    )
    .expect("valid");
    group.bench_function("garment_400_points", |b| {
        b.iter(|| v.matrix(&sub).expect("valid"))
    });
    group.finish();
}

criterion_group!(benches, queries);
criterion_main!(benches);
