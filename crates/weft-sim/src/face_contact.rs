//! Body vertices through cloth faces: the other half of a contact projection.
//!
//! [`crate::project_contacts`] and a push-out move garment *vertices* out of the body.
//! A convex part of the body can still come through a garment *between* its vertices:
//! a knee through a 3 cm triangle whose three corners lie outside the skin, the middle
//! of the triangle inside it (docs/hood.md item 12). Collision handling in simulators
//! takes both point–triangle cases for this reason (Bridson et al. 2002); here the
//! body is the point side. Every body vertex that came through the cloth in the step,
//! whose nearest cloth point within a reach lies inside a face or on an interior edge,
//! on a face roughly parallel to the skin there and turned the way most such faces
//! turn, and less than a margin out along the body's normal, pushes that face's
//! corners out along the normal, weighted by its barycentric coordinates, so that the
//! body vertex ends under the cloth (a point–triangle constraint with an immovable
//! point, as position-based dynamics takes them, Müller et al. 2007, bounded by the
//! depth); of several pushes on one garment vertex the largest is taken.

use rayon::prelude::*;
use weft_body::query::{BodySurface, SurfaceFeature};
use weft_mesh::topology::Topology;
use weft_mesh::vec3::{dot, norm, sub};
use weft_mesh::TriMesh;

use crate::error::{check_len, check_nonneg, SimError};

/// How far from a body vertex a cloth face is looked for (m): a part of the body that
/// came through the cloth by more than this in one step is not pulled back.
pub const FACE_CONTACT_REACH: f64 = 0.04;

/// The cosine between a cloth face's normal and the body's normal above which the face
/// counts as lying on the skin there: a panel passing beside a thigh, seen edge-on from
/// an inner-thigh vertex, is not pushed sideways.
const PARALLEL: f64 = 0.5;

/// A garment's faces, which of its vertices lie on its boundary (a body vertex whose
/// nearest cloth point is there may be past a hem, not through the cloth) and which
/// may move.
#[derive(Clone, Debug)]
pub struct FaceContact {
    faces: Vec<[u32; 3]>,
    boundary: Vec<bool>,
    movable: Vec<bool>,
    skipped: Vec<bool>,
}

impl FaceContact {
    /// The faces of `garment` (its rest mesh) with `pinned` vertices kept in place;
    /// body vertices flagged in `skipped` (the hands, whose fingers hang against a
    /// skirt's sides from the first frame, or none if empty) push no faces.
    pub fn new(garment: &TriMesh, pinned: &[bool], skipped: &[bool]) -> Result<Self, SimError> {
        let n = garment.vertex_count();
        check_len("pinned flags", n, pinned.len())?;
        let topology = Topology::new(garment);
        let mut boundary = vec![false; n];
        for e in topology.boundary_edges() {
            for v in topology.edges[e] {
                boundary[v as usize] = true;
            }
        }
        Ok(FaceContact {
            faces: garment.faces.clone(),
            boundary,
            movable: pinned.iter().map(|&p| !p).collect(),
            skipped: skipped.to_vec(),
        })
    }

    /// A step from the garment at `cloth` on `start` (both at the beginning of the
    /// step) to the body `end`: which body vertices were already on the cloth's outer
    /// side, and the body's normals at the end.
    pub fn step(
        &self,
        cloth: &[[f64; 3]],
        start: &BodySurface,
        end: &BodySurface,
    ) -> Result<ContactStep, SimError> {
        check_len("positions at the start", self.movable.len(), cloth.len())?;
        check_len(
            "body vertices at the end",
            start.positions().len(),
            end.positions().len(),
        )?;
        // With a zero margin a positive depth is a face behind the body vertex.
        let behind = self
            .finds(cloth, start, &start.vertex_normals(), 0.0)?
            .into_iter()
            .map(|p| p.filter(|p| p.depth > 0.0).map(|p| p.facing))
            .collect();
        Ok(ContactStep {
            behind,
            normals: end.vertex_normals(),
        })
    }

