//! `weft garment generate`: procedural garment templates fitted to a body.
//! `weft garment resize | drape | prepare`: fit any garment (a template or an OBJ) to a
//! body shape, settle it on the rest body with the simulator, transfer skinning weights.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use serde_json::json;
use weft_body::BodyModel;
use weft_garment::prepare::{
    drape, resize, write_positions_into_obj, DrapeOptions, DrapeReport, Material, ResizeOptions,
    ResizeReport,
};
use weft_garment::{DressTop, FitBody, GarmentKind, SkirtLength, Style};
use weft_mesh::{Topology, TriMesh};

use super::body_args::{shape, BodyArgs, BodyModelArg, ShapeLimit};
use super::{emit, has_extension};

#[derive(Subcommand)]
pub enum GarmentCommand {
    /// Write a procedural garment template (OBJ with UVs) fitted to a body.
    Generate(GenerateArgs),
    /// Move a garment fitted to body shape --from-betas onto shape --to-betas.
    Resize(ResizeArgs),
    /// Settle a garment on the rest-pose body with the cloth simulator.
    Drape(DrapeArgs),
    /// Resize to --betas, drape, and optionally write skinning weights: a garment ready
    /// for simulation and the LBS baselines.
    Prepare(PrepareArgs),
}

// Values are taken as text and parsed here so every bad argument is one line of error.
#[derive(Args)]
pub struct GenerateArgs {
    /// skirt, dress, tshirt, tank, longsleeve, shorts, pants or jumpsuit.
    #[arg(long)]
    kind: String,
    /// Target vertex count (300 to 50 000; within ±15% from 500 to 12 000).
    #[arg(long, default_value = "4000")]
    vertices: String,
    #[command(flatten)]
    body: BodyArgs,
    /// Seed of the style parameters (ease, flare, length, dress top, hem waviness).
    #[arg(long, default_value = "0")]
    seed: String,
    /// Skirt/dress length: mini, knee or maxi (default: drawn from the seed).
    #[arg(long)]
    length: Option<String>,
    /// Skirt/dress flare, 0 to 1 (default: drawn from the seed).
    #[arg(long, allow_hyphen_values = true)]
    flare: Option<String>,
    /// Dress top: strapless, straps or sleeves (default: drawn from the seed).
    #[arg(long)]
    dress_top: Option<String>,
    /// Output OBJ (positions, vt UVs in metres, faces).
    #[arg(long)]
    out: PathBuf,
    /// Cut the garment open down the front, from the neckline to the hem (a jacket from
    /// a top), with this many button pairs across the cut, written to --buttons.
    #[arg(long, value_name = "BUTTONS", requires = "buttons")]
    open_front: Option<std::num::NonZeroUsize>,
    /// Where --open-front writes its button pairs: JSON `[[a, b], ...]`, 0-based vertex
    /// indices, as `weft simulate --buttons` and `weft animate --buttons` read them.
    #[arg(long, value_name = "PAIRS.json", requires = "open_front")]
    buttons: Option<PathBuf>,
}

/// The garment to prepare and the body it is on.
#[derive(Args)]
pub struct GarmentOnBody {
    /// The garment (OBJ or PLY, metres, in the body's rest-pose frame). OBJ in and OBJ
    /// out keeps the file's UVs, groups and face corners: only `v` lines change.
    #[arg(long)]
    garment: PathBuf,
    #[command(flatten)]
    body: BodyModelArg,
    #[command(flatten)]
    limit: ShapeLimit,
}

/// Drape parameters shared by `drape` and `prepare`.
#[derive(Args)]
pub struct DrapeFlags {
    /// Cloth material: a preset (hood, silk, cotton, jersey, denim, leather) or a TOML
    /// file of its fields laid over HOOD's material (see `weft simulate --help`).
    #[arg(long, default_value = "cotton", value_name = "NAME|FILE.toml")]
    material: String,
    /// Frame budget of the drape (30 fps).
    #[arg(long, default_value = "120")]
    frames: String,
    /// Settled when the largest vertex speed falls below this (m/s).
    #[arg(long, default_value = "0.02")]
    settle_speed: String,
    /// Do not hold the top opening (waistband or neckline) in place.
    #[arg(long)]
    no_pin: bool,
}

#[derive(Args)]
pub struct ResizeArgs {
    #[command(flatten)]
    garment: GarmentOnBody,
    /// β of the body the garment was fitted to, comma-separated (default: all 0).
    #[arg(
        long,
        value_name = "B1,B2,…",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    from_betas: Vec<f64>,
    /// β of the body to fit it to.
    #[arg(
        long,
        required = true,
        value_name = "B1,B2,…",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    to_betas: Vec<f64>,
    /// Output mesh (.obj or .ply).
    #[arg(long)]
    out: PathBuf,
    /// Write what was done as JSON here.
    #[arg(long)]
    report: Option<PathBuf>,
}

