//! `weft bench simulate`: the cloth simulator (`weft simulate`'s
//! [`simulate_sequence`]) on a garment and a motion, its cost — seconds, Newton and PCG
//! iterations per frame — and the quality bought with it — edge strain and depth in the
//! body — so that a faster solver is never a sloppier one unnoticed.

use serde::Serialize;
use weft_body::BodyModel;
use weft_eval::metrics::{self, GarmentTopology};
use weft_mesh::TriMesh;
use weft_motion::Motion;
use weft_sim::{simulate_sequence, Material, SequenceOptions, SimulatedSequence};

use crate::{BenchError, Row};

/// What one simulation cost and how good it was. Output frame 0 (the warm-up, draping
/// from the rest pose) is left out of every figure but `warmup_seconds`.
#[derive(Clone, Debug, Serialize)]
pub struct SimulateFigures {
    /// `"simulate"`.
    pub bench: &'static str,
    /// Garment vertices.
    pub vertices: usize,
    /// The material preset.
    pub material: String,
    /// Frames per second of the motion.
    pub fps: f64,
    /// Output frames after the first.
    pub frames: usize,
    /// Implicit-Euler steps per frame.
    pub substeps: usize,
    /// Threads of the pool.
    pub threads: usize,
    /// Mean wall time per frame, s.
    pub seconds_per_frame: f64,
    /// The warm-up, s.
    pub warmup_seconds: f64,
    /// Mean Newton iterations per frame.
    pub newton_iterations: f64,
    /// Mean PCG iterations per frame.
    pub pcg_iterations: f64,
    /// Mean `|l/l̄ − 1|` over edges and frames.
    pub strain_mean: f64,
    /// Its 99th percentile.
    pub strain_p99: f64,
    /// Its largest value.
    pub strain_max: f64,
    /// The deepest garment vertex inside the body at the end of any frame, mm.
    pub max_penetration_mm: f64,
}

/// Simulates `garment` in `material` on `body` (β = 0) through `motion` with `opts` and
/// measures it.
pub fn bench_simulate(
    garment: &TriMesh,
    material: &Material,
    body: &BodyModel,
    motion: &Motion,
    opts: &SequenceOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<SimulateFigures, BenchError> {
    let total = opts
        .max_frames
        .map_or(motion.frame_count(), |f| f.min(motion.frame_count()));
    let mut done = 0;
    let seq = simulate_sequence(garment, material, body, &[], motion, opts, &mut |p| {
        if let weft_sim::SequenceProgress::Frame(_) = p {
            done += 1;
            progress(done, total);
        }
    })
    .map_err(BenchError::stage("simulating"))?;
    figures(garment, material, motion.fps(), opts.substeps, &seq)
}

fn figures(
    garment: &TriMesh,
    material: &Material,
    fps: f64,
    substeps: usize,
    seq: &SimulatedSequence,
) -> Result<SimulateFigures, BenchError> {
    let after = &seq.stats[1.min(seq.stats.len())..];
    let n = after.len().max(1) as f64;
    let mut strains = edge_strains(garment, &seq.frames[1.min(seq.frames.len())..])?;
    strains.sort_by(f64::total_cmp);
    let mean = strains.iter().sum::<f64>() / strains.len().max(1) as f64;
    let p99 = strains
        .get((strains.len() * 99 / 100).min(strains.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0);
    Ok(SimulateFigures {
        bench: "simulate",
        vertices: garment.vertex_count(),
        material: material.name.to_string(),
        fps,
        frames: after.len(),
        substeps,
        threads: rayon::current_num_threads(),
        seconds_per_frame: after.iter().map(|s| s.seconds).sum::<f64>() / n,
        warmup_seconds: seq.stats.first().map_or(0.0, |s| s.seconds),
        newton_iterations: after
            .iter()
            .map(|s| s.newton_iterations as f64)
            .sum::<f64>()
            / n,
        pcg_iterations: after.iter().map(|s| s.cg_iterations as f64).sum::<f64>() / n,
        strain_mean: mean,
        strain_p99: p99,
        strain_max: strains.last().copied().unwrap_or(0.0),
        max_penetration_mm: 1e3 * after.iter().map(|s| s.max_penetration).fold(0.0, f64::max),
    })
}

/// `|l/l̄ − 1|` of every edge of `garment` in every frame of `frames`, as the evaluator
/// measures it (edges of zero rest length left out).
fn edge_strains(garment: &TriMesh, frames: &[Vec<[f32; 3]>]) -> Result<Vec<f64>, BenchError> {
    let stage = || BenchError::stage("measuring edge strain");
    let topology = GarmentTopology::new(garment).map_err(stage())?;
    let mut all = Vec::with_capacity(frames.len() * topology.edges.len());
    for x in frames {
        let strains =
            metrics::edge_strains(&topology.edges, &topology.rest_lengths, x).map_err(stage())?;
        all.extend(strains.into_iter().filter(|s| !s.is_nan()));
    }
    Ok(all)
}

impl Row for SimulateFigures {
    fn cells(&self) -> Vec<(&'static str, String)> {
        vec![
            ("N", self.vertices.to_string()),
            ("material", self.material.clone()),
            ("frames", self.frames.to_string()),
            ("substeps", self.substeps.to_string()),
            ("s/frame", format!("{:.3}", self.seconds_per_frame)),
            ("Newton/frame", format!("{:.1}", self.newton_iterations)),
            ("PCG/frame", format!("{:.0}", self.pcg_iterations)),
            ("strain mean %", format!("{:.3}", 100.0 * self.strain_mean)),
            ("strain p99 %", format!("{:.3}", 100.0 * self.strain_p99)),
            ("strain max %", format!("{:.2}", 100.0 * self.strain_max)),
            ("max depth mm", format!("{:.2}", self.max_penetration_mm)),
        ]
    }
}
