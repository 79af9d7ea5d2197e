//! `weft demo`: the whole path with no arguments — tiny dataset, `cpu` training,
//! evaluation against the LBS-only baseline, an unseen garment animated on an unseen
//! motion, one attribution map, one HTML report (weft_pipeline::demo).

use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;
use weft_data::progress::FrameBar;
use weft_data::Physics;
use weft_pipeline::demo::{run_demo, DemoOptions};

use super::emit;

#[derive(Args)]
pub struct DemoArgs {
    /// Output directory: data/ (the dataset), run/ (the trained model and its
    /// evaluation in run/report/), animation/, attribution.png and report.html. Running
    /// the demo again reuses what is complete there.
    #[arg(long, value_name = "DIR", default_value = "weft-demo")]
    out: PathBuf,
    /// A micro configuration (two-sequence dataset, a few training steps) that checks
    /// every stage in a minute; the figures it reports mean nothing.
    #[arg(long)]
    quick: bool,
    /// Training steps, at least 1 (default: the cpu preset's 10 000, as `weft train`;
    /// fewer train faster and less accurately on the same schedule).
    #[arg(long)]
    steps: Option<std::num::NonZeroUsize>,
}

pub fn run(args: &DemoArgs) -> Result<()> {
    let started = Instant::now();
    if args.out.exists() && !args.out.is_dir() {
        bail!(
            "--out {}: exists and is not a directory; expected a directory for the demo's dataset, run and report",
            args.out.display()
        );
    }
    eprintln!(
        "weft demo: dataset, training, evaluation, animation and attribution in {}",
        args.out.display()
    );
    let opts = DemoOptions {
        out: args.out.clone(),
        quick: args.quick,
        steps: args.steps.map(usize::from),
    };
    let bar = FrameBar::new();
    let summary = run_demo(&opts, &Physics, &bar, &mut |line| eprintln!("{line}"))
        .with_context(|| format!("weft demo in {}", args.out.display()))?;
    emit(&format!(
        "done in {:.1} min: test-split vertex error {:.2} mm (model) vs {:.2} mm (LBS only)\nreport: {}",
        started.elapsed().as_secs_f64() / 60.0,
        summary.model_mm,
        summary.lbs_mm,
        summary.report.display()
    ))
}
