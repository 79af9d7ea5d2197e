//! Contacts over one long step of a fast body, without tunnelling: [`SweptBody`].
//!
//! HOOD (and [`PosedBody`]) pairs the garment at `t` with the body at `t + 1`. When a limb
//! moves farther in one step than it is thick (a running thigh travels 15–27 cm in a
//! 1/30 s frame, world translation included, and is about 12 cm across), the garment
//! vertex it swept through lies on the limb's far side at `t + 1`, so the closest point
//! pushes the cloth through the leg rather than back in front of it. The simulator avoids
//! this with sub-steps; a learned model that takes one step per frame cannot.
//!
//! A swept body also looks at `t`, where the vertex was outside: the closest point there
//! (within the query radius plus the farthest any body vertex moves in the step) is a
//! material point of one triangle, carried to `t + 1` with the same barycentric
//! coordinates, and its normal is turned as the triangle turned. That carried contact
//! replaces the closest point at `t + 1` only when the two disagree about the side:
//! the carried plane says the vertex is behind it and the closest point at `t + 1`
//! either faces the other way or is more than the query radius away. A surface that only
//! slides under the vertex (a twisting torso) keeps the closest point at `t + 1`, whose
//! normal agrees with the carried one.

use weft_mesh::vec3::{add, cross, dot, normalize_or_zero, scale, sub};

use crate::body::{contact_normal, farthest_move, PosedBody};
use crate::contact::{BodyContact, BodyProximity, Proximity};
use crate::error::SimError;

/// The body at the start and at the end of one step (module documentation).
#[derive(Debug)]
pub struct SweptBody {
    before: PosedBody,
    after: PosedBody,
    /// How far from the body at `t` a vertex can be and still be reached by `t + 1`.
    reach: f64,
}

impl SweptBody {
    /// The body at `t` (`before`) and at `t + 1` (`after`), the same mesh.
    pub fn new(before: PosedBody, after: PosedBody) -> Result<Self, SimError> {
        let (a, b) = (before.surface(), after.surface());
        crate::error::check_len(
            "the swept body's end state",
            a.positions().len(),
            b.positions().len(),
        )?;
        if a.faces() != b.faces() {
            return Err(SimError::InvalidVector {
                what: "the swept body's end state".into(),
                message: "expected the triangles of its start",
            });
        }
        let reach = after.query_radius() + farthest_move(a.positions(), b.positions());
        Ok(SweptBody {
            before,
            after,
            reach,
        })
    }

    /// The body at `t`.
    pub fn before(&self) -> &PosedBody {
        &self.before
    }

    /// The body at `t + 1`.
    pub fn after(&self) -> &PosedBody {
        &self.after
    }

    /// `x`'s closest body point at `t`, carried to `t + 1` (module documentation), with
    /// how far it moved; `None` when `x` was inside the body at `t` or out of reach.
    fn carried(&self, x: [f64; 3]) -> Option<(BodyContact, [f64; 3])> {
        let c = self
            .before
            .surface()
            .closest_point_within(x, self.reach)
            .ok()??;
        if c.signed_distance < 0.0 {
            return None;
        }
        let face = self.after.surface().faces()[c.triangle as usize];
        let corners = |p: &[[f64; 3]]| face.map(|v| p[v as usize]);
        let (from, to) = (
            corners(self.before.surface().positions()),
            corners(self.after.surface().positions()),
        );
        let point = (0..3).fold([0.0; 3], |s, k| add(s, scale(to[k], c.barycentric[k])));
        let normal = turned(contact_normal(x, &c), face_normal(from), face_normal(to));
        Some((BodyContact { point, normal }, sub(point, c.point)))
    }
}

/// The unit normal of triangle `p` (zero for a degenerate one).
fn face_normal(p: [[f64; 3]; 3]) -> [f64; 3] {
    normalize_or_zero(cross(sub(p[1], p[0]), sub(p[2], p[0])))
}

/// `v` turned by the smallest rotation taking unit `a` to unit `b` (Rodrigues); `v` as it
/// is when either is degenerate or they are opposite (no smallest rotation).
fn turned(v: [f64; 3], a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let c = dot(a, b);
    if c <= -1.0 + 1e-9 || dot(a, a) == 0.0 || dot(b, b) == 0.0 {
        return v;
    }
    let k = cross(a, b);
    let out = add(
        add(scale(v, c), cross(k, v)),
        scale(k, dot(k, v) / (1.0 + c)),
    );
    normalize_or_zero(out)
}

impl BodyProximity for SweptBody {
    fn closest(&self, x: [f64; 3]) -> Option<BodyContact> {
        self.closest_moving(x).map(|(c, _)| c)
    }

    fn closest_moving(&self, x: [f64; 3]) -> Option<(BodyContact, [f64; 3])> {
        match self.proximity(x) {
            Proximity::Contact(c, moved) => Some((c, moved)),
            Proximity::Clear(_) => None,
        }
    }

    fn proximity(&self, x: [f64; 3]) -> Proximity {
        let after = self.after.proximity(x);
        let Some((carried, moved)) = self.carried(x) else {
            return after;
        };
        let behind = carried.signed_distance(x);
        let swept = match after {
            Proximity::Contact(a, _) => behind < 0.0 && dot(a.normal, carried.normal) < 0.0,
            Proximity::Clear(_) => behind < -self.after.query_radius(),
        };
        if swept {
            Proximity::Contact(carried, moved)
        } else {
            after
        }
    }

    // `travelled` stays `None`: a `Clearance` skips nothing, since a carried contact
    // can reach farther than the body at `t + 1` is from the vertex.
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::tests::unit_sphere;

