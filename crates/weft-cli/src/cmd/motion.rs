//! `weft motion generate`, `weft motion info` and `weft motion convert`.

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use serde_json::json;
use std::fmt::Write as _;
use std::path::PathBuf;
use weft_body::joints::SMPL_JOINT_COUNT;
use weft_motion::{
    body_rest_joints, generate, load_motion, motion_stats, write_motion, BvhUnits, LoadedMotion,
    MapChoice, MotionFileOptions, MotionFormat, MotionKind, MotionSource, NameMap,
    ProceduralParams, SkeletonPreset, UpAxis,
};

use super::body_args::BodyArgs;
use super::emit;
use super::motion_args::Up;

#[derive(Subcommand)]
pub enum MotionCommand {
    /// Generate a procedural motion (walk, run, jump, dance, kick, raise-arms, twist, bow)
    /// and write it as AMASS-style .npz or as BVH on the SMPL skeleton.
    Generate(GenerateArgs),
    /// Frames, frame rate, duration, range of motion per joint and root path of an .npz
    /// or .bvh motion (BVH files are retargeted to SMPL's 24 joints first).
    Info(InfoArgs),
    /// Convert a motion between BVH and AMASS-style .npz (either way, or .npz to .npz to
    /// change the up axis, .bvh to .bvh to put it on the SMPL skeleton), optionally
    /// resampled with --fps. Goes through SMPL's 24 joints, as every command reads motions.
    Convert(ConvertArgs),
}

#[derive(Args)]
pub struct GenerateArgs {
    /// The motion: walk, run, jump, dance, kick, raise-arms, twist or bow.
    #[arg(long, value_parser = parse_kind)]
    kind: MotionKind,
    /// Number of frames.
    #[arg(long, default_value_t = 120, value_parser = super::frame_count)]
    frames: usize,
    /// Frames per second.
    #[arg(long, default_value_t = 30.0, value_parser = super::frame_rate)]
    fps: f64,
    /// Seed of the small random variations (phase, tempo, amplitude, posture).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Forward speed in m/s for walk (default 1.2) and run (default 3.0); a tempo factor
    /// for the other kinds (default 1).
    #[arg(long, value_parser = super::positive)]
    speed: Option<f64>,
    /// Scales every joint excursion; 1 is natural, 0 stands still, at most 3.
    #[arg(long, default_value_t = 1.0, value_parser = super::amplitude)]
    amplitude: f64,
    /// Output file: .npz (AMASS layout) or .bvh (SMPL skeleton, metres, Y up).
    #[arg(long)]
    out: PathBuf,
    /// Up axis of an .npz output: z as AMASS stores it, or y as weft works.
    #[arg(long, value_enum, default_value_t = Up::Z)]
    npz_up: Up,
    #[command(flatten)]
    body: BodyArgs,
}

/// The rest joints J(β) of the body a motion file is written or read against: they
/// shape the BVH skeleton, the retargeting target and the placement of AMASS's root.
fn rest_joints(body: &BodyArgs) -> Result<[[f64; 3]; SMPL_JOINT_COUNT]> {
    let (model, _) = body.load()?;
    Ok(body_rest_joints(&model, &body.betas(&model)?)?)
}

#[derive(Args)]
pub struct InfoArgs {
    /// An .npz (AMASS layout) or .bvh motion.
    file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    read: ReadArgs,
}

#[derive(Args)]
pub struct ConvertArgs {
    /// The motion to read: .npz (AMASS layout) or .bvh.
    #[arg(value_name = "IN")]
    input: PathBuf,
    /// The file to write: .npz (AMASS layout) or .bvh (SMPL skeleton, metres, Y up).
    /// Written atomically.
    #[arg(value_name = "OUT")]
    output: PathBuf,
    /// Up axis of an .npz output: z as AMASS stores it, or y as weft works.
    #[arg(long, value_enum, default_value_t = Up::Z)]
    npz_up: Up,
    /// Print one JSON object describing what was written.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    read: ReadArgs,
}

/// How a motion file is read: its up axis, BVH name map and unit, the frame rate to
/// resample to, and the body whose rest joints it is read against.
#[derive(Args)]
struct ReadArgs {
    /// The file's up axis (default: z for .npz as in AMASS, y for .bvh).
    #[arg(long, value_enum)]
    up: Option<Up>,
    /// BVH joint-name map: a preset (smpl, mixamo, cmu, mpfb) or a .toml/.json file of
    /// BVH name = SMPL name; default: the preset that fits the file best.
    #[arg(long)]
    map: Option<String>,
    /// BVH length unit in metres per file unit (0.01 for centimetres); default: guessed
    /// from the skeleton's size.
    #[arg(long, value_parser = super::positive)]
    scale: Option<f64>,
    /// Frames per second: a file recording another rate is resampled to it (said on
    /// stderr), an .npz recording none is taken to run at it.
    #[arg(long, value_parser = super::frame_rate)]
    fps: Option<f64>,
    #[command(flatten)]
    body: BodyArgs,
}

