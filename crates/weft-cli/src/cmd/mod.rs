//! Subcommands, one module each.

mod animate;
mod attribute;
mod body;
mod body_args;
mod config;
mod data;
mod demo;
mod eval;
mod export;
mod garment;
mod mesh;
mod motion;
mod render;
mod simulate;
mod train;

use clap::Subcommand;

#[derive(Subcommand)]
pub enum Command {
    /// Start here: builds the tiny dataset, trains the cpu preset, evaluates it against
    /// the LBS-only baseline, animates an unseen garment and writes a report (in
    /// ./weft-demo unless --out says otherwise; about 20 minutes).
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
