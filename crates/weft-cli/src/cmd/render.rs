//! `weft render`: a mesh, or a directory of frames, to a PNG picture, optionally over a
//! body and coloured by one value per vertex from a `.npy` file.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use weft_mesh::export::npy::NpyData;
use weft_mesh::io::load_mesh;
use weft_mesh::TriMesh;
use weft_render::{
    render, render_frames, render_sequence, render_turntable, write_apng, Colormap, MeshStats,
    Paint, RenderOptions, Rendered, ScalarPaint, ScalarRange, SceneMesh, Shading, View, BODY_COLOR,
    GARMENT_COLOR,
};

use super::body_args::BodyArgs;
use super::emit;

#[derive(Args)]
#[command(mut_arg("body", |a| a
    .value_name("FILE")
    .help("A body drawn under the garment in a neutral grey: an .obj/.ply mesh (e.g. a frame of `weft body pose`), or an SMPL-format body model (.npz) in its rest pose at --betas")))]
pub struct RenderArgs {
    /// An .obj or .ply mesh, or a directory of .obj/.ply frames (drawn as a contact sheet
    /// in natural file-name order, or as an animation with --animate).
    input: PathBuf,
    #[command(flatten)]
    body: BodyArgs,
    /// Draw weft's built-in body under the garment, in its rest pose at --betas.
    #[arg(long, conflicts_with = "body")]
    default_body: bool,
    /// A .npy array of f32 or f64 values, one per garment vertex: shape (N,), or for a
    /// directory of frames (N,) for every frame or (frames, N) one row per frame.
    /// Non-finite values are drawn magenta and reported.
    #[arg(long = "color-by", value_name = "FILE.npy")]
    color_by: Option<PathBuf>,
    /// Camera preset; all meshes are framed automatically.
    #[arg(long, value_enum, default_value_t = CameraArg::ThreeQuarter)]
    camera: CameraArg,
    /// Number of views of --camera turntable.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=36))]
    views: u32,
    /// Picture side in pixels; a contact sheet or turntable is about this wide.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(64..=8192))]
    size: u32,
    /// Colour map of --color-by: viridis for magnitudes, diverging (blue-white-red,
    /// white at 0) for signed values.
    #[arg(long, value_enum, default_value_t = ColormapArg::Viridis)]
    colormap: ColormapArg,
    /// Fixed colour range MIN:MAX (e.g. 0:20, or --range=-5:5); default: the data's range
    /// (symmetric around 0 for the diverging map).
    #[arg(long, value_name = "MIN:MAX", value_parser = parse_range, allow_hyphen_values = true)]
    range: Option<(f64, f64)>,
    /// Legend title, e.g. "vertex error (mm)"; default: the .npy file's stem.
    #[arg(long)]
    label: Option<String>,
    /// Flat shading shows the facets; smooth interpolates normals.
    #[arg(long, value_enum, default_value_t = ShadingArg::Smooth)]
    shading: ShadingArg,
    /// A title drawn at the top left.
    #[arg(long)]
    title: Option<String>,
    /// For a directory of frames: write an animated PNG (APNG) instead of a sheet.
    #[arg(long)]
    animate: bool,
    /// Frames per second of --animate.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u16).range(1..=120))]
    fps: u16,
    /// The output .png file (written atomically: never a partial file).
    #[arg(long, value_name = "PNG")]
    out: PathBuf,
}

#[derive(Clone, Copy, ValueEnum)]
enum CameraArg {
    Front,
    Side,
    ThreeQuarter,
    Turntable,
}

#[derive(Clone, Copy, ValueEnum)]
enum ColormapArg {
    Viridis,
    Diverging,
}

#[derive(Clone, Copy, ValueEnum)]
enum ShadingArg {
    Flat,
    Smooth,
}

fn parse_range(s: &str) -> Result<(f64, f64), String> {
    let err = || {
        format!("`{s}` is not a range; expected MIN:MAX with finite numbers, MIN < MAX (e.g. 0:20)")
    };
    let (a, b) = s.split_once(':').ok_or_else(err)?;
    let (a, b): (f64, f64) = (
        a.trim().parse().map_err(|_| err())?,
        b.trim().parse().map_err(|_| err())?,
    );
    if !(a.is_finite() && b.is_finite() && a < b) {
        return Err(err());
    }
    Ok((a, b))
}

