//! `--body` and `--betas`: the one argument type of every command that takes a body, so
//! that each loads the model, names it and checks β the same way.

use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::PathBuf;
use weft_body::default_body::DEFAULT_BODY_NAME;
use weft_body::{BodyModel, BETA_LIMIT};

/// `--body`: the body model alone, for commands that take no shape (or name theirs
/// differently, as `garment resize` does).
#[derive(Args)]
pub struct BodyModelArg {
    /// An SMPL-format body model (.npz: v_template, shapedirs, J_regressor, weights,
    /// kintree_table, f, optionally posedirs); default: weft's built-in body
    /// (assets/body).
    #[arg(long, value_name = "FILE.npz")]
    pub body: Option<PathBuf>,
}

impl BodyModelArg {
    /// The model and a name for messages (the file, or the built-in body).
    pub fn load(&self) -> Result<(BodyModel, String)> {
        let model = BodyModel::load_or_default(self.body.as_deref())?;
        let name = match &self.body {
            Some(path) => path.display().to_string(),
            None => format!("the {DEFAULT_BODY_NAME}"),
        };
        Ok((model, name))
    }
}

/// `--body` and `--betas`: a body model and its shape β.
#[derive(Args)]
pub struct BodyArgs {
    #[command(flatten)]
    pub model: BodyModelArg,
    /// Shape coefficients β1,β2,… of the body (missing ones are 0; negative ones as in
    /// `--betas -1,2`).
    #[arg(
        long,
        value_name = "B1,B2,…",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub betas: Vec<f64>,
    #[command(flatten)]
    pub limit: ShapeLimit,
}

/// `--allow-extreme-shapes`: lifts the ±[`BETA_LIMIT`] bound on β for whoever needs
/// bodies outside the scanned population (stress tests, stylised characters).
#[derive(Args, Clone, Copy, Default)]
pub struct ShapeLimit {
    /// Accept shape coefficients beyond ±5 (β are standard deviations of the body
    /// population; past 5 the body is no longer human-like). Non-finite values are
    /// always refused.
    #[arg(long)]
    pub allow_extreme_shapes: bool,
}

impl BodyArgs {
    /// The model and a name for messages (the file, or the built-in body).
    pub fn load(&self) -> Result<(BodyModel, String)> {
        self.model.load()
    }

    /// `--betas` as the model's shape vector (see [`shape`]).
    pub fn betas(&self, model: &BodyModel) -> Result<Vec<f64>> {
        shape(model, &self.betas, "betas", self.limit)
    }
}

/// The β given with `--flag`, padded with zeros to the model's count; more values than
/// the model has, and (unless `limit` lifts it) any beyond ±[`BETA_LIMIT`], are refused,
/// naming the flag and the limit.
pub fn shape(model: &BodyModel, given: &[f64], flag: &str, limit: ShapeLimit) -> Result<Vec<f64>> {
    let betas = model.betas(given).with_context(|| format!("--{flag}"))?;
    if !limit.allow_extreme_shapes {
        if let Some((i, b)) = betas.iter().enumerate().find(|(_, b)| b.abs() > BETA_LIMIT) {
            bail!(
                "--{flag}: β{} = {b} is outside ±{BETA_LIMIT} (β are standard deviations of the body population; past {BETA_LIMIT} the body is no longer human-like); pass --allow-extreme-shapes to use it anyway",
                i + 1
            );
        }
    }
    Ok(betas)
}
