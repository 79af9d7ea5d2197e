//! Triangle meshes for weft: reading and writing, validation, topology, graphs, hop
//! distances, eccentricity, geodesics and the Nyström spectrum of a garment.
//!
//! Everything here is plain `f64` geometry with no learning dependency, so the crate
//! builds and tests in seconds and every other crate can stand on it.

pub mod cut;
pub mod eccentricity;
pub mod error;
pub mod export;
pub mod geodesic;
pub mod graph;
pub mod io;
pub mod mesh;
pub mod nystrom;
pub mod primitives;
pub mod rng;
pub mod topology;
pub mod validate;
pub mod vec3;

pub use error::MeshError;
pub use geodesic::{GeodesicError, Geodesics};
pub use graph::{Bfs, Components, Graph, UNREACHED};
pub use io::{load_mesh, read_mesh, write_mesh, LoadReport, MeshFormat};
pub use mesh::{vertex_normals_of, Aabb, TriMesh};
pub use nystrom::{farthest_point_sampling, NystromError, NystromSpectrum};
pub use topology::{Hinge, Topology};
pub use validate::{Finding, Severity};