/// The per-vertex values of --color-by: one row for all frames, or one per frame.
struct Values {
    path: PathBuf,
    rows: Vec<Vec<f64>>,
}

impl Values {
    fn row(&self, frame: usize) -> &[f64] {
        &self.rows[if self.rows.len() == 1 { 0 } else { frame }]
    }
}

pub fn run(args: &RenderArgs) -> Result<()> {
    if !super::has_extension(&args.out, &["png"]) {
        bail!(
            "{}: the output must be a .png file (weft render writes PNG{})",
            args.out.display(),
            if args.animate {
                ", animated as APNG"
            } else {
                ""
            }
        );
    }
    let is_dir = args.input.is_dir();
    if is_dir && matches!(args.camera, CameraArg::Turntable) {
        bail!(
            "{}: --camera turntable draws one mesh from all sides; for a directory of frames pick front, side or three-quarter",
            args.input.display()
        );
    }
    if args.animate && !is_dir {
        bail!(
            "{}: --animate needs a directory of frames",
            args.input.display()
        );
    }
    let frame_paths = if is_dir {
        frame_files(&args.input)?
    } else {
        vec![args.input.clone()]
    };
    let mut frames = Vec::with_capacity(frame_paths.len());
    for p in &frame_paths {
        frames.push(load_mesh(p)?.mesh);
    }
    let body = body_mesh(args)?;
    let values = match &args.color_by {
        Some(p) => Some(read_values(p, &frame_paths, &frames)?),
        None => None,
    };
    let label = args.label.clone().unwrap_or_else(|| {
        args.color_by
            .as_deref()
            .and_then(Path::file_stem)
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
    });
    let colormap = match args.colormap {
        ColormapArg::Viridis => Colormap::Viridis,
        ColormapArg::Diverging => Colormap::Diverging,
    };
    let range = match args.range {
        Some((a, b)) => ScalarRange::fixed(a, b)?,
        None => ScalarRange::Auto,
    };
    let shading = match args.shading {
        ShadingArg::Flat => Shading::Flat,
        ShadingArg::Smooth => Shading::Smooth,
    };
    let names: Vec<String> = frame_paths
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let scenes: Vec<Vec<SceneMesh<'_>>> = frames
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let paint = match &values {
                Some(v) => Paint::Scalars(ScalarPaint {
                    values: v.row(i),
                    colormap,
                    range,
                    label: &label,
                }),
                None => Paint::Solid(GARMENT_COLOR),
            };
            let mut scene = Vec::with_capacity(2);
            if let Some((b, _)) = &body {
                scene.push(
                    SceneMesh::new("--body", b, Paint::Solid(BODY_COLOR)).with_shading(shading),
                );
            }
            scene.push(SceneMesh::new(names[i].clone(), m, paint).with_shading(shading));
            scene
        })
        .collect();
    let view = match args.camera {
        CameraArg::Front => View::Front,
        CameraArg::Side => View::Side,
        CameraArg::ThreeQuarter | CameraArg::Turntable => View::ThreeQuarter,
    };
    let opts = |w: u32, h: u32| RenderOptions {
        view,
        title: args.title.clone(),
        ..RenderOptions::new(w, h)
    };
    let labels: Vec<String> = frame_paths
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let stem = p
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
            format!("{i}: {stem}")
        })
        .collect();
    let (width, height, stats) = if args.animate {
        let r = render_frames(&scenes, &labels, &opts(args.size, args.size))?;
        write_apng(&args.out, &r.frames, args.fps)
            .context("cannot write the animation (nothing was written)")?;
        (args.size, args.size, r.meshes)
    } else {
        let r: Rendered = if is_dir {
            let cols = (frames.len() as f64).sqrt().ceil().max(1.0) as u32;
            let tile = (args.size / cols).max(96);
            render_sequence(&scenes, &labels, &opts(tile, tile), Some(cols))?
        } else if matches!(args.camera, CameraArg::Turntable) {
            let cols = args.views.min(4);
            let tile = (args.size / cols).max(96);
            render_turntable(&scenes[0], args.views, &opts(tile, tile), Some(cols))?
        } else {
            render(&scenes[0], &opts(args.size, args.size))?
        };
        r.image
            .write_png(&args.out)
            .context("cannot write the picture (nothing was written)")?;
        (r.image.width(), r.image.height(), r.meshes)
    };
    warn_nonfinite(&stats, values.as_ref(), frames.len());
    let mut out = String::new();
    write!(out, "wrote {} ({width}×{height}", args.out.display())?;
    if args.animate {
        write!(out, ", {} frames at {} fps", frames.len(), args.fps)?;
    }
    write!(out, "): ")?;
    if is_dir {
        write!(out, "{} frames from {}", frames.len(), args.input.display())?;
    } else {
        write!(
            out,
            "{} ({} vertices)",
            args.input.display(),
            frames[0].vertex_count()
        )?;
    }
    if let Some((_, name)) = &body {
        write!(out, " over {name}")?;
    }
    if let Some(v) = &values {
        let all = v.rows.iter().flatten().copied();
        let (lo, hi) = range.resolve(all, colormap);
        write!(
            out,
            ", coloured by {} ({}, {} to {})",
            v.path.display(),
            colormap.name(),
            short(lo),
            short(hi)
        )?;
    }
    emit(&out)
}

