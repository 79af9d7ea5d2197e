//! `weft.Garment`, `weft.generate_garment` and `weft.load_garment`: triangle meshes with
//! corner UVs (the sewing pattern), procedural or read from OBJ/PLY.

use std::path::PathBuf;

use numpy::{PyArray2, PyArray3};
use pyo3::prelude::*;
use weft_garment::{FitBody, GarmentKind, Style};
use weft_mesh::TriMesh;

use crate::arrays::{to_2d, to_3d};
use crate::body::{model_of, Body};
use crate::error::{os_error, value_error};

/// A garment: rest positions `(N, 3)`, triangles `(F, 3)` and, when it has them, the
/// UV of each triangle corner `(F, 3, 2)` in metres.
#[pyclass(module = "weft", frozen)]
pub struct Garment {
    pub(crate) mesh: TriMesh,
    pub(crate) uvs: Option<Vec<[[f32; 2]; 3]>>,
    kind: String,
}

impl Garment {
    /// The rest positions as stored in files and arrays.
    fn positions_f32(&self) -> Vec<[f32; 3]> {
        self.mesh
            .positions
            .iter()
            .map(|p| p.map(|c| c as f32))
            .collect()
    }
}

#[pymethods]
impl Garment {
    /// Rest positions, `float32` `(N, 3)`.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        to_2d(py, &self.positions_f32())
    }

    /// Triangles, `uint32` `(F, 3)`.
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u32>> {
        to_2d(py, &self.mesh.faces)
    }

    /// Corner UVs, `float32` `(F, 3, 2)`, or `None`.
    #[getter]
    fn corner_uvs<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray3<f32>>>> {
        self.uvs
            .as_ref()
            .map(|uvs| {
                let frames: Vec<Vec<[f32; 2]>> = uvs.iter().map(|t| t.to_vec()).collect();
                to_3d(py, &frames)
            })
            .transpose()
    }

    /// What it is (`skirt`, …; `custom` for a loaded mesh).
    #[getter]
    fn kind(&self) -> &str {
        &self.kind
    }

    /// Number of vertices.
    #[getter]
    fn vertex_count(&self) -> usize {
        self.mesh.vertex_count()
    }

    /// Writes the garment as OBJ with its UVs (`vt`, `f v/vt`), atomically.
    fn save(&self, path: PathBuf) -> PyResult<()> {
        let p = self.positions_f32();
        weft_mesh::export::write_obj_with_uvs(&path, &p, &self.mesh.faces, self.uvs.as_deref())
            .map_err(os_error)
    }

    fn __repr__(&self) -> String {
        format!(
            "Garment({}, {} vertices, {} faces)",
            self.kind,
            self.mesh.vertex_count(),
            self.mesh.faces.len()
        )
    }
}

/// A procedural garment (skirt, dress, tshirt, tank, longsleeve, shorts, pants,
/// jumpsuit) of about `vertices` vertices, fitted to `body` at `betas` in its rest
/// pose; `seed` draws the style (length, flare, ease, …).
#[pyfunction]
#[pyo3(signature = (kind, vertices=4000, seed=0, body=None, betas=Vec::new()))]
pub fn generate_garment(
    kind: &str,
    vertices: usize,
    seed: u64,
    body: Option<&Body>,
    betas: Vec<f64>,
) -> PyResult<Garment> {
    let kind = GarmentKind::parse(kind).map_err(value_error)?;
    let model = model_of(body)?;
    let model = model.as_ref();
    let fit = FitBody::new(model, &betas).map_err(value_error)?;
    let g = fit
        .generate(kind, &Style::from_seed(kind, seed), vertices)
        .map_err(value_error)?;
    Ok(Garment {
        uvs: Some(
            g.corner_uvs
                .iter()
                .map(|t| t.map(|uv| uv.map(|x| x as f32)))
                .collect(),
        ),
        mesh: g.mesh,
        kind: g.kind.name().to_owned(),
    })
}

/// A garment from an OBJ (UVs kept when every face corner has one) or PLY file.
#[pyfunction]
pub fn load_garment(path: PathBuf) -> PyResult<Garment> {
    let loaded = weft_mesh::io::load_mesh(&path).map_err(value_error)?;
    Ok(Garment {
        mesh: loaded.mesh,
        uvs: loaded.corner_uvs,
        kind: "custom".into(),
    })
}
