//! `weft.simulate`: weft's implicit-Euler cloth simulator on a moving body.

use numpy::PyArray3;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use weft_sim::{simulate_sequence, Attachment, Material, SequenceOptions};

use crate::arrays::to_3d;
use crate::body::{model_of, Body};
use crate::error::{invalid, value_error};
use crate::garment::Garment;
use crate::motion::Motion;

/// What [`simulate`] returns: the frames and one statistics dict per frame.
type Simulated<'py> = (Bound<'py, PyArray3<f32>>, Vec<Bound<'py, PyDict>>);

/// Simulates `garment` (fitted to the body at `betas`, rest pose) on `body` (default:
/// weft's) following `motion`. `material` is a preset name (hood, silk, cotton, jersey,
/// denim, leather); `attach` "top" holds the waistband or neckline on the skin, "none"
/// leaves contact and friction alone; `pinned` adds vertex indices held on the skin;
/// `buttons` are vertex pairs `(a, b)` held together (a spring as stiff as the fabric)
/// until output frame `unbutton_at`, if given.
/// Returns `(frames, stats)`: positions `float32` `(T, N, 3)` and one dict per frame
/// (seconds, Newton and CG iterations, edge strain, penetration). The GIL is released
/// while it runs.
#[pyfunction]
#[pyo3(signature = (garment, motion, material="cotton", body=None, betas=Vec::new(),
    substeps=4, warmup=15, frames=None, attach="top", pinned=Vec::new(), buttons=Vec::new(),
    unbutton_at=None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    garment: &Garment,
    motion: &Motion,
    material: &str,
    body: Option<&Body>,
    betas: Vec<f64>,
    substeps: usize,
    warmup: usize,
    frames: Option<usize>,
    attach: &str,
    pinned: Vec<u32>,
    buttons: Vec<[u32; 2]>,
    unbutton_at: Option<usize>,
) -> PyResult<Simulated<'py>> {
    let material = Material::preset(material).map_err(value_error)?;
    let attachment = match attach {
        "top" => Attachment::TopOpening,
        "none" => Attachment::None,
        _ => {
            return Err(invalid(format!(
                "attach {attach:?}; expected \"top\" or \"none\""
            )))
        }
    };
    let opts = SequenceOptions {
        substeps,
        warmup_frames: warmup,
        max_frames: frames,
        attachment,
        pinned,
        buttons,
        unbutton_at,
        ..SequenceOptions::default()
    };
    let model = model_of(body)?;
    let model = model.as_ref();
    let (mesh, motion) = (&garment.mesh, &motion.inner);
    // A diverged run is an error naming the frame (the finished frames are not
    // returned: a Python caller wants all of them or an exception).
    let seq = py
        .detach(|| simulate_sequence(mesh, &material, model, &betas, motion, &opts, &mut |_| {}))
        .map_err(value_error)?;
    let positions = to_3d(py, &seq.frames)?;
    let stats = seq
        .stats
        .iter()
        .map(|s| {
            let d = PyDict::new(py);
            d.set_item("frame", s.frame)?;
            d.set_item("seconds", s.seconds)?;
            d.set_item("newton_iterations", s.newton_iterations)?;
            d.set_item("cg_iterations", s.cg_iterations)?;
            d.set_item("mean_edge_strain", s.mean_edge_strain)?;
            d.set_item("max_edge_strain", s.max_edge_strain)?;
            d.set_item("max_penetration", s.max_penetration)?;
            d.set_item("penetrations", s.penetrations)?;
            Ok(d)
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok((positions, stats))
}
