//! weft for Python (`import weft`): the toolkit's building blocks with numpy arrays in
//! and out — bodies posed by SMPL parameters, motions read, converted and generated,
//! procedural garments, the cloth simulator, datasets, trained models animating any
//! garment, and the renderer. Built with maturin (`pip install ./crates/weft-py`).
//!
//! Conventions are weft's everywhere: metres, seconds, Y up; positions `float32` of
//! shape `(N, 3)` or `(T, N, 3)`, triangles `uint32` `(F, 3)`, poses `float32`
//! `(T, 24, 3)` axis-angle in SMPL's joint order. Errors are `ValueError` (bad input) or
//! `OSError` (files) with weft's message, which names the file and the field.

mod arrays;
mod body;
mod dataset;
mod error;
mod garment;
mod model;
mod motion;
mod render;
mod simulate;

use pyo3::prelude::*;

/// The native module; `weft/__init__.py` re-exports it with type hints.
#[pymodule]
fn _weft(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<body::Body>()?;
    m.add_class::<motion::Motion>()?;
    m.add_class::<garment::Garment>()?;
    m.add_class::<dataset::Dataset>()?;
    m.add_class::<model::Run>()?;
    m.add_function(wrap_pyfunction!(motion::load_motion, m)?)?;
    m.add_function(wrap_pyfunction!(motion::procedural_motion, m)?)?;
    m.add_function(wrap_pyfunction!(garment::generate_garment, m)?)?;
    m.add_function(wrap_pyfunction!(garment::load_garment, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(dataset::import_dataset, m)?)?;
    Ok(())
}
