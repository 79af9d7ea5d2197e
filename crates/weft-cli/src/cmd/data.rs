//! `weft data generate | import | info | merge | characters`: simulated and imported
//! datasets, and seed 001's character datasets (weft-data).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use weft_data::characters::{build_characters, CharacterConfig};
use weft_data::progress::FrameBar;
use weft_data::{generate, DataConfig, DataError, DatasetInfo, GenerateOptions, Job, Physics};

use super::emit;

#[derive(Subcommand)]
pub enum DataCommand {
    /// Simulate a dataset (garments × body shapes × motions) into safetensors shards
    /// and a manifest; resumes an interrupted run in the same directory.
    Generate(GenerateArgs),
    /// Summarise a dataset: counts per split, vertex counts, materials, size on disk,
    /// diverged, failed and missing sequences.
    Info(InfoArgs),
    /// Merge the partial manifests of `--shard i/n` jobs into manifest.json.
    Merge(MergeArgs),
    /// Turn your own simulations (PC2, MDD, .npy or OBJ-sequence caches from Marvelous
    /// Designer, Houdini, Blender, …, with each garment's rest mesh, the body shape and
    /// its motion) into a dataset every model trains and evaluates on.
    Import(ImportArgs),
    /// Build a character dataset for DenseGATs / MultiResGNet: dressed characters (body
    /// and tight garment layers as one mesh) in random and clip poses, with a nonlinear
    /// ground-truth deformation of every pose; resumes an interrupted build.
    Characters(CharactersArgs),
}

#[derive(Args)]
pub struct CharactersArgs {
    /// A built-in config: tiny (minutes here) or paper (seed 001's proportions).
    #[arg(long, conflicts_with = "config")]
    preset: Option<String>,
    /// A character dataset config (TOML); see `--print-config` for every field.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Print the config (the preset's, default tiny) as TOML and exit.
    #[arg(long)]
    print_config: bool,
    /// Override the config's seed.
    #[arg(long)]
    seed: Option<u64>,
    /// Output directory.
    #[arg(long, required_unless_present = "print_config")]
    out: Option<PathBuf>,
}

