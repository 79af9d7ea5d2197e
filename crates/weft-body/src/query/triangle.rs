//! The closest point of one triangle to a query point, with the feature (vertex, edge or
//! interior) it lies on.
//!
//! The feature matters as much as the point: the sign of a distance to a closed surface
//! is only robust when it comes from the pseudo-normal of the feature the closest point
//! lies on (Bærentzen & Aanæs 2005, see [`super::signed`]). Region tests follow Ericson,
//! *Real-Time Collision Detection* §5.1.5 (Voronoi regions of the triangle), with a
//! fallback to the three edges for degenerate (zero-area) triangles, which that test
//! divides by.

use weft_mesh::vec3::{add_scaled, dot, norm_sq, sub};

/// Barycentric coordinates at or below this are snapped to zero when naming the feature,
/// so that a closest point that is on an edge up to rounding is reported on the edge.
const SNAP: f64 = 1e-12;

/// Where on a triangle `[a, b, c]` a closest point lies, in the triangle's own corners.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LocalFeature {
    /// Corner `k` (0 = a, 1 = b, 2 = c).
    Vertex(u8),
    /// Edge `k` from corner `k` to corner `(k + 1) % 3` (0 = ab, 1 = bc, 2 = ca).
    Edge(u8),
    /// The open interior.
    Face,
}

/// The closest point of a triangle: barycentric coordinates (non-negative, summing to
/// one), the point itself, the squared distance, and the feature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrianglePoint {
    /// Weights of corners a, b, c.
    pub barycentric: [f64; 3],
    /// `a·u + b·v + c·w`.
    pub point: [f64; 3],
    /// Squared distance from the query point.
    pub distance_sq: f64,
    /// The feature the point lies on.
    pub feature: LocalFeature,
}

/// The closest point of triangle `[a, b, c]` to `p`.
pub fn closest_point_on_triangle(p: [f64; 3], tri: [[f64; 3]; 3]) -> TrianglePoint {
    let bary = ericson(p, tri)
        .filter(|b| b.iter().all(|x| x.is_finite()))
        .unwrap_or_else(|| degenerate(p, tri));
    finish(p, tri, bary)
}

/// Names the feature from the barycentric coordinates (after snapping) and computes the
/// point and its distance.
fn finish(p: [f64; 3], [a, b, c]: [[f64; 3]; 3], mut bary: [f64; 3]) -> TrianglePoint {
    for x in &mut bary {
        if *x <= SNAP {
            *x = 0.0;
        }
    }
    let s = bary[0] + bary[1] + bary[2];
    if s > 0.0 {
        bary = bary.map(|x| x / s);
    }
    let zero = bary.map(|x| x == 0.0);
    let feature = match zero {
        [false, false, false] => LocalFeature::Face,
        [false, false, true] => LocalFeature::Edge(0),
        [true, false, false] => LocalFeature::Edge(1),
        [false, true, false] => LocalFeature::Edge(2),
        [false, true, true] => LocalFeature::Vertex(0),
        [true, false, true] => LocalFeature::Vertex(1),
        _ => LocalFeature::Vertex(2),
    };
    let point = match feature {
        LocalFeature::Vertex(0) => a,
        LocalFeature::Vertex(1) => b,
        LocalFeature::Vertex(_) => c,
        _ => add_scaled(add_scaled(a, sub(b, a), bary[1]), sub(c, a), bary[2]),
    };
    TrianglePoint {
        barycentric: bary,
        point,
        distance_sq: norm_sq(sub(p, point)),
        feature,
    }
}

/// Ericson's Voronoi-region test; `None` only if a denominator vanished (degenerate
/// triangle), reported as non-finite coordinates by the caller's filter.
fn ericson(p: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> Option<[f64; 3]> {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return Some([1.0, 0.0, 0.0]);
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return Some([0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return Some([1.0 - v, v, 0.0]);
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return Some([0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return Some([1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return Some([0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    if denom <= 0.0 {
        return None;
    }
    let v = vb / denom;
    let w = vc / denom;
    Some([1.0 - v - w, v, w])
}

/// Closest point of a zero-area triangle: the best of its three edges.
fn degenerate(p: [f64; 3], tri: [[f64; 3]; 3]) -> [f64; 3] {
    let mut best = ([1.0, 0.0, 0.0], f64::INFINITY);
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        let (a, b) = (tri[i], tri[j]);
        let ab = sub(b, a);
        let len_sq = norm_sq(ab);
        let t = if len_sq > 0.0 {
            (dot(sub(p, a), ab) / len_sq).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let q = add_scaled(a, ab, t);
        let d = norm_sq(sub(p, q));
        if d < best.1 {
            let mut bary = [0.0; 3];
            bary[i] = 1.0 - t;
            bary[j] += t;
            best = (bary, d);
        }
    }
    best.0
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: [[f64; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn regions_of_the_unit_triangle() {
        let q = closest_point_on_triangle([0.2, 0.3, 2.0], T);
        assert_eq!(q.feature, LocalFeature::Face);
        assert!((q.distance_sq - 4.0).abs() < 1e-12);
        assert!((q.barycentric[1] - 0.2).abs() < 1e-12);
        assert!((q.barycentric[2] - 0.3).abs() < 1e-12);
        assert_eq!(
            closest_point_on_triangle([-1.0, -1.0, 0.5], T).feature,
            LocalFeature::Vertex(0)
        );
        assert_eq!(
            closest_point_on_triangle([2.0, -0.1, 0.0], T).feature,
            LocalFeature::Vertex(1)
        );
        assert_eq!(
            closest_point_on_triangle([0.5, -1.0, 0.0], T).feature,
            LocalFeature::Edge(0)
        );
        assert_eq!(
            closest_point_on_triangle([1.0, 1.0, 0.0], T).feature,
            LocalFeature::Edge(1)
        );
        let q = closest_point_on_triangle([-3.0, 0.5, 1.0], T);
        assert_eq!(q.feature, LocalFeature::Edge(2));
        assert!((q.distance_sq - 10.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_triangles_fall_back_to_edges() {
        let line = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let q = closest_point_on_triangle([1.5, 1.0, 0.0], line);
        assert!((q.distance_sq - 1.0).abs() < 1e-12);
        assert!((q.point[0] - 1.5).abs() < 1e-12);
        let dot = [[1.0; 3]; 3];
        let q = closest_point_on_triangle([1.0, 1.0, 3.0], dot);
        assert!((q.distance_sq - 4.0).abs() < 1e-12);
        assert!(q.barycentric.iter().all(|x| x.is_finite()));
    }
}
