//! Procedural closed meshes for the feature and query tests (generated, not committed).

#![allow(dead_code)]

use std::collections::HashMap;

use weft_mesh::vec3::{cross, dot, sub};

pub type Mesh = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// Six times the signed volume enclosed by a closed mesh (positive when outward).
pub fn signed_volume6((p, f): &Mesh) -> f64 {
    f.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| p[i as usize]);
            let n = cross(b, c);
            a[0] * n[0] + a[1] * n[1] + a[2] * n[2]
        })
        .sum()
}

/// Flips every face if the mesh encloses a negative volume.
pub fn orient_outwards(mut m: Mesh) -> Mesh {
    if signed_volume6(&m) < 0.0 {
        for t in &mut m.1 {
            t.swap(1, 2);
        }
    }
    m
}

/// A unit-radius icosphere with `subdivisions` loop-free midpoint subdivisions
/// (12, 42, 162, 642, 2562, 10242 vertices), outward, mirror-symmetric in x, y, z.
pub fn icosphere(subdivisions: usize) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let unit = |v: [f64; 3]| {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    };
    p.iter_mut().for_each(|v| *v = unit(*v));
    for _ in 0..subdivisions {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut nf = Vec::with_capacity(4 * f.len());
        for tri in &f {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[k] = *mid.entry(key).or_insert_with(|| {
                    let (pa, pb) = (p[a as usize], p[b as usize]);
                    p.push(unit([
                        0.5 * (pa[0] + pb[0]),
                        0.5 * (pa[1] + pb[1]),
                        0.5 * (pa[2] + pb[2]),
                    ]));
                    (p.len() - 1) as u32
                });
            }
            nf.push([tri[0], m[0], m[2]]);
            nf.push([tri[1], m[1], m[0]]);
            nf.push([tri[2], m[2], m[1]]);
            nf.push([m[0], m[1], m[2]]);
        }
        f = nf;
    }
    orient_outwards((p, f))
}

/// An ellipsoid with semi-axes `r` centred at `c`, from an icosphere.
pub fn ellipsoid(subdivisions: usize, r: [f64; 3], c: [f64; 3]) -> Mesh {
    let (p, f) = icosphere(subdivisions);
    let p = p
        .into_iter()
        .map(|v| [c[0] + r[0] * v[0], c[1] + r[1] * v[1], c[2] + r[2] * v[2]])
        .collect();
    (p, f)
}

/// The axis-aligned box `[lo, hi]`, 12 outward triangles.
pub fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> Mesh {
    let p: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]
        })
        .collect();
    let quads: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let f = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    orient_outwards((p, f))
}

/// The centreline of [`u_tube`]: down the left arm (x = −R) from y = H to 0, round the
/// bottom semicircle (centre origin, radius R), up the right arm to y = H.
pub fn u_path(radius_u: f64, height: f64, steps: usize) -> Vec<[f64; 3]> {
    let mut path = Vec::new();
    for k in 0..steps {
        path.push([-radius_u, height * (1.0 - k as f64 / steps as f64), 0.0]);
    }
    for k in 0..steps {
        let a = std::f64::consts::PI * (1.0 + k as f64 / steps as f64);
        path.push([radius_u * a.cos(), radius_u * a.sin(), 0.0]);
    }
    for k in 0..=steps {
        path.push([radius_u, height * k as f64 / steps as f64, 0.0]);
    }
    path
}

/// A closed tube of radius `r` around a planar (XY) polyline, with flat end caps.
pub fn tube(path: &[[f64; 3]], r: f64, around: usize) -> Mesh {
    let n = path.len();
    let mut p = Vec::new();
    for i in 0..n {
        let prev = path[i.saturating_sub(1)];
        let next = path[(i + 1).min(n - 1)];
        let t = sub(next, prev);
        let tl = (t[0] * t[0] + t[1] * t[1]).sqrt();
        // In-plane normal, perpendicular to the tangent.
        let nrm = [-t[1] / tl, t[0] / tl, 0.0];
        for k in 0..around {
            let phi = std::f64::consts::TAU * k as f64 / around as f64;
            let (s, c) = phi.sin_cos();
            p.push([
                path[i][0] + r * c * nrm[0],
                path[i][1] + r * c * nrm[1],
                path[i][2] + r * s,
            ]);
        }
    }
    let id = |i: usize, k: usize| (i * around + k % around) as u32;
    let mut f = Vec::new();
    for i in 0..n - 1 {
        for k in 0..around {
            f.push([id(i, k), id(i + 1, k), id(i + 1, k + 1)]);
            f.push([id(i, k), id(i + 1, k + 1), id(i, k + 1)]);
        }
    }
    let c0 = p.len() as u32;
    p.push(path[0]);
    let c1 = p.len() as u32;
    p.push(path[n - 1]);
    for k in 0..around {
        f.push([c0, id(0, k), id(0, k + 1)]);
        f.push([c1, id(n - 1, k + 1), id(n - 1, k)]);
    }
    orient_outwards((p, f))
}

