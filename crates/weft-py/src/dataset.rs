//! `weft.Dataset`: a dataset directory (generated or imported) read as numpy arrays.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use weft_data::{SequenceRecord, Split};

use crate::arrays::{to_2d, to_3d};
use crate::body::Body;
use crate::error::{invalid, value_error};

/// A weft dataset: `manifest.json` and one safetensors shard per sequence.
#[pyclass(module = "weft", frozen)]
pub struct Dataset {
    inner: weft_data::Dataset,
}

fn parse_split(name: &str) -> PyResult<Split> {
    Split::ALL
        .into_iter()
        .find(|s| s.name() == name)
        .ok_or_else(|| {
            invalid(format!(
                "split {name:?}; expected train, validation or test"
            ))
        })
}

fn record_dict<'py>(py: Python<'py>, r: &SequenceRecord) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("id", &r.id)?;
    d.set_item("split", r.split.name())?;
    d.set_item("garment", &r.garment_id)?;
    d.set_item("garment_kind", &r.garment_kind)?;
    d.set_item("body", &r.body_id)?;
    d.set_item("betas", r.betas.clone())?;
    d.set_item("motion", &r.motion_id)?;
    d.set_item("frames", r.frames)?;
    d.set_item("fps", r.fps)?;
    d.set_item("vertices", r.vertices)?;
    d.set_item("status", r.status.name())?;
    Ok(d)
}

#[pymethods]
impl Dataset {
    /// Opens `path` (reads and validates its manifest).
    #[new]
    fn new(path: PathBuf) -> PyResult<Self> {
        Ok(Dataset {
            inner: weft_data::Dataset::open(&path).map_err(value_error)?,
        })
    }

    /// Frames per second of every sequence.
    #[getter]
    fn fps(&self) -> f64 {
        self.inner.manifest().fps
    }

    /// The loadable sequences (done, or diverged with frames) of `split` ("train",
    /// "validation", "test"), or of every split, as dicts (id, split, garment, body,
    /// betas, motion, frames, fps, vertices, status).
    #[pyo3(signature = (split=None))]
    fn records<'py>(
        &self,
        py: Python<'py>,
        split: Option<&str>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let splits = match split {
            Some(s) => vec![parse_split(s)?],
            None => Split::ALL.to_vec(),
        };
        splits
            .into_iter()
            .flat_map(|s| self.inner.records_in(s))
            .map(|r| record_dict(py, r))
            .collect()
    }

    /// One sequence by id, as arrays: `positions` `(T, N, 3)`, `poses` `(T, 24, 3)`,
    /// `trans` `(T, 3)`, `betas` `(B,)` list, `rest_positions` `(N, 3)`, `faces`
    /// `(F, 3)`, `corner_uvs` `(F, 3, 2)`. `verify` also checks the shard's SHA-256.
    #[pyo3(signature = (id, verify=false))]
    fn load<'py>(&self, py: Python<'py>, id: &str, verify: bool) -> PyResult<Bound<'py, PyDict>> {
        let record = self.inner.record(id).map_err(value_error)?;
        let seq = if verify {
            self.inner.load_verified(record)
        } else {
            self.inner.load(record)
        }
        .map_err(value_error)?;
        let d = PyDict::new(py);
        d.set_item("positions", to_3d(py, &seq.positions)?)?;
        let poses: Vec<Vec<[f32; 3]>> = seq.poses.iter().map(|p| p.to_vec()).collect();
        d.set_item("poses", to_3d(py, &poses)?)?;
        d.set_item("trans", to_2d(py, &seq.trans))?;
        d.set_item("betas", record.betas.clone())?;
        let rest: Vec<[f32; 3]> = seq
            .garment
            .positions
            .iter()
            .map(|p| p.map(|c| c as f32))
            .collect();
        d.set_item("rest_positions", to_2d(py, &rest))?;
        d.set_item("faces", to_2d(py, &seq.garment.faces))?;
        let uvs: Vec<Vec<[f32; 2]>> = seq.corner_uvs.iter().map(|t| t.to_vec()).collect();
        d.set_item("corner_uvs", to_3d(py, &uvs)?)?;
        d.set_item("fps", record.fps)?;
        Ok(d)
    }

    /// The body model the β belong to.
    fn body(&self) -> PyResult<Body> {
        Ok(Body {
            model: self.inner.body_model().map_err(value_error)?,
        })
    }

    fn __len__(&self) -> usize {
        self.inner.records().len()
    }
}

/// Imports your own simulations into a new dataset directory `out`: `spec` is a TOML
/// import file (fps, [[garments]] with rest meshes, [[sequences]] with caches, motions,
/// betas and splits; see docs/datasets.md). Returns the dataset.
#[pyfunction]
pub fn import_dataset(spec: PathBuf, out: PathBuf) -> PyResult<Dataset> {
    weft_data::import(&spec, &out).map_err(value_error)?;
    Dataset::new(out)
}
