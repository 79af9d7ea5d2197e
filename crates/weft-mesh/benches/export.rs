//! Export time for 1 000 frames of the 4 000-vertex built-in garment to each format
//! (issue 5, part 6), written to a temporary directory on the local disk.
//!
//! Each iteration writes the whole file (or directory) through the atomic path,
//! fsync included, because that is what a user waits for. Sample sizes are small so the
//! group finishes in a minute or two: one iteration writes 48 MB (PC2, MDD), 100 MB (glb)
//! or 251 MB (OBJ). Removing the previous output is untimed setup.

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use std::path::PathBuf;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use weft_mesh::export::{export, ExportFormat, Frames};
use weft_mesh::primitives::builtin_garment;

const FRAMES: usize = 1000;

/// A swaying, breathing tube: every vertex moves every frame, so no format gets an easy
/// (constant) input.
fn animation() -> (weft_mesh::TriMesh, Frames) {
    let garment = builtin_garment();
    let mut frames = Frames::with_vertex_count(garment.vertex_count()).expect("vertices");
    for k in 0..FRAMES {
        let t = k as f64 / 30.0;
        let positions: Vec<[f64; 3]> = garment
            .positions
            .iter()
            .map(|p| {
                let s = 1.0 + 0.05 * (3.0 * t + 10.0 * p[1]).sin();
                [p[0] * s + 0.02 * (2.0 * t).sin(), p[1], p[2] * s]
            })
            .collect();
        frames.push_frame_f64(&positions).expect("frame length");
    }
    (garment, frames)
}

/// A scratch directory under the system temp dir, removed on drop.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Removes a previous output file or directory, if any.
fn remove(path: &std::path::Path) {
    let _ = std::fs::remove_dir_all(path);
    let _ = std::fs::remove_file(path);
}

fn bench_export(c: &mut Criterion) {
    let (garment, frames) = animation();
    let scratch =
        Scratch(std::env::temp_dir().join(format!("weft-bench-export-{}", std::process::id())));
    std::fs::create_dir_all(&scratch.0).expect("scratch dir");

    let mut group = c.benchmark_group("export_1000x4000");
    group.sample_size(10);
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(10));
    group.throughput(Throughput::Elements(FRAMES as u64));
    for format in ExportFormat::ALL {
        let out = scratch.0.join(format!("out.{}", format.name()));
        // Each timed export writes a fresh output: removing the previous one (1 000
        // files for OBJ) happens in the untimed setup, as a user exports to a new path.
        group.bench_function(format.name(), |b| {
            b.iter_batched(
                || remove(&out),
                |()| export(format, &garment, None, &frames, 30.0, &out).expect("export"),
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_export);
criterion_main!(benches);
