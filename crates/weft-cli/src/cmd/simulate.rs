//! `weft simulate`: a garment simulated on a body that follows a motion, written as a
//! PC2 point cache, an .npy array `[T, N, 3]` (f32), optionally an OBJ sequence and a USD
//! scene with the body, and a per-frame statistics JSON.

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::path::{Path, PathBuf};
use weft_body::{BodyModel, PosedSequence};
use weft_eval::animate::write_animation;
use weft_eval::skinned::write_skinned_animation;
use weft_mesh::export::{
    remove_obj_sequence, write_obj_sequence, write_pc2, CornerUvs, ExportFormat, Frames, Pc2Timing,
};
use weft_mesh::io::{load_mesh, write_atomic};
use weft_mesh::TriMesh;
use weft_sim::{
    simulate_sequence, Attachment, FrameStats, SequenceError, SequenceOptions, SequenceProgress,
    SimulatedSequence,
};

use super::body_args::BodyArgs;
use super::emit;
use super::motion_args::MotionArgs;

#[derive(Args)]
pub struct SimulateArgs {
    /// The garment's rest mesh (.obj or .ply), fitted to the body in its rest pose (as
    /// `weft garment generate` writes it).
    #[arg(long, value_name = "G.obj")]
    garment: PathBuf,
    #[command(flatten)]
    body: BodyArgs,
    #[command(flatten)]
    motion: MotionArgs,
    /// Output directory (created): frames.pc2, frames.npy, stats.json, obj/ with --obj,
    /// scene.usda with --usd, scene.glb with --glb.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Material: a preset (hood, silk, cotton, jersey, denim, leather) or a TOML file
    /// of its fields (density, young_modulus, poisson_ratio, thickness,
    /// bending_stiffness, friction) laid over HOOD's material.
    #[arg(long, default_value = "cotton", value_name = "NAME|FILE.toml")]
    material: String,
    #[command(flatten)]
    solver: SolverArgs,
    /// Simulate at most this many frames (a procedural motion is generated this long;
    /// default 60).
    #[arg(long, value_parser = super::frame_count)]
    frames: Option<usize>,
    /// Also write an OBJ sequence to DIR/obj/ (with the garment's UVs).
    #[arg(long)]
    obj: bool,
    /// Also write DIR/scene.usda: the garment (with its UVs) and the posed body as
    /// time-sampled USD meshes, Y up, metres, at the motion's frame rate.
    #[arg(long)]
    usd: bool,
    /// Also write DIR/scene.glb: a skinned glTF for game engines — the body's skeleton
    /// animated by the motion, body and garment skinned to it (the garment with weights
    /// transferred from the body), per-frame corrective morph targets making each frame
    /// exact.
    #[arg(long)]
    glb: bool,
    /// Garment vertices that follow the body's skin: `top` (the highest opening — a
    /// waistband or neckline — as a sewn-in elastic would hold it) or `none` (contact
    /// and friction only; loose templates may slide down).
    #[arg(long, value_enum, default_value_t = AttachArg::Top)]
    attach: AttachArg,
    /// Vertex pairs buttoned together, a JSON file `[[a, b], ...]` of 0-based garment
    /// vertex indices: each pair is held by a spring as stiff as the fabric around it
    /// (a jacket's front held closed).
    #[arg(long, value_name = "PAIRS.json")]
    buttons: Option<PathBuf>,
    /// The output frame from which the buttons are undone.
    #[arg(long, value_name = "FRAME", requires = "buttons")]
    unbutton_at: Option<usize>,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum AttachArg {
    Top,
    None,
}

/// Frames a procedural motion gets when --frames is not given.
const DEFAULT_PROCEDURAL_FRAMES: usize = 60;

pub fn run(args: &SimulateArgs) -> Result<()> {
    let material = super::cloth_args::material(&args.material)?;
    let loaded = load_mesh(&args.garment)
        .with_context(|| format!("reading the garment {}", args.garment.display()))?;
    let garment = loaded.mesh;
    let (model, _) = args.body.load()?;
    let betas = args.body.betas(&model)?;
    let motion = args.motion.load(
        &model,
        &betas,
        args.frames.unwrap_or(DEFAULT_PROCEDURAL_FRAMES),
    )?;
    let solver = args.solver.load()?;
    let opts = SequenceOptions {
        max_frames: args.frames.or(solver.max_frames),
        attachment: match args.attach {
            AttachArg::Top => Attachment::TopOpening,
            AttachArg::None => Attachment::None,
        },
        buttons: match &args.buttons {
            Some(path) => {
                let pairs = super::cloth_args::buttons(path)?;
                weft_sim::buttons::check_pairs(&pairs, garment.vertex_count())
                    .with_context(|| format!("--buttons {}", path.display()))?;
                pairs
            }
            None => solver.buttons.clone(),
        },
        unbutton_at: args.unbutton_at.or(solver.unbutton_at),
        ..solver
    };
    // The directory is made when there is something to write (a failed run leaves
    // nothing behind); a path that cannot be one is refused before the simulation.
    if args.out.exists() && !args.out.is_dir() {
        bail!(
            "--out {}: exists and is not a directory; expected a directory for frames.pc2, frames.npy and stats.json",
            args.out.display()
        );
    }

    let total = args
        .frames
        .map_or(motion.frame_count(), |f| f.min(motion.frame_count()));
    let bar = ProgressBar::new(total as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} simulate [{bar:30}] {pos}/{len} frames  {per_sec}  ETA {eta}  {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar.set_message("warming up");
    let result = simulate_sequence(
        &garment,
        &material,
        &model,
        &betas,
        &motion,
        &opts,
        &mut |p| match p {
            SequenceProgress::Warmup { done, total } => {
                bar.set_message(format!("warming up {done}/{total}"));
            }
            SequenceProgress::Frame(s) => {
                bar.set_message(format!(
                    "strain {:.2}% (max {:.1}%)",
                    100.0 * s.mean_edge_strain,
                    100.0 * s.max_edge_strain
                ));
                bar.inc(1);
            }
        },
    );
    bar.finish_and_clear();
    let betas32: Vec<f32> = betas.iter().map(|&b| b as f32).collect();
    let body = BodyScene {
        model: &model,
        betas: &betas32,
        motion: &motion,
    };
    let template = Template {
        mesh: &garment,
        uvs: loaded.corner_uvs.as_deref(),
    };
    let info = Info {
        garment: &args.garment,
        body: model.source(),
        material: material.name,
        motion: &args.motion.motion,
        fps: motion.fps(),
        substeps: opts.substeps,
        warmup: opts.warmup_frames,
    };
    match result {
        Ok(seq) => {
            write_outputs(args, &template, &body, &seq, &info, None)?;
            emit(&summary(args, &seq, &info))
        }
        Err(SequenceError::Diverged {
            frame,
            message,
            finished,
        }) => {
            if !finished.frames.is_empty() {
                write_outputs(
                    args,
                    &template,
                    &body,
                    &finished,
                    &info,
                    Some((frame, &message)),
                )?;
            }
            bail!(
                "the simulation diverged at frame {frame}: {message}; {} finished frames written to {}",
                finished.frames.len(),
                args.out.display()
            )
        }
        Err(e) => Err(e).with_context(|| format!("simulating {}", args.garment.display())),
    }
}

/// `--options`, `--substeps` and `--warmup`: the simulator's settings, for `weft
/// simulate` and `weft bench simulate` alike.
#[derive(Args)]
pub struct SolverArgs {
    /// The simulator's options as TOML (`substeps`, `warmup_frames`, `skinning`, a
    /// `[sim]` table with `[sim.newton]`, …: the keys of `weft_sim::SequenceOptions`),
    /// laid over the defaults; the other flags override it. An unknown key is refused.
    #[arg(long, value_name = "FILE.toml")]
    options: Option<PathBuf>,
    /// Implicit-Euler steps per frame (1 to 100; default 4).
    #[arg(long, value_parser = super::substeps)]
    substeps: Option<usize>,
    /// Warm-up frames before the first output frame (rest pose → first pose; 0 to
    /// 10000, default 15).
    #[arg(long, value_parser = super::warmup_frames)]
    warmup: Option<usize>,
    /// Garment vertices held on the body's skin beside the --attach ones: 0-based
    /// indices and ranges (`0,5,17-30`) or a .txt file of them (e.g. a vertex group
    /// exported from Blender). Added to the `pinned` list of an --options file.
    #[arg(long, value_name = "LIST|FILE.txt")]
    pin: Option<String>,
}

impl SolverArgs {
    /// `SequenceOptions::default()` with the `--options` file laid over it
    /// ([`weft_config::overlay`]: unknown keys refused, naming the file and the key),
    /// then `--substeps`, `--warmup` and `--pin`.
    pub fn load(&self) -> Result<SequenceOptions> {
        let mut opts = SequenceOptions::default();
        if let Some(path) = &self.options {
            let text = weft_mesh::io::read_input_to_string(path)
                .with_context(|| format!("--options {}", path.display()))?;
            let table = weft_config::parse_table(&text)
                .map_err(|message| anyhow::anyhow!("--options {}: {message}", path.display()))?;
            opts = weft_config::overlay(&opts, &table, &path.display().to_string(), "")?;
        }
        if let Some(s) = self.substeps {
            opts.substeps = s;
        }
        if let Some(w) = self.warmup {
            opts.warmup_frames = w;
        }
        if let Some(spec) = &self.pin {
            opts.pinned.extend(super::cloth_args::pinned(spec)?);
        }
        Ok(opts)
    }
}

/// What the run was, for stats.json and the summary.
struct Info<'a> {
    garment: &'a Path,
    body: &'a str,
    material: &'a str,
    motion: &'a str,
    fps: f64,
    substeps: usize,
    warmup: usize,
}

fn totals(seq: &SimulatedSequence) -> serde_json::Value {
    let after: Vec<&FrameStats> = seq.stats.iter().skip(1).collect();
    let n = after.len().max(1) as f64;
    let max = |f: fn(&FrameStats) -> f64| seq.stats.iter().map(f).fold(0.0, f64::max);
    json!({
        "frames": seq.stats.len(),
        "warmup_seconds": seq.stats.first().map_or(0.0, |s| s.seconds),
        "seconds": seq.stats.iter().map(|s| s.seconds).sum::<f64>(),
        "mean_seconds_per_frame": after.iter().map(|s| s.seconds).sum::<f64>() / n,
        "mean_edge_strain": seq.stats.iter().map(|s| s.mean_edge_strain).sum::<f64>()
            / seq.stats.len().max(1) as f64,
        "max_edge_strain": max(|s| s.max_edge_strain),
        "max_penetration": max(|s| s.max_penetration),
        "frames_with_penetration": seq.stats.iter().filter(|s| s.penetrations > 0).count(),
        "newton_iterations": seq.stats.iter().map(|s| s.newton_iterations).sum::<usize>(),
        "cg_iterations": seq.stats.iter().map(|s| s.cg_iterations).sum::<usize>(),
        "pushed_out_at_start": seq.pushed_out,
    })
}

/// The garment's rest mesh and UVs, for the OBJ, USD and glTF outputs.
struct Template<'a> {
    mesh: &'a TriMesh,
    uvs: Option<&'a CornerUvs>,
}