impl ReadArgs {
    /// The options for `file` (its format picks which of --up applies).
    fn options(&self, file: &std::path::Path) -> Result<MotionFileOptions> {
        let format = MotionFormat::from_path(file)?;
        let mut options = MotionFileOptions {
            rest_joints: rest_joints(&self.body)?,
            ..MotionFileOptions::default()
        };
        if let Some(up) = self.up {
            match format {
                MotionFormat::Npz => options.npz_up = Some(up.into()),
                MotionFormat::Bvh => options.bvh_up = up.into(),
            }
        }
        if let Some(map) = &self.map {
            options.bvh_map = match SkeletonPreset::parse(map) {
                Some(p) => MapChoice::Preset(p),
                None => {
                    // A name that is no file and has no name-map extension is a mistyped
                    // preset, not a missing file.
                    let path = std::path::Path::new(map);
                    if !path.exists() && !super::has_extension(path, &["toml", "json"]) {
                        let presets: Vec<&str> =
                            SkeletonPreset::ALL.iter().map(|p| p.name()).collect();
                        bail!(
                            "--map {map}: neither a preset ({}) nor a .toml or .json name-map file",
                            presets.join(", ")
                        );
                    }
                    MapChoice::Custom(NameMap::read(path).context("--map")?)
                }
            };
        }
        if let Some(scale) = self.scale {
            options.bvh_units = BvhUnits::MetresPerUnit(scale);
        }
        Ok(options)
    }

    /// Reads `file`, reporting notes and a resampling on stderr.
    fn load(&self, file: &std::path::Path) -> Result<(LoadedMotion, MotionFileOptions)> {
        let options = self.options(file)?;
        let read = load_motion(file, &options, self.fps)?;
        super::motion_args::report(file, &read);
        Ok((read, options))
    }
}

pub fn run(command: MotionCommand) -> Result<()> {
    match command {
        MotionCommand::Generate(a) => generate_cmd(&a),
        MotionCommand::Info(a) => info(&a),
        MotionCommand::Convert(a) => convert(&a),
    }
}

fn parse_kind(s: &str) -> Result<MotionKind, String> {
    MotionKind::parse(s).ok_or_else(|| {
        let names: Vec<&str> = MotionKind::ALL.iter().map(|k| k.name()).collect();
        format!("unknown motion '{s}'; expected one of {}", names.join(", "))
    })
}

fn generate_cmd(args: &GenerateArgs) -> Result<()> {
    // Fail on the output's extension before generating anything.
    MotionFormat::from_path(&args.out)?;
    let params = ProceduralParams {
        kind: args.kind,
        frames: args.frames,
        fps: args.fps,
        seed: args.seed,
        speed: args.speed,
        amplitude: args.amplitude,
    };
    // What the parsers cannot know is the kind's own speed range.
    let motion = generate(&params).with_context(|| match args.speed {
        Some(s) => format!("--speed {s} for {}", args.kind),
        None => format!("generating {}", args.kind),
    })?;
    let options = MotionFileOptions {
        npz_up: Some(args.npz_up.into()),
        rest_joints: rest_joints(&args.body)?,
        ..MotionFileOptions::default()
    };
    write_motion(&args.out, &motion, &options)?;
    let speed = args.speed.unwrap_or(args.kind.default_speed());
    let speed = if args.kind.is_locomotion() {
        format!("{speed} m/s")
    } else {
        format!("tempo ×{speed}")
    };
    emit(&format!(
        "wrote {}: {}, {} frames at {} fps ({:.3} s), seed {}, {speed}, amplitude {}",
        args.out.display(),
        args.kind,
        motion.frame_count(),
        motion.fps(),
        motion.duration(),
        args.seed,
        args.amplitude
    ))
}

fn convert(args: &ConvertArgs) -> Result<()> {
    // Fail on the output's extension before reading anything.
    let out_format = MotionFormat::from_path(&args.output).context("OUT")?;
    let (read, read_options) = args.read.load(&args.input)?;
    let motion = read.motion;
    let options = MotionFileOptions {
        npz_up: Some(args.npz_up.into()),
        ..read_options
    };
    write_motion(&args.output, &motion, &options)?;
    let format = match out_format {
        MotionFormat::Npz => "npz",
        MotionFormat::Bvh => "bvh",
    };
    if args.json {
        return emit(&serde_json::to_string_pretty(&json!({
            "in": args.input,
            "out": args.output,
            "format": format,
            "frames": motion.frame_count(),
            "fps": motion.fps(),
            "resampled_from_fps": read.resampled_from.map(|(fps, _)| fps),
            "npz_up": (out_format == MotionFormat::Npz).then(|| up_name(args.npz_up.into())),
        }))?);
    }
    let up = match out_format {
        MotionFormat::Npz => format!(", {} up", up_name(args.npz_up.into())),
        MotionFormat::Bvh => ", SMPL skeleton, Y up".to_owned(),
    };
    emit(&format!(
        "wrote {} ({format}{up}): {} frames at {} fps ({:.3} s)",
        args.output.display(),
        motion.frame_count(),
        motion.fps(),
        motion.duration()
    ))
}

