//! `weft animate`: a trained model drives any garment (unseen topology included) on a
//! body shape through a motion, written as an OBJ sequence, PC2/MDD point cache, glTF
//! binary or USD layer.

use anyhow::{bail, Context, Result};
use clap::Args;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;
use weft_body::PosedSequence;
use weft_eval::animate::{animate, check_animation, push_out_of_body, write_animation};
use weft_eval::skinned::write_skinned_animation;
use weft_garment::prepare::{fit_onto, FitOntoOptions};
use weft_garment::FitBody;
use weft_mesh::export::ExportFormat;
use weft_models::hood::HoodPredictor;
use weft_models::{load_deformer, Clip, Deformer, ModelKind};

use super::body_args::BodyArgs;
use super::emit;
use super::hood_args::HoodArgs;
use super::motion_args::MotionArgs;

#[derive(Args)]
pub struct AnimateArgs {
    /// Run directory written by `weft train` (any model kind: the run names it).
    #[arg(value_name = "RUN")]
    run: PathBuf,
    /// The garment (.obj/.ply), any topology, dressed on the body at --betas in its rest
    /// pose (e.g. from `weft garment generate`); for a DenseGATs or MultiResGNet run, the
    /// character mesh (body and tight clothes as one mesh, `--character`), bound to the
    /// body at --betas.
    #[arg(long, value_name = "G.obj", alias = "character")]
    garment: PathBuf,
    #[command(flatten)]
    body: BodyArgs,
    #[command(flatten)]
    motion: MotionArgs,
    /// Procedural motions: number of frames.
    #[arg(long, default_value_t = 120, value_parser = super::frame_count)]
    frames: usize,
    /// Output: a directory for obj, a file otherwise.
    #[arg(long, value_name = "PATH")]
    out: PathBuf,
    /// obj, pc2, mdd, glb or usd (glb and usd also hold the animated body; the garment's
    /// UVs go into obj, glb and usd).
    #[arg(long, value_name = "obj|pc2|mdd|glb|usd")]
    format: String,
    /// glb only: a skinned glTF for game engines (the body's skeleton animated, body and
    /// garment skinned to it, per-frame corrective morph targets) instead of one morph
    /// target per frame.
    #[arg(long)]
    skinned: bool,
    /// Post-process: move predicted vertices that are inside the posed body, or within
    /// this many millimetres of it, to its surface plus that distance. The network has
    /// no hard contact constraint (legs can pass through a predicted skirt); 4 is the
    /// margin garments are fitted with. A HOOD rollout does it after every step
    /// instead, against the collision term's contact planes with the material's
    /// friction against the body, pushes the cloth's faces off any part of the body
    /// that came through them between vertices, and goes on from the garment outside
    /// the body.
    #[arg(long, value_name = "MM")]
    push_out: Option<f64>,
    /// The β the garment was made for (comma-separated), when that is not the --betas
    /// body: it is first fitted onto the --betas body as GarFitNet's data is made
    /// (resized, then draped in the rest pose with its own shape as the rest shape:
    /// tight on a fuller body, loose on a slimmer one). Without it the garment must
    /// already be dressed on the --betas body.
    #[arg(
        long,
        value_name = "B0,B1,..",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    made_for: Option<Vec<f64>>,
    /// The fabric: a preset (silk, cotton, jersey, denim, leather, hood) or a TOML file
    /// of material fields. For --made-for, the fabric of that drape (default silk); for
    /// a HOOD run, what the garment is made of (default HOOD's material; a
    /// comma-separated list with --material-map).
    #[arg(long, value_name = "NAME|FILE.toml")]
    material: Option<String>,
    #[command(flatten)]
    hood: HoodArgs,
    /// Print one JSON object describing what was written.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &AnimateArgs) -> Result<()> {
    let format: ExportFormat = args.format.parse().context("--format")?;
    if args.skinned && format != ExportFormat::Glb {
        anyhow::bail!(
            "--skinned applies to --format glb only, not {}",
            format.name()
        );
    }
    let push_out = args.push_out.map(super::hood_args::push_out).transpose()?;
    // The options and inputs first (cheap, and named by their flags), then the run.
    let (body, _) = args.body.load()?;
    let betas64 = args.body.betas(&body)?;
    let betas: Vec<f32> = betas64.iter().map(|&b| b as f32).collect();
    let motion = args.motion.load(&body, &betas64, args.frames)?;
    let loaded = weft_mesh::io::load_mesh(&args.garment)
        .with_context(|| format!("reading the garment {}", args.garment.display()))?;
    let mut garment = loaded.mesh;
    if let Some(made_for) = &args.made_for {
        let material = super::cloth_args::material(args.material.as_deref().unwrap_or("silk"))?;
        let from = FitBody::new(&body, made_for).context("--made-for")?;
        let to = FitBody::new(&body, &betas64).context("--betas")?;
        let (fitted, _) = fit_onto(&garment, &from, &to, &material, &FitOntoOptions::default())
            .with_context(|| {
                format!(
                    "fitting {} (made for --made-for) onto the --betas body",
                    args.garment.display()
                )
            })?;
        garment.positions = fitted;
    }
    let loading = || format!("loading run {}", args.run.display());
    let (header, _) = weft_models::run::read_run_config(&args.run).with_context(loading)?;
    let started = Instant::now();
    let (deformer, mut frames, stopped, corrections, outside) = if header.model == ModelKind::Hood {
        let mut hood = HoodPredictor::load(&args.run).with_context(loading)?;
        let outside =
            args.hood
                .configure(&mut hood, args.material.as_deref(), garment.vertex_count())?;
        hood.options.contact_margin = push_out;
        let clip = Clip {
            betas: &betas,
            poses: motion.poses(),
            trans: motion.trans(),
            fps: motion.fps(),
        };
        let rollout = hood.roll_out_clip(&garment, &body, &clip)?;
        let frames: Vec<Vec<[f32; 3]>> = rollout
            .frames
            .iter()
            .map(|f| f.iter().map(|p| p.map(|x| x as f32)).collect())
            .collect();
        let corrections = hood.options.over(&hood.config).corrects();
        let corrections = corrections.then_some(rollout.corrections);
        (
            Box::new(hood) as Box<dyn Deformer + Send>,
            frames,
            rollout.stopped,
            corrections,
            Some(outside),
        )
    } else {
        if let Some(flag) = args.hood.given() {
            bail!(
                "{flag} applies to a hood run; {} is a {} run",
                args.run.display(),
                header.model
            );
        }
        if args.material.is_some() && args.made_for.is_none() {
            bail!(
                "--material needs --made-for (its drape) or a hood run; {} is a {} run",
                args.run.display(),
                header.model
            );
        }
        let deformer = load_deformer(&args.run).with_context(loading)?;
        let frames = animate(deformer.as_ref(), &garment, &body, &betas, &motion)?;
        (deformer, frames, None, None, None)
    };
    let seconds = started.elapsed().as_secs_f64();
    // A diverged rollout keeps its finished frames: they are written, then reported.
    let motion = match &stopped {
        Some(_) => weft_motion::Motion::new(
            motion.fps(),
            motion.poses()[..frames.len()].to_vec(),
            motion.trans()[..frames.len()].to_vec(),
            motion.betas().map(<[f32]>::to_vec),
        )?,
        None => motion,
    };
    // The body goes into a morph-target scene here; a skinned one poses it itself.
    let scene_body = format.holds_scene() && !args.skinned;
    let posed = PosedSequence::new(&body, &betas, motion.poses(), motion.trans())?;
    let pushed = match push_out {
        Some(margin) if header.model != ModelKind::Hood => {
            Some(push_out_of_body(&mut frames, &posed, margin)?)
        }
        _ => None,
    };
    let check = check_animation(&garment, &frames, &posed)?;
    let bodies = scene_body.then(|| {
        (0..posed.len())
            .filter_map(|t| posed.mesh(t))
            .map(|m| {
                m.positions
                    .iter()
                    .map(|p| p.map(|x| x as f32))
                    .collect::<Vec<[f32; 3]>>()
            })
            .collect::<Vec<_>>()
    });
    if args.skinned {
        write_skinned_animation(
            &garment,
            loaded.corner_uvs.as_deref(),
            &frames,
            &body,
            &betas,
            &motion,
            &args.out,
        )?;
    } else {
        write_animation(
            format,
            &garment,
            loaded.corner_uvs.as_deref(),
            &frames,
            motion.fps(),
            bodies.as_ref().map(|b| (body.faces(), b.as_slice())),
            &args.out,
        )?;
    }
    if let Some((frame, why)) = &stopped {
        bail!(
            "the rollout diverged at frame {frame}: {why}; the {} finished frames were written to {} ({check})",
            frames.len(),
            args.out.display()
        );
    }
    if args.json {
        emit(&serde_json::to_string_pretty(&json!({
            "out": args.out,
            "format": format.name(),
            "frames": frames.len(),
            "vertices": garment.vertex_count(),
            "fps": motion.fps(),
            "model": deformer.name(),
            "inference_seconds": seconds,
            "pushed_out_vertices": pushed,
            "materials_outside": outside,
            "rollout_corrections": corrections.map(|c| json!({
                "edges_limited": c.edges_limited,
                "vertices_projected": c.vertices_projected,
            })),
            "check": check,
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
        if let Some(c) = corrections {
            emit(&format!(
                "during the rollout: {} edges shortened to the strain limit, {} vertex positions moved onto contact planes or out of the body (over all steps)",
                c.edges_limited, c.vertices_projected
            ))?;
        }
        if let Some(n) = pushed {
            emit(&format!(
                "pushed {n} vertex positions (over all frames) out of the body"
            ))?;
        }
        emit(&check.to_string())?;
    }
    Ok(())
}
