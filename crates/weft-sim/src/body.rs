//! The posed body as a collision surface for the simulator: closest point and outward
//! normal of a garment vertex ([`BodyProximity`]), built on weft-body's
//! [`BodySurface`] (AABB tree over the triangles, angle-weighted pseudo-normals) and
//! refitted whenever the body moves (every sub-step of a sequence).
//!
//! The contact normal is the direction of the gradient of the signed distance at the
//! query point, `±(x − p)/|x − p|` with the sign of the pseudo-normal test: then
//! `(x − p)·n` *is* the signed distance, on faces, edges and vertices alike, and the
//! linearised contact of the cubic penalty is tangent to the body's distance level set.
//! Points (almost) on the surface, where that direction is undefined, use the
//! pseudo-normal of the closest feature.
//!
//! The body also remembers its previous vertex positions, so a contact can say how far
//! the touched surface point moved during the last update (same triangle, same
//! barycentric coordinates): the anchor of HOOD's friction term on a moving body.

use rayon::prelude::*;
use weft_body::query::{BodySurface, ClosestPoint};
use weft_mesh::vec3::{dist, is_finite, scale, sub};

use std::sync::atomic::{AtomicU64, Ordering};

use crate::contact::{BodyContact, BodyProximity, Proximity};
use crate::error::SimError;

/// Default query radius (m): contacts farther than this are not reported. It matches
/// [`crate::SimOptions::contact_radius`].
pub const DEFAULT_QUERY_RADIUS: f64 = 2e-2;

/// Below this distance (m) the contact direction falls back to the pseudo-normal.
const ON_SURFACE: f64 = 1e-9;

/// A posed body mesh prepared for contact queries.
#[derive(Debug)]
pub struct PosedBody {
    surface: BodySurface,
    previous: Vec<[f64; 3]>,
    query_radius: f64,
    /// This surface's number and the sum over its updates of the farthest any vertex
    /// moved ([`BodyProximity::travelled`]).
    travelled: (u64, f64),
}

/// Numbers the surfaces, so that a [`crate::Clearance`] recorded against one is never
/// read against another.
static SURFACES: AtomicU64 = AtomicU64::new(0);

fn next_surface() -> u64 {
    SURFACES.fetch_add(1, Ordering::Relaxed)
}

/// A clone moves on its own from here, so it is another surface.
impl Clone for PosedBody {
    fn clone(&self) -> Self {
        PosedBody {
            surface: self.surface.clone(),
            previous: self.previous.clone(),
            query_radius: self.query_radius,
            travelled: (next_surface(), 0.0),
        }
    }
}

/// The farthest a garment may start from the body at its closest vertex (m). Garments
/// are worn: a waistband or neckline touches the body, and even a loose dress hangs
/// within centimetres of the shoulders. Half a metre of air everywhere means the mesh is
/// in another frame or unit, and simulating it would silently produce a garment falling
/// beside the body.
pub const MAX_GARMENT_GAP: f64 = 0.5;

/// Refuses a garment whose every vertex is more than [`MAX_GARMENT_GAP`] from the body,
/// given the vertices' signed distances.
pub fn check_garment_gap(signed: impl IntoIterator<Item = f64>) -> Result<(), SimError> {
    let gap = signed.into_iter().fold(f64::INFINITY, f64::min);
    if gap > MAX_GARMENT_GAP {
        return Err(SimError::OffBody {
            gap,
            max: MAX_GARMENT_GAP,
        });
    }
    Ok(())
}

/// The outward contact normal of `x` at its closest point `c` (module documentation):
/// the direction of the signed distance's gradient, or the pseudo-normal on the surface.
pub(crate) fn contact_normal(x: [f64; 3], c: &ClosestPoint) -> [f64; 3] {
    if c.distance > ON_SURFACE {
        let s = if c.signed_distance < 0.0 { -1.0 } else { 1.0 };
        scale(sub(x, c.point), s / c.distance)
    } else {
        c.normal
    }
}

