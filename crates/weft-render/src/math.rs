//! The 3-vector operations the camera and shading need: weft-mesh's (one copy for every
//! crate), `f64` on `[f64; 3]` like its meshes.

pub(crate) type V3 = [f64; 3];

pub(crate) use weft_mesh::vec3::{
    add, cross, dot, is_finite, normalize_or_zero as normalize, scale, sub,
};
