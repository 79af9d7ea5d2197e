//! `weft.Motion`, `weft.load_motion` and `weft.procedural_motion`: SMPL-parametrised
//! motions from AMASS `.npz`, BVH of any skeleton, or weft's procedural library.

use std::path::PathBuf;

use numpy::{PyArray2, PyArray3};
use pyo3::prelude::*;
use weft_motion::{
    body_rest_joints, generate, load_motion as read, write_motion, MotionFileOptions, MotionKind,
    ProceduralParams, UpAxis,
};

use crate::arrays::{coerce, rows3, to_2d, to_3d};
use crate::body::{model_of, to_poses, Body};
use crate::error::{invalid, os_error, value_error};

/// A motion: SMPL poses `(T, 24, 3)`, root translations `(T, 3)` and a frame rate.
#[pyclass(module = "weft", frozen)]
pub struct Motion {
    pub(crate) inner: weft_motion::Motion,
}

#[pymethods]
impl Motion {
    /// A motion from arrays: `poses` `(T, 24, 3)` axis-angle, `trans` `(T, 3)` metres.
    #[new]
    #[pyo3(signature = (poses, trans, fps))]
    fn new(poses: &Bound<'_, PyAny>, trans: &Bound<'_, PyAny>, fps: f64) -> PyResult<Self> {
        let poses = to_poses(poses)?;
        let trans = rows3(&coerce(trans, "float32", "trans")?, "trans")?;
        let inner = weft_motion::Motion::new(fps, poses, trans, None).map_err(value_error)?;
        Ok(Motion { inner })
    }

    /// Frames per second.
    #[getter]
    fn fps(&self) -> f64 {
        self.inner.fps()
    }

    /// Number of frames.
    #[getter]
    fn frame_count(&self) -> usize {
        self.inner.frame_count()
    }

    fn __len__(&self) -> usize {
        self.inner.frame_count()
    }

    /// Axis-angle per joint per frame, `float32` `(T, 24, 3)`.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let frames: Vec<Vec<[f32; 3]>> = self.inner.poses().iter().map(|p| p.to_vec()).collect();
        to_3d(py, &frames)
    }

    /// Root translation per frame (metres, Y up), `float32` `(T, 3)`.
    #[getter]
    fn trans<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        to_2d(py, self.inner.trans())
    }

    /// Writes the motion as AMASS-style `.npz` (`npz_up`: "z" as AMASS, or "y") or as
    /// `.bvh` on SMPL's skeleton, for `body` at `betas` (default: weft's body).
    #[pyo3(signature = (path, npz_up="z", body=None, betas=Vec::new()))]
    fn save(
        &self,
        path: PathBuf,
        npz_up: &str,
        body: Option<&Body>,
        betas: Vec<f64>,
    ) -> PyResult<()> {
        let options = file_options(body, &betas, Some(parse_up(npz_up)?))?;
        write_motion(&path, &self.inner, &options).map_err(os_error)
    }

    fn __repr__(&self) -> String {
        format!(
            "Motion({} frames at {} fps)",
            self.inner.frame_count(),
            self.inner.fps()
        )
    }
}

fn parse_up(up: &str) -> PyResult<UpAxis> {
    match up.to_ascii_lowercase().as_str() {
        "y" => Ok(UpAxis::Y),
        "z" => Ok(UpAxis::Z),
        _ => Err(invalid(format!("up axis {up:?}; expected \"y\" or \"z\""))),
    }
}

/// Motion-file options for `body` (default: weft's) at `betas`.
fn file_options(
    body: Option<&Body>,
    betas: &[f64],
    up: Option<UpAxis>,
) -> PyResult<MotionFileOptions> {
    let model = model_of(body)?;
    let model = model.as_ref();
    let rest = body_rest_joints(model, betas).map_err(value_error)?;
    Ok(MotionFileOptions::for_body(rest, up))
}

/// Reads an AMASS-style `.npz` or a `.bvh` (any skeleton, retargeted to SMPL) for
/// `body` at `betas`, as every weft command reads motions; `fps` resamples it, `up`
/// ("y" or "z") overrides the file's up axis.
#[pyfunction]
#[pyo3(signature = (path, fps=None, up=None, body=None, betas=Vec::new()))]
pub fn load_motion(
    path: PathBuf,
    fps: Option<f64>,
    up: Option<&str>,
    body: Option<&Body>,
    betas: Vec<f64>,
) -> PyResult<Motion> {
    let up = up.map(parse_up).transpose()?;
    let options = file_options(body, &betas, up)?;
    let read = read(&path, &options, fps).map_err(value_error)?;
    Ok(Motion { inner: read.motion })
}

/// A motion of weft's procedural library: walk, run, jump, dance, kick, raise-arms,
/// twist or bow.
#[pyfunction]
#[pyo3(signature = (kind, frames=120, fps=30.0, seed=0, speed=None, amplitude=1.0))]
pub fn procedural_motion(
    kind: &str,
    frames: usize,
    fps: f64,
    seed: u64,
    speed: Option<f64>,
    amplitude: f64,
) -> PyResult<Motion> {
    let kind = MotionKind::parse(kind).ok_or_else(|| {
        let names: Vec<&str> = MotionKind::ALL.iter().map(|k| k.name()).collect();
        invalid(format!(
            "motion {kind:?}; expected one of {}",
            names.join(", ")
        ))
    })?;
    let params = ProceduralParams {
        kind,
        frames,
        fps,
        seed,
        speed,
        amplitude,
    };
    Ok(Motion {
        inner: generate(&params).map_err(value_error)?,
    })
}
