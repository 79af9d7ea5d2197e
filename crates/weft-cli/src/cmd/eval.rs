//! `weft eval`: a trained run (any model kind) and the LBS and DQS baselines against the
//! simulated ground truth of a dataset split (RUN/report/), or several runs side by side
//! as Table 1.

use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};
use weft_data::Split;
use weft_eval::evaluate::EvalOptions;
use weft_eval::report::{markdown_table, write_text, Comparison, EvalReport};
use weft_models::hood::RolloutOptions;
use weft_models::run::read_run_config;
use weft_render::Report;

use super::emit;

#[derive(Args)]
pub struct EvalArgs {
    /// Run directories written by `weft train`. One run is evaluated into RUN/report/
    /// (eval.json, eval.md, eval.html and pictures); with --compare, every run is
    /// evaluated (or its RUN/report/eval.json reused with --reuse) and the Table 1
    /// comparison is written to --out.
    #[arg(required = true, value_name = "RUN")]
    runs: Vec<PathBuf>,
    /// The dataset directory (written by `weft data generate`).
    #[arg(long, value_name = "DIR")]
    data: Option<PathBuf>,
    /// Which split: test (reported numbers), validation or train.
    #[arg(long, default_value = "test", value_parser = parse_split)]
    split: Split,
    /// Compare the runs (one per pooling variant, same data and budget) as Table 1.
    #[arg(long)]
    compare: bool,
    /// Where --compare writes table1.md, table1.html and table1.json.
    #[arg(long, value_name = "DIR", default_value = "table1")]
    out: PathBuf,
    /// With --compare: reuse a run's RUN/report/eval.json when it was made on the same
    /// data and split, instead of evaluating again.
    #[arg(long)]
    reuse: bool,
    /// Evaluate only the first N sequences of the split (N ≥ 1).
    #[arg(long, value_name = "N")]
    max_sequences: Option<std::num::NonZeroUsize>,
    /// Skip the garment–body collision check (one distance query per vertex and frame).
    #[arg(long)]
    no_collisions: bool,
    /// Skip timing inference.
    #[arg(long)]
    no_timing: bool,
    /// HOOD runs: skip scoring every method's steps by the run's potential (how far
    /// above its minimiser each step lies; one implicit Euler step per frame and method).
    #[arg(long)]
    no_potential: bool,
    /// Print the report (or the comparison) as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// HOOD runs: shorten edges stretched more than this many percent after every step
    /// of the rollout (`weft animate --strain-limit`). The report (RUN/report/) is then
    /// of the corrected rollouts, and the method is named with the corrections.
    #[arg(long, value_name = "PERCENT")]
    strain_limit: Option<f64>,
    /// HOOD runs: lengthen edges shortened more than this many percent after every step
    /// (`weft animate --compression-limit`).
    #[arg(long, value_name = "PERCENT")]
    compression_limit: Option<f64>,
    /// HOOD runs: after every step, move vertices inside the body or nearer than this
    /// many millimetres onto its surface at that distance (`weft animate --push-out`).
    #[arg(long, value_name = "MM")]
    push_out: Option<f64>,
    /// HOOD runs: leave out the step projection a run was trained with (`weft animate
    /// --no-projection`).
    #[arg(long)]
    no_projection: bool,
    /// HOOD runs: this many Newton iterations of each step's incremental potential after
    /// the network's step (`weft animate --refine`).
    #[arg(long, value_name = "ITERATIONS", default_value_t = 0)]
    refine: usize,
    /// HOOD runs: also score the run's objective, a row of its own: the same rollout
    /// with every step weft-sim's implicit Euler step of the potential the network is
    /// trained on (`weft animate --objective`).
    #[arg(long)]
    objective: bool,
    /// Character datasets only: move the root of every pose by this (x,y,z, metres), the
    /// translation test of seed 001 Fig. 3.23.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3)]
    translate: Option<[f64; 3]>,
}

fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("{x:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([x, y, z]),
        _ => Err(format!("{s:?}: expected three finite numbers x,y,z")),
    }
}