    /// Pushes the faces of the garment at `x` off every vertex of `body` (the end of
    /// `step`) that came through them in the step, to `margin` (m) out along the
    /// body's normal, in at most `passes` passes; returns how many garment vertices
    /// moved. A body vertex that was already on the cloth's outer side at the start
    /// (the back of a hand held in front of a skirt, thinner than the reach) is not one
    /// that came through.
    pub fn apply(
        &self,
        step: &ContactStep,
        x: &mut [[f64; 3]],
        body: &BodySurface,
        margin: f64,
        passes: usize,
    ) -> Result<usize, SimError> {
        check_len(
            "body vertices of the step",
            body.positions().len(),
            step.behind.len(),
        )?;
        check_nonneg(|| "face contact margin".into(), margin, true)?;
        let mut moved = vec![false; x.len()];
        for _ in 0..passes {
            let found = self.finds(x, body, &step.normals, margin)?;
            // Which way the garment's faces turn: the way most faces over the skin
            // turn (a mesh may be wound either way). A face turned the other way is
            // the far side of a thin limb or the underside of a fold, not cloth the
            // body came through.
            let outward = found
                .iter()
                .flatten()
                .map(|p| if p.facing { 1i64 } else { -1 })
                .sum::<i64>()
                >= 0;
            let pushes: Vec<&Push> = found
                .iter()
                .zip(&step.behind)
                .filter(|(_, behind)| **behind != Some(outward))
                .filter_map(|(p, _)| p.as_ref())
                .filter(|p| p.depth > 0.0 && p.facing == outward)
                .collect();
            if pushes.is_empty() {
                break;
            }
            // Each garment vertex takes the largest of the pushes on it: an average
            // with the shallower body vertices around the deepest under-corrects.
            let mut largest: Vec<Option<[f64; 3]>> = vec![None; x.len()];
            for p in pushes {
                for (&v, &w) in p.corners.iter().zip(&p.shares) {
                    let push = p.unit.map(|x| w * x);
                    let slot = &mut largest[v as usize];
                    if w > 0.0 && slot.map_or(true, |s| norm(push) > norm(s)) {
                        *slot = Some(push);
                    }
                }
            }
            for (v, push) in largest.iter().enumerate() {
                if let Some(push) = push {
                    for k in 0..3 {
                        x[v][k] += push[k];
                    }
                    moved[v] = true;
                }
            }
        }
        Ok(moved.iter().filter(|&&m| m).count())
    }

    /// [`FaceContact::push`] for every vertex of `body` against the garment at `cloth`
    /// (none for a skipped body vertex or one farther than the reach from the
    /// garment's bounding box).
    fn finds(
        &self,
        cloth: &[[f64; 3]],
        body: &BodySurface,
        normals: &[[f64; 3]],
        margin: f64,
    ) -> Result<Vec<Option<Push>>, SimError> {
        check_len("positions", self.movable.len(), cloth.len())?;
        if !self.skipped.is_empty() {
            check_len(
                "skipped body flags",
                body.positions().len(),
                self.skipped.len(),
            )?;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in cloth {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k] - FACE_CONTACT_REACH);
                hi[k] = hi[k].max(p[k] + FACE_CONTACT_REACH);
            }
        }
        let near = |p: &[f64; 3]| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
        let surface = BodySurface::new(cloth, &self.faces)?;
        Ok(body
            .positions()
            .par_iter()
            .zip(normals)
            .enumerate()
            .map(|(j, (p, &n))| match self.skipped.get(j) {
                Some(true) => None,
                _ if !near(p) => None,
                _ => self.push(&surface, *p, n, margin),
            })
            .collect())
    }

    /// What the body vertex at `p` with outward normal `n` finds of the cloth: its
    /// nearest face inside the reach, if that lies on the skin there (not past a hem,
    /// not edge-on), and the push it gives that face's corners.
    fn push(&self, cloth: &BodySurface, p: [f64; 3], n: [f64; 3], margin: f64) -> Option<Push> {
        let c = cloth.closest_point_within(p, FACE_CONTACT_REACH).ok()??;
        let on_boundary = |v: &u32| self.boundary[*v as usize];
        match c.feature {
            SurfaceFeature::Face(_) => {}
            SurfaceFeature::Edge(e) if !e.iter().any(on_boundary) => {}
            _ => return None,
        }
        let turn = dot(cloth.face_normals()[c.triangle as usize], n);
        if turn.abs() < PARALLEL {
            return None;
        }
        let corners = self.faces[c.triangle as usize];
        // Each movable corner moves along n by the depth times its barycentric share
        // over the largest movable share: the nearest corner by the whole depth, the
        // others less. The exact position-based answer (bᵢ / Σ bⱼ²) moves a lone
        // movable corner of small share by many times the depth, and flung a dress's
        // vertex at 90 m/s.
        let shares: [f64; 3] = std::array::from_fn(|k| {
            if self.movable[corners[k] as usize] {
                c.barycentric[k]
            } else {
                0.0
            }
        });
        let largest = shares.iter().cloned().fold(0.0, f64::max);
        if largest <= 1e-9 {
            return None;
        }
        let depth = margin - dot(sub(c.point, p), n);
        Some(Push {
            corners,
            shares: shares.map(|b| b / largest),
            unit: n.map(|x| x * depth),
            depth,
            facing: turn > 0.0,
        })
    }
}

