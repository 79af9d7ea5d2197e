//! `weft.render`: meshes drawn by weft's software rasteriser into an RGB array (and a
//! PNG file).

use std::path::PathBuf;

use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use weft_render::{Paint, RenderOptions, SceneMesh, View, BODY_COLOR, GARMENT_COLOR};

use crate::arrays::{coerce, faces, rows3};
use crate::error::{invalid, os_error, value_error};

/// Draws `meshes`, a list of `(positions (N, 3), faces (F, 3))` or `(positions, faces,
/// (r, g, b))` tuples (the first is painted as a garment, the others as bodies unless
/// a colour is given), seen from `view` ("front", "side", "three-quarter") at
/// `width × height`. Returns `uint8` `(height, width, 3)`; `path` also writes a PNG.
#[pyfunction]
#[pyo3(signature = (meshes, width=512, height=512, view="three-quarter", path=None))]
pub fn render<'py>(
    py: Python<'py>,
    meshes: Vec<Bound<'py, PyTuple>>,
    width: u32,
    height: u32,
    view: &str,
    path: Option<PathBuf>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let view = match view {
        "front" => View::Front,
        "side" => View::Side,
        "three-quarter" => View::ThreeQuarter,
        _ => {
            return Err(invalid(format!(
                "view {view:?}; expected \"front\", \"side\" or \"three-quarter\""
            )))
        }
    };
    let mut parts = Vec::with_capacity(meshes.len());
    for (i, mesh) in meshes.iter().enumerate() {
        if !(2..=3).contains(&mesh.len()) {
            return Err(invalid(format!(
                "meshes[{i}] has {} items; expected (positions, faces) or (positions, faces, (r, g, b))",
                mesh.len()
            )));
        }
        let p: PyReadonlyArray2<'_, f32> = coerce(&mesh.get_item(0)?, "float32", "positions")?;
        let f: PyReadonlyArray2<'_, i64> = coerce(&mesh.get_item(1)?, "int64", "faces")?;
        let positions: Vec<[f64; 3]> = rows3(&p, "positions")?
            .iter()
            .map(|q| q.map(f64::from))
            .collect();
        let tris = faces(&f, positions.len())?;
        let color: Option<(u8, u8, u8)> = match mesh.get_item(2) {
            Ok(c) => Some(c.extract().map_err(|_| {
                invalid(format!(
                    "meshes[{i}]: colour {c}; expected (r, g, b) of 0-255"
                ))
            })?),
            Err(_) => None,
        };
        let rgb = match color {
            Some((r, g, b)) => [r, g, b],
            None if i == 0 => GARMENT_COLOR,
            None => BODY_COLOR,
        };
        parts.push((positions, tris, rgb));
    }
    let scene: Vec<SceneMesh<'_>> = parts
        .iter()
        .enumerate()
        .map(|(i, (p, f, rgb))| {
            SceneMesh::from_parts(format!("mesh {i}"), p, f, Paint::Solid(*rgb))
        })
        .collect();
    let options = RenderOptions {
        view,
        ..RenderOptions::new(width, height)
    };
    let picture = weft_render::render(&scene, &options).map_err(value_error)?;
    if let Some(path) = path {
        picture.image.write_png(&path).map_err(os_error)?;
    }
    let (w, h) = (
        picture.image.width() as usize,
        picture.image.height() as usize,
    );
    let array = Array3::from_shape_vec((h, w, 3), picture.image.as_bytes().to_vec())
        .map_err(|e| invalid(e.to_string()))?;
    Ok(array.into_pyarray(py))
}
