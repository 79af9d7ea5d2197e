//! Garment vertices attached to the body's skin: a waistband or a neckline that moves
//! with the body instead of sliding over it.
//!
//! Real garments stay up because of elastic waistbands, collars resting on the neck and
//! friction under tension — a per-vertex contact model with lagged friction on a
//! 500–12 000-vertex template does not reproduce that, and a skirt slides over the hips
//! while a t-shirt slips off the shoulders as the arms come down from the rest pose
//! (measured, docs/physics.md). Production pipelines pin such seams to the skin; so do
//! we: each attached vertex is anchored to its closest body triangle (barycentric
//! coordinates plus its offset in the triangle's local frame, taken at the start) and
//! follows that triangle every sub-step. Because the anchor is on the body surface, it
//! works for any body vertex positions, including the linear blends between frames.

use weft_body::query::BodySurface;
use weft_mesh::vec3::{add, add_scaled, cross, dot, normalize_or_zero, scale, sub};
use weft_mesh::{Topology, TriMesh};

use crate::error::SimError;

/// Which garment vertices follow the body's skin (in TOML: `none`, `top_opening`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Attachment {
    /// None: the garment is held by contact and friction alone.
    None,
    /// The boundary loop with the highest mean height on the rest garment: a skirt's or
    /// trousers' waistband, a top's neckline.
    #[default]
    TopOpening,
}

impl Attachment {
    /// The garment vertices this attachment holds.
    pub fn vertices(self, garment: &TriMesh) -> Vec<u32> {
        match self {
            Attachment::None => Vec::new(),
            Attachment::TopOpening => top_opening(garment),
        }
    }
}

/// The vertices of the boundary loop with the highest mean height (empty for a closed
/// garment).
pub fn top_opening(garment: &TriMesh) -> Vec<u32> {
    let mean_y = |l: &[u32]| {
        l.iter()
            .map(|&v| garment.positions[v as usize][1])
            .sum::<f64>()
            / l.len().max(1) as f64
    };
    Topology::new(garment)
        .boundary_loops()
        .into_iter()
        .max_by(|a, b| mean_y(a).total_cmp(&mean_y(b)))
        .unwrap_or_default()
}

/// Garment vertices anchored to body triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinAnchors {
    vertices: Vec<u32>,
    triangles: Vec<u32>,
    barycentric: Vec<[f64; 3]>,
    /// Offset from the anchor point in the triangle frame `(t, b, n)`.
    local: Vec<[f64; 3]>,
}

/// The orthonormal frame `(t, b, n)` of triangle `[a, b, c]`: `t` along `b − a`, `n` the
/// unit face normal. `None` for a degenerate triangle.
fn frame(p: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let e1 = sub(p[1], p[0]);
    let n = normalize_or_zero(cross(e1, sub(p[2], p[0])));
    let t = normalize_or_zero(e1);
    if dot(n, n) == 0.0 || dot(t, t) == 0.0 {
        return None;
    }
    Some([t, cross(n, t), n])
}

fn corners(positions: &[[f64; 3]], face: [u32; 3]) -> [[f64; 3]; 3] {
    face.map(|v| positions[v as usize])
}

fn interpolate(p: [[f64; 3]; 3], w: [f64; 3]) -> [f64; 3] {
    add(add(scale(p[0], w[0]), scale(p[1], w[1])), scale(p[2], w[2]))
}

impl SkinAnchors {
    /// Anchors `vertices` (at `positions`) to their closest triangles of `body`.
    pub fn new(
        body: &BodySurface,
        positions: &[[f64; 3]],
        vertices: &[u32],
    ) -> Result<Self, SimError> {
        let mut a = SkinAnchors {
            vertices: Vec::with_capacity(vertices.len()),
            triangles: Vec::with_capacity(vertices.len()),
            barycentric: Vec::with_capacity(vertices.len()),
            local: Vec::with_capacity(vertices.len()),
        };
        for (i, &v) in vertices.iter().enumerate() {
            crate::error::check_vertex("attachment", i, v, positions.len())?;
            let x = positions[v as usize];
            let c = body.closest_point(x)?;
            let face = body.faces()[c.triangle as usize];
            // A degenerate body triangle cannot carry a frame: leave that vertex free.
            let Some(f) = frame(corners(body.positions(), face)) else {
                continue;
            };
            let d = sub(x, c.point);
            a.vertices.push(v);
            a.triangles.push(c.triangle);
            a.barycentric.push(c.barycentric);
            a.local.push(f.map(|axis| dot(d, axis)));
        }
        Ok(a)
    }

    /// The anchored garment vertices.
    pub fn vertices(&self) -> &[u32] {
        &self.vertices
    }

    /// Where each anchored vertex goes when the body's vertices are at `body`
    /// (`faces`: the body's triangles), in the order of [`Self::vertices`].
    pub fn targets(&self, body: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<[f64; 3]> {
        (0..self.vertices.len())
            .map(|i| {
                let p = corners(body, faces[self.triangles[i] as usize]);
                let base = interpolate(p, self.barycentric[i]);
                match frame(p) {
                    Some(f) => (0..3).fold(base, |acc, k| add_scaled(acc, f[k], self.local[i][k])),
                    // The triangle collapsed in this pose: keep the normal offset only.
                    None => base,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives::cylinder;

    fn box_body() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let p = vec![
            [-1.0, -1.0, -1.0],
            [1.0, -1.0, -1.0],
            [1.0, 1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, 1.0],
            [-1.0, 1.0, 1.0],
        ];
        let f = vec![
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [3, 6, 2],
            [3, 7, 6],
            [0, 4, 7],
            [0, 7, 3],
            [1, 2, 6],
            [1, 6, 5],
        ];
        (p, f)
    }

    /// At the start the anchors reproduce the garment exactly; under a rigid motion of
    /// the body they move rigidly with it (distances to the body are kept).
    #[test]
    fn anchors_follow_a_rigid_body_motion() {
        let (body, faces) = box_body();
        let surface = BodySurface::new(&body, &faces).unwrap();
        let garment = [[0.3, 0.2, 1.05], [1.1, -0.4, 0.2], [-0.5, 1.2, -0.7]];
        let anchors = SkinAnchors::new(&surface, &garment, &[0, 1, 2]).unwrap();
        for (t, g) in anchors.targets(&body, &faces).iter().zip(&garment) {
            assert!(weft_mesh::vec3::dist(*t, *g) < 1e-12, "{t:?} vs {g:?}");
        }
        // Rotate by 90° about y and translate.
        let rot = |p: [f64; 3]| [p[2] + 0.5, p[1] - 0.25, -p[0] + 2.0];
        let moved: Vec<_> = body.iter().map(|&p| rot(p)).collect();
        for (t, g) in anchors.targets(&moved, &faces).iter().zip(&garment) {
            assert!(weft_mesh::vec3::dist(*t, rot(*g)) < 1e-12, "{t:?} vs {g:?}");
        }
    }

    /// The top opening of an open cylinder is its upper ring.
    #[test]
    fn top_opening_is_the_upper_ring() {
        let tube = cylinder(5, 8, 0.3, 0.2);
        let top = Attachment::TopOpening.vertices(&tube);
        assert_eq!(top.len(), 8);
        let ymax = tube.positions.iter().map(|p| p[1]).fold(f64::MIN, f64::max);
        assert!(top
            .iter()
            .all(|&v| (tube.positions[v as usize][1] - ymax).abs() < 1e-12));
        assert!(Attachment::None.vertices(&tube).is_empty());
    }
}