fn info(args: &InfoArgs) -> Result<()> {
    // Notes and warnings go to stderr, so stdout stays one parseable report.
    let (read, _) = args.read.load(&args.file)?;
    let (motion, source) = (read.motion, read.source);
    let stats = motion_stats(&motion);

    if args.json {
        let source_json = match &source {
            MotionSource::Amass(r) => json!({
                "format": "npz",
                "layout": r.layout.name(),
                "up": r.up.name(),
                "up_from": r.up_from.phrase(),
                "frame_rate_key": r.frame_rate_key,
                "dropped_joints": r.dropped_joints,
                "unused_keys": r.unused_keys,
            }),
            MotionSource::Bvh(r) => json!({
                "format": "bvh",
                "map": r.map,
                "unit": r.unit,
                "metres_per_unit": r.metres_per_unit,
                "rest_extent_m": r.rest_extent,
                "root_scale": r.root_scale,
                "unmapped_smpl_joints": r.unmapped,
                "unused_bvh_joints": r.unused,
                "warnings": r.warnings,
            }),
        };
        let out = json!({
            "file": args.file,
            "frames": stats.frames,
            "fps": stats.fps,
            "duration_s": stats.duration,
            "joint_count": stats.joints.len(),
            "betas": stats.betas,
            "root_path_length_m": stats.root_path_length,
            "root_displacement_m": stats.root_displacement,
            "joints": stats.joints.iter().map(|j| json!({
                "name": j.name,
                "min_deg": j.min_deg,
                "max_deg": j.max_deg,
                "max_angle_deg": j.max_angle_deg,
            })).collect::<Vec<_>>(),
            "source": source_json,
        });
        return emit(&serde_json::to_string_pretty(&out)?);
    }

    let mut out = String::new();
    match &source {
        MotionSource::Amass(r) => writeln!(
            out,
            "{}: AMASS-style npz, {} poses, file {} up ({}; read as Y up)",
            args.file.display(),
            r.layout.name(),
            up_name(r.up),
            r.up_from.phrase()
        )?,
        MotionSource::Bvh(r) => writeln!(
            out,
            "{}: BVH retargeted to SMPL with the {} map, units {} ({} m), skeleton {:.2} m across, root path scaled ×{:.3}",
            args.file.display(),
            r.map,
            r.unit,
            short(r.metres_per_unit),
            r.rest_extent,
            r.root_scale
        )?,
    }
    writeln!(
        out,
        "  {} frames at {} fps, {:.3} s",
        stats.frames, stats.fps, stats.duration
    )?;
    writeln!(
        out,
        "  {} joints (SMPL order), betas: {}",
        stats.joints.len(),
        stats
            .betas
            .map_or("none".to_string(), |b| format!("{b} coefficients"))
    )?;
    let d = stats.root_displacement;
    writeln!(
        out,
        "  root path {:.3} m, displacement ({:.3}, {:.3}, {:.3}) m",
        stats.root_path_length, d[0], d[1], d[2]
    )?;
    writeln!(
        out,
        "  range of motion, degrees (axis-angle components, largest angle):"
    )?;
    writeln!(
        out,
        "    {:<15} {:>15} {:>15} {:>15} {:>7}",
        "joint", "x", "y", "z", "angle"
    )?;
    for j in &stats.joints {
        let range = |k: usize| format!("[{:.1}, {:.1}]", j.min_deg[k], j.max_deg[k]);
        writeln!(
            out,
            "    {:<15} {:>15} {:>15} {:>15} {:>7.1}",
            j.name,
            range(0),
            range(1),
            range(2),
            j.max_angle_deg
        )?;
    }
    match &source {
        MotionSource::Amass(r) => {
            if r.dropped_joints > 0 {
                writeln!(
                    out,
                    "  {} hand/face joints beyond SMPL's body were not used",
                    r.dropped_joints
                )?;
            }
            if !r.unused_keys.is_empty() {
                writeln!(out, "  unused keys: {}", r.unused_keys.join(", "))?;
            }
        }
        MotionSource::Bvh(r) => {
            if !r.unmapped.is_empty() {
                writeln!(
                    out,
                    "  SMPL joints without a BVH joint (kept at rest): {}",
                    r.unmapped.join(", ")
                )?;
            }
            if !r.unused.is_empty() {
                writeln!(out, "  BVH joints not used: {}", r.unused.join(", "))?;
            }
        }
    }
    emit(&out)
}

/// Up to six decimals, without trailing zeros.
fn short(x: f64) -> String {
    let s = format!("{x:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn up_name(up: UpAxis) -> &'static str {
    match up {
        UpAxis::Y => "Y",
        UpAxis::Z => "Z",
    }
}
