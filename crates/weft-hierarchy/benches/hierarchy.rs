//! Hierarchy construction (3 levels, mesh graph included) on grids and open cylinders of
//! about 10k, 100k and 1M vertices. Figures go to docs/benchmarks.md.

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use weft_hierarchy::Hierarchy;
use weft_mesh::primitives::{cylinder, grid};
use weft_mesh::TriMesh;

fn shapes() -> Vec<(String, TriMesh)> {
    let mut out = Vec::new();
    for side in [100, 316, 1000] {
        out.push((format!("grid {side}x{side}"), grid(side, side, 0.01)));
    }
    // 100 vertices around, as the built-in garment, growing in length.
    for rings in [100, 1000, 10000] {
        out.push((
            format!("cylinder {rings}x100"),
            cylinder(rings, 100, 0.3, 0.01),
        ));
    }
    out
}

fn hierarchy(c: &mut Criterion) {
    let mut group = c.benchmark_group("hierarchy_3_levels");
    group.sample_size(10);
    for (name, mesh) in shapes() {
        group.bench_with_input(BenchmarkId::from_parameter(&name), &mesh, |b, m| {
            b.iter(|| Hierarchy::build(m.graph(), 3).expect("meshes are valid"))
        });
    }
    group.finish();
}

criterion_group!(benches, hierarchy);
criterion_main!(benches);