#[derive(Args)]
pub struct DrapeArgs {
    #[command(flatten)]
    garment: GarmentOnBody,
    /// β of the body (default: all 0).
    #[arg(
        long,
        value_name = "B1,B2,…",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    betas: Vec<f64>,
    #[command(flatten)]
    drape: DrapeFlags,
    /// Output mesh (.obj or .ply).
    #[arg(long)]
    out: PathBuf,
    /// Write what was done as JSON here.
    #[arg(long)]
    report: Option<PathBuf>,
}

#[derive(Args)]
pub struct PrepareArgs {
    #[command(flatten)]
    garment: GarmentOnBody,
    /// β of the body the garment was fitted to (default: all 0).
    #[arg(
        long,
        value_name = "B1,B2,…",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    from_betas: Vec<f64>,
    /// β of the body to prepare it for (default: all 0, no resize).
    #[arg(
        long,
        value_name = "B1,B2,…",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    betas: Vec<f64>,
    /// Skip the drape (resize and weights only).
    #[arg(long)]
    no_drape: bool,
    #[command(flatten)]
    drape: DrapeFlags,
    /// Output mesh (.obj or .ply).
    #[arg(long)]
    out: PathBuf,
    /// Skinning weights of the prepared garment: float32 .npy, vertices × joints, rows
    /// summing to 1 (closest body surface point, barycentric).
    #[arg(long)]
    weights: Option<PathBuf>,
    /// Write what was done as JSON here.
    #[arg(long)]
    report: Option<PathBuf>,
}

pub fn run(command: GarmentCommand) -> Result<()> {
    match command {
        GarmentCommand::Generate(a) => run_generate(&a),
        GarmentCommand::Resize(a) => run_resize(&a),
        GarmentCommand::Drape(a) => run_drape(&a),
        GarmentCommand::Prepare(a) => run_prepare(&a),
    }
}

fn number<T: std::str::FromStr>(flag: &str, text: &str) -> Result<T> {
    text.trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("--{flag} {text:?} is not a valid number"))
}

/// Whether `path` ends in `.ext` (any case).
fn run_generate(a: &GenerateArgs) -> Result<()> {
    let kind = GarmentKind::parse(&a.kind).context("--kind")?;
    let vertices: usize = number("vertices", &a.vertices)?;
    let seed: u64 = number("seed", &a.seed)?;
    let mut style = Style::from_seed(kind, seed);
    if let Some(l) = &a.length {
        style.length = match l.as_str() {
            "mini" => SkirtLength::Mini,
            "knee" => SkirtLength::Knee,
            "maxi" => SkirtLength::Maxi,
            _ => bail!("--length {l:?}: expected mini, knee or maxi"),
        };
    }
    if let Some(f) = &a.flare {
        style.flare = number("flare", f)?;
        if !(0.0..=1.0).contains(&style.flare) {
            bail!("--flare {f}: expected a number from 0 to 1");
        }
    }
    if let Some(t) = &a.dress_top {
        style.dress_top = match t.as_str() {
            "strapless" => DressTop::Strapless,
            "straps" => DressTop::Straps,
            "sleeves" => DressTop::Sleeves,
            _ => bail!("--dress-top {t:?}: expected strapless, straps or sleeves"),
        };
    }
    let (model, name) = a.body.load()?;
    let betas = a.body.betas(&model)?;
    if !has_extension(&a.out, &["obj"]) {
        bail!(
            "--out {}: expected an .obj file (garments are written as OBJ with their UVs)",
            a.out.display()
        );
    }
    let fit = FitBody::new(&model, &betas).with_context(|| format!("{name}: fitting"))?;
    let mut garment = fit.generate(kind, &style, vertices)?;
    let fitted_to = name;
    let mut buttons = None;
    if let (Some(count), Some(path)) = (a.open_front, &a.buttons) {
        let open = garment
            .open_front(count.get())
            .with_context(|| format!("--open-front {count}"))?;
        garment = open.garment;
        buttons = Some((path, open.buttons));
    }
    // The garment first: a buttons file never points into a garment that was not written,
    // and a garment whose buttons could not be written is taken back.
    weft_garment::obj::write_obj(&a.out, &garment)?;
    if let Some((path, pairs)) = &buttons {
        let text = serde_json::to_string(pairs)?;
        if let Err(e) = weft_mesh::io::write_atomic(path, |w| w.write_all(text.as_bytes())) {
            let _ = std::fs::remove_file(&a.out);
            return Err(e).with_context(|| format!("--buttons {}: cannot write", path.display()));
        }
    }
    let openings = Topology::new(&garment.mesh).boundary_loops().len();
    let buttoned = match &buttons {
        Some((path, pairs)) => format!(", {} button pairs in {}", pairs.len(), path.display()),
        None => String::new(),
    };
    emit(&format!(
        "wrote {}: {} with {} vertices, {} faces, {} openings, fitted to {}{buttoned}",
        a.out.display(),
        kind.name(),
        garment.mesh.vertex_count(),
        garment.mesh.face_count(),
        openings,
        fitted_to
    ))
}

