//! Pictures for weft: garments and bodies drawn to PNG by a small software rasteriser,
//! per-vertex colour maps (errors, attributions) with a legend, contact sheets and
//! animations of sequences, plots of training and evaluation, and self-contained HTML
//! reports that bundle them.
//!
//! Why a software rasteriser: pictures are made on CI machines and servers without a GPU
//! or a display, and they are compared across runs, so drawing must need nothing from
//! the system and give the same bytes for the same input. A z-buffer over a garment and a
//! body (40 000 triangles) at 1024 × 1024 with 2 × 2 supersampling takes about 0.15 s on
//! one CPU core, which is nothing next to simulating or training.
//!
//! ```
//! use weft_render::{render, Colormap, Paint, RenderOptions, ScalarPaint, ScalarRange, SceneMesh};
//! let garment = weft_mesh::primitives::cylinder(20, 40, 0.3, 0.02);
//! let error: Vec<f64> = garment.positions.iter().map(|p| -p[1] * 100.0).collect();
//! let scene = [SceneMesh::new("garment", &garment, Paint::Scalars(ScalarPaint {
//!     values: &error,
//!     colormap: Colormap::Viridis,
//!     range: ScalarRange::Auto,
//!     label: "error (mm)",
//! }))];
//! let picture = render(&scene, &RenderOptions::new(256, 256))?;
//! assert_eq!(picture.nonfinite_values(), 0);
//! let png = picture.image.encode_png()?;
//! # assert!(png.starts_with(b"\x89PNG"));
//! # Ok::<(), weft_render::RenderError>(())
//! ```
//!
//! Depends on weft-mesh (geometry, atomic file writes) and the `png` encoder only.

pub mod camera;
pub mod colormap;
pub mod error;
pub mod font;
mod font_data;
pub mod image;
mod legend;
mod math;
pub mod plot;
mod raster;
pub mod render;
pub mod report;
pub mod scene;
pub mod shading;
pub mod sheet;
mod ticks;

pub use camera::{Camera, View};
pub use colormap::{Colormap, ScalarRange, ERROR_COLOR};
pub use error::RenderError;
pub use font::{Align, Font, TextStyle};
pub use image::{encode_apng, write_apng, Image, Rgb, MAX_SIDE};
pub use plot::{Histogram, HistogramSeries, LinePlot, Series, PALETTE};
pub use render::{render, RenderOptions, Rendered};
pub use report::Report;
pub use scene::{MeshStats, Paint, ScalarPaint, SceneMesh, BODY_COLOR, GARMENT_COLOR};
pub use shading::Shading;
pub use sheet::{render_frames, render_sequence, render_turntable, RenderedFrames};