/// One step of [`FaceContact::step`]: per body vertex, whether the cloth was behind it
/// at the start of the step (and which way that face turned), and the body's vertex
/// normals at its end.
#[derive(Clone, Debug)]
pub struct ContactStep {
    behind: Vec<Option<bool>>,
    normals: Vec<[f64; 3]>,
}

/// One body vertex's find: a cloth face over the skin and the push it would give it.
struct Push {
    corners: [u32; 3],
    /// The corners' shares of the push: barycentric over the largest movable one (0
    /// for a pinned corner).
    shares: [f64; 3],
    /// The push of a corner with share 1: the depth along the body's normal.
    unit: [f64; 3],
    /// How far the face is inside the margin along the body's normal (≤ 0: clear).
    depth: f64,
    /// Whether the face's normal turns the way the body's does.
    facing: bool,
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives::grid;

    /// A sphere of radius `r` about `c` as a closed, outward-oriented mesh (a UV
    /// sphere).
    fn sphere(c: [f64; 3], r: f64) -> BodySurface {
        let (rings, around) = (24usize, 48usize);
        let mut positions = vec![[c[0], c[1] + r, c[2]]];
        for i in 1..rings {
            let theta = std::f64::consts::PI * i as f64 / rings as f64;
            for j in 0..around {
                let phi = 2.0 * std::f64::consts::PI * j as f64 / around as f64;
                positions.push([
                    c[0] + r * theta.sin() * phi.cos(),
                    c[1] + r * theta.cos(),
                    c[2] + r * theta.sin() * phi.sin(),
                ]);
            }
        }
        positions.push([c[0], c[1] - r, c[2]]);
        let bottom = (positions.len() - 1) as u32;
        let ring = |i: usize, j: usize| (1 + (i - 1) * around + j % around) as u32;
        let mut faces = Vec::new();
        for j in 0..around {
            faces.push([0, ring(1, j + 1), ring(1, j)]);
            faces.push([bottom, ring(rings - 1, j), ring(rings - 1, j + 1)]);
        }
        for i in 1..rings - 1 {
            for j in 0..around {
                let (a, b, c2, d) = (
                    ring(i, j),
                    ring(i, j + 1),
                    ring(i + 1, j),
                    ring(i + 1, j + 1),
                );
                faces.push([a, b, d]);
                faces.push([a, d, c2]);
            }
        }
        let surface = BodySurface::new(&positions, &faces).unwrap();
        assert!(surface.is_closed());
        surface
    }

