//! `weft.Body`: an SMPL-format body model (weft's default or a user's `.npz`), shaped
//! by β and posed by SMPL parameters.

use std::borrow::Cow;
use std::path::PathBuf;

use numpy::{PyArray2, PyArray3, PyReadonlyArray3};
use pyo3::prelude::*;
use weft_body::{BodyModel, Pose, PosedSequence};

use crate::arrays::{coerce, frames3, rows3, to_2d, to_3d};
use crate::error::{invalid, value_error};

/// An SMPL-format body model: `Body()` is weft's default body, `Body("model.npz")` a
/// SMPL-layout file (v_template, shapedirs, J_regressor, weights, kintree_table, f).
#[pyclass(module = "weft", frozen)]
pub struct Body {
    pub(crate) model: BodyModel,
}

#[pymethods]
impl Body {
    #[new]
    #[pyo3(signature = (path=None))]
    fn new(path: Option<PathBuf>) -> PyResult<Self> {
        let model = BodyModel::load_or_default(path.as_deref()).map_err(value_error)?;
        Ok(Body { model })
    }

    /// Where the model came from.
    #[getter]
    fn source(&self) -> String {
        self.model.source().to_owned()
    }

    /// Number of vertices.
    #[getter]
    fn vertex_count(&self) -> usize {
        self.model.vertex_count()
    }

    /// Number of shape coefficients β the model has.
    #[getter]
    fn num_betas(&self) -> usize {
        self.model.num_betas()
    }

    /// Triangles, `uint32` of shape `(F, 3)`.
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u32>> {
        to_2d(py, self.model.faces())
    }

    /// The body at shape `betas` in its rest pose, `float32` `(V, 3)`.
    #[pyo3(signature = (betas=Vec::new()))]
    fn rest<'py>(&self, py: Python<'py>, betas: Vec<f64>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let shaped = self.model.shaped(&betas).map_err(value_error)?;
        let v: Vec<[f32; 3]> = shaped
            .vertices
            .iter()
            .map(|p| p.map(|c| c as f32))
            .collect();
        Ok(to_2d(py, &v))
    }

    /// The rest joints J(β), `float32` `(24, 3)`.
    #[pyo3(signature = (betas=Vec::new()))]
    fn joints<'py>(&self, py: Python<'py>, betas: Vec<f64>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let j = self.model.joints(&betas).map_err(value_error)?;
        let j: Vec<[f32; 3]> = j.iter().map(|p| p.map(|c| c as f32)).collect();
        Ok(to_2d(py, &j))
    }

    /// The body posed by linear blend skinning: `poses` `(T, 24, 3)` axis-angle per
    /// joint, `trans` `(T, 3)` root translations (metres), shape `betas`. Returns the
    /// vertices per frame, `float32` `(T, V, 3)`.
    #[pyo3(signature = (poses, trans, betas=Vec::new()))]
    fn pose<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
        trans: &Bound<'py, PyAny>,
        betas: Vec<f32>,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let poses = to_poses(poses)?;
        let trans = rows3(&coerce(trans, "float32", "trans")?, "trans")?;
        if trans.len() != poses.len() {
            return Err(invalid(format!(
                "{} poses but {} root translations; expected one per frame",
                poses.len(),
                trans.len()
            )));
        }
        let posed = PosedSequence::new(&self.model, &betas, &poses, &trans).map_err(value_error)?;
        let frames: Vec<Vec<[f32; 3]>> = (0..posed.len())
            .filter_map(|t| posed.frame(t).map(<[_]>::to_vec))
            .collect();
        to_3d(py, &frames)
    }
}

/// `body`'s model, or weft's default body when none is given.
pub fn model_of(body: Option<&Body>) -> PyResult<Cow<'_, BodyModel>> {
    match body {
        Some(b) => Ok(Cow::Borrowed(&b.model)),
        None => Ok(Cow::Owned(weft_body::default_body().map_err(value_error)?)),
    }
}

/// `(T, 24, 3)` poses (`(T, 72)` is accepted too, as AMASS stores them).
pub fn to_poses(obj: &Bound<'_, PyAny>) -> PyResult<Vec<Pose>> {
    let obj = match obj.getattr("ndim").and_then(|n| n.extract::<usize>()) {
        Ok(2) => obj.call_method1("reshape", (-1, 24, 3))?,
        _ => obj.clone(),
    };
    let a: PyReadonlyArray3<'_, f32> = coerce(&obj, "float32", "poses")?;
    let frames = frames3(&a, "poses")?;
    frames
        .into_iter()
        .map(|f| {
            Pose::try_from(f.as_slice()).map_err(|_| {
                invalid(format!(
                    "poses: {} joints per frame; expected (T, 24, 3) in SMPL's joint order",
                    f.len()
                ))
            })
        })
        .collect()
}