fn fit_body(model: &BodyModel, betas: &[f64], name: &str) -> Result<FitBody> {
    FitBody::new(model, betas).with_context(|| format!("{name} at β = {betas:?}"))
}

/// The garment mesh and, for OBJ input, its text (so UVs survive).
struct GarmentFile {
    mesh: TriMesh,
    obj_text: Option<String>,
}

fn read_garment(path: &Path) -> Result<GarmentFile> {
    let mesh = weft_mesh::io::read_mesh(path)?;
    let is_obj = matches!(
        weft_mesh::io::MeshFormat::from_path(path)?,
        weft_mesh::io::MeshFormat::Obj
    );
    let obj_text = if is_obj {
        Some(
            weft_mesh::io::read_input_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?,
        )
    } else {
        None
    };
    Ok(GarmentFile { mesh, obj_text })
}

/// Writes the garment with new positions: into its own OBJ text when both are OBJ,
/// else as a fresh mesh in the output's format.
fn write_garment(
    input: &Path,
    garment: &GarmentFile,
    positions: &[[f64; 3]],
    out: &Path,
) -> Result<()> {
    let out_is_obj = matches!(
        weft_mesh::io::MeshFormat::from_path(out)?,
        weft_mesh::io::MeshFormat::Obj
    );
    match (&garment.obj_text, out_is_obj) {
        (Some(text), true) => {
            let text = write_positions_into_obj(text, positions, input)?;
            weft_mesh::io::write_atomic(out, |w| w.write_all(text.as_bytes()))
                .with_context(|| format!("cannot write {}", out.display()))?;
        }
        _ => {
            let mesh = TriMesh::new(positions.to_vec(), garment.mesh.faces.clone());
            weft_mesh::io::write_mesh(out, &mesh)?;
        }
    }
    Ok(())
}

fn write_report(path: Option<&Path>, value: &serde_json::Value) -> Result<()> {
    let Some(path) = path else { return Ok(()) };
    let text = serde_json::to_string_pretty(value)?;
    weft_mesh::io::write_atomic(path, |w| w.write_all(text.as_bytes()))
        .with_context(|| format!("cannot write {}", path.display()))
}

fn drape_options(flags: &DrapeFlags) -> Result<(DrapeOptions, Material)> {
    let material = super::cloth_args::material(&flags.material)?;
    let options = DrapeOptions {
        max_frames: number("frames", &flags.frames)?,
        settle_speed: number("settle-speed", &flags.settle_speed)?,
        pin_top_opening: !flags.no_pin,
        ..DrapeOptions::default()
    };
    if options.max_frames == 0 {
        bail!("--frames 0: expected at least 1 frame");
    }
    if !(options.settle_speed.is_finite() && options.settle_speed > 0.0) {
        bail!(
            "--settle-speed {}: expected a speed above 0 (m/s)",
            flags.settle_speed
        );
    }
    Ok((options, material))
}

fn resize_json(r: &ResizeReport) -> serde_json::Value {
    json!({
        "mean_displacement_m": r.mean_displacement,
        "max_displacement_m": r.max_displacement,
        "inside_before_push_out": r.before_push_out.count,
        "pushed_out": r.pushed_out,
        "max_push_m": r.max_push,
        "inside_after": r.after.count,
        "deepest_after_m": r.after.max_depth,
    })
}

fn drape_json(r: &DrapeReport) -> serde_json::Value {
    json!({
        "inside_before": r.before.count,
        "deepest_before_m": r.before.max_depth,
        "pushed_out": r.pushed_out,
        "inside_after": r.after.count,
        "deepest_after_m": r.after.max_depth,
        "deeper_than_threshold_after": r.after.beyond_tolerance,
        "frames": r.frames,
        "settled": r.settled,
        "final_max_speed_m_s": r.max_speeds.last().copied().unwrap_or(0.0),
        "max_speeds_m_s": r.max_speeds,
        "newton_iterations": r.newton_iterations,
        "pinned": r.pinned,
        "seconds": r.seconds,
    })
}