    #[test]
    fn a_sphere_through_the_middle_of_a_cell_lifts_its_faces() {
        // A sheet of 10 cm cells at y = 0; a sphere of radius 0.2 whose top, at y = 1 cm,
        // comes through the middle of a cell. Every sheet vertex is outside the sphere
        // (the nearest corners by 2.7 mm), so a vertex push-out moves nothing.
        // Either winding of the sheet: the faces' turn is taken from the contacts.
        let up = grid(4, 4, 0.1);
        let mut down = up.clone();
        for f in &mut down.faces {
            f.swap(1, 2);
        }
        let body = sphere([0.15, -0.19, 0.15], 0.2);
        // At the start of the step the sphere was 5 mm under the sheet.
        let before = sphere([0.15, -0.205, 0.15], 0.2);
        for sheet in [up, down] {
            let n = sheet.vertex_count();
            let mut x = sheet.positions.clone();
            let outside = body.signed_distances(&x).unwrap();
            assert!(outside.iter().all(|&d| d > 0.0), "{outside:?}");
            let contact = FaceContact::new(&sheet, &vec![false; n], &[]).unwrap();
            let step = contact.step(&sheet.positions, &before, &body).unwrap();
            let moved = contact.apply(&step, &mut x, &body, 0.002, 3).unwrap();
            assert!(moved >= 3, "{moved} vertices moved");
            // The sphere's top is now under the cloth: the cloth above it by the
            // margin, near enough (the faces are flat, the sphere is not).
            let cloth = BodySurface::new(&x, &sheet.faces).unwrap();
            let top = [0.15, 0.01, 0.15];
            let c = cloth.closest_point(top).unwrap();
            assert!(c.point[1] - top[1] > 0.0015, "{c:?}");
            // Corners far from the sphere stay.
            assert_eq!(x[0], sheet.positions[0]);
            assert_eq!(x[n - 1], sheet.positions[n - 1]);
        }
    }

    /// The garment vertices `contact` moves on the sheet at rest, in the step from the
    /// body `before` to `after` (2 mm margin), and where they end.
    fn moved(
        contact: &FaceContact,
        sheet: &TriMesh,
        before: &BodySurface,
        after: &BodySurface,
    ) -> (usize, Vec<[f64; 3]>) {
        let mut x = sheet.positions.clone();
        let step = contact.step(&sheet.positions, before, after).unwrap();
        let n = contact.apply(&step, &mut x, after, 0.002, 3).unwrap();
        (n, x)
    }

    #[test]
    fn hems_pinned_corners_and_far_bodies_are_left_alone() {
        let sheet = grid(4, 4, 0.1);
        let n = sheet.vertex_count();
        let contact = FaceContact::new(&sheet, &vec![false; n], &[]).unwrap();
        let unmoved = (0, sheet.positions.clone());
        // Beyond the hem at x = 0.3: the sphere rises above y = 0 only past x = 0.318,
        // where the body vertices' nearest cloth is the hem's edge, and lies 6.7 mm
        // under the hem, so nothing moves.
        let past_the_hem = sphere([0.38, -0.19, 0.15], 0.2);
        assert_eq!(
            moved(&contact, &sheet, &past_the_hem, &past_the_hem),
            unmoved
        );
        // Every corner pinned: nothing moves.
        let pinned = FaceContact::new(&sheet, &vec![true; n], &[]).unwrap();
        let body = sphere([0.15, -0.19, 0.15], 0.2);
        let under = sphere([0.15, -0.25, 0.15], 0.2);
        assert_eq!(moved(&pinned, &sheet, &under, &body), unmoved);
        // A body well under the cloth: nothing moves.
        assert_eq!(moved(&contact, &sheet, &under, &under), unmoved);
        // A hand held in front of the cloth, thinner than the reach: the cloth is
        // behind the back of the hand, as it was at the start of the step, so it did
        // not come through and nothing moves.
        let hand = sphere([0.15, 0.016, 0.15], 0.012);
        assert_eq!(moved(&contact, &sheet, &hand, &hand), unmoved);
        // The same hand come up through the cloth in the step: the cloth goes over it,
        // unless the hand's vertices are skipped.
        let hand_under = sphere([0.15, -0.016, 0.15], 0.012);
        let hands = vec![true; hand.positions().len()];
        let skipping = FaceContact::new(&sheet, &vec![false; n], &hands).unwrap();
        assert_eq!(moved(&skipping, &sheet, &hand_under, &hand), unmoved);
        assert!(moved(&contact, &sheet, &hand_under, &hand).0 > 0);
        // Bad input, named.
        let step = contact.step(&sheet.positions, &under, &under).unwrap();
        let mut x = sheet.positions.clone();
        let err = contact
            .apply(&step, &mut x[..n - 1], &under, 0.002, 3)
            .unwrap_err();
        assert!(err.to_string().contains("positions"), "{err}");
        let err = FaceContact::new(&sheet, &vec![false; n - 1], &[]).unwrap_err();
        assert!(err.to_string().contains("pinned flags"), "{err}");
    }
}