/// The farthest any vertex moved from `before` to `after` (m).
pub(crate) fn farthest_move(before: &[[f64; 3]], after: &[[f64; 3]]) -> f64 {
    before
        .iter()
        .zip(after)
        .map(|(&a, &b)| dist(a, b))
        .fold(0.0, f64::max)
}

/// How many garment vertices lie inside the body, and how deep the deepest is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Penetration {
    /// Vertices with a negative signed distance.
    pub count: usize,
    /// The largest depth (m), 0 when none is inside.
    pub max_depth: f64,
    /// Vertices deeper than the tolerance given to [`PosedBody::penetration`].
    pub beyond_tolerance: usize,
}

impl PosedBody {
    /// Contacts are reported within the query radius, and for every point inside the
    /// body however deep.
    ///
    /// The body mesh `positions`/`faces` (closed, outward-oriented for signs to hold;
    /// weft's default body and SMPL are).
    pub fn new(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<Self, SimError> {
        let surface = BodySurface::new(positions, faces)?;
        Ok(PosedBody {
            surface,
            previous: positions.to_vec(),
            query_radius: DEFAULT_QUERY_RADIUS,
            travelled: (next_surface(), 0.0),
        })
    }

    /// Sets the query radius (m, finite and `> 0`).
    pub fn with_query_radius(mut self, radius: f64) -> Result<Self, SimError> {
        crate::error::check_nonneg(|| "body query radius".into(), radius, true)?;
        self.query_radius = radius;
        Ok(self)
    }

    /// The query radius, m.
    pub fn query_radius(&self) -> f64 {
        self.query_radius
    }

    /// Moves the body to `positions` (same vertex count): the tree is refitted, the
    /// normals updated, and the old positions kept for [`BodyProximity::closest_moving`].
    pub fn refit(&mut self, positions: &[[f64; 3]]) -> Result<(), SimError> {
        self.previous.clear();
        self.previous.extend_from_slice(self.surface.positions());
        if let Err(e) = self.surface.refit(positions) {
            // Keep the state consistent: previous = current on failure.
            self.previous.clear();
            self.previous.extend_from_slice(self.surface.positions());
            return Err(e.into());
        }
        self.travelled.1 += farthest_move(&self.previous, self.surface.positions());
        Ok(())
    }

    /// Moves the body to `positions` (same vertex count) with a fresh tree, at rest there
    /// (no motion remembered): for a pose far from the one the tree was built on. The
    /// edge numbering of the pseudo-normals is kept, so this costs a tree build, not the
    /// sort of every half-edge that [`PosedBody::new`] does.
    pub fn rebuild(&mut self, positions: &[[f64; 3]]) -> Result<(), SimError> {
        let before = self.surface.positions().to_vec();
        self.surface.rebuild(positions)?;
        self.travelled.1 += farthest_move(&before, self.surface.positions());
        self.settle();
        Ok(())
    }

    /// Forgets the motion of the last refit (the body is taken to be at rest).
    pub fn settle(&mut self) {
        self.previous.clear();
        self.previous.extend_from_slice(self.surface.positions());
    }

    /// The underlying surface (current positions).
    pub fn surface(&self) -> &BodySurface {
        &self.surface
    }

    /// Signed distances of `points` to the body (negative inside), unbounded, in
    /// parallel.
    pub fn signed_distances(&self, points: &[[f64; 3]]) -> Result<Vec<f64>, SimError> {
        Ok(self.surface.signed_distances(points)?)
    }

    /// Counts the points inside the body and those deeper than `tolerance` (m).
    pub fn penetration(
        &self,
        points: &[[f64; 3]],
        tolerance: f64,
    ) -> Result<Penetration, SimError> {
        let d = self.signed_distances(points)?;
        Ok(d.par_iter()
            .fold(Penetration::default, |mut p, &d| {
                if d < 0.0 {
                    p.count += 1;
                    p.max_depth = p.max_depth.max(-d);
                    if -d > tolerance {
                        p.beyond_tolerance += 1;
                    }
                }
                p
            })
            .reduce(Penetration::default, |a, b| Penetration {
                count: a.count + b.count,
                max_depth: a.max_depth.max(b.max_depth),
                beyond_tolerance: a.beyond_tolerance + b.beyond_tolerance,
            }))
    }

    /// The contact of `x` (closest point, outward normal, triangle, barycentric
    /// coordinates), or how far outside the body it is when it has none (0 when not
    /// known: a non-finite point).
    fn query(&self, x: [f64; 3]) -> Result<(BodyContact, u32, [f64; 3]), f64> {
        if !is_finite(x) {
            return Err(0.0);
        }
        // Within the radius, or anywhere inside: a vertex pushed deeper than the radius
        // (squeezed between an arm and the torso, say) must still be pushed back out
        // rather than left to fall through the body.
        let c = match self.surface.closest_point_within(x, self.query_radius) {
            Ok(Some(c)) => c,
            Ok(None) => {
                let c = self.surface.closest_point(x).map_err(|_| 0.0)?;
                if c.signed_distance >= 0.0 {
                    return Err(c.distance);
                }
                c
            }
            Err(_) => return Err(0.0),
        };
        Ok((
            BodyContact {
                point: c.point,
                normal: contact_normal(x, &c),
            },
            c.triangle,
            c.barycentric,
        ))
    }
}

impl BodyProximity for PosedBody {
    fn closest(&self, x: [f64; 3]) -> Option<BodyContact> {
        self.query(x).ok().map(|(c, _, _)| c)
    }

