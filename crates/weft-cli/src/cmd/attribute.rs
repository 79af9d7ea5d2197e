//! `weft attribute`: the Aumann–Shapley attribution of seed 000 §4.1 (eq. 9) for one
//! output vertex of a trained model, drawn as a heat map on the garment.

use anyhow::{bail, Context, Result};
use clap::Args;
use serde_json::json;
use std::path::PathBuf;
use weft_data::{Dataset, Split};
use weft_eval::animate::MotionSpec;
use weft_eval::attribution::DEFAULT_SAMPLES;
use weft_eval::explain::explain_vertex;
use weft_eval::pictures::attribution_map;
use weft_models::multilevel::predictor::read_run_config;
use weft_models::multilevel::Predictor;
use weft_models::run::latest_checkpoint;
use weft_models::Clip;

use super::body_args::BodyArgs;
use super::emit;

#[derive(Args)]
pub struct AttributeArgs {
    /// Run directory written by `weft train`.
    #[arg(value_name = "RUN")]
    run: PathBuf,
    /// The output vertex whose position is explained.
    #[arg(long)]
    vertex: usize,
    /// The frame of the motion.
    #[arg(long, default_value_t = 0)]
    frame: usize,
    /// The heat map (.png).
    #[arg(long, value_name = "PNG")]
    out: PathBuf,
    /// Take garment, body shape and motion from a dataset sequence (with --sequence, or
    /// the first sequence of the test split).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["garment", "body", "betas"])]
    data: Option<PathBuf>,
    /// The dataset sequence id (see `weft data info`).
    #[arg(long, value_name = "ID", requires = "data")]
    sequence: Option<String>,
    /// Or a garment (.obj/.ply) dressed on the body in its rest pose, at --betas.
    #[arg(long, value_name = "G.obj")]
    garment: Option<PathBuf>,
    #[command(flatten)]
    body: BodyArgs,
    /// Motion for --garment: an .npz/.bvh file or a procedural name (walk, run, dance, …).
    #[arg(long, default_value = "walk")]
    motion: String,
    /// Gauss–Legendre nodes N_s of eq. 9 (the paper: 50), 1 to 1000.
    #[arg(long, default_value_t = DEFAULT_SAMPLES,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=1000))]
    samples: usize,
    /// Picture side in pixels, 64 to 8192.
    #[arg(long, default_value_t = 900, value_parser = clap::value_parser!(u32).range(64..=8192))]
    size: u32,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &AttributeArgs) -> Result<()> {
    if !super::has_extension(&args.out, &["png"]) {
        bail!("--out {} must end in .png", args.out.display());
    }
    // The garment, shape and motion are checked before the run is loaded, so a bad one
    // is named as such (and costs no model load).
    let own = match (&args.data, &args.garment) {
        (None, Some(path)) => {
            let (body, _) = args.body.load()?;
            let betas: Vec<f32> = args.body.betas(&body)?.iter().map(|&b| b as f32).collect();
            let spec = MotionSpec::parse(&args.motion, args.frame.max(1) + 1, 0, 30.0)
                .context("--motion")?;
            Some((path, body, betas, spec))
        }
        _ => None,
    };
    let config = read_run_config(&args.run)?;
    let checkpoint = latest_checkpoint(&args.run)?;
    let predictor =
        Predictor::from_checkpoint(config, &checkpoint, &weft_nn::backend::cpu_autodiff())?;
    let (garment, body, betas, poses, trans, fps, what) = match (&args.data, own) {
        (Some(dir), _) => {
            let ds = Dataset::open(dir)?;
            let record = match &args.sequence {
                Some(id) => ds.record(id)?.clone(),
                None => ds
                    .records_in(Split::Test)
                    .first()
                    .copied()
                    .cloned()
                    .with_context(|| format!("{} has no test sequence", dir.display()))?,
            };
            let seq = ds.load(&record)?;
            let body = ds.body_model()?;
            (
                seq.garment,
                body,
                record.betas.clone(),
                seq.poses,
                seq.trans,
                record.fps,
                format!("sequence {}", record.id),
            )
        }
        (None, Some((path, body, betas, spec))) => {
            let garment = weft_mesh::read_mesh(path)
                .with_context(|| format!("reading the garment {}", path.display()))?;
            let motion = spec.load(&body, &betas)?;
            (
                garment,
                body,
                betas,
                motion.poses().to_vec(),
                motion.trans().to_vec(),
                motion.fps(),
                format!("{} on motion {}", path.display(), args.motion),
            )
        }
        (None, None) => bail!("give --data DIR (a dataset sequence) or --garment G.obj"),
    };
    let clip = Clip {
        betas: &betas,
        poses: &poses,
        trans: &trans,
        fps,
    };
    let a = explain_vertex(
        predictor.model(),
        &garment,
        &body,
        &clip,
        args.vertex,
        args.frame,
        args.samples,
    )?;
    let title = format!(
        "attribution of vertex {} at frame {}",
        args.vertex, args.frame
    );
    let img = attribution_map(&a.predicted, &a.scores, args.vertex, args.size, &title)?;
    img.write_png(&args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    let r = &a.attribution;
    let total: f64 = r.values.iter().sum();
    if args.json {
        emit(&serde_json::to_string_pretty(&json!({
            "out": args.out,
            "input": what,
            "vertex": args.vertex,
            "frame": args.frame,
            "samples": r.samples,
            "direction": a.direction,
            "output": r.output,
            "baseline_output": r.baseline_output,
            "attribution_sum": total,
            "completeness_gap": r.completeness_gap(),
        }))?)?;
    } else {
        emit(&format!(
            "wrote {} ({}×{}): {what}, vertex {} at frame {}, N_s = {}\n\
             f_i (position along {:?}): {:.6} m at X, {:.6} m at the zero baseline; \
             attributions sum to {:.6} (completeness gap {:.2e})",
            args.out.display(),
            img.width(),
            img.height(),
            args.vertex,
            args.frame,
            r.samples,
            a.direction,
            r.output,
            r.baseline_output,
            total,
            r.completeness_gap()
        ))?;
    }
    Ok(())
}