fn drape_line(r: &DrapeReport) -> String {
    format!(
        "drape: {} frames ({}, last max speed {:.3} m/s, {:.1} s); inside the body before {} (deepest {:.1} mm), pushed out {}, after {} (deepest {:.1} mm); {} vertices pinned",
        r.frames,
        if r.settled { "settled" } else { "frame budget reached before settling" },
        r.max_speeds.last().copied().unwrap_or(0.0),
        r.seconds,
        r.before.count,
        r.before.max_depth * 1e3,
        r.pushed_out,
        r.after.count,
        r.after.max_depth * 1e3,
        r.pinned
    )
}

fn resize_line(r: &ResizeReport) -> String {
    format!(
        "resize: moved {:.1} mm on average (largest {:.1} mm); inside the new body {} before push-out, pushed out {} (largest {:.1} mm), inside after {}",
        r.mean_displacement * 1e3,
        r.max_displacement * 1e3,
        r.before_push_out.count,
        r.pushed_out,
        r.max_push * 1e3,
        r.after.count
    )
}

fn run_resize(a: &ResizeArgs) -> Result<()> {
    let (model, name) = a.garment.body.load()?;
    let from = shape(&model, &a.from_betas, "from-betas", a.garment.limit)?;
    let to = shape(&model, &a.to_betas, "to-betas", a.garment.limit)?;
    let g = read_garment(&a.garment.garment)?;
    let r = resize(
        &g.mesh,
        &fit_body(&model, &from, &name)?,
        &fit_body(&model, &to, &name)?,
        &ResizeOptions::default(),
    )?;
    write_garment(&a.garment.garment, &g, &r.positions, &a.out)?;
    write_report(a.report.as_deref(), &json!({ "resize": resize_json(&r) }))?;
    emit(&format!("{}\nwrote {}", resize_line(&r), a.out.display()))
}

fn run_drape(a: &DrapeArgs) -> Result<()> {
    let (model, name) = a.garment.body.load()?;
    let betas = shape(&model, &a.betas, "betas", a.garment.limit)?;
    let (options, material) = drape_options(&a.drape)?;
    let g = read_garment(&a.garment.garment)?;
    let r = drape(
        &g.mesh,
        &fit_body(&model, &betas, &name)?,
        &material,
        &options,
    )?;
    write_garment(&a.garment.garment, &g, &r.positions, &a.out)?;
    write_report(a.report.as_deref(), &json!({ "drape": drape_json(&r) }))?;
    emit(&format!("{}\nwrote {}", drape_line(&r), a.out.display()))
}

fn run_prepare(a: &PrepareArgs) -> Result<()> {
    if let Some(path) = a.weights.as_deref().filter(|p| !has_extension(p, &["npy"])) {
        bail!(
            "--weights {}: expected a .npy file (float32, vertices × joints)",
            path.display()
        );
    }
    let (model, name) = a.garment.body.load()?;
    let from = shape(&model, &a.from_betas, "from-betas", a.garment.limit)?;
    let to = shape(&model, &a.betas, "betas", a.garment.limit)?;
    let (options, material) = drape_options(&a.drape)?;
    let g = read_garment(&a.garment.garment)?;
    let body = fit_body(&model, &to, &name)?;
    let mut lines = Vec::new();
    let mut report = serde_json::Map::new();
    let mut mesh = g.mesh.clone();
    if from != to {
        let r = resize(
            &mesh,
            &fit_body(&model, &from, &name)?,
            &body,
            &ResizeOptions::default(),
        )?;
        lines.push(resize_line(&r));
        report.insert("resize".into(), resize_json(&r));
        mesh.positions = r.positions;
    }
    if !a.no_drape {
        let r = drape(&mesh, &body, &material, &options)?;
        lines.push(drape_line(&r));
        report.insert("drape".into(), drape_json(&r));
        mesh.positions = r.positions;
    }
    let weights = match &a.weights {
        Some(path) => Some((path, body.weights_at(&model, &mesh.positions)?)),
        None => None,
    };
    // The mesh is written last and the earlier files removed if a later one fails, so
    // a failed run never leaves a prepared mesh without the weights asked for with it.
    let mut written: Vec<&Path> = Vec::new();
    let result = (|| {
        if let Some((path, w)) = &weights {
            let shape = [w.vertex_count(), w.joint_count()];
            weft_mesh::export::npy::write_npy(path, &shape, &w.to_f32())?;
            written.push(path);
            lines.push(format!(
                "wrote {}: skinning weights, {} vertices × {} joints",
                path.display(),
                shape[0],
                shape[1]
            ));
        }
        write_report(a.report.as_deref(), &serde_json::Value::Object(report))?;
        written.extend(a.report.as_deref());
        write_garment(&a.garment.garment, &g, &mesh.positions, &a.out)?;
        lines.push(format!("wrote {}", a.out.display()));
        anyhow::Ok(())
    })();
    if let Err(e) = result {
        for path in written {
            let _ = std::fs::remove_file(path);
        }
        return Err(e);
    }
    emit(&lines.join("\n"))
}