    fn closest_moving(&self, x: [f64; 3]) -> Option<(BodyContact, [f64; 3])> {
        match self.proximity(x) {
            Proximity::Contact(c, moved) => Some((c, moved)),
            Proximity::Clear(_) => None,
        }
    }

    fn proximity(&self, x: [f64; 3]) -> Proximity {
        let (c, tri, bary) = match self.query(x) {
            Ok(found) => found,
            Err(clear) => return Proximity::Clear(clear),
        };
        let face = self.surface.faces()[tri as usize];
        let mut before = [0.0; 3];
        for (&v, &b) in face.iter().zip(&bary) {
            let p = self.previous[v as usize];
            for k in 0..3 {
                before[k] += b * p[k];
            }
        }
        let moved = sub(c.point, before);
        // The closest point is on the current triangle; `before` is the same material
        // point one update earlier. A huge jump means a non-finite or teleported body.
        if !is_finite(moved) || dist(c.point, before) > 1e3 {
            return Proximity::Contact(c, [0.0; 3]);
        }
        Proximity::Contact(c, moved)
    }

    fn travelled(&self) -> Option<(u64, f64)> {
        Some(self.travelled)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A closed, outward-oriented unit UV sphere.
    pub(crate) fn unit_sphere() -> weft_mesh::TriMesh {
        uv_sphere(24, 48, 1.0)
    }

    /// A closed, outward-oriented UV sphere of `rings` latitude bands.
    pub(crate) fn uv_sphere(rings: usize, around: usize, r: f64) -> weft_mesh::TriMesh {
        use std::f64::consts::PI;
        let mut p = vec![[0.0, r, 0.0]];
        for i in 1..rings {
            let th = PI * i as f64 / rings as f64;
            for j in 0..around {
                let ph = 2.0 * PI * j as f64 / around as f64;
                p.push([
                    r * th.sin() * ph.cos(),
                    r * th.cos(),
                    -r * th.sin() * ph.sin(),
                ]);
            }
        }
        p.push([0.0, -r, 0.0]);
        let south = (p.len() - 1) as u32;
        let ring = |i: usize, j: usize| (1 + (i - 1) * around + j % around) as u32;
        let mut f = Vec::new();
        for j in 0..around {
            f.push([0, ring(1, j), ring(1, j + 1)]);
            f.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
        }
        for i in 1..rings - 1 {
            for j in 0..around {
                f.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                f.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
            }
        }
        weft_mesh::TriMesh::new(p, f)
    }

    #[test]
    fn contacts_give_signed_distance_and_motion() {
        let s = unit_sphere();
        let mut body = PosedBody::new(&s.positions, &s.faces)
            .unwrap()
            .with_query_radius(0.1)
            .unwrap();
        // Outside, within the radius: the normal points out and (x − p)·n = distance.
        let x = [0.0, 1.05, 0.0];
        let c = body.closest(x).unwrap();
        assert!((c.signed_distance(x) - 0.05).abs() < 0.01, "{c:?}");
        assert!(c.normal[1] > 0.99);
        // Inside: negative signed distance, normal still outward.
        let y = [0.0, 0.95, 0.0];
        let c = body.closest(y).unwrap();
        assert!(c.signed_distance(y) < 0.0 && c.normal[1] > 0.99, "{c:?}");
        // Deep inside, beyond the radius: still a contact, pointing out.
        let deep = [0.0, 0.5, 0.0];
        let c = body.closest(deep).unwrap();
        assert!((c.signed_distance(deep) + 0.5).abs() < 0.01, "{c:?}");
        assert!(c.normal[1] > 0.99, "{c:?}");
        // Far outside: no contact.
        assert!(body.closest([0.0, 2.0, 0.0]).is_none());
        assert!(body.closest([f64::NAN, 0.0, 0.0]).is_none());
        // Translate the body: the contact reports the surface displacement.
        let moved: Vec<[f64; 3]> = s
            .positions
            .iter()
            .map(|p| [p[0] + 0.02, p[1], p[2]])
            .collect();
        body.refit(&moved).unwrap();
        let (_, d) = body.closest_moving(x).unwrap();
        assert!((d[0] - 0.02).abs() < 1e-12 && d[1].abs() < 1e-12, "{d:?}");
        body.settle();
        assert_eq!(body.closest_moving(x).unwrap().1, [0.0; 3]);
        // Penetration statistics.
        let p = body
            .penetration(
                &[[0.02, 0.0, 0.0], [0.02, 0.99, 0.0], [0.0, 3.0, 0.0]],
                0.05,
            )
            .unwrap();
        assert_eq!(p.count, 2);
        assert_eq!(p.beyond_tolerance, 1);
        assert!(p.max_depth > 0.9);
    }

    #[test]
    fn bad_bodies_are_errors() {
        assert!(matches!(
            PosedBody::new(&[[0.0; 3]], &[]),
            Err(SimError::BodySurface(_))
        ));
        let s = unit_sphere();
        let mut b = PosedBody::new(&s.positions, &s.faces).unwrap();
        assert!(b.refit(&s.positions[1..]).is_err());
        let mut nan = s.positions.clone();
        nan[3][1] = f64::NAN;
        assert!(b.refit(&nan).is_err());
        assert!(b.clone().with_query_radius(0.0).is_err());
        // Still usable after a failed refit.
        assert!(b.closest([0.0, 1.01, 0.0]).is_some());
    }

    /// Counts the queries a contact search makes.
    struct Counted<'a> {
        body: &'a PosedBody,
        calls: std::sync::atomic::AtomicUsize,
    }