/// `--strain-limit`, `--compression-limit` and `--push-out` by flag, as given.
fn correction_flags(args: &EvalArgs) -> [(&'static str, Option<f64>); 3] {
    [
        ("--strain-limit", args.strain_limit),
        ("--compression-limit", args.compression_limit),
        ("--push-out", args.push_out),
    ]
}

/// The run-time corrections of `--strain-limit`, `--compression-limit` and `--push-out`,
/// refused unless one of the runs is a HOOD run (the only kind that takes them).
fn hood_options(args: &EvalArgs) -> Result<RolloutOptions> {
    use super::hood_args::{push_out, strain_bounds};
    let given = correction_flags(args)
        .iter()
        .find(|(_, v)| v.is_some())
        .map(|(flag, _)| *flag)
        .or(args.no_projection.then_some("--no-projection"))
        .or((args.refine > 0).then_some("--refine"))
        .or(args.objective.then_some("--objective"));
    if let Some(flag) = given {
        let hood = args.runs.iter().any(|r| {
            read_run_config(r).is_ok_and(|(h, _)| h.model == weft_models::ModelKind::Hood)
        });
        if !hood {
            bail!("{flag} applies to hood runs; none of the runs given is one");
        }
    }
    Ok(RolloutOptions {
        strain_limit: strain_bounds(args.strain_limit, args.compression_limit)?,
        contact_margin: args.push_out.map(push_out).transpose()?,
        projection: !args.no_projection,
        refine: args.refine,
        ..RolloutOptions::default()
    })
}

fn parse_split(s: &str) -> Result<Split, String> {
    Split::ALL
        .into_iter()
        .find(|x| x.name() == s)
        .ok_or_else(|| format!("unknown split {s:?}; expected train, validation or test"))
}

/// The command line as typed, for the reports' "reproduce with".
pub fn command_line() -> String {
    std::env::args()
        .map(|a| {
            if a.is_empty() || a.contains(|c: char| c.is_whitespace() || c == '"' || c == '\'') {
                format!("'{}'", a.replace('\'', "'\\''"))
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Evaluates `run` (whatever model kind trained it; a HOOD run with `hood`'s run-time
/// corrections) and the LBS and DQS baselines on `data`, writes RUN/report/ and returns
/// the report.
pub fn evaluate_run(
    run: &Path,
    data: &Path,
    opts: &EvalOptions,
    hood: &RolloutOptions,
    objective: bool,
    quiet: bool,
) -> Result<EvalReport> {
    // The heading is printed with the first progress line, so input that fails while
    // loading gives the one line of its error and nothing before it.
    let mut heading = Some(format!(
        "evaluating {} on the {} split of {}",
        run.display(),
        opts.split,
        data.display()
    ));
    let mut progress = |line: &str| {
        if let Some(h) = heading.take() {
            eprintln!("{h}");
        }
        if !quiet {
            eprintln!("  {line}");
        }
    };
    let (eval, html) =
        weft_pipeline::evaluate::evaluate_run(run, data, opts, hood, objective, &mut progress)?;
    if let Some(h) = heading {
        eprintln!("{h}");
    }
    eprintln!("  {}", eval.report.methods_line());
    eprintln!(
        "wrote {} (and eval.md, eval.json, pictures)",
        html.display()
    );
    Ok(eval.report)
}

pub fn run(args: &EvalArgs) -> Result<()> {
    let Some(data) = &args.data else {
        bail!("--data DIR is required: the dataset to evaluate on (the run does not record it)");
    };
    if data
        .join(weft_data::characters::CHARACTER_MANIFEST)
        .is_file()
    {
        return run_characters(args, data);
    }
    if args.runs.len() > 1 && !args.compare {
        bail!(
            "{} runs given; pass --compare to evaluate several runs as one table",
            args.runs.len()
        );
    }
    if data
        .join(weft_data::characters::CHARACTER_MANIFEST)
        .is_file()
    {
        return run_characters(args, data);
    }
    let hood = hood_options(args)?;
    let opts = EvalOptions {
        split: args.split,
        max_sequences: args.max_sequences.map(usize::from),
        collisions: !args.no_collisions,
        fps_batches: if args.no_timing { vec![] } else { vec![1, 16] },
        command: command_line(),
        potential: !args.no_potential,
        ..EvalOptions::default()
    };
    if !args.compare {
        let report = evaluate_run(&args.runs[0], data, &opts, &hood, args.objective, args.json)?;
        if args.json {
            emit(&serde_json::to_string_pretty(&report)?)?;
        } else {
            emit(&report.to_markdown())?;
        }
        return Ok(());
    }
    let mut reports = Vec::new();
    for run in &args.runs {
        let cached = run.join("report").join("eval.json");
        // A cached report does not say which corrections it was made with.
        let reused = if args.reuse
            && hood == RolloutOptions::default()
            && !args.objective
            && cached.is_file()
        {
            let r = EvalReport::read(&cached)?;
            (r.data == data.display().to_string() && r.split == args.split.name()).then_some(r)
        } else {
            None
        };
        let report = match reused {
            Some(r) => {
                eprintln!("reusing {}", cached.display());
                r
            }
            None => {
                let mut o = opts.clone();
                o.command = format!(
                    "weft eval {} --data {} --split {}",
                    run.display(),
                    data.display(),
                    args.split
                );
                // The corrections change a HOOD run's frames: the line must repeat them.
                for (flag, value) in correction_flags(args) {
                    if let Some(v) = value {
                        o.command += &format!(" {flag} {v}");
                    }
                }
                if args.no_projection {
                    o.command += " --no-projection";
                }
                evaluate_run(run, data, &o, &hood, args.objective, args.json)?
            }
        };
        reports.push(report);
    }
    let table = Comparison::new(reports, opts.command.clone())?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let md = table.to_markdown();
    write_text(&args.out.join("table1.md"), &md)?;
    let json: Vec<&EvalReport> = table.reports.iter().collect();
    write_text(
        &args.out.join("table1.json"),
        &serde_json::to_string_pretty(&json)?,
    )?;
    let mut html = Report::new("Table 1: pooling variants against the LBS-only baseline");
    let (h, rows) = table.table();
    html.table(h.clone(), rows.clone());
    html.paragraph("Mean (± std) over every vertex of every frame of the split.");
    html.heading("Reproduce");
    html.code(table.command.clone());
    html.write(&args.out.join("table1.html"))?;
    eprintln!(
        "wrote {} (and table1.md, table1.json)",
        args.out.join("table1.html").display()
    );
    if args.json {
        emit(&serde_json::to_string_pretty(&json)?)?;
    } else {
        let mut s = String::new();
        markdown_table(&mut s, &h, &rows);
        emit(&s)?;
    }
    Ok(())
}

/// A character dataset: every run (DenseGATs, MultiResGNet) and the LBS/DQS baselines as
/// seed 001's tables, written to --out (characters.md, characters.json, characters.png and
/// the joint close-ups elbows.png, knees.png, shoulders.png, hips.png).
fn run_characters(args: &EvalArgs, data: &Path) -> Result<()> {
    let (table, pictures) = weft_pipeline::characters::evaluate_characters(
        &args.runs,
        data,
        args.split,
        args.translate.unwrap_or([0.0; 3]),
    )?;
    let md = format!(
        "{}\nReproduce with: `{}`\n",
        table.markdown(),
        command_line()
    );
    std::fs::create_dir_all(&args.out).with_context(|| args.out.display().to_string())?;
    write_text(&args.out.join("characters.md"), &md)?;
    write_text(
        &args.out.join("characters.json"),
        &serde_json::to_string_pretty(&table)?,
    )?;
    for (name, picture) in &pictures {
        picture.write_png(&args.out.join(format!("{name}.png")))?;
    }
    if args.json {
        emit(&serde_json::to_string_pretty(&table)?)
    } else {
        emit(&md)
    }
}