    fn moved(mesh: &weft_mesh::TriMesh, f: impl Fn([f64; 3]) -> [f64; 3]) -> PosedBody {
        let p: Vec<[f64; 3]> = mesh.positions.iter().map(|&p| f(p)).collect();
        PosedBody::new(&p, &mesh.faces).unwrap()
    }

    /// The unit sphere moved by `f` over one step, its end state refitted from its
    /// start as a rollout's is, so that it knows how far each surface point moved.
    fn swept(f: impl Fn([f64; 3]) -> [f64; 3]) -> SweptBody {
        let s = unit_sphere();
        let before = moved(&s, |p| p);
        let mut after = before.clone();
        after.refit(moved(&s, f).surface().positions()).unwrap();
        SweptBody::new(before, after).unwrap()
    }

    fn near(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9)
    }

    #[test]
    fn a_vertex_swept_through_is_pushed_back_to_its_side() {
        let x = [-1.05, 0.0, 0.0];
        // The sphere (radius 1) moves 1.5 towards -x: x ends inside, nearer its far side,
        // where the closest point at t + 1 would push it out through the sphere.
        let body = swept(|p| [p[0] - 1.5, p[1], p[2]]);
        let plain = body.after().closest(x).unwrap();
        assert!(plain.normal[0] > 0.99, "{plain:?}");
        let (c, m) = body.closest_moving(x).unwrap();
        assert!(near(c.point, [-2.5, 0.0, 0.0]) && near(c.normal, [-1.0, 0.0, 0.0]));
        assert!(near(m, [-1.5, 0.0, 0.0]));
        assert!((c.signed_distance(x) + 1.45).abs() < 1e-9);
        // Moved 2.5: x is outside again, on the far side, and still held to its own.
        let body = swept(|p| [p[0] - 2.5, p[1], p[2]]);
        assert!(body.after().closest(x).is_none());
        let c = body.closest(x).unwrap();
        assert!((c.signed_distance(x) + 2.45).abs() < 1e-9);
    }

    /// A strip of cloth 0.4 wide across the front of the sphere (radius 1), which moves
    /// 0.5 into it in one step while the cloth stays where it was (a learned step that
    /// did not see it coming): pushed out along their own planes, the strip's ends go
    /// round the sphere's sides (an edge at 2.5 rest lengths); held by friction
    /// (μ = 0.5), the strip goes on with the points it touched, in one piece (1.006).
    #[test]
    fn friction_carries_a_strip_a_body_sweeps_into_in_one_piece() {
        use crate::{project_contacts, ClothModel, Material, SimOptions};
        let n = 9;
        let positions: Vec<[f64; 3]> = (0..2 * n)
            .map(|i| [-1.05, -0.2 + 0.05 * (i % n) as f64, 0.05 * (i / n) as f64])
            .collect();
        let faces = (0..n as u32 - 1)
            .flat_map(|j| {
                let m = n as u32;
                [[j, j + 1, j + m], [j + 1, j + m + 1, j + m]]
            })
            .collect();
        let strip = weft_mesh::TriMesh::new(positions, faces);
        let body = swept(|p| [p[0] - 0.5, p[1], p[2]]);
        let longest = |friction: f64| {
            let material = Material {
                friction,
                ..Material::cotton()
            };
            let model = ClothModel::uniform(&strip, &material, SimOptions::default()).unwrap();
            let contacts = model
                .contacts(&strip.positions, &vec![false; 2 * n], Some(&body))
                .unwrap();
            assert_eq!(contacts.collision.len(), 2 * n);
            assert_eq!(contacts.grips.len(), 2 * n);
            let mut x = strip.positions.clone();
            let moved = project_contacts(&mut x, &contacts.collision, &contacts.grips, 0.002);
            assert_eq!(moved.unwrap(), 2 * n);
            let after = body.after().surface().signed_distances(&x).unwrap();
            assert!(after.iter().all(|&d| d > 0.0), "{after:?}");
            strip
                .edges()
                .iter()
                .map(|&[a, b]| {
                    let (a, b) = (a as usize, b as usize);
                    weft_mesh::vec3::dist(x[a], x[b])
                        / weft_mesh::vec3::dist(strip.positions[a], strip.positions[b])
                })
                .fold(0.0, f64::max)
        };
        let (slid, held) = (longest(0.0), longest(0.5));
        assert!(slid > 1.3, "{slid}");
        assert!(held < 1.05, "{held}");
    }

    #[test]
    fn slow_and_sliding_bodies_keep_the_closest_point() {
        let x = [-1.005, 0.0, 0.0];
        // A small step: both instants agree.
        let body = swept(|p| [p[0] - 0.01, p[1], p[2]]);
        assert_eq!(body.proximity(x), body.after().proximity(x));
        // A quarter turn about z: the surface slides under x, whose side is unchanged
        // (the carried point is a quarter of the way round, its plane behind x).
        let body = swept(|p| [-p[1], p[0], p[2]]);
        let (carried, _) = body.carried(x).unwrap();
        assert!(carried.signed_distance(x) < -0.5);
        assert_eq!(body.proximity(x), body.after().proximity(x));
        // A vertex inside at t has no carried contact.
        assert!(body.carried([-0.9, 0.0, 0.0]).is_none());
    }

    #[test]
    fn turning_keeps_unit_length_and_follows_the_rotation() {
        let v = normalize_or_zero([1.0, 2.0, 0.5]);
        let (a, b) = ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]);
        // The quarter turn about x taking z to y takes (x, y, z) to (x, z, -y).
        assert!(near(turned(v, a, b), [v[0], v[2], -v[1]]));
        assert!(near(turned(v, a, a), v));
        let bad = SweptBody::new(
            moved(&unit_sphere(), |p| p),
            moved(&crate::body::tests::uv_sphere(6, 8, 1.0), |p| p),
        );
        assert!(bad.unwrap_err().to_string().contains("swept body"));
    }
}
