//! Render time of a 12 000-vertex garment (`cylinder(120, 100, 0.3, 0.01)`) over a
//! body-sized mesh at 1024 × 1024, three-quarter view, with and without a per-vertex
//! colour map, at the default 2 × 2 supersampling and without it. Figures go to
//! docs/benchmarks.md.

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use weft_render::{
    render, Colormap, Paint, RenderOptions, ScalarPaint, ScalarRange, SceneMesh, BODY_COLOR,
    GARMENT_COLOR,
};

#[path = "../tests/support/mod.rs"]
mod support;

fn bench(c: &mut Criterion) {
    let body = support::mannequin();
    let garment = support::tube_dress();
    let error: Vec<f64> = garment
        .positions
        .iter()
        .map(|p| p[1].sin() * 10.0)
        .collect();
    let mut group = c.benchmark_group("render_1024");
    group.sample_size(10);
    for ss in [1u32, 2] {
        let opts = RenderOptions {
            supersample: ss,
            ..RenderOptions::new(1024, 1024)
        };
        let solid = [
            SceneMesh::new("body", &body, Paint::Solid(BODY_COLOR)),
            SceneMesh::new("garment", &garment, Paint::Solid(GARMENT_COLOR)),
        ];
        group.bench_function(
            format!(
                "garment 12k + body {}k, solid, ss{ss}",
                body.vertex_count() / 1000
            ),
            |b| b.iter(|| render(&solid, &opts).expect("valid scene")),
        );
        let mapped = [
            SceneMesh::new("body", &body, Paint::Solid(BODY_COLOR)),
            SceneMesh::new(
                "garment",
                &garment,
                Paint::Scalars(ScalarPaint {
                    values: &error,
                    colormap: Colormap::Viridis,
                    range: ScalarRange::Auto,
                    label: "error (mm)",
                }),
            ),
        ];
        group.bench_function(
            format!(
                "garment 12k + body {}k, colour map + legend, ss{ss}",
                body.vertex_count() / 1000
            ),
            |b| b.iter(|| render(&mapped, &opts).expect("valid scene")),
        );
    }
    let opts = RenderOptions::new(1024, 1024);
    let mapped = [SceneMesh::new(
        "garment",
        &garment,
        Paint::Solid(GARMENT_COLOR),
    )];
    let img = render(&mapped, &opts).expect("valid scene").image;
    group.bench_function("png encode 1024x1024", |b| {
        b.iter(|| img.encode_png().expect("encodes"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
