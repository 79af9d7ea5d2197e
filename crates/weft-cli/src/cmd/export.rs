//! `weft export`: a frame sequence on a template's faces, written as an OBJ sequence, a
//! PC2 or MDD point cache, a glTF binary with morph-target animation, or a USD layer with
//! time-sampled points. The template's UVs go into every format that holds them.

use anyhow::{bail, Context, Result};
use clap::Args;
use serde_json::json;
use std::path::{Path, PathBuf};
use weft_mesh::export::gltf::{write_glb, GlbOptions};
use weft_mesh::export::{
    validate_fps, write_scene, AnimatedMesh, ExportFormat, Frames, BODY_COLOR, GARMENT_COLOR,
};
use weft_mesh::io::load_mesh;
use weft_mesh::TriMesh;

use super::emit;

#[derive(Args)]
pub struct ExportArgs {
    /// The animation: a directory of OBJ frames (read in name order), a .npy array of
    /// shape (frames, vertices, 3), f32 or f64, or a .pc2 or .mdd point cache.
    #[arg(long, value_name = "DIR|FILE.npy|FILE.pc2|FILE.mdd")]
    frames: PathBuf,
    /// The template mesh (.obj or .ply) whose faces the frames move; its vertex order
    /// must be the frames' vertex order. Its UVs (OBJ `vt` on every face corner) are
    /// written into obj, glb and usd.
    #[arg(long, value_name = "G.obj")]
    faces: PathBuf,
    /// Output format: obj (a directory of frame_NNNNN.obj), pc2, mdd, glb or usd (text
    /// USD, .usda or .usd).
    #[arg(long, value_name = "obj|pc2|mdd|glb|usd")]
    format: String,
    /// Frames per second: the MDD frame times and the glTF key times are k / fps, and
    /// USD's time codes per second. PC2 stores no rate (sample k is frame k).
    #[arg(long, default_value_t = 30.0)]
    fps: f32,
    /// Output: a directory for obj (created, or replaced if it holds only an earlier
    /// sequence), a file otherwise. Written atomically: a failure leaves nothing behind.
    #[arg(long, value_name = "PATH")]
    out: PathBuf,
    /// glb and usd only: a body mesh (.obj or .ply) added as a second mesh, static unless
    /// --body-frames animates it.
    #[arg(long, value_name = "B.obj")]
    body: Option<PathBuf>,
    /// glb and usd only: the body's frames (DIR or FILE.npy), as many as the garment's.
    #[arg(long, value_name = "DIR|FILE.npy", requires = "body")]
    body_frames: Option<PathBuf>,
    /// glb only: leave out vertex normals (smaller files; viewers shade flat).
    #[arg(long)]
    no_normals: bool,
    /// Print one JSON object describing what was written.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &ExportArgs) -> Result<()> {
    let format: ExportFormat = args.format.parse().context("--format")?;
    validate_fps(args.fps).context("--fps")?;
    if !format.holds_scene() && args.body.is_some() {
        bail!(
            "--body and --body-frames apply to --format glb and usd only, not {}",
            format.name()
        );
    }
    if format != ExportFormat::Glb && args.no_normals {
        bail!(
            "--no-normals applies to --format glb only, not {}",
            format.name()
        );
    }

    let loaded = load_mesh(&args.faces)?;
    let template = loaded.mesh;
    let frames = load_frames(&args.frames, &template, &args.faces)?;
    let body = match &args.body {
        Some(path) => Some(load_body(path, args.body_frames.as_deref())?),
        None => None,
    };

    let mut meshes = vec![AnimatedMesh {
        name: "garment",
        faces: &template.faces,
        uvs: loaded.corner_uvs.as_deref(),
        frames: &frames,
        color: GARMENT_COLOR,
    }];
    if let Some((mesh, body_frames)) = &body {
        meshes.push(AnimatedMesh {
            name: "body",
            faces: &mesh.faces,
            uvs: None,
            frames: body_frames,
            color: BODY_COLOR,
        });
    }
    if format == ExportFormat::Glb {
        let options = GlbOptions {
            fps: args.fps,
            normals: !args.no_normals,
        };
        write_glb(&args.out, &meshes, options)?;
    } else {
        write_scene(format, &meshes, args.fps, &args.out)?;
    }
    report(args, format, &frames, loaded.corner_uvs.is_some())
}

/// The frames at `path`, checked against the template at `template_path`: same vertex
/// count, every coordinate finite.
fn load_frames(path: &Path, template: &TriMesh, template_path: &Path) -> Result<Frames> {
    let frames = Frames::load(path)?;
    if frames.vertex_count() != template.vertex_count() {
        bail!(
            "{} has {} vertices per frame but the template {} has {}; the frames must have one position per template vertex, in the template's order",
            path.display(),
            frames.vertex_count(),
            template_path.display(),
            template.vertex_count()
        );
    }
    frames
        .check_finite()
        .with_context(|| path.display().to_string())?;
    Ok(frames)
}

/// The body mesh, with its frames or, without them, its own positions as one frame.
fn load_body(path: &Path, frames: Option<&Path>) -> Result<(TriMesh, Frames)> {
    let mesh = load_mesh(path)?.mesh;
    let frames = match frames {
        Some(f) => load_frames(f, &mesh, path)?,
        None => {
            let mut f = Frames::with_vertex_count(mesh.vertex_count())?;
            f.push_frame_f64(&mesh.positions)?;
            f.check_finite()
                .with_context(|| format!("{}: as f32", path.display()))?;
            f
        }
    };
    Ok((mesh, frames))
}

fn report(args: &ExportArgs, format: ExportFormat, frames: &Frames, uvs: bool) -> Result<()> {
    let bytes = output_size(&args.out, format)
        .with_context(|| format!("{}: written, but cannot be measured", args.out.display()))?;
    if args.json {
        let out = json!({
            "format": format.name(),
            "out": args.out,
            "frames": frames.frame_count(),
            "vertices": frames.vertex_count(),
            "fps": args.fps,
            "bytes": bytes,
            "body": args.body,
            "uvs": uvs && !matches!(format, ExportFormat::Pc2 | ExportFormat::Mdd),
        });
        return emit(&serde_json::to_string_pretty(&out)?);
    }
    let what = if format.writes_directory() {
        format!("{} files", frames.frame_count())
    } else {
        "one file".to_owned()
    };
    emit(&format!(
        "wrote {} frames × {} vertices as {format} to {} ({what}, {:.1} MB)",
        frames.frame_count(),
        frames.vertex_count(),
        args.out.display(),
        bytes as f64 / 1e6
    ))
}

/// Bytes written: the file, or the sum over the sequence's files.
fn output_size(out: &Path, format: ExportFormat) -> std::io::Result<u64> {
    if !format.writes_directory() {
        return Ok(std::fs::metadata(out)?.len());
    }
    let mut total = 0;
    for entry in std::fs::read_dir(out)? {
        total += entry?.metadata()?.len();
    }
    Ok(total)
}
