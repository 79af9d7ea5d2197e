//! Body contacts as plain data: for a garment vertex, the closest point on the body and
//! the body's outward normal there, at the current body state.
//!
//! The body and its closest-point queries live elsewhere (weft-body); the collision and
//! friction energies only see these records, which keeps them pure functions of the
//! positions. The simulator refreshes them (each step, from the positions at the start
//! of the step, as HOOD does) through the small [`BodyProximity`] trait, which weft-body
//! can implement and which the analytic [`Plane`] and [`Sphere`] here implement for tests.

use crate::error::{check_vertex, SimError};
use crate::math::{finite3, v3};
use weft_mesh::vec3::{add, dot, norm, scale, sub};

/// The closest body point to a garment vertex and the body's outward unit normal there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyContact {
    /// Closest point on the body, m.
    pub point: [f64; 3],
    /// Outward unit normal of the body at `point`.
    pub normal: [f64; 3],
}

impl BodyContact {
    /// The signed distance of `x` along the normal: `(x − p)·n` (positive outside).
    pub fn signed_distance(&self, x: [f64; 3]) -> f64 {
        (0..3)
            .map(|k| (x[k] - self.point[k]) * self.normal[k])
            .sum()
    }
}

/// A contact of one garment vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexContact {
    /// The garment vertex.
    pub vertex: u32,
    /// Its body contact.
    pub contact: BodyContact,
}

/// What [`project_contacts`]' friction needs of one contact: where its vertex would be
/// had it stuck over the step to the body point it touched (`x_t + Δp_body`, the anchor
/// of HOOD's friction term, [`crate::FrictionContact`]) and the friction coefficient.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grip {
    /// `x_t + Δp_body`, m.
    pub anchor: [f64; 3],
    /// Friction coefficient μ (0: the vertex slides freely).
    pub mu: f64,
}

/// The hard form of the cubic collision term's constraint `(x − p)·n ≥ ε`: every
/// contact's vertex nearer than `margin` to its contact plane, or behind it, moves along
/// the normal onto the plane at `margin`. For a step that is not the potential's
/// minimiser (a learned one), where the penalty alone lets a fast limb through the
/// cloth. Returns how many vertices moved; errors on a contact vertex out of range.
///
/// With `grips` (one per contact, or none for frictionless planes), each moved vertex
/// also takes Coulomb friction in position form (Müller et al. 2007, Macklin et al.
/// 2014): the tangential part of its displacement from the anchor is taken away up to
/// μ times the normal correction (static friction), and shortened by that much beyond
/// it (sliding). Without it a limb that sweeps into the cloth pushes each vertex out
/// along its own plane, those in front of a running thigh to either side of it, and
/// the sheet is cut in two; with it they move on with the body points they touched.
pub fn project_contacts(
    x: &mut [[f64; 3]],
    contacts: &[VertexContact],
    grips: &[Grip],
    margin: f64,
) -> Result<usize, SimError> {
    crate::error::check_nonneg(|| "contact margin".into(), margin, false)?;
    if !grips.is_empty() {
        crate::error::check_len("contact grips", contacts.len(), grips.len())?;
    }
    if let Some(i) = grips
        .iter()
        .position(|g| !(finite3(g.anchor) && g.mu.is_finite() && g.mu >= 0.0))
    {
        return Err(SimError::InvalidVector {
            what: format!("contact grip {i}"),
            message: "expected a finite anchor and a finite, non-negative μ",
        });
    }
    let mut moved = 0;
    for (i, c) in contacts.iter().enumerate() {
        check_vertex("contact", i, c.vertex, x.len())?;
        let p = &mut x[c.vertex as usize];
        let n = c.contact.normal;
        let gap = margin - c.contact.signed_distance(*p);
        if gap <= 0.0 {
            continue;
        }
        *p = add(*p, scale(n, gap));
        moved += 1;
        if let Some(g) = grips.get(i).filter(|g| g.mu > 0.0) {
            let u = sub(*p, g.anchor);
            let slip = sub(u, scale(n, dot(u, n)));
            let (len, hold) = (norm(slip), g.mu * gap);
            let taken = if len <= hold { 1.0 } else { hold / len };
            *p = sub(*p, scale(slip, taken));
        }
    }
    Ok(moved)
}

/// Checks vertex indices and finiteness and normalises the normals.
pub(crate) fn validate_contacts(
    mut contacts: Vec<VertexContact>,
    vertex_count: usize,
) -> Result<Vec<VertexContact>, SimError> {
    for (i, c) in contacts.iter_mut().enumerate() {
        check_vertex("contact", i, c.vertex, vertex_count)?;
        c.contact.normal = unit(c.contact.normal, || format!("contact {i} normal"))?;
        if !finite3(c.contact.point) {
            return Err(SimError::InvalidVector {
                what: format!("contact {i} point"),
                message: "not finite",
            });
        }
    }
    Ok(contacts)
}