    impl BodyProximity for Counted<'_> {
        fn closest(&self, x: [f64; 3]) -> Option<BodyContact> {
            self.body.closest(x)
        }
        fn proximity(&self, x: [f64; 3]) -> Proximity {
            self.calls.fetch_add(1, Ordering::Relaxed);
            self.body.proximity(x)
        }
        fn travelled(&self) -> Option<(u64, f64)> {
            self.body.travelled()
        }
    }

    #[test]
    fn far_points_report_their_clearance_and_the_body_its_travel() {
        let s = unit_sphere();
        let mut body = PosedBody::new(&s.positions, &s.faces).unwrap();
        match body.proximity([0.0, 2.0, 0.0]) {
            Proximity::Clear(d) => assert!((d - 1.0).abs() < 0.01, "{d}"),
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            body.proximity([0.0, 1.01, 0.0]),
            Proximity::Contact(..)
        ));
        let (id, t0) = body.travelled().unwrap();
        assert_eq!(t0, 0.0);
        let moved: Vec<[f64; 3]> = s
            .positions
            .iter()
            .map(|p| [p[0], p[1] + 0.03, p[2]])
            .collect();
        body.refit(&moved).unwrap();
        let (same, t1) = body.travelled().unwrap();
        assert_eq!(same, id);
        assert!((t1 - 0.03).abs() < 1e-12, "{t1}");
        body.rebuild(&s.positions).unwrap();
        assert!((body.travelled().unwrap().1 - 0.06).abs() < 1e-12);
        // A clone moves on its own: another surface.
        assert_ne!(body.clone().travelled().unwrap().0, id);
    }

    #[test]
    fn a_clearance_skips_far_vertices_and_finds_the_same_contacts() {
        use crate::cloth::ClothModel;
        use crate::contact::Clearance;
        use crate::{Material, SimOptions};
        let s = unit_sphere();
        let mut body = PosedBody::new(&s.positions, &s.faces).unwrap();
        // A cloth over the top of the sphere: its middle within reach, its rim 5-9 cm off.
        let rest = weft_mesh::primitives::grid(12, 12, 0.05);
        let n = rest.vertex_count();
        let model = ClothModel::uniform(&rest, &Material::hood(), SimOptions::default()).unwrap();
        let pinned = vec![false; n];
        let mut clearance = Clearance::default();
        let mut calls = Vec::new();
        for step in 0..6 {
            // The body rises 5 mm per update; the cloth sags and ripples.
            let lift = 0.005 * step as f64;
            let posed: Vec<[f64; 3]> = s
                .positions
                .iter()
                .map(|p| [p[0], p[1] + lift, p[2]])
                .collect();
            body.refit(&posed).unwrap();
            let x: Vec<[f64; 3]> = rest
                .positions
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let ripple = 0.002 * ((i + step) as f64).sin();
                    [
                        p[0] - 0.275,
                        1.015 + ripple - 0.001 * step as f64,
                        p[2] - 0.275,
                    ]
                })
                .collect();
            let counted = Counted {
                body: &body,
                calls: Default::default(),
            };
            let skipping = model
                .contacts_with(&x, &pinned, Some(&counted), &mut clearance)
                .unwrap();
            let fresh = model.contacts(&x, &pinned, Some(&body)).unwrap();
            assert_eq!(skipping, fresh, "step {step}");
            assert!(!fresh.collision.is_empty());
            calls.push(counted.calls.into_inner());
        }
        // The first search knows nothing; the next skip the rim (31 of 144 queried
        // when written), less of it as the body rises towards it.
        assert_eq!(calls[0], n);
        assert!(calls[1] < n / 2, "{calls:?}");
        assert!(calls.windows(2).skip(1).all(|w| w[0] <= w[1]), "{calls:?}");
        assert!(calls[1..].iter().all(|&c| c < n), "{calls:?}");
        // Against another surface the record is not used.
        let other = body.clone();
        let counted = Counted {
            body: &other,
            calls: Default::default(),
        };
        let x = rest
            .positions
            .iter()
            .map(|p| [p[0] - 0.275, 1.01, p[2] - 0.275])
            .collect::<Vec<_>>();
        model
            .contacts_with(&x, &pinned, Some(&counted), &mut clearance)
            .unwrap();
        assert_eq!(counted.calls.into_inner(), n);
    }
}
