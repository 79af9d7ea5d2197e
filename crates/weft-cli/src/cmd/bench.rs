//! `weft bench`: what weft's networks and simulator cost on this machine, from the
//! release binary, as a Markdown table (one row per measured configuration, printed as
//! it is measured) or `--json` (one object per configuration per line, for scripts that
//! compare weft with other tools). The measurements live in weft-bench.

use anyhow::{Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use weft_bench::densegats::DenseGatsBench;
use weft_bench::garfitnet::GarFitNetBench;
use weft_bench::gat::GatBench;
use weft_bench::hood::HoodBench;
use weft_bench::multilevel::MultilevelBench;
use weft_bench::multiresgnet::MultiResGnetBench;
use weft_bench::simulate::bench_simulate;
use weft_bench::{BenchDevice, Row};
use weft_mesh::io::load_mesh;
use weft_sim::SequenceOptions;

use super::body_args::BodyModelArg;
use super::emit;
use super::motion_args::MotionArgs;
use super::simulate::SolverArgs;

#[derive(Subcommand)]
pub enum BenchCommand {
    /// The Multilevel model per stage (inputs, E^t1, E^t2, M^mp, LBS) in ms per frame,
    /// with the embedding GEMM's floor and rate; --train adds a training step.
    Multilevel(MultilevelArgs),
    /// One GAT layer, fused kernel against burn's generic path, forward and backward.
    Gat(GatArgs),
    /// DenseGATs (seed 001 §3.2) on a character, one frame per stage (pose inputs, input
    /// transform, each dense module, output transform) in ms, with the linear maps' floor.
    Densegats(RefineArgs),
    /// MultiResGNet (seed 001 §3.3) on the same character, one frame per stage (pose
    /// inputs, input transform, local branch, global branch, output transform) in ms.
    Multiresgnet(RefineArgs),
    /// GarFitNet (seed 001 ch. 4) on the benchmark skirt, one frame per stage (posed body,
    /// coarse regressor, refinement; the pair's one-off preparation apart) in ms.
    Garfitnet(RefineArgs),
    /// HOOD (seed 004) on the benchmark skirt over the walking body, one rollout step per
    /// stage (step graph, inputs, network, whole step) in ms, at each batch of garments
    /// advanced together; the scene's one-off preparation apart.
    Hood(HoodArgs),
    /// The cloth simulator: seconds, Newton and PCG iterations per frame, edge strain
    /// and depth in the body.
    Simulate(SimulateArgs),
}

/// The device a network bench runs on.
#[derive(Clone, Copy, ValueEnum)]
pub enum DeviceArg {
    /// burn's flex CPU backend, with weft's fused kernels.
    Cpu,
    /// burn's wgpu backend on the default GPU adapter (generic tensor path); needs a
    /// binary built with `--features wgpu`.
    Wgpu,
}

impl From<DeviceArg> for BenchDevice {
    fn from(d: DeviceArg) -> Self {
        match d {
            DeviceArg::Cpu => BenchDevice::Cpu,
            DeviceArg::Wgpu => BenchDevice::Wgpu,
        }
    }
}

/// What every bench takes.
#[derive(Args)]
pub struct Common {
    #[command(flatten)]
    body: BodyModelArg,
    /// Print one JSON object per measured configuration, one per line.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
pub struct MultilevelArgs {
    /// Model preset: cpu or paper.
    #[arg(long, default_value = "cpu")]
    preset: String,
    /// Vertices of the benchmark skirt (several: 1000,4000,12000).
    #[arg(long, value_delimiter = ',', default_value = "4000")]
    vertices: Vec<usize>,
    /// Frames inferred together (several: 1,16).
    #[arg(long, value_delimiter = ',', default_value = "1,16")]
    batch: Vec<usize>,
    /// Timed runs per figure, after one warm-up (the median is reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    reps: u32,
    /// Also time one training step (forward, loss terms, backward, Adamax) per window
    /// of --batch frames.
    #[arg(long)]
    train: bool,
    /// Device: cpu (flex) or wgpu (a binary built with `--features wgpu`).
    #[arg(long, value_enum, default_value = "cpu")]
    device: DeviceArg,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
pub struct GatArgs {
    /// Vertices of the skirt whose mesh graph the layer runs on.
    #[arg(long, default_value_t = 4000)]
    vertices: usize,
    /// Input channels.
    #[arg(long, default_value_t = 32)]
    input: usize,
    /// Attention heads.
    #[arg(long, default_value_t = 4)]
    heads: usize,
    /// Output channels per head.
    #[arg(long, default_value_t = 32)]
    channels: usize,
    /// Timed runs per figure, after one warm-up (the median is reported).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10000))]
    reps: u32,
    /// Device: cpu (flex; fused and generic paths) or wgpu (generic path; a binary built
    /// with `--features wgpu`).
    #[arg(long, value_enum, default_value = "cpu")]
    device: DeviceArg,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
pub struct RefineArgs {
    /// Model preset: cpu or paper.
    #[arg(long, default_value = "paper")]
    preset: String,
    /// Vertices of the character (several: 10000,17000).
    #[arg(long, value_delimiter = ',', default_value = "10000")]
    vertices: Vec<usize>,
    /// Timed runs per figure, after one warm-up (the median is reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=10000))]
    reps: u32,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
pub struct HoodArgs {
    /// Model preset: cpu or paper.
    #[arg(long, default_value = "paper")]
    preset: String,
    /// Message-passing schedule in place of the preset's, as `[model] schedule` writes
    /// it: "0 x15" is Fine15, "0 x48" Fine48 (seed 004 Table 1).
    #[arg(long, value_name = "STEPS")]
    schedule: Option<String>,
    /// Vertices of the skirt (several: 4000,12000).
    #[arg(long, value_delimiter = ',', default_value = "4000")]
    vertices: Vec<usize>,
    /// Garments advanced in one forward pass (several: 1,16).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    batch: Vec<usize>,
    /// Timed runs per figure, after one warm-up (the median is reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=10000))]
    reps: u32,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
pub struct SimulateArgs {
    /// The garment (.obj/.ply) fitted to the body in its rest pose; default: a skirt of
    /// --vertices vertices.
    #[arg(long, value_name = "G.obj", conflicts_with = "vertices")]
    garment: Option<std::path::PathBuf>,
    /// Vertices of the generated skirt when no --garment is given.
    #[arg(long, default_value_t = 4000)]
    vertices: usize,
    #[command(flatten)]
    motion: MotionArgs,
    /// Material: a preset (hood, silk, cotton, jersey, denim, leather) or a TOML file of
    /// its fields (see `weft simulate --help`).
    #[arg(long, default_value = "silk", value_name = "NAME|FILE.toml")]
    material: String,
    /// Frames to simulate after the warm-up.
    #[arg(long, default_value_t = 30, value_parser = super::frame_count)]
    frames: usize,
    #[command(flatten)]
    solver: SolverArgs,
    #[command(flatten)]
    common: Common,
}

pub fn run(command: BenchCommand) -> Result<()> {
    match command {
        BenchCommand::Multilevel(a) => multilevel(&a),
        BenchCommand::Gat(a) => gat(&a),
        BenchCommand::Densegats(a) => densegats(&a),
        BenchCommand::Garfitnet(a) => garfitnet(&a),
        BenchCommand::Hood(a) => hood(&a),
        BenchCommand::Multiresgnet(a) => multiresgnet(&a),
        BenchCommand::Simulate(a) => simulate(&a),
    }
}

fn multilevel(args: &MultilevelArgs) -> Result<()> {
    let device = BenchDevice::from(args.device);
    device.check()?;
    let (body, _) = args.common.body.load()?;
    let mut out = Output::new(args.common.json);
    for &vertices in &args.vertices {
        for &batch in &args.batch {
            let bench = MultilevelBench {
                preset: args.preset.clone(),
                vertices,
                batch,
                reps: args.reps as usize,
                train: args.train,
                device,
            };
            let label = format!(
                "multilevel {} N≈{vertices} T={batch} on {device}",
                args.preset
            );
            let spinner = spinner(&label);
            let figures = bench.run(&body, &mut |stage| spinner.set_message(stage.to_string()));
            spinner.finish_and_clear();
            out.row(&figures.with_context(|| label.clone())?)?;
        }
    }
    Ok(())
}

fn gat(args: &GatArgs) -> Result<()> {
    let device = BenchDevice::from(args.device);
    device.check()?;
    let (body, _) = args.common.body.load()?;
    let bench = GatBench {
        vertices: args.vertices,
        input: args.input,
        heads: args.heads,
        channels: args.channels,
        reps: args.reps as usize,
        device,
    };
    let spinner = spinner("gat");
    let figures = bench.run(&body, &mut |stage| spinner.set_message(stage.to_string()));
    spinner.finish_and_clear();
    let mut out = Output::new(args.common.json);
    for f in figures? {
        out.row(&f)?;
    }
    Ok(())
}

fn densegats(args: &RefineArgs) -> Result<()> {
    let (body, _) = args.common.body.load()?;
    let mut out = Output::new(args.common.json);
    for &vertices in &args.vertices {
        let bench = DenseGatsBench {
            preset: args.preset.clone(),
            vertices,
            reps: args.reps as usize,
        };
        let label = format!("densegats {} N≈{vertices}", args.preset);
        let spinner = spinner(&label);
        let figures = bench.run(&body, &mut |stage| spinner.set_message(stage.to_string()));
        spinner.finish_and_clear();
        out.row(&figures.with_context(|| label.clone())?)?;
    }
    Ok(())
}

fn multiresgnet(args: &RefineArgs) -> Result<()> {
    let (body, _) = args.common.body.load()?;
    let mut out = Output::new(args.common.json);
    for &vertices in &args.vertices {
        let bench = MultiResGnetBench {
            preset: args.preset.clone(),
            vertices,
            reps: args.reps as usize,
        };
        let label = format!("multiresgnet {} N≈{vertices}", args.preset);
        let spinner = spinner(&label);
        let figures = bench.run(&body, &mut |stage| spinner.set_message(stage.to_string()));
        spinner.finish_and_clear();
        out.row(&figures.with_context(|| label.clone())?)?;
    }
    Ok(())
}

fn garfitnet(args: &RefineArgs) -> Result<()> {
    let (body, _) = args.common.body.load()?;
    let mut out = Output::new(args.common.json);
    for &vertices in &args.vertices {
        let bench = GarFitNetBench {
            preset: args.preset.clone(),
            vertices,
            reps: args.reps as usize,
        };
        let label = format!("garfitnet {} N≈{vertices}", args.preset);
        let spinner = spinner(&label);
        let figures = bench.run(&body, &mut |stage| spinner.set_message(stage.to_string()));
        spinner.finish_and_clear();
        out.row(&figures.with_context(|| label.clone())?)?;
    }
    Ok(())
}

fn hood(args: &HoodArgs) -> Result<()> {
    let (body, _) = args.common.body.load()?;
    let mut out = Output::new(args.common.json);
    for &vertices in &args.vertices {
        for &batch in &args.batch {
            let bench = HoodBench {
                preset: args.preset.clone(),
                schedule: args.schedule.clone(),
                vertices,
                batch,
                reps: args.reps as usize,
            };
            let label = format!("hood {} N≈{vertices} batch {batch}", args.preset);
            let spinner = spinner(&label);
            let figures = bench.run(&body, &mut |stage| spinner.set_message(stage.to_string()));
            spinner.finish_and_clear();
            out.row(&figures.with_context(|| label.clone())?)?;
        }
    }
    Ok(())
}

fn simulate(args: &SimulateArgs) -> Result<()> {
    let material = super::cloth_args::material(&args.material)?;
    let (body, _) = args.common.body.load()?;
    let garment = match &args.garment {
        Some(path) => {
            load_mesh(path)
                .with_context(|| format!("reading the garment {}", path.display()))?
                .mesh
        }
        None => weft_bench::skirt(&body, args.vertices).context("--vertices")?,
    };
    let motion = args.motion.load(&body, &[], args.frames)?;
    let opts = SequenceOptions {
        max_frames: Some(args.frames),
        ..args.solver.load()?
    };
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} bench simulate [{bar:30}] {pos}/{len} frames  ETA {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let figures = bench_simulate(
        &garment,
        &material,
        &body,
        &motion,
        &opts,
        &mut |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    );
    bar.finish_and_clear();
    Output::new(args.common.json).row(&figures?)
}

/// A spinner on stderr saying which stage runs.
fn spinner(label: &str) -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template(&format!("{{spinner}} bench {label}: {{msg}}  {{elapsed}}"))
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

/// Rows as they come: a Markdown table (header before the first row) or JSON lines.
struct Output {
    json: bool,
    header: bool,
}

impl Output {
    fn new(json: bool) -> Self {
        Output {
            json,
            header: false,
        }
    }

    fn row<R: Row + Serialize>(&mut self, row: &R) -> Result<()> {
        if self.json {
            return emit(&serde_json::to_string(row)?);
        }
        let cells = row.cells();
        if !self.header {
            self.header = true;
            let names: Vec<&str> = cells.iter().map(|(name, _)| *name).collect();
            emit(&format!("| {} |", names.join(" | ")))?;
            emit(&format!("|{}", "---|".repeat(names.len())))?;
        }
        let values: Vec<&str> = cells.iter().map(|(_, v)| v.as_str()).collect();
        emit(&format!("| {} |", values.join(" | ")))
    }
}