/// `n / |n|`, an error for a zero or non-finite vector.
pub(crate) fn unit(n: [f64; 3], what: impl Fn() -> String) -> Result<[f64; 3], SimError> {
    let l = v3(n).norm();
    if !(l.is_finite() && l > 0.0) {
        return Err(SimError::InvalidVector {
            what: what(),
            message: "expected a finite, non-zero direction",
        });
    }
    Ok(n.map(|c| c / l))
}

/// Closest-point queries against a body at one instant.
pub trait BodyProximity {
    /// The closest body point to `x` and the outward normal there, `None` when the body
    /// is farther than the query cares about (no contact).
    fn closest(&self, x: [f64; 3]) -> Option<BodyContact>;

    /// [`BodyProximity::closest`] together with how far the body surface point under
    /// the contact moved during the last body update (m): the friction anchor of a
    /// moving body (HOOD's `Δp_body`). The default is a body at rest.
    fn closest_moving(&self, x: [f64; 3]) -> Option<(BodyContact, [f64; 3])> {
        self.closest(x).map(|c| (c, [0.0; 3]))
    }

    /// [`BodyProximity::closest_moving`], or where it finds no contact, how far outside
    /// the body `x` is at least (m). The default knows no distance (`Clear(0.0)`).
    fn proximity(&self, x: [f64; 3]) -> Proximity {
        match self.closest_moving(x) {
            Some((c, moved)) => Proximity::Contact(c, moved),
            None => Proximity::Clear(0.0),
        }
    }

    /// Which surface this is and a running total of how far it has moved over all its
    /// updates (m): between two readings of the same surface, no surface point moved
    /// farther than their difference. `None` (the default): not tracked, and a
    /// [`Clearance`] then skips nothing.
    fn travelled(&self) -> Option<(u64, f64)> {
        None
    }
}

/// What a body query found for one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Proximity {
    /// A contact and how far the touched surface point moved in the last body update.
    Contact(BodyContact, [f64; 3]),
    /// No contact; the point is outside the body, at least this far from it (m).
    Clear(f64),
}

/// How far outside the body each garment vertex was at the last contact search, so
/// that the next search skips the vertices that cannot have come within reach.
///
/// Exact, not a heuristic: the distance to the surface changes by at most the vertex's
/// own motion plus the farthest any surface point moved, so a vertex that was `d`
/// outside, moved `δx` while the surface moved at most `δb`, is still outside and at
/// least `d − δx − δb` away (it cannot have crossed a surface it never came near). A
/// query for a vertex beyond the body's query radius is the most expensive kind, an
/// unbounded nearest-triangle search to tell outside from deep inside, and most of a
/// skirt is beyond it.
///
/// The argument needs a closed surface that does not pass through itself. Where a
/// posed body does (thighs pressed together, an arm into the torso), inside and
/// outside are not well defined away from the surface: the sign of a far point comes
/// from whichever part is nearest, and can change without the point crossing any
/// surface. There a skipped vertex keeps its last reading (outside) where a fresh
/// search might have called it deep inside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clearance {
    /// Each vertex's position and its distance bound at the last search (0: unknown).
    at: Vec<([f64; 3], f64)>,
    /// The body's [`BodyProximity::travelled`] then.
    travelled: Option<(u64, f64)>,
}

impl Clearance {
    /// The bound for vertex `i` now at `x`, with the body's `travelled` now: `None`
    /// where nothing is known.
    pub(crate) fn bound(
        &self,
        i: usize,
        x: [f64; 3],
        travelled: Option<(u64, f64)>,
    ) -> Option<f64> {
        let ((then_id, then), (now_id, now)) = (self.travelled?, travelled?);
        let (at, d) = *self.at.get(i)?;
        (then_id == now_id && now >= then && d > 0.0)
            .then(|| d - (v3(x) - v3(at)).norm() - (now - then))
    }

    /// Replaces the record: one `(position, bound)` per vertex.
    pub(crate) fn record(&mut self, at: Vec<([f64; 3], f64)>, travelled: Option<(u64, f64)>) {
        self.at = at;
        self.travelled = travelled;
    }
}

/// An infinite plane (a floor), outward normal `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// A point on the plane.
    pub point: [f64; 3],
    /// Outward unit normal.
    pub normal: [f64; 3],
}

impl BodyProximity for Plane {
    fn closest(&self, x: [f64; 3]) -> Option<BodyContact> {
        let d: f64 = (0..3)
            .map(|k| (x[k] - self.point[k]) * self.normal[k])
            .sum();
        Some(BodyContact {
            point: std::array::from_fn(|k| x[k] - d * self.normal[k]),
            normal: self.normal,
        })
    }
}

/// A sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre, m.
    pub center: [f64; 3],
    /// Radius, m.
    pub radius: f64,
}