/// A flat square grid in the plane y = `y` (normals +y), `n × n` vertices over
/// `[-half, half]²`.
pub fn plane(n: usize, half: f64, y: f64) -> Mesh {
    let mut p = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let x = -half + 2.0 * half * i as f64 / (n - 1) as f64;
            let z = -half + 2.0 * half * j as f64 / (n - 1) as f64;
            p.push([x, y, z]);
        }
    }
    let id = |i: usize, j: usize| (j * n + i) as u32;
    let mut f = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            f.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    (p, f)
}

/// Brute-force inside test for a closed mesh: parity of crossings of a ray from `q`
/// in a fixed, generic direction (Möller–Trumbore).
pub fn inside_by_parity((p, f): &Mesh, q: [f64; 3]) -> bool {
    let d = [0.5773, 0.5801, 0.5749];
    let mut hits = 0;
    for t in f {
        let [a, b, c] = t.map(|i| p[i as usize]);
        let e1 = sub(b, a);
        let e2 = sub(c, a);
        let h = cross(d, e2);
        let det = e1[0] * h[0] + e1[1] * h[1] + e1[2] * h[2];
        if det.abs() < 1e-14 {
            continue;
        }
        let s = sub(q, a);
        let u = (s[0] * h[0] + s[1] * h[1] + s[2] * h[2]) / det;
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let qv = cross(s, e1);
        let v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
        if v < 0.0 || u + v > 1.0 {
            continue;
        }
        let tt = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
        if tt > 0.0 {
            hits += 1;
        }
    }
    hits % 2 == 1
}

/// Closest point on a triangle by brute force: dense barycentric sampling is too slow,
/// so minimise over the interior projection (when inside) and the three edges.
pub fn brute_triangle_distance(q: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> f64 {
    let seg = |a: [f64; 3], b: [f64; 3]| {
        let ab = sub(b, a);
        let l = dot(ab, ab);
        let t = if l > 0.0 {
            (dot(sub(q, a), ab) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let p = [a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]];
        dot(sub(q, p), sub(q, p)).sqrt()
    };
    let mut best = seg(a, b).min(seg(b, c)).min(seg(c, a));
    // Interior: solve for the projection's barycentric coordinates.
    let (e1, e2, w) = (sub(b, a), sub(c, a), sub(q, a));
    let (d11, d12, d22) = (dot(e1, e1), dot(e1, e2), dot(e2, e2));
    let det = d11 * d22 - d12 * d12;
    if det > 1e-300 {
        let (r1, r2) = (dot(w, e1), dot(w, e2));
        let v = (d22 * r1 - d12 * r2) / det;
        let u = (d11 * r2 - d12 * r1) / det;
        if v >= 0.0 && u >= 0.0 && u + v <= 1.0 {
            let p = [
                a[0] + v * e1[0] + u * e2[0],
                a[1] + v * e1[1] + u * e2[1],
                a[2] + v * e1[2] + u * e2[2],
            ];
            best = best.min(dot(sub(q, p), sub(q, p)).sqrt());
        }
    }
    best
}

/// Whether every directed edge appears exactly once and its reverse exactly once: a
/// closed, consistently oriented 2-manifold edge structure.
pub fn consistently_oriented((_, f): &Mesh) -> bool {
    let mut seen: HashMap<(u32, u32), u32> = HashMap::new();
    for t in f {
        for k in 0..3 {
            *seen.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    seen.iter()
        .all(|(&(a, b), &c)| c == 1 && seen.get(&(b, a)) == Some(&1))
}
