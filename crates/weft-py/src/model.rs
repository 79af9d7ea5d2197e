//! `weft.Run`: a trained run of any model (`weft train`'s output directory), animating
//! any garment on any body shape and motion.

use std::path::PathBuf;

use numpy::PyArray3;
use pyo3::prelude::*;
use weft_models::{load_deformer, Deformer};

use crate::arrays::to_3d;
use crate::body::{model_of, Body};
use crate::error::value_error;
use crate::garment::Garment;
use crate::motion::Motion;

/// A trained run, loaded from its directory (the model kind is read from the run).
#[pyclass(module = "weft", frozen)]
pub struct Run {
    deformer: Box<dyn Deformer + Send>,
}

#[pymethods]
impl Run {
    #[new]
    fn new(path: PathBuf) -> PyResult<Self> {
        Ok(Run {
            deformer: load_deformer(&path).map_err(value_error)?,
        })
    }

    /// The model's name ("Multilevel", …).
    #[getter]
    fn name(&self) -> String {
        self.deformer.name()
    }

    /// The garment (any topology, fitted to the body at `betas` in the rest pose)
    /// deformed through `motion`: positions `float32` `(T, N, 3)`. The GIL is released
    /// while the network runs.
    #[pyo3(signature = (garment, motion, betas=Vec::new(), body=None))]
    fn animate<'py>(
        &self,
        py: Python<'py>,
        garment: &Garment,
        motion: &Motion,
        betas: Vec<f32>,
        body: Option<&Body>,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let model = model_of(body)?;
        let model = model.as_ref();
        let deformer = self.deformer.as_ref();
        let (mesh, motion) = (&garment.mesh, &motion.inner);
        let frames = py
            .detach(|| weft_eval::animate::animate(deformer, mesh, model, &betas, motion))
            .map_err(value_error)?;
        to_3d(py, &frames)
    }
}
