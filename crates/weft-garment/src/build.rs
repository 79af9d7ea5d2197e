//! The mesh builder every garment part writes into: vertices, faces and per-corner UVs.
//!
//! Garments are unions of tubes and panels that share their border vertices, so parts
//! are welded by construction (no merging by distance, which could fuse nearby layers).
//! Rows of vertices ([`Ring`]) carry their own unwrap coordinates, so a vertex on the
//! seam between two parts can have different UVs in each: UVs are stored per face corner,
//! as weft-sim's `RestFrames::from_corner_uvs` takes them.

use std::collections::HashSet;

/// A row of vertices with its unwrap coordinates: `u` is arc length along the row, `v`
/// the distance from the part's start (metres).
#[derive(Clone, Debug)]
pub struct Ring {
    /// Vertex indices in order.
    pub idx: Vec<u32>,
    /// `(u, v)` of each vertex in this row's unwrap.
    pub uv: Vec<[f64; 2]>,
    /// Whether the row closes on itself (a tube's cross section).
    pub closed: bool,
    /// Perimeter of a closed row: the `u` offset for the seam after the last vertex.
    pub period: f64,
}

/// Accumulates the garment mesh.
#[derive(Clone, Debug, Default)]
pub struct Builder {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
    /// UV of each corner of each triangle.
    pub corner_uvs: Vec<[[f64; 2]; 3]>,
}

pub use weft_mesh::vec3::{add, cross, dot, norm, scale, sub};

/// The point a fraction `t` of the way from `a` to `b`.
pub fn lerp3(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    add(a, scale(sub(b, a), t))
}

impl Builder {
    /// Adds a vertex, returning its index.
    pub fn vertex(&mut self, p: [f64; 3]) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    /// A row over existing vertices, `u` by arc length, `v` given.
    pub fn row(&self, idx: Vec<u32>, v: f64, closed: bool) -> Ring {
        let mut uv = Vec::with_capacity(idx.len());
        let mut u = 0.0;
        for (k, &i) in idx.iter().enumerate() {
            if k > 0 {
                u += norm(sub(
                    self.positions[i as usize],
                    self.positions[idx[k - 1] as usize],
                ));
            }
            uv.push([u, v]);
        }
        let period = match (closed, idx.first(), idx.last()) {
            (true, Some(&f), Some(&l)) => {
                u + norm(sub(self.positions[f as usize], self.positions[l as usize]))
            }
            _ => u,
        };
        Ring {
            idx,
            uv,
            closed,
            period,
        }
    }

    /// Adds new vertices and returns them as a row.
    pub fn new_row(&mut self, points: &[[f64; 3]], v: f64, closed: bool) -> Ring {
        let idx = points.iter().map(|&p| self.vertex(p)).collect();
        self.row(idx, v, closed)
    }

    /// Triangulates the band between two rows of equal length. For a face `(a_k, b_k,
    /// b_k+1)` the normal is `(b_k - a_k) × (b_k+1 - a_k)`; callers order the rows so that
    /// it points away from the body. Each quad is split along its shorter diagonal, which
    /// keeps triangles closest to equilateral.
    pub fn strip(&mut self, a: &Ring, b: &Ring) {
        let n = a.idx.len().min(b.idx.len());
        let segments = if a.closed { n } else { n.saturating_sub(1) };
        for k in 0..segments {
            let k1 = (k + 1) % n;
            let wrap = k1 == 0;
            let ua = |r: &Ring, i: usize| {
                let mut uv = r.uv[i];
                if wrap && i == 0 {
                    uv[0] += r.period;
                }
                uv
            };
            let (a0, a1, b0, b1) = (a.idx[k], a.idx[k1], b.idx[k], b.idx[k1]);
            let (ta0, ta1, tb0, tb1) = (a.uv[k], ua(a, k1), b.uv[k], ua(b, k1));
            let p = |i: u32| self.positions[i as usize];
            if norm(sub(p(a0), p(b1))) <= norm(sub(p(a1), p(b0))) {
                self.face([a0, b0, b1], [ta0, tb0, tb1]);
                self.face([a0, b1, a1], [ta0, tb1, ta1]);
            } else {
                self.face([a0, b0, a1], [ta0, tb0, ta1]);
                self.face([b0, b1, a1], [tb0, tb1, ta1]);
            }
        }
    }

    fn face(&mut self, f: [u32; 3], uv: [[f64; 2]; 3]) {
        self.faces.push(f);
        self.corner_uvs.push(uv);
    }