impl BodyProximity for Sphere {
    fn closest(&self, x: [f64; 3]) -> Option<BodyContact> {
        let d = v3(x) - v3(self.center);
        let l = d.norm();
        if !(l > 0.0 && l.is_finite()) {
            return None;
        }
        let n = d / l;
        Some(BodyContact {
            point: std::array::from_fn(|k| self.center[k] + self.radius * n[k]),
            normal: [n.x, n.y, n.z],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_bodies() {
        let s = Sphere {
            center: [0.0, 1.0, 0.0],
            radius: 0.5,
        };
        let c = s.closest([0.0, 3.0, 0.0]).unwrap();
        assert_eq!(c.point, [0.0, 1.5, 0.0]);
        assert!((c.signed_distance([0.0, 3.0, 0.0]) - 1.5).abs() < 1e-15);
        assert!(s.closest([0.0, 1.0, 0.0]).is_none());
        let p = Plane {
            point: [0.0; 3],
            normal: [0.0, 1.0, 0.0],
        };
        assert!(
            (p.closest([1.0, -0.2, 3.0])
                .unwrap()
                .signed_distance([1.0, -0.2, 3.0])
                + 0.2)
                .abs()
                < 1e-15
        );
    }

    #[test]
    fn validation_normalises_and_rejects() {
        let c = |n| VertexContact {
            vertex: 0,
            contact: BodyContact {
                point: [0.0; 3],
                normal: n,
            },
        };
        let v = validate_contacts(vec![c([0.0, 2.0, 0.0])], 1).unwrap();
        assert_eq!(v[0].contact.normal, [0.0, 1.0, 0.0]);
        assert!(validate_contacts(vec![c([0.0; 3])], 1).is_err());
        assert!(validate_contacts(vec![c([0.0, 1.0, 0.0])], 0).is_err());
    }

    /// `vertex`'s contact with the floor `y = 0`.
    fn floor(vertex: u32) -> VertexContact {
        VertexContact {
            vertex,
            contact: BodyContact {
                point: [0.0; 3],
                normal: [0.0, 1.0, 0.0],
            },
        }
    }

    #[test]
    fn projection_moves_only_vertices_nearer_than_the_margin_onto_it() {
        // Behind the plane, in front within the margin, in front beyond it.
        let mut x = vec![[0.3, -0.05, 0.1], [0.0, 0.001, 0.0], [1.0, 0.5, 0.0]];
        let contacts = [floor(0), floor(1), floor(2)];
        let moved = project_contacts(&mut x, &contacts, &[], 0.004).unwrap();
        assert_eq!(moved, 2);
        assert!((x[0][1] - 0.004).abs() < 1e-15 && x[0][0] == 0.3 && x[0][2] == 0.1);
        assert!((x[1][1] - 0.004).abs() < 1e-15);
        assert_eq!(x[2], [1.0, 0.5, 0.0]);
        let err = project_contacts(&mut x, &[floor(3)], &[], 0.004).unwrap_err();
        assert!(err.to_string().contains("contact"), "{err}");
        assert!(project_contacts(&mut x, &[floor(0)], &[], -1.0).is_err());
    }

    /// The normal correction of a vertex 5 cm behind the floor is 5.4 cm, so μ = 0.5
    /// holds it to an anchor up to 2.7 cm along the floor and slides it that far
    /// towards one farther; a vertex the floor does not move takes no friction.
    #[test]
    fn friction_holds_a_projected_vertex_to_its_anchor_up_to_mu_times_the_push() {
        let grip = |x: f64, mu| Grip {
            anchor: [x, 0.004, 0.0],
            mu,
        };
        let contacts = [floor(0), floor(1), floor(2), floor(3)];
        let mut x = vec![
            [0.0, -0.05, 0.0],
            [0.0, -0.05, 0.0],
            [0.0, -0.05, 0.0],
            [0.0, 0.5, 0.0],
        ];
        let grips = [
            grip(0.02, 0.5),
            grip(0.1, 0.5),
            grip(0.1, 0.0),
            grip(0.1, 0.5),
        ];
        assert_eq!(
            project_contacts(&mut x, &contacts, &grips, 0.004).unwrap(),
            3
        );
        let near = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12);
        assert!(near(x[0], [0.02, 0.004, 0.0]), "{:?}", x[0]);
        assert!(near(x[1], [0.027, 0.004, 0.0]), "{:?}", x[1]);
        assert!(near(x[2], [0.0, 0.004, 0.0]), "{:?}", x[2]);
        assert_eq!(x[3], [0.0, 0.5, 0.0]);
        // One grip per contact, finite, μ ≥ 0.
        assert!(project_contacts(&mut x, &contacts, &grips[..2], 0.004).is_err());
        let bad = [grip(0.0, -0.5), grips[1], grips[2], grips[3]];
        let err = project_contacts(&mut x, &contacts, &bad, 0.004).unwrap_err();
        assert!(err.to_string().contains("grip 0"), "{err}");
    }
}