/// The body drawn under the garment and its name: a mesh file as it is, or a body model
/// (the file's or the built-in one) at --betas; `None` when no body was asked for.
fn body_mesh(args: &RenderArgs) -> Result<Option<(TriMesh, String)>> {
    let b = &args.body;
    match &b.model.body {
        Some(p) if !super::has_extension(p, &["npz"]) => {
            if !b.betas.is_empty() {
                bail!(
                    "--betas shapes a body model (.npz or --default-body); {} is a mesh",
                    p.display()
                );
            }
            Ok(Some((load_mesh(p)?.mesh, p.display().to_string())))
        }
        None if !args.default_body => {
            if !b.betas.is_empty() {
                bail!("--betas shapes the body of --body FILE.npz or --default-body; give one of them");
            }
            Ok(None)
        }
        _ => {
            let (model, name) = b.load()?;
            let mesh = model.shape(&b.betas(&model)?)?;
            Ok(Some((mesh, name)))
        }
    }
}

/// `v` with at most 4 decimals and no trailing zeros: 7.989999771 -> 7.99.
fn short(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// The .obj/.ply files of `dir`, in natural order (frame_2 before frame_10).
fn frame_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot list the directory", dir.display()))?;
    let mut files = Vec::new();
    for e in entries {
        let e = e.with_context(|| format!("{}: cannot list the directory", dir.display()))?;
        let p = e.path();
        if super::has_extension(&p, &["obj", "ply"]) && p.is_file() {
            files.push(p);
        }
    }
    if files.is_empty() {
        bail!(
            "{}: no .obj or .ply files in the directory; expected one mesh file per frame",
            dir.display()
        );
    }
    files.sort_by_key(|p| natural_key(p));
    Ok(files)
}

/// Sort key that orders digit runs by value: `f2` < `f10`.
fn natural_key(p: &Path) -> Vec<(u8, String)> {
    let name = p
        .file_name()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let mut key = Vec::new();
    let mut chars = name.chars().peekable();
    while let Some(&c) = chars.peek() {
        let digit = c.is_ascii_digit();
        let mut run = String::new();
        while let Some(&d) = chars.peek() {
            if d.is_ascii_digit() != digit {
                break;
            }
            run.push(d);
            chars.next();
        }
        if digit {
            let trimmed = run.trim_start_matches('0');
            // Longer numbers are larger; equal lengths compare as text.
            // Ties (f01, f1) fall back to the digits as written.
            key.push((1, format!("{trimmed:0>40}/{run}")));
        } else {
            key.push((0, run));
        }
    }
    key
}