    /// Whether some face already walks the directed edge `a → b`.
    pub fn has_directed_edge(&self, a: u32, b: u32) -> bool {
        let set: HashSet<(u32, u32)> = self
            .faces
            .iter()
            .flat_map(|f| [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])])
            .collect();
        set.contains(&(a, b))
    }
}

/// Points of an ellipse in the plane spanned by `e1`, `e2` around `center`, at angles
/// `theta0 + 2πk/n`, with radial factor `1 + wave(θ)` (hem waviness; ≥ 1 keeps ease).
pub fn ellipse(
    center: [f64; 3],
    e1: [f64; 3],
    e2: [f64; 3],
    radii: [f64; 2],
    n: usize,
    wave: &dyn Fn(f64) -> f64,
) -> Vec<[f64; 3]> {
    (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            let f = 1.0 + wave(t);
            add(
                center,
                add(
                    scale(e1, radii[0] * f * t.cos()),
                    scale(e2, radii[1] * f * t.sin()),
                ),
            )
        })
        .collect()
}

/// Where the rings of an extruded tube go: `(centre, radius)` per ring and how far each
/// has blended from the start loop's shape (0) to a circle (1).
pub struct ExtrudeRing {
    /// Ring centre.
    pub center: [f64; 3],
    /// Circle radius once blended.
    pub radius: f64,
    /// 0: the translated loop shape, 1: a circle with evenly spaced vertices.
    pub blend: f64,
}

/// Extrudes a closed boundary loop of the mesh into a tube (a sleeve or a trouser leg).
///
/// The loop keeps its own vertex count along the tube, so the tube welds onto it without
/// any remeshing; its shape morphs into a circle around the limb axis over the first
/// rings. `e1`, `e2` span the cross-section plane. The band is oriented against the
/// loop's existing faces, so the whole garment stays consistently oriented. Returns the
/// last ring (the open end).
pub fn extrude(
    b: &mut Builder,
    loop_idx: &[u32],
    e1: [f64; 3],
    e2: [f64; 3],
    rings: &[ExtrudeRing],
) -> Ring {
    let n = loop_idx.len();
    let pts: Vec<[f64; 3]> = loop_idx.iter().map(|&i| b.positions[i as usize]).collect();
    let centroid = scale(
        pts.iter().fold([0.0; 3], |s, &p| add(s, p)),
        1.0 / n.max(1) as f64,
    );
    let axis = cross(e1, e2);
    // Unwrapped angles of the loop vertices around the centroid.
    let mut angles = Vec::with_capacity(n);
    let mut prev = 0.0f64;
    for (k, p) in pts.iter().enumerate() {
        let d = sub(*p, centroid);
        let a = dot(d, e2).atan2(dot(d, e1));
        let a = if k == 0 {
            a
        } else {
            let delta = (a - prev + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            prev + delta
        };
        angles.push(a);
        prev = a;
    }
    let direction = if angles.last().copied().unwrap_or(0.0) >= angles[0] {
        1.0
    } else {
        -1.0
    };
    let start = b.row(loop_idx.to_vec(), 0.0, true);
    // Faces must walk the loop's edges opposite to the faces already there.
    let loop_first = match (loop_idx.first(), loop_idx.get(1)) {
        (Some(&x), Some(&y)) => b.has_directed_edge(x, y),
        _ => false,
    };
    let mut prev_ring = start;
    let mut v = 0.0;
    let mut prev_center = centroid;
    for r in rings {
        let in_plane = |d: [f64; 3]| sub(d, scale(axis, dot(d, axis)));
        let mut points = Vec::with_capacity(n);
        for (k, p) in pts.iter().enumerate() {
            let shaped = add(r.center, in_plane(sub(*p, centroid)));
            let phi = angles[0] + direction * std::f64::consts::TAU * k as f64 / n as f64;
            let circle = add(
                r.center,
                add(
                    scale(e1, r.radius * phi.cos()),
                    scale(e2, r.radius * phi.sin()),
                ),
            );
            points.push(lerp3(shaped, circle, r.blend.clamp(0.0, 1.0)));
        }
        v += norm(sub(r.center, prev_center));
        prev_center = r.center;
        let ring = b.new_row(&points, v, true);
        if loop_first {
            b.strip(&prev_ring, &ring);
        } else {
            b.strip(&ring, &prev_ring);
        }
        prev_ring = ring;
    }
    prev_ring
}