#[derive(Args)]
pub struct ImportArgs {
    /// The import file (TOML): fps, optional body/scale/up, [[garments]] (id, template)
    /// and [[sequences]] (garment, cache, motion, betas, split, start); paths relative to
    /// it. See docs/datasets.md ("Importing your own simulations").
    #[arg(value_name = "IMPORT.toml")]
    spec: PathBuf,
    /// The new dataset directory (must not exist or be empty; written all or nothing).
    #[arg(long)]
    out: PathBuf,
    /// Print one JSON object describing what was written.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
pub struct GenerateArgs {
    /// A built-in config: tiny (a minute on a laptop), small (7× tiny's training data,
    /// minutes), paper (seed 000's proportions), or GarFitNet's fit data (one garment on
    /// bodies of different weight): garfit-tiny (minutes) and garfit-paper (seed 001
    /// ch. 4's proportions).
    #[arg(long, conflicts_with = "config")]
    preset: Option<String>,
    /// A dataset config (TOML); see `--print-config` for every field.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Print the config (the preset's, default tiny) as TOML and exit.
    #[arg(long)]
    print_config: bool,
    /// Override the config's seed.
    #[arg(long)]
    seed: Option<u64>,
    /// Output directory.
    #[arg(long, required_unless_present = "print_config")]
    out: Option<PathBuf>,
    /// Generate only sequences with index % n == i (one of n cluster jobs), writing
    /// manifest.part-i-of-n.json; merge with `weft data merge DIR`.
    #[arg(long)]
    shard: Option<String>,
}

#[derive(Args)]
pub struct InfoArgs {
    /// The dataset directory.
    dir: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Also load every shard and check it against the manifest (fails if any is broken).
    #[arg(long)]
    verify: bool,
}

#[derive(Args)]
pub struct MergeArgs {
    /// The dataset directory the jobs wrote to.
    dir: PathBuf,
}

pub fn run(command: DataCommand) -> Result<()> {
    match command {
        DataCommand::Generate(a) => run_generate(&a),
        DataCommand::Info(a) => run_info(&a),
        DataCommand::Merge(a) => {
            let path = weft_data::merge_directory(&a.dir)?;
            emit(&format!("wrote {}", path.display()))
        }
        DataCommand::Import(a) => run_import(&a),
        DataCommand::Characters(a) => run_characters(&a),
    }
}

fn run_characters(a: &CharactersArgs) -> Result<()> {
    let mut config = match (&a.config, &a.preset) {
        (Some(path), _) => {
            CharacterConfig::load(path).with_context(|| path.display().to_string())?
        }
        (None, Some(name)) => CharacterConfig::preset(name).context("--preset")?,
        (None, None) => CharacterConfig::tiny(),
    };
    if let Some(seed) = a.seed {
        config.seed = seed;
    }
    if a.print_config {
        return emit(&config.to_toml());
    }
    let Some(out) = &a.out else {
        bail!("--out DIR is required to build");
    };
    let r = build_characters(&config, out, true)
        .with_context(|| format!("building the character dataset in {}", out.display()))?;
    emit(&format!(
        "{}: {} characters built ({} poses in {:.1} s), {} kept from an earlier run",
        out.join(weft_data::characters::CHARACTER_MANIFEST)
            .display(),
        r.built,
        r.poses,
        r.seconds,
        r.kept
    ))
}

fn run_import(a: &ImportArgs) -> Result<()> {
    let r = weft_data::import(&a.spec, &a.out)?;
    let [train, validation, test] = r.sequences;
    if a.json {
        return emit(&serde_json::to_string_pretty(&serde_json::json!({
            "out": r.dir,
            "train": train,
            "validation": validation,
            "test": test,
            "frames": r.frames,
            "flattened_uvs": r.flattened,
        }))?);
    }
    for g in &r.flattened {
        eprintln!(
            "note: garment {g}: its rest mesh has no UVs; each triangle is laid flat as its rest frame"
        );
    }
    emit(&format!(
        "imported {} sequences ({train} train, {validation} validation, {test} test; {} frames) into {}",
        train + validation + test,
        r.frames,
        r.dir.display()
    ))
}

fn run_generate(a: &GenerateArgs) -> Result<()> {
    // A bad config value (weft-data names its key) also names the file it came from.
    let in_config_file = |e: DataError| -> anyhow::Error {
        match (&a.config, &e) {
            (Some(path), DataError::Config { .. }) => {
                anyhow::Error::new(e).context(path.display().to_string())
            }
            _ => e.into(),
        }
    };
    let mut config = match (&a.config, &a.preset) {
        (Some(path), _) => DataConfig::load(path).map_err(in_config_file)?,
        (None, Some(name)) => DataConfig::preset(name).context("--preset")?,
        (None, None) => DataConfig::tiny(),
    };
    if let Some(seed) = a.seed {
        config.seed = seed;
    }
    if a.print_config {
        return emit(&config.to_toml()?);
    }
    let Some(out) = &a.out else {
        bail!("--out DIR is required to generate");
    };
    let job = a.shard.as_deref().map(Job::parse).transpose()?;
    let bar = FrameBar::new();
    let report = generate(&config, out, &GenerateOptions { job }, &Physics, &bar)
        .map_err(in_config_file)
        .with_context(|| format!("generating the dataset in {}", out.display()))?;
    let mut text = format!(
        "{}: {} sequences in this job, {} kept from an earlier run, {} simulated ({} frames in {:.1} s)",
        report.manifest_path.display(),
        report.owned,
        report.kept,
        report.done + report.diverged.len(),
        report.frames,
        report.seconds
    );
    for (id, frame) in &report.diverged {
        text.push_str(&format!("\ndiverged: {id} at frame {frame}"));
    }
    for (id, why) in &report.failed {
        text.push_str(&format!("\nfailed: {id}: {why}"));
    }
    emit(&text)?;
    if !report.failed.is_empty() {
        bail!(
            "{} sequences failed (recorded in {})",
            report.failed.len(),
            report.manifest_path.display()
        );
    }
    Ok(())
}

fn run_info(a: &InfoArgs) -> Result<()> {
    let mut info = DatasetInfo::of(&a.dir)?;
    if a.verify {
        info.verify(&a.dir)?;
    }
    if a.json {
        emit(&serde_json::to_string_pretty(&info)?)?;
    } else {
        emit(&info.to_string())?;
    }
    match &info.verified {
        Some(v) if !v.broken.is_empty() => bail!(
            "{} of {} shards are broken or changed since they were written ({}); run `weft data generate` again with the dataset's config and `--out {}` to simulate them again",
            v.broken.len(),
            v.broken.len() + v.loaded,
            v.broken
                .iter()
                .map(|(id, _)| weft_data::manifest::shard_path(id))
                .collect::<Vec<_>>()
                .join(", "),
            a.dir.display()
        ),
        _ => Ok(()),
    }
}
