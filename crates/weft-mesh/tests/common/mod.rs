//! What the exporter tests share: a garment with seamed UVs over a body, both animated.

use weft_mesh::export::{AnimatedMesh, CornerUvs, Frames, BODY_COLOR, GARMENT_COLOR};
use weft_mesh::primitives::{builtin_garment, cylinder};
use weft_mesh::TriMesh;

/// The built-in garment (with UVs) over a cylinder body, both animated over `t` frames.
pub struct Scene {
    pub garment: TriMesh,
    pub body: TriMesh,
    pub garment_frames: Frames,
    pub body_frames: Frames,
    pub uvs: Vec<[[f32; 2]; 3]>,
}

impl Scene {
    pub fn new(t: usize) -> Self {
        let garment = builtin_garment();
        let body = cylinder(30, 40, 0.25, 0.05);
        Scene {
            garment_frames: frames_of(&garment, t, 0.05),
            body_frames: frames_of(&body, t, 0.01),
            uvs: seamed_uvs(&garment),
            garment,
            body,
        }
    }

    /// The garment with its UVs and the body, as the writers take them.
    pub fn meshes(&self) -> [AnimatedMesh<'_>; 2] {
        [
            self.garment_mesh(&self.uvs),
            self.body_mesh(&self.body_frames),
        ]
    }

    pub fn garment_mesh<'a>(&'a self, uvs: &'a CornerUvs) -> AnimatedMesh<'a> {
        AnimatedMesh {
            name: "garment",
            faces: &self.garment.faces,
            uvs: Some(uvs),
            frames: &self.garment_frames,
            color: GARMENT_COLOR,
        }
    }

    /// The body moving through `frames` (one frame: static).
    pub fn body_mesh<'a>(&'a self, frames: &'a Frames) -> AnimatedMesh<'a> {
        AnimatedMesh {
            name: "body",
            faces: &self.body.faces,
            uvs: None,
            frames,
            color: BODY_COLOR,
        }
    }
}

/// `t` frames of `mesh` breathing in XZ and bobbing in Y.
pub fn frames_of(mesh: &TriMesh, t: usize, amplitude: f64) -> Frames {
    let mut f = Frames::with_vertex_count(mesh.vertex_count()).unwrap();
    for k in 0..t {
        let phase = k as f64 * 0.2;
        let p: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .map(|p| {
                let s = 1.0 + amplitude * (phase + 8.0 * p[1]).sin();
                [p[0] * s, p[1] + 0.01 * phase.sin(), p[2] * s]
            })
            .collect();
        f.push_frame_f64(&p).unwrap();
    }
    f
}

/// Cylindrical UVs (angle around Y, height) with a seam where the angle wraps: the
/// faces across it get the angle unwrapped, so seam vertices carry two UVs.
pub fn seamed_uvs(mesh: &TriMesh) -> Vec<[[f32; 2]; 3]> {
    mesh.faces
        .iter()
        .map(|f| {
            let angle = |i: u32| {
                let p = mesh.positions[i as usize];
                p[2].atan2(p[0]) as f32
            };
            let wraps = f.iter().any(|&i| angle(i) > 2.0) && f.iter().any(|&i| angle(i) < -2.0);
            f.map(|i| {
                let mut a = angle(i);
                if wraps && a < 0.0 {
                    a += std::f32::consts::TAU;
                }
                [a, mesh.positions[i as usize][1] as f32]
            })
        })
        .collect()
}