/// The body the garment was simulated on, posed again for the USD scene.
struct BodyScene<'a> {
    model: &'a BodyModel,
    betas: &'a [f32],
    motion: &'a weft_motion::Motion,
}

impl BodyScene<'_> {
    /// The body's vertices at the first `frames` frames of the motion (output frame k is
    /// motion frame k).
    fn frames(&self, frames: usize) -> Result<Vec<Vec<[f32; 3]>>> {
        let posed = PosedSequence::new(
            self.model,
            self.betas,
            &self.motion.poses()[..frames],
            &self.motion.trans()[..frames],
        )?;
        Ok(posed.into_frames())
    }
}

fn write_outputs(
    args: &SimulateArgs,
    template: &Template<'_>,
    body: &BodyScene<'_>,
    seq: &SimulatedSequence,
    info: &Info<'_>,
    diverged: Option<(usize, &str)>,
) -> Result<()> {
    let frames = Frames::from_frames(&seq.frames)?;
    let out = &args.out;
    std::fs::create_dir_all(out)
        .with_context(|| format!("creating the output directory {}", out.display()))?;
    write_pc2(&out.join("frames.pc2"), &frames, Pc2Timing::default())?;
    frames
        .write_npy(&out.join("frames.npy"))
        .with_context(|| format!("writing {}", out.join("frames.npy").display()))?;
    if args.obj {
        write_obj_sequence(
            &out.join("obj"),
            &template.mesh.faces,
            template.uvs,
            &frames,
        )?;
    } else if remove_obj_sequence(&out.join("obj"))? {
        eprintln!(
            "removed {}: the OBJ sequence of an earlier run (this one wrote none; --obj writes one)",
            out.join("obj").display()
        );
    }
    let usd = out.join("scene.usda");
    if args.usd {
        let bodies = body.frames(seq.frames.len())?;
        let body = Some((body.model.faces(), bodies.as_slice()));
        let fps = info.fps;
        write_animation(
            ExportFormat::Usd,
            template.mesh,
            template.uvs,
            &seq.frames,
            fps,
            body,
            &usd,
        )?;
    }
    let glb = out.join("scene.glb");
    if args.glb {
        write_skinned_animation(
            template.mesh,
            template.uvs,
            &seq.frames,
            body.model,
            body.betas,
            body.motion,
            &glb,
        )?;
    }
    for (path, wanted, flag) in [(&usd, args.usd, "--usd"), (&glb, args.glb, "--glb")] {
        if !wanted && path.is_file() {
            std::fs::remove_file(path).with_context(|| format!("removing {}", path.display()))?;
            eprintln!(
                "removed {}: the scene of an earlier run (this one wrote none; {flag} writes one)",
                path.display()
            );
        }
    }
    let stats = json!({
        "garment": info.garment.display().to_string(),
        "body": info.body,
        "betas": args.body.betas,
        "material": info.material,
        "motion": info.motion,
        "fps": info.fps,
        "substeps": info.substeps,
        "warmup_frames": info.warmup,
        "vertices": frames.vertex_count(),
        "diverged": diverged.map(|(frame, message)| json!({"frame": frame, "message": message})),
        "totals": totals(seq),
        "frames": seq.stats,
    });
    let text = serde_json::to_string_pretty(&stats)?;
    let path = out.join("stats.json");
    write_atomic(&path, |w| w.write_all(text.as_bytes()))
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

fn summary(args: &SimulateArgs, seq: &SimulatedSequence, info: &Info<'_>) -> String {
    let t = totals(seq);
    let get = |k: &str| t[k].as_f64().unwrap_or(0.0);
    format!(
        "wrote {}: {} frames of {} vertices ({}, {} sub-steps at {} fps); {:.3} s per frame after a {:.1} s warm-up; edge strain mean {:.3}% max {:.2}%; deepest penetration {:.2} mm",
        args.out.display(),
        seq.frames.len(),
        seq.frames.first().map_or(0, Vec::len),
        info.material,
        info.substeps,
        info.fps,
        get("mean_seconds_per_frame"),
        get("warmup_seconds"),
        100.0 * get("mean_edge_strain"),
        100.0 * get("max_edge_strain"),
        1e3 * get("max_penetration"),
    )
}
