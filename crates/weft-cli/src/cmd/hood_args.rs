//! `weft animate`'s choices for a HOOD run, which picks them at run time: what the
//! garment is made of (one material, or a per-vertex map over a list of them), button
//! vertex pairs, the frame at which they come undone, run-time strain limiting
//! (stretch and compression), and whether the run's own step projection applies.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use weft_mesh::export::npy::{read_npy, NpyData};
use weft_models::hood::{HoodPredictor, Materials, OUTSIDE_MATERIAL_SPACE};
use weft_sim::StrainBounds;

use super::cloth_args::{buttons, material};

#[derive(Args)]
pub struct HoodArgs {
    /// HOOD: a material per garment vertex, as a .npy of one integer per vertex that
    /// indexes the comma-separated --material list (with --material denim,silk, 0 is
    /// denim and 1 silk).
    #[arg(long, value_name = "MAP.npy")]
    material_map: Option<PathBuf>,
    /// HOOD: button pairs, a JSON file `[[a, b], ...]` of 0-based garment vertex
    /// indices; each pair is held together by an extra graph edge.
    #[arg(long, value_name = "PAIRS.json")]
    buttons: Option<PathBuf>,
    /// HOOD: the buttons come undone at this frame (their edges leave the graph).
    #[arg(long, value_name = "FRAME", requires = "buttons")]
    unbutton_at: Option<usize>,
    /// HOOD: after every step, shorten edges stretched more than this many percent
    /// beyond their rest length (strain limiting, Provot 1995), and go on from there.
    /// Off by default: the network's steps as they are.
    #[arg(long, value_name = "PERCENT")]
    strain_limit: Option<f64>,
    /// HOOD: after every step, lengthen edges shortened more than this many percent
    /// below their rest length, so that the cloth buckles out of its plane instead of
    /// shrinking in it (with --strain-limit: both bounds, in the same sweeps). Off by
    /// default.
    #[arg(long, value_name = "PERCENT")]
    compression_limit: Option<f64>,
    /// HOOD: leave out the step projection the run was trained with (its `[model]
    /// project_*` bounds, which a rollout applies by default): the network's steps with
    /// only the corrections these flags ask for.
    #[arg(long)]
    no_projection: bool,
    /// HOOD: after every network step, this many Newton iterations of the step's
    /// incremental potential (the physics the network was trained to minimise),
    /// started from the network's prediction. 0 (the default): the network's steps.
    #[arg(long, value_name = "ITERATIONS", default_value_t = 0)]
    refine: usize,
    /// HOOD: roll out the run's objective instead of its network: every step the
    /// implicit Euler step of the incremental potential the network is trained on, from
    /// the same start and with the same corrections (what the network would give were it
    /// exact).
    #[arg(long)]
    objective: bool,
}

impl HoodArgs {
    /// The first HOOD-only flag given, to refuse it for a run of another model.
    pub fn given(&self) -> Option<&'static str> {
        if self.material_map.is_some() {
            Some("--material-map")
        } else if self.buttons.is_some() {
            Some("--buttons")
        } else if self.strain_limit.is_some() {
            Some("--strain-limit")
        } else if self.compression_limit.is_some() {
            Some("--compression-limit")
        } else if self.no_projection {
            Some("--no-projection")
        } else if self.refine > 0 {
            Some("--refine")
        } else if self.objective {
            Some("--objective")
        } else {
            None
        }
    }

    /// Sets `hood`'s materials (from `--material`, default HOOD's own) and buttons for a
    /// garment of `vertices` vertices. Returns what of the materials lies outside the
    /// run's material space, each also printed as a warning.
    pub fn configure(
        &self,
        hood: &mut HoodPredictor,
        materials: Option<&str>,
        vertices: usize,
    ) -> Result<Vec<String>> {
        let list: Vec<_> = match materials {
            Some(spec) => spec.split(',').map(material).collect::<Result<_>>()?,
            None => vec![weft_sim::Material::hood()],
        };
        hood.materials = match &self.material_map {
            None if list.len() > 1 => bail!(
                "--material {}: a list of materials needs --material-map to say which vertex is which",
                materials.unwrap_or_default()
            ),
            None => Materials::Uniform(list[0]),
            Some(path) => Materials::PerVertex(
                material_map(path, vertices, list.len())?
                    .into_iter()
                    .map(|k| list[k])
                    .collect(),
            ),
        };
        let outside = hood.materials_outside();
        for note in &outside {
            eprintln!("warning: --material {note}: {OUTSIDE_MATERIAL_SPACE}");
        }
        if let Some(path) = &self.buttons {
            hood.buttons = buttons(path)?;
        }
        hood.options.unbutton_at = self.unbutton_at;
        hood.options.strain_limit = strain_bounds(self.strain_limit, self.compression_limit)?;
        hood.options.projection = !self.no_projection;
        hood.options.refine = self.refine;
        hood.options.objective = self.objective;
        Ok(outside)
    }
}

/// `--strain-limit PERCENT` and `--compression-limit PERCENT` (`weft animate`, `weft
/// eval`) as fractions of the rest length.
pub(super) fn strain_bounds(
    stretch: Option<f64>,
    compression: Option<f64>,
) -> Result<StrainBounds> {
    if let Some(p) = stretch.filter(|p| !(p.is_finite() && *p >= 0.0)) {
        bail!("--strain-limit {p}: expected a percentage >= 0");
    }
    if let Some(p) = compression.filter(|p| !(p.is_finite() && (0.0..100.0).contains(p))) {
        bail!("--compression-limit {p}: expected a percentage >= 0 and below 100");
    }
    Ok(StrainBounds {
        stretch: stretch.map(|p| p / 100.0),
        compression: compression.map(|p| p / 100.0),
    })
}

/// `--push-out MM` (`weft animate` for every model, `weft eval` for HOOD) in metres.
pub(super) fn push_out(mm: f64) -> Result<f64> {
    if !(mm.is_finite() && mm >= 0.0) {
        bail!("--push-out {mm}: expected a distance in millimetres >= 0");
    }
    Ok(mm / 1000.0)
}

/// The per-vertex material indices in `path`: `vertices` integers below `materials`.
fn material_map(path: &std::path::Path, vertices: usize, materials: usize) -> Result<Vec<usize>> {
    let array = read_npy(path).with_context(|| format!("--material-map {}", path.display()))?;
    let values: Vec<i64> = match array.data {
        NpyData::I32(v) => v.into_iter().map(i64::from).collect(),
        NpyData::I64(v) => v,
        NpyData::U32(v) => v.into_iter().map(i64::from).collect(),
        NpyData::U8(v) => v.into_iter().map(i64::from).collect(),
        other => bail!(
            "--material-map {}: elements of type {}; expected integers (indices into --material)",
            path.display(),
            other.descr()
        ),
    };
    if values.len() != vertices {
        bail!(
            "--material-map {}: {} entries; expected one per garment vertex ({vertices})",
            path.display(),
            values.len()
        );
    }
    values
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            usize::try_from(k).ok().filter(|&k| k < materials).ok_or_else(|| {
                anyhow::anyhow!(
                    "--material-map {}: entry {i} is {k}; expected an index below the {materials} --material given",
                    path.display()
                )
            })
        })
        .collect()
}