/// Reads --color-by and checks its shape against the frames.
fn read_values(path: &Path, frame_paths: &[PathBuf], frames: &[TriMesh]) -> Result<Values> {
    let (shape, data) = read_npy_floats(path)?;
    let first = &frame_paths[0];
    let n = frames[0].vertex_count();
    let rows: Vec<Vec<f64>> = match shape.as_slice() {
        [_] => vec![data],
        [f, len] if frames.len() > 1 => {
            if *f != frames.len() {
                bail!(
                    "{}: {f} rows of values for {} frames in {}; expected shape ({}, {n}) or ({n},)",
                    path.display(),
                    frames.len(),
                    first.parent().map_or_else(String::new, |d| d.display().to_string()),
                    frames.len()
                );
            }
            data.chunks(*len.max(&1)).map(<[f64]>::to_vec).collect()
        }
        s => bail!(
            "{}: an array of shape {s:?}; expected one value per vertex, shape ({n},){}",
            path.display(),
            if frames.len() > 1 {
                format!(" or ({}, {n})", frames.len())
            } else {
                String::new()
            }
        ),
    };
    for (i, (m, p)) in frames.iter().zip(frame_paths).enumerate() {
        let row = &rows[if rows.len() == 1 { 0 } else { i }];
        if row.len() != m.vertex_count() {
            bail!(
                "{} holds {} values per row, but {} has {} vertices; expected one value per vertex",
                path.display(),
                row.len(),
                p.display(),
                m.vertex_count()
            );
        }
    }
    Ok(Values {
        path: path.to_path_buf(),
        rows,
    })
}

/// Warnings on stderr for data drawn in the error colour.
fn warn_nonfinite(stats: &[MeshStats], values: Option<&Values>, frames: usize) {
    for s in stats {
        if s.nonfinite_scalars > 0 {
            let from = values.map_or_else(String::new, |v| format!(" of {}", v.path.display()));
            let scope = if frames > 1 {
                " (summed over frames)"
            } else {
                ""
            };
            let (noun, verb) = if s.nonfinite_scalars == 1 {
                ("value", "is")
            } else {
                ("values", "are")
            };
            eprintln!(
                "warning: {}: {} {noun}{from} {verb} not finite (NaN or infinite){scope}; drawn in magenta",
                s.name, s.nonfinite_scalars
            );
        }
        if s.nonfinite_positions > 0 {
            eprintln!(
                "warning: {}: {} vertex positions are not finite; their faces are drawn in magenta",
                s.name, s.nonfinite_positions
            );
        }
        if s.skipped_faces > 0 {
            eprintln!(
                "warning: {}: {} faces have no finite corner position and were not drawn",
                s.name, s.skipped_faces
            );
        }
    }
}

/// Shape and values (as f64) of the f32 or f64 `.npy` array in `path`.
fn read_npy_floats(path: &Path) -> Result<(Vec<usize>, Vec<f64>)> {
    let array = weft_mesh::export::npy::read_npy(path)?;
    let values = match array.data {
        NpyData::F32(v) => v.into_iter().map(f64::from).collect(),
        NpyData::F64(v) => v,
        other => bail!(
            "{}: elements of type {}; expected float32 or float64 values",
            path.display(),
            other.descr()
        ),
    };
    Ok((array.shape, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order_of_frame_files() {
        let mut v: Vec<PathBuf> = ["f10.obj", "f2.obj", "f1.obj", "f01.obj", "a.obj"]
            .iter()
            .map(PathBuf::from)
            .collect();
        v.sort_by_key(|p| natural_key(p));
        let names: Vec<_> = v.iter().map(|p| p.display().to_string()).collect();
        assert_eq!(names, ["a.obj", "f01.obj", "f1.obj", "f2.obj", "f10.obj"]);
    }

    #[test]
    fn ranges_parse() {
        assert_eq!(parse_range("0:20"), Ok((0.0, 20.0)));
        assert_eq!(parse_range("-5.5 : 5"), Ok((-5.5, 5.0)));
        assert!(parse_range("5:5").is_err());
        assert!(parse_range("x:1").is_err());
        assert!(parse_range("1").is_err());
    }
}
