//! `weft garment generate`: procedural garment templates fitted to a body.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use weft_body::BodyModel;
use weft_garment::{DressTop, FitBody, GarmentKind, SkirtLength, Style};
use weft_mesh::Topology;

use super::emit;

#[derive(Subcommand)]
pub enum GarmentCommand {
    /// Write a procedural garment template (OBJ with UVs) fitted to a body.
    Generate(GenerateArgs),
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
    /// A body model in the SMPL .npz layout to fit to; default: weft's default body.
    #[arg(long)]
    body: Option<PathBuf>,
    /// Shape coefficients β of that body, comma-separated (missing ones are 0).
    #[arg(long, allow_hyphen_values = true)]
    betas: Option<String>,
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
}

pub fn run(command: GarmentCommand) -> Result<()> {
    match command {
        GarmentCommand::Generate(a) => run_generate(&a),
    }
}

fn number<T: std::str::FromStr>(flag: &str, text: &str) -> Result<T> {
    text.trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("--{flag} {text:?} is not a valid number"))
}

fn run_generate(a: &GenerateArgs) -> Result<()> {
    let kind = GarmentKind::parse(&a.kind)?;
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
    }
    if let Some(t) = &a.dress_top {
        style.dress_top = match t.as_str() {
            "strapless" => DressTop::Strapless,
            "straps" => DressTop::Straps,
            "sleeves" => DressTop::Sleeves,
            _ => bail!("--dress-top {t:?}: expected strapless, straps or sleeves"),
        };
    }
    let betas: Vec<f64> = match &a.betas {
        None => Vec::new(),
        Some(text) => text
            .split(',')
            .map(|b| number("betas", b))
            .collect::<Result<_>>()?,
    };
    let (model, name) = match &a.body {
        Some(path) => (BodyModel::load(path)?, path.display().to_string()),
        None => (weft_body::default_body()?, "the default body".to_string()),
    };
    if betas.len() > model.num_betas() {
        bail!(
            "--betas has {} values; {name} has {}",
            betas.len(),
            model.num_betas()
        );
    }
    let mut betas = betas;
    betas.resize(model.num_betas(), 0.0);
    let fit = FitBody::new(&model, &betas).with_context(|| format!("{name}: fitting"))?;
    let garment = fit.generate(kind, &style, vertices)?;
    let fitted_to = name;
    weft_garment::obj::write_obj(&a.out, &garment)?;
    let openings = Topology::new(&garment.mesh).boundary_loops().len();
    emit(&format!(
        "wrote {}: {} with {} vertices, {} faces, {} openings, fitted to {}",
        a.out.display(),
        kind.name(),
        garment.mesh.vertex_count(),
        garment.mesh.face_count(),
        openings,
        fitted_to
    ))
}
