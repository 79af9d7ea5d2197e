//! `weft animate`: a trained model drives any garment (unseen topology included) on a
//! body shape through a motion, written as an OBJ sequence, PC2/MDD point cache or glTF
//! binary.

use anyhow::{Context, Result};
use clap::Args;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;
use weft_eval::animate::{animate, write_animation, MotionSpec};
use weft_eval::PosedBodies;
use weft_mesh::export::ExportFormat;
use weft_models::multilevel::Predictor;

use super::emit;

#[derive(Args)]
pub struct AnimateArgs {
    /// Run directory written by `weft train`.
    #[arg(value_name = "RUN")]
    run: PathBuf,
    /// The garment (.obj/.ply), any topology, dressed on the body at --betas in its rest
    /// pose (e.g. from `weft garment generate`).
    #[arg(long, value_name = "G.obj")]
    garment: PathBuf,
    /// An SMPL-format body model (.npz); weft's default body when left out.
    #[arg(long, value_name = "FILE")]
    body: Option<PathBuf>,
    /// Shape β (comma separated), zeros when left out.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    betas: Vec<f32>,
    /// The motion: an AMASS .npz or .bvh file, or a procedural name (walk, run, jump,
    /// dance, kick, …).
    #[arg(long, value_name = "FILE|NAME")]
    motion: String,
    /// Procedural motions: number of frames.
    #[arg(long, default_value_t = 120)]
    frames: usize,
    /// Procedural motions: seed of the variations.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Procedural motions: frames per second.
    #[arg(long, default_value_t = 30.0)]
    fps: f64,
    /// Output: a directory for obj, a file otherwise.
    #[arg(long, value_name = "PATH")]
    out: PathBuf,
    /// obj, pc2, mdd or glb (glb also holds the animated body).
    #[arg(long, value_name = "obj|pc2|mdd|glb")]
    format: String,
    /// Print one JSON object describing what was written.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &AnimateArgs) -> Result<()> {
    let format: ExportFormat = args.format.parse()?;
    let predictor = Predictor::load(&args.run)
        .with_context(|| format!("loading run {}", args.run.display()))?;
    let garment = weft_mesh::read_mesh(&args.garment)
        .with_context(|| format!("reading the garment {}", args.garment.display()))?;
    let body = weft_data::generate::load_body(args.body.as_deref())?;
    let motion = MotionSpec::parse(&args.motion, args.frames, args.seed, args.fps)?
        .load(&body, &args.betas)?;
    let started = Instant::now();
    let frames = animate(&predictor, &garment, &body, &args.betas, &motion)?;
    let seconds = started.elapsed().as_secs_f64();
    let poses = weft_eval::animate::flat_poses(&motion);
    let bodies = if format == ExportFormat::Glb {
        let posed = PosedBodies::new(&body, &args.betas, &poses, motion.trans())?;
        Some(
            (0..posed.len())
                .filter_map(|t| posed.mesh(t))
                .map(|m| {
                    m.positions
                        .iter()
                        .map(|p| p.map(|x| x as f32))
                        .collect::<Vec<[f32; 3]>>()
                })
                .collect::<Vec<_>>(),
        )
    } else {
        None
    };
    write_animation(
        format,
        &garment,
        &frames,
        motion.fps(),
        bodies.as_ref().map(|b| (body.faces(), b.as_slice())),
        &args.out,
    )?;
    if args.json {
        emit(&serde_json::to_string_pretty(&json!({
            "out": args.out,
            "format": format.name(),
            "frames": frames.len(),
            "vertices": garment.vertex_count(),
            "fps": motion.fps(),
            "inference_seconds": seconds,
        }))?)?;
    } else {
        emit(&format!(
            "wrote {} ({}, {} frames of {} vertices at {} fps; inference {:.2} s, {:.1} frames/s)",
            args.out.display(),
            format,
            frames.len(),
            garment.vertex_count(),
            motion.fps(),
            seconds,
            frames.len() as f64 / seconds.max(1e-9)
        ))?;
    }
    Ok(())
}
