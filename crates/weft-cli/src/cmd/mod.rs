//! Subcommands, one module each.

mod animate;
mod attribute;
mod bench;
mod body;
mod body_args;
mod cloth_args;
mod config;
mod data;
mod demo;
mod eval;
mod export;
mod garment;
mod hood_args;
mod mesh;
mod motion;
mod motion_args;
mod render;
mod simulate;
mod train;

use clap::Subcommand;

#[derive(Subcommand)]
pub enum Command {
    /// Start here: builds the tiny dataset, trains the cpu preset, evaluates it against
    /// the LBS-only baseline, animates an unseen garment and writes a report (in
    /// ./weft-demo unless --out says otherwise; about 7 minutes on two cores).
    Demo(demo::DemoArgs),
    /// Inspect meshes and build their multilevel graph hierarchies.
    #[command(subcommand)]
    Mesh(mesh::MeshCommand),
    /// The SMPL-format body: inspect, shape, pose, and import the default body.
    #[command(subcommand)]
    Body(body::BodyCommand),
    /// Generate procedural motions and inspect motion files (AMASS .npz, BVH).
    #[command(subcommand)]
    Motion(motion::MotionCommand),
    /// Draw a mesh or a directory of frames to PNG, optionally over a body and coloured
    /// by one value per vertex.
    Render(render::RenderArgs),
    /// Procedural garment templates (skirts, dresses, tops, shorts, pants, jumpsuits)
    /// fitted to a body.
    #[command(subcommand)]
    Garment(garment::GarmentCommand),
    /// Write a frame sequence as an OBJ sequence, PC2/MDD point cache or glTF binary.
    Export(export::ExportArgs),
    /// Simulate a garment on a body following a motion (ground truth): PC2, .npy,
    /// OBJ sequence and per-frame statistics.
    Simulate(simulate::SimulateArgs),
    /// Simulated datasets: generate (resumable, shardable), info, merge.
    #[command(subcommand)]
    Data(data::DataCommand),
    /// Train the Multilevel model on a dataset (two-step schedule, resumable checkpoints).
    Train(train::TrainArgs),
    /// Model and training configurations: `weft config show --preset cpu|paper`.
    #[command(subcommand)]
    Config(config::ConfigCommand),
    /// Evaluate a trained run against the simulated ground truth and the LBS-only
    /// baseline (RUN/report/), or compare runs as Table 1 (--compare).
    Eval(eval::EvalArgs),
    /// Attribution of one output vertex (seed 000 eq. 9) drawn as a heat map.
    Attribute(attribute::AttributeArgs),
    /// Animate any garment on a body shape and motion with a trained run; export as
    /// OBJ sequence, PC2/MDD or glTF binary.
    Animate(animate::AnimateArgs),
    /// What the networks and the simulator cost on this machine, per stage: a Markdown
    /// table or JSON lines (`weft bench multilevel|gat|simulate`).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Demo(a) => demo::run(&a),
        Command::Mesh(c) => mesh::run(c),
        Command::Body(c) => body::run(c),
        Command::Motion(c) => motion::run(c),
        Command::Render(a) => render::run(&a),
        Command::Export(a) => export::run(&a),
        Command::Simulate(a) => simulate::run(&a),
        Command::Garment(c) => garment::run(c),
        Command::Data(c) => data::run(c),
        Command::Train(a) => train::run(&a),
        Command::Config(c) => config::run(c),
        Command::Eval(a) => eval::run(&a),
        Command::Attribute(a) => attribute::run(&a),
        Command::Animate(a) => animate::run(&a),
        Command::Bench(c) => bench::run(c),
    }
}

/// Writes a command's output to stdout. A closed pipe (`weft … | head`) is the reader's
/// choice, not an error, so it ends the command quietly instead of panicking.
pub fn emit(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    let written = stdout.write_all(text.as_bytes()).and_then(|()| {
        if text.ends_with('\n') {
            Ok(())
        } else {
            stdout.write_all(b"\n")
        }
    });
    match written.and_then(|()| stdout.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// Whether `path` ends in one of `extensions` (without the dot, any case): the one
/// extension test of every command, so that `OUT.PNG` and `out.png` are alike everywhere.
pub fn has_extension(path: &std::path::Path, extensions: &[&str]) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| extensions.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// The value parser of every `--fps`: a frame rate above 0 and at most
/// [`weft_motion::MAX_FPS`], refused by clap naming the flag (`invalid value '-3' for
/// '--fps <FPS>': …`) rather than later by the motion code in words that name none.
pub fn frame_rate(text: &str) -> Result<f64, String> {
    let fps: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if fps.is_finite() && fps > 0.0 && fps <= weft_motion::MAX_FPS {
        Ok(fps)
    } else {
        Err(format!(
            "expected frames per second above 0 and at most {}",
            weft_motion::MAX_FPS
        ))
    }
}

/// The value parser of a frame count: 1 to [`weft_motion::MAX_FRAMES`].
pub fn frame_count(text: &str) -> Result<usize, String> {
    count(text, 1, weft_motion::MAX_FRAMES, "frames")
}

/// The value parser of a count from `min` to `max` (`what`: its unit, plural).
fn count(text: &str, min: usize, max: usize, what: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number"))?;
    if (min..=max).contains(&n) {
        Ok(n)
    } else {
        Err(format!("expected {min} to {max} {what}"))
    }
}

/// The value parser of a simulation's warm-up: 0 to [`weft_sim::MAX_WARMUP_FRAMES`]
/// frames.
pub fn warmup_frames(text: &str) -> Result<usize, String> {
    count(text, 0, weft_sim::MAX_WARMUP_FRAMES, "warm-up frames")
}

/// The value parser of sub-steps per frame: 1 to [`weft_sim::MAX_SUBSTEPS`].
pub fn substeps(text: &str) -> Result<usize, String> {
    count(text, 1, weft_sim::MAX_SUBSTEPS, "sub-steps per frame")
}

/// The value parser of a finite number above 0 (a scale, a speed).
pub fn positive(text: &str) -> Result<f64, String> {
    let x: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err("expected a finite number above 0".into())
    }
}

/// The value parser of a procedural motion's amplitude: 0 to
/// [`weft_motion::MAX_AMPLITUDE`].
pub fn amplitude(text: &str) -> Result<f64, String> {
    let x: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if x.is_finite() && (0.0..=weft_motion::MAX_AMPLITUDE).contains(&x) {
        Ok(x)
    } else {
        Err(format!("expected 0 to {}", weft_motion::MAX_AMPLITUDE))
    }
}
