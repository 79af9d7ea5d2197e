//! A garment's physics, and the incremental potential of one of its steps: the one place
//! both the simulator ([`crate::ClothSimulator`]) and a network's self-supervised loss
//! (HOOD, seed 004 eq. 5) build the potential from.
//!
//! [`ClothModel`] holds what does not change from step to step: the rest mesh, StVK
//! stretching with per-face parameters, dihedral bending with per-hinge stiffness, the
//! lumped vertex masses, the per-vertex friction coefficient and the [`SimOptions`].
//! [`ClothModel::step_potential`] adds what one step brings ([`StepInputs`]): the
//! inertial target and time step, and the body contacts found from the start-of-step
//! positions, and returns the [`IncrementalPotential`]
//!
//! `E(x) = stretching + bending + gravity + inertia(x̂, h) + collision(k_c) + friction
//! [+ buttons]`,
//!
//! every term with weight 1, in that order, the buttons only while the garment has some
//! ([`ClothModel::with_buttons`]); `k_c` is the collision term's stiffness. Minimising it
//! over the end-of-step positions is one implicit-Euler step (what the simulator does);
//! its value and gradient at a network's predicted positions are HOOD's loss.
//!
//! The stretching and bending terms share their data with the model (`Arc`), so building
//! a step's potential copies only the masses twice (gravity and inertia) and takes the
//! target and the contacts; the body queries are the only real work.
//!
//! Heterogeneous garments ([`ClothModel::from_vertex_materials`], a material per vertex,
//! e.g. a silk skirt sewn to a denim bodice) take each face's parameters as the mean of
//! its three vertices' and each hinge's stiffness as the mean of its edge's two vertices'
//! (see there).

use std::sync::Arc;

use rayon::prelude::*;
use weft_mesh::vec3::add;
use weft_mesh::{Hinge, Topology, TriMesh};

use crate::bending::Bending;
use crate::buttons::Buttons;
use crate::collision::CubicCollision;
use crate::contact::{BodyProximity, Clearance, Grip, Proximity, VertexContact};
use crate::error::{check_count, check_len, check_nonneg, check_vertex, SimError};
use crate::friction::{Friction, FrictionContact};
use crate::gravity::{lumped_masses, Gravity};
use crate::inertia::Inertia;
use crate::material::Material;
use crate::math::{finite3, v3};
use crate::membrane::RestFrames;
use crate::potential::{IncrementalPotential, Term};
use crate::solver::SimOptions;
use crate::stretch::{Stretch, StretchParams};

/// A garment's physics: rest shape, materials (per face, per hinge, per vertex), masses
/// and simulator options. Cheap to clone (the rest data is shared).
#[derive(Clone, Debug)]
pub struct ClothModel {
    rest: Arc<TriMesh>,
    hinges: Arc<[Hinge]>,
    hinge_stiffness: Arc<[f64]>,
    stretch: Stretch,
    bending: Bending,
    masses: Arc<[f64]>,
    friction: Arc<[f64]>,
    options: SimOptions,
    /// Button pairs held together, if the garment has any ([`ClothModel::with_buttons`]).
    buttons: Option<Buttons>,
}

/// What one step brings to the potential ([`ClothModel::step_potential`]).
#[derive(Clone, Copy)]
pub struct StepInputs<'a> {
    /// The start-of-step positions `x_t` (one per vertex, finite): contacts are found
    /// from them, and friction anchors start at them.
    pub start: &'a [[f64; 3]],
    /// The inertial target `x̂ = x_t + h v_t` (HOOD: `x_t + (x_t − x_{t−1})`, see
    /// [`crate::inertial_target`]); pinned vertices usually get their pin targets.
    pub target: &'a [[f64; 3]],
    /// The step length `h > 0`, s.
    pub dt: f64,
    /// Pinned vertices (one flag per vertex): they get no body contact.
    pub pinned: &'a [bool],
    /// The body at its end-of-step state; `None`: no body (no collision or friction
    /// contacts).
    pub body: Option<&'a (dyn BodyProximity + Sync)>,
    /// The cubic collision stiffness `k_c` of this step, J/m³ (HOOD ramps it during
    /// training); `None`: [`SimOptions::collision_stiffness`].
    pub collision_stiffness: Option<f64>,
}

impl std::fmt::Debug for StepInputs<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StepInputs")
            .field("vertices", &self.start.len())
            .field("dt", &self.dt)
            .field("body", &self.body.is_some())
            .field("collision_stiffness", &self.collision_stiffness)
            .finish_non_exhaustive()
    }
}

/// The body contacts of one step, found from the start-of-step positions.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepContacts {
    /// Cubic collision contacts: every free vertex within
    /// [`SimOptions::contact_radius`] of the body.
    pub collision: Vec<VertexContact>,
    /// HOOD friction contacts: every free vertex within
    /// [`SimOptions::friction_radius`] whose friction coefficient is positive.
    pub friction: Vec<FrictionContact>,
    /// One per `collision` contact, in its order: the anchor and friction coefficient
    /// that [`project_contacts`](crate::project_contacts) holds the vertex with.
    pub grips: Vec<Grip>,
}

impl ClothModel {
    /// A garment `rest` (its rest shape) made of one `material` everywhere.
    pub fn uniform(
        rest: &TriMesh,
        material: &Material,
        options: SimOptions,
    ) -> Result<Self, SimError> {
        material.validate()?;
        let hinges = hinges_of(rest)?;
        let maps = MaterialMaps::uniform(rest, hinges.len(), material);
        Self::build(Arc::new(rest.clone()), None, hinges.into(), maps, options)
    }

    /// A garment `rest` with one material per vertex (`materials[i]` for vertex `i`), for
    /// garments made of several fabrics. The rule, so that every element has one value:
    ///
    /// * a face takes the mean of its three vertices' Lamé `μ` and `λ` (from each
    ///   material's `E`, `ν` by [`Material::lame`]), density and thickness;
    /// * a hinge takes the mean of its edge's two vertices' bending stiffness;
    /// * a vertex keeps its own friction coefficient.
    ///
    /// So where a silk panel meets a denim one, the faces and hinges that have vertices
    /// of both (one band along the seam) blend the two, and every other element has its
    /// panel's material exactly. Means of equal values are those values exactly
    /// (`a + ((b − a) + (c − a))/3`), so a garment whose vertices all have the same
    /// material is exactly [`ClothModel::uniform`].
    pub fn from_vertex_materials(
        rest: &TriMesh,
        materials: &[Material],
        options: SimOptions,
    ) -> Result<Self, SimError> {
        validate_vertex_materials(rest.vertex_count(), materials)?;
        let hinges = hinges_of(rest)?;
        let maps = MaterialMaps::per_vertex(rest, &hinges, materials);
        Self::build(Arc::new(rest.clone()), None, hinges.into(), maps, options)
    }

    /// This garment made of `material` instead: shares the rest mesh, rest frames and
    /// hinges (no topology or rest-frame work), recomputes masses and per-element
    /// parameters. What a trainer that samples a material per sample calls.
    pub fn with_material(&self, material: &Material) -> Result<Self, SimError> {
        material.validate()?;
        let maps = MaterialMaps::uniform(&self.rest, self.hinges.len(), material);
        self.rebuilt(maps)
    }

    /// This garment with one material per vertex instead (the rule of
    /// [`ClothModel::from_vertex_materials`]); shares the rest data like
    /// [`ClothModel::with_material`].
    pub fn with_vertex_materials(&self, materials: &[Material]) -> Result<Self, SimError> {
        validate_vertex_materials(self.vertex_count(), materials)?;
        let maps = MaterialMaps::per_vertex(&self.rest, &self.hinges, materials);
        self.rebuilt(maps)
    }

    fn rebuilt(&self, maps: MaterialMaps) -> Result<Self, SimError> {
        let model = Self::build(
            Arc::clone(&self.rest),
            Some(&self.stretch),
            Arc::clone(&self.hinges),
            maps,
            self.options,
        )?;
        // The buttons' stiffness follows the new material.
        match &self.buttons {
            Some(b) => model.with_buttons(b.pairs()),
            None => Ok(model),
        }
    }

    /// This garment with `pairs` of vertices buttoned together (none: unbuttoned), each
    /// pair a zero-length spring in the potential ([`Buttons`]). A pair's stiffness is
    /// the cloth's own: Young's modulus times the thickness, `4μ(λ + μ)/(λ + 2μ) · t`
    /// (N/m; with the plane-stress λ this is `E t` exactly), averaged over the faces
    /// around its two vertices (33 N/m for HOOD's default material, 1 050 for cotton),
    /// so a button holds like the fabric it is sewn to. Errors on an index out of range
    /// or a vertex paired with itself.
    pub fn with_buttons(&self, pairs: &[[u32; 2]]) -> Result<Self, SimError> {
        if pairs.is_empty() {
            return Ok(self.without_buttons());
        }
        let n = self.vertex_count();
        crate::buttons::check_pairs(pairs, n)?;
        let (mut sum, mut count) = (vec![0.0; n], vec![0usize; n]);
        for (face, p) in self.rest.faces.iter().zip(self.stretch.params()) {
            let k = 4.0 * p.mu * (p.lambda + p.mu) / (p.lambda + 2.0 * p.mu) * p.thickness;
            for &v in face {
                sum[v as usize] += k;
                count[v as usize] += 1;
            }
        }
        let mut stiffness = Vec::with_capacity(pairs.len());
        for &[a, b] in pairs {
            let (a, b) = (a as usize, b as usize);
            let faces = count[a] + count[b];
            // A vertex on no face has no fabric to borrow from: `Buttons::new` refuses 0.
            stiffness.push(if faces == 0 {
                0.0
            } else {
                (sum[a] + sum[b]) / faces as f64
            });
        }
        Ok(ClothModel {
            buttons: Some(Buttons::new(n, pairs.to_vec(), stiffness)?),
            ..self.clone()
        })
    }

    /// This garment unbuttoned.
    pub fn without_buttons(&self) -> Self {
        ClothModel {
            buttons: None,
            ..self.clone()
        }
    }

    /// The button springs, if the garment is buttoned.
    pub fn buttons(&self) -> Option<&Buttons> {
        self.buttons.as_ref()
    }

    /// Builds the model; `frames_of`: a stretch term whose rest frames (of `rest`) to
    /// share, `None` to compute them.
    fn build(
        rest: Arc<TriMesh>,
        frames_of: Option<&Stretch>,
        hinges: Arc<[Hinge]>,
        maps: MaterialMaps,
        options: SimOptions,
    ) -> Result<Self, SimError> {
        validate_options(&options)?;
        let n = rest.vertex_count();
        let masses = lumped_masses(&rest, &maps.face_density)?;
        let stretch = match frames_of {
            Some(s) => s.with_params(maps.face_params)?,
            None => Stretch::new(RestFrames::from_rest_mesh(&rest)?, maps.face_params)?,
        };
        let bending = Bending::new(
            &rest,
            &hinges,
            &maps.hinge_stiffness,
            options.bending_scale,
            options.rest_angle,
        )?;
        check_count("friction", "vertex", n, maps.vertex_friction.len())?;
        for (i, &mu) in maps.vertex_friction.iter().enumerate() {
            check_nonneg(|| format!("vertex {i} friction"), mu, false)?;
        }
        Ok(ClothModel {
            rest,
            hinges,
            hinge_stiffness: maps.hinge_stiffness.into(),
            stretch,
            bending,
            masses: masses.into(),
            friction: maps.vertex_friction.into(),
            options,
            buttons: None,
        })
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.rest.vertex_count()
    }

    /// The rest mesh.
    pub fn rest(&self) -> &TriMesh {
        &self.rest
    }

    /// The stretching term (per-face parameters: [`Stretch::params`]).
    pub fn stretch(&self) -> &Stretch {
        &self.stretch
    }

    /// The bending term.
    pub fn bending(&self) -> &Bending {
        &self.bending
    }

    /// The hinges of the rest mesh, in the bending term's order.
    pub fn hinges(&self) -> &[Hinge] {
        &self.hinges
    }

    /// The bending stiffness `k_e` of each hinge (N·m).
    pub fn hinge_stiffness(&self) -> &[f64] {
        &self.hinge_stiffness
    }

    /// Lumped vertex masses (kg).
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// The garment–body friction coefficient of each vertex.
    pub fn vertex_friction(&self) -> &[f64] {
        &self.friction
    }

    /// The options.
    pub fn options(&self) -> &SimOptions {
        &self.options
    }

    /// The incremental potential of one step (module docs): the model's stretching,
    /// bending and gravity, inertia towards `step.target` with `step.dt`, the cubic
    /// collision penalty (stiffness `step.collision_stiffness`, threshold
    /// [`SimOptions::collision_eps`]) and HOOD friction over the contacts
    /// [`ClothModel::contacts`] finds from `step.start`.
    pub fn step_potential(&self, step: &StepInputs<'_>) -> Result<IncrementalPotential, SimError> {
        let contacts = self.contacts(step.start, step.pinned, step.body)?;
        self.potential_with_contacts(step, contacts)
    }

    /// [`ClothModel::step_potential`] over contacts found beforehand (`step.start`,
    /// `step.pinned` and `step.body` are not read again).
    pub fn potential_with_contacts(
        &self,
        step: &StepInputs<'_>,
        contacts: StepContacts,
    ) -> Result<IncrementalPotential, SimError> {
        let n = self.vertex_count();
        let o = &self.options;
        let stiffness = step.collision_stiffness.unwrap_or(o.collision_stiffness);
        let potential = IncrementalPotential::new(n)
            .with(1.0, Term::Stretch(self.stretch.clone()))?
            .with(1.0, Term::Bending(self.bending.clone()))?
            .with(
                1.0,
                Term::Gravity(Gravity::new(self.masses.to_vec(), o.gravity)?),
            )?
            .with(
                1.0,
                Term::Inertia(Inertia::new(
                    self.masses.to_vec(),
                    step.dt,
                    step.target.to_vec(),
                )?),
            )?
            .with(
                1.0,
                Term::Collision(CubicCollision::new(
                    n,
                    stiffness,
                    o.collision_eps,
                    contacts.collision,
                )?),
            )?
            .with(
                1.0,
                Term::Friction(Friction::new(n, o.friction_eps, contacts.friction)?),
            )?;
        match &self.buttons {
            Some(b) => potential.with(1.0, Term::Buttons(b.clone())),
            None => Ok(potential),
        }
    }

    /// The body contacts of the free vertices at `start` (HOOD: each vertex's closest
    /// body point, the body at its end-of-step state), queried in parallel: a collision
    /// contact within [`SimOptions::contact_radius`], and within
    /// [`SimOptions::friction_radius`] a HOOD friction contact
    /// ([`FrictionContact::hood`]: anchor `x_t + Δp_body` following the touched body
    /// point, [`BodyProximity::closest_moving`]; normal force `m g`; the vertex's
    /// friction coefficient, none where it is 0). Contacts are in vertex order.
    pub fn contacts(
        &self,
        start: &[[f64; 3]],
        pinned: &[bool],
        body: Option<&(dyn BodyProximity + Sync)>,
    ) -> Result<StepContacts, SimError> {
        self.contacts_with(start, pinned, body, &mut Clearance::default())
    }

    /// [`ClothModel::contacts`], skipping the vertices that `clearance` (the last
    /// search's record, which this one replaces) shows cannot be within reach of the
    /// body: the same contacts, fewer queries.
    pub fn contacts_with(
        &self,
        start: &[[f64; 3]],
        pinned: &[bool],
        body: Option<&(dyn BodyProximity + Sync)>,
        clearance: &mut Clearance,
    ) -> Result<StepContacts, SimError> {
        let n = self.vertex_count();
        check_len("start positions", n, start.len())?;
        check_len("pinned flags", n, pinned.len())?;
        if let Some(i) = start.iter().position(|p| !finite3(*p)) {
            return Err(SimError::InvalidVector {
                what: format!("start position of vertex {i}"),
                message: "not finite",
            });
        }
        let Some(body) = body else {
            clearance.record(Vec::new(), None);
            return Ok(StepContacts::default());
        };
        let o = &self.options;
        let g = v3(o.gravity).norm();
        let reach = o.contact_radius.max(o.friction_radius);
        let travelled = body.travelled();
        // Pinned vertices, and found contacts that are not finite, count as unknown.
        let searched: Vec<Proximity> = start
            .par_iter()
            .enumerate()
            .map(|(i, &p)| {
                if pinned[i] {
                    return Proximity::Clear(0.0);
                }
                if let Some(bound) = clearance.bound(i, p, travelled) {
                    if bound > reach {
                        return Proximity::Clear(bound);
                    }
                }
                match body.proximity(p) {
                    Proximity::Contact(c, m)
                        if !(finite3(c.point) && finite3(c.normal) && finite3(m)) =>
                    {
                        Proximity::Clear(0.0)
                    }
                    found => found,
                }
            })
            .collect();
        clearance.record(
            start
                .iter()
                .zip(&searched)
                .map(|(&p, s)| match s {
                    Proximity::Clear(d) => (p, *d),
                    Proximity::Contact(..) => (p, 0.0),
                })
                .collect(),
            travelled,
        );
        let found = searched
            .into_iter()
            .enumerate()
            .filter_map(|(i, s)| match s {
                Proximity::Contact(c, m) => Some((i as u32, c, m)),
                Proximity::Clear(_) => None,
            });
        let mut out = StepContacts::default();
        for (i, c, m) in found {
            let p = start[i as usize];
            let d = c.signed_distance(p);
            let mu = self.friction[i as usize];
            if d < o.contact_radius {
                out.collision.push(VertexContact {
                    vertex: i,
                    contact: c,
                });
                out.grips.push(Grip {
                    anchor: add(p, m),
                    mu,
                });
            }
            if d < o.friction_radius && mu > 0.0 {
                let before: [f64; 3] = std::array::from_fn(|k| c.point[k] - m[k]);
                out.friction.push(FrictionContact::hood(
                    i,
                    p,
                    before,
                    c.point,
                    c.normal,
                    c.normal,
                    self.masses[i as usize],
                    g,
                    mu,
                ));
            }
        }
        Ok(out)
    }
}

/// Per-element material values of a garment.
struct MaterialMaps {
    face_params: Vec<StretchParams>,
    face_density: Vec<f64>,
    hinge_stiffness: Vec<f64>,
    vertex_friction: Vec<f64>,
}

impl MaterialMaps {
    fn uniform(rest: &TriMesh, hinge_count: usize, m: &Material) -> Self {
        MaterialMaps {
            face_params: vec![m.stretch_params(); rest.face_count()],
            face_density: vec![m.density; rest.face_count()],
            hinge_stiffness: vec![m.bending_stiffness; hinge_count],
            vertex_friction: vec![m.friction; rest.vertex_count()],
        }
    }

    /// The rule of [`ClothModel::from_vertex_materials`]; `rest`'s faces and `hinges`
    /// are checked, `materials` has one entry per vertex.
    fn per_vertex(rest: &TriMesh, hinges: &[Hinge], materials: &[Material]) -> Self {
        let lame: Vec<(f64, f64)> = materials.iter().map(Material::lame).collect();
        let mean = |f: &[u32; 3], value: &dyn Fn(usize) -> f64| {
            let [a, b, c] = f.map(|v| value(v as usize));
            a + ((b - a) + (c - a)) / 3.0
        };
        MaterialMaps {
            face_params: rest
                .faces
                .iter()
                .map(|f| StretchParams {
                    mu: mean(f, &|v| lame[v].0),
                    lambda: mean(f, &|v| lame[v].1),
                    thickness: mean(f, &|v| materials[v].thickness),
                })
                .collect(),
            face_density: rest
                .faces
                .iter()
                .map(|f| mean(f, &|v| materials[v].density))
                .collect(),
            hinge_stiffness: hinges
                .iter()
                .map(|h| {
                    let [a, b] = h.edge.map(|v| materials[v as usize].bending_stiffness);
                    0.5 * (a + b)
                })
                .collect(),
            vertex_friction: materials.iter().map(|m| m.friction).collect(),
        }
    }
}

/// One valid material per vertex.
fn validate_vertex_materials(vertex_count: usize, materials: &[Material]) -> Result<(), SimError> {
    check_count("materials", "vertex", vertex_count, materials.len())?;
    for (i, m) in materials.iter().enumerate() {
        m.validate().map_err(|e| match e {
            SimError::InvalidParameter {
                what,
                value,
                expected,
            } => SimError::InvalidParameter {
                what: format!("vertex {i}: {what}"),
                value,
                expected,
            },
            e => e,
        })?;
    }
    Ok(())
}

/// The options' contact and gravity values, checked as the terms would check them.
fn validate_options(o: &SimOptions) -> Result<(), SimError> {
    check_nonneg(
        || "collision stiffness".into(),
        o.collision_stiffness,
        false,
    )?;
    check_nonneg(|| "collision threshold".into(), o.collision_eps, false)?;
    check_nonneg(|| "contact radius".into(), o.contact_radius, false)?;
    check_nonneg(|| "friction radius".into(), o.friction_radius, false)?;
    check_nonneg(|| "friction slip length".into(), o.friction_eps, true)?;
    if !finite3(o.gravity) {
        return Err(SimError::InvalidVector {
            what: "gravity".into(),
            message: "not finite",
        });
    }
    Ok(())
}

/// The hinges of `rest`, after checking its faces' vertex indices (the topology
/// assumes them valid).
fn hinges_of(rest: &TriMesh) -> Result<Vec<Hinge>, SimError> {
    for (fi, f) in rest.faces.iter().enumerate() {
        for &v in f {
            check_vertex("face", fi, v, rest.vertex_count())?;
        }
    }
    Ok(Topology::new(rest).hinges(rest))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{Plane, Sphere};
    use crate::energy::Energy;
    use crate::inertia::inertial_target;
    use crate::solver::ClothSimulator;
    use weft_mesh::primitives::grid;
    use weft_mesh::rng::SplitMix64;

    /// `x` moved by up to `s` per coordinate.
    fn jiggled(x: &[[f64; 3]], rng: &mut SplitMix64, s: f64) -> Vec<[f64; 3]> {
        x.iter()
            .map(|p| p.map(|c| c + rng.uniform(-s, s)))
            .collect()
    }

    fn relative_gap(a: f64, b: f64) -> f64 {
        (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
    }

    /// Value and gradient of two energies at `x` agree to `rtol` (gradient: relative to
    /// its largest entry).
    fn assert_same_energy(a: &dyn Energy, b: &dyn Energy, x: &[[f64; 3]], rtol: f64) {
        let (ga, gb) = (
            crate::energy::gradient_of(a, x).unwrap().1,
            crate::energy::gradient_of(b, x).unwrap().1,
        );
        let (va, vb) = (a.value(x).unwrap(), b.value(x).unwrap());
        assert!(relative_gap(va, vb) <= rtol, "value {va} vs {vb}");
        let scale = ga.iter().flatten().fold(0.0f64, |m, c| m.max(c.abs()));
        assert!(scale > 0.0);
        for (p, q) in ga.iter().zip(&gb) {
            for k in 0..3 {
                assert!((p[k] - q[k]).abs() <= rtol * scale, "{p:?} vs {q:?}");
            }
        }
    }

    /// The builder's potential is the sum of the six terms assembled by hand from the
    /// material, the options and contacts found by hand (a sphere the cloth dips into
    /// at its centre; a floor under all of it, with friction everywhere), with the
    /// default and a ramped collision stiffness.
    #[test]
    fn step_potential_is_the_hand_assembled_potential() {
        let rest = grid(6, 6, 0.05);
        let n = rest.vertex_count();
        let material = Material::hood();
        let options = SimOptions::default();
        let model = ClothModel::uniform(&rest, &material, options).unwrap();
        let mut rng = SplitMix64::new(3);
        let sphere = Sphere {
            center: [0.125, -0.199, 0.125],
            radius: 0.2,
        };
        let floor = Plane {
            point: [0.0, -0.0015, 0.0],
            normal: [0.0, 1.0, 0.0],
        };
        let bodies: [&(dyn BodyProximity + Sync); 2] = [&sphere, &floor];
        let start = jiggled(&rest.positions, &mut rng, 2e-4);
        let previous = jiggled(&start, &mut rng, 3e-3);
        let target = inertial_target(&start, &previous, 1.0).unwrap();
        let mut pinned = vec![false; n];
        pinned[0] = true;
        let dt = 1.0 / 30.0;
        for body in bodies {
            for stiffness in [None, Some(5e3)] {
                let built = model
                    .step_potential(&StepInputs {
                        start: &start,
                        target: &target,
                        dt,
                        pinned: &pinned,
                        body: Some(body),
                        collision_stiffness: stiffness,
                    })
                    .unwrap();
                // By hand.
                let masses =
                    lumped_masses(&rest, &vec![material.density; rest.face_count()]).unwrap();
                let mut contacts = Vec::new();
                let mut friction = Vec::new();
                for i in (0..n).filter(|&i| !pinned[i]) {
                    let c = body.closest(start[i]).unwrap();
                    let d = c.signed_distance(start[i]);
                    if d < options.contact_radius {
                        contacts.push(VertexContact {
                            vertex: i as u32,
                            contact: c,
                        });
                    }
                    if d < options.friction_radius {
                        friction.push(FrictionContact {
                            vertex: i as u32,
                            anchor: start[i],
                            normal: c.normal,
                            normal_force: masses[i] * 9.81,
                            mu: material.friction,
                        });
                    }
                }
                assert!(!contacts.is_empty() && !friction.is_empty());
                let hand = IncrementalPotential::new(n)
                    .with(
                        1.0,
                        Term::Stretch(Stretch::uniform(&rest, material.stretch_params()).unwrap()),
                    )
                    .unwrap()
                    .with(
                        1.0,
                        Term::Bending(
                            Bending::uniform(
                                &rest,
                                material.bending_stiffness,
                                options.bending_scale,
                                options.rest_angle,
                            )
                            .unwrap(),
                        ),
                    )
                    .unwrap()
                    .with(
                        1.0,
                        Term::Gravity(Gravity::new(masses.clone(), options.gravity).unwrap()),
                    )
                    .unwrap()
                    .with(
                        1.0,
                        Term::Inertia(Inertia::new(masses.clone(), dt, target.clone()).unwrap()),
                    )
                    .unwrap()
                    .with(
                        1.0,
                        Term::Collision(
                            CubicCollision::new(
                                n,
                                stiffness.unwrap_or(options.collision_stiffness),
                                options.collision_eps,
                                contacts.clone(),
                            )
                            .unwrap(),
                        ),
                    )
                    .unwrap()
                    .with(
                        1.0,
                        Term::Friction(
                            Friction::new(n, options.friction_eps, friction.clone()).unwrap(),
                        ),
                    )
                    .unwrap();
                assert_eq!(
                    built.collision().unwrap().contacts(),
                    hand.collision().unwrap().contacts()
                );
                let (fb, fh) = (
                    built.friction().unwrap().contacts(),
                    hand.friction().unwrap().contacts(),
                );
                assert_eq!(fb.len(), fh.len());
                for (b, h) in fb.iter().zip(fh) {
                    // The body is at rest: the anchor is the start, to rounding.
                    let moved = (0..3).map(|k| (b.anchor[k] - h.anchor[k]).abs());
                    assert!(moved.fold(0.0, f64::max) < 1e-15, "{b:?} {h:?}");
                    assert_eq!((b.vertex, b.normal, b.mu), (h.vertex, h.normal, h.mu));
                    assert!(relative_gap(b.normal_force, h.normal_force) < 1e-14);
                }
                // At the end of a step that slides and dips: every term is active.
                let mut x = jiggled(&target, &mut rng, 2e-3);
                for p in &mut x {
                    p[1] -= 3e-3;
                }
                for t in built.breakdown(&x).unwrap() {
                    assert!(t.2 != 0.0, "{t:?}");
                }
                assert_same_energy(&built, &hand, &x, 1e-12);
                // The collision term on its own: its stiffness is the one asked for.
                assert_same_energy(
                    built.collision().unwrap(),
                    hand.collision().unwrap(),
                    &x,
                    1e-12,
                );
            }
        }
    }

    /// Every vertex of the same material is exactly the uniform model (per element, and
    /// the step potential bit for bit); so is another material's model given this
    /// material afterwards.
    #[test]
    fn equal_vertex_materials_are_exactly_the_uniform_model() {
        let mut rest = grid(7, 5, 0.04);
        let mut rng = SplitMix64::new(11);
        rest.positions = jiggled(&rest.positions, &mut rng, 5e-3);
        let options = SimOptions {
            rest_angle: crate::RestAngle::FromRest,
            ..SimOptions::default()
        };
        // Thirds of odd values, so the means are rounded if not taken with care.
        let material = Material {
            density: 0.1 + 1.0 / 3.0,
            young_modulus: 1.0e5 / 3.0,
            poisson_ratio: 0.1 + 0.7 / 3.0,
            thickness: 7e-4 / 3.0,
            bending_stiffness: 1e-4 / 3.0,
            ..Material::denim()
        };
        let uniform = ClothModel::uniform(&rest, &material, options).unwrap();
        let per_vertex =
            ClothModel::from_vertex_materials(&rest, &vec![material; rest.vertex_count()], options)
                .unwrap();
        let rematerialled = ClothModel::uniform(&rest, &Material::silk(), options)
            .unwrap()
            .with_material(&material)
            .unwrap();
        let sphere = Sphere {
            center: [0.12, -0.2, 0.08],
            radius: 0.2,
        };
        let x = jiggled(&rest.positions, &mut rng, 1e-2);
        let pinned = vec![false; rest.vertex_count()];
        let step = StepInputs {
            start: &rest.positions,
            target: &x,
            dt: 0.01,
            pinned: &pinned,
            body: Some(&sphere),
            collision_stiffness: None,
        };
        let reference = uniform.step_potential(&step).unwrap();
        let (v0, g0) = reference.gradient(&x).unwrap();
        assert!(reference.collision().unwrap().contacts().len() > 3);
        for other in [&per_vertex, &rematerialled] {
            assert_eq!(other.stretch().params(), uniform.stretch().params());
            assert_eq!(other.masses(), uniform.masses());
            assert_eq!(other.hinge_stiffness(), uniform.hinge_stiffness());
            assert_eq!(other.vertex_friction(), uniform.vertex_friction());
            assert_eq!(
                other.bending().value(&x).unwrap().to_bits(),
                uniform.bending().value(&x).unwrap().to_bits()
            );
            let (v, g) = other.step_potential(&step).unwrap().gradient(&x).unwrap();
            assert_eq!(v.to_bits(), v0.to_bits());
            assert_eq!(g, g0);
        }
        let thirds = Material::from_lame("custom", 0.3, 2e4 / 3.0, 1e4 / 3.0, 1e-3 / 3.0, 0.0, 0.5);
        let (a, b) = (
            ClothModel::uniform(&rest, &thirds, options).unwrap(),
            per_vertex
                .with_vertex_materials(&vec![thirds; rest.vertex_count()])
                .unwrap(),
        );
        assert_eq!(a.stretch().params(), b.stretch().params());
        assert_eq!(a.masses(), b.masses());
    }

    /// A grid whose near half is silk and far half denim: faces and hinges inside each
    /// half have that fabric's values exactly, the band of faces across the seam the
    /// mean of its vertices', vertices keep their own friction; the simulator runs it.
    #[test]
    fn half_silk_half_denim_differs_where_expected() {
        let (nx, nz) = (6, 6);
        let rest = grid(nx, nz, 0.05);
        let (silk, denim) = (Material::silk(), Material::denim());
        let is_silk = |v: u32| (v as usize / nx) < nz / 2;
        let materials: Vec<Material> = (0..rest.vertex_count() as u32)
            .map(|v| if is_silk(v) { silk } else { denim })
            .collect();
        let model =
            ClothModel::from_vertex_materials(&rest, &materials, SimOptions::default()).unwrap();
        let (s, d) = (silk.stretch_params(), denim.stretch_params());
        let mut mixed = 0;
        for (f, p) in rest.faces.iter().zip(model.stretch().params()) {
            let silk_corners = f.iter().filter(|&&v| is_silk(v)).count();
            match silk_corners {
                3 => assert_eq!(*p, s),
                0 => assert_eq!(*p, d),
                k => {
                    mixed += 1;
                    let w = k as f64 / 3.0;
                    let want = |a: f64, b: f64| w * a + (1.0 - w) * b;
                    assert!(relative_gap(p.mu, want(s.mu, d.mu)) < 1e-14, "{p:?}");
                    assert!(relative_gap(p.lambda, want(s.lambda, d.lambda)) < 1e-14);
                    assert!(relative_gap(p.thickness, want(s.thickness, d.thickness)) < 1e-14);
                    assert!(p.mu > s.mu && p.mu < d.mu);
                }
            }
        }
        assert_eq!(mixed, 2 * (nx - 1), "one band of faces across the seam");
        let mut seam_hinges = 0;
        for (h, &k) in model.hinges().iter().zip(model.hinge_stiffness()) {
            let want = match h.edge.map(is_silk) {
                [true, true] => silk.bending_stiffness,
                [false, false] => denim.bending_stiffness,
                _ => {
                    seam_hinges += 1;
                    0.5 * (silk.bending_stiffness + denim.bending_stiffness)
                }
            };
            assert_eq!(k, want, "{h:?}");
        }
        assert!(seam_hinges > 0);
        for (v, &mu) in model.vertex_friction().iter().enumerate() {
            assert_eq!(mu, materials[v].friction);
        }
        // An interior vertex of each half has six faces of its fabric around it (area
        // h²/2 each, a third to the vertex).
        let interior_mass = |rho: f64| rho * 6.0 * 0.5 * 0.05 * 0.05 / 3.0;
        let (vs, vd) = (nx + 2, (nz - 2) * nx + 2);
        assert!(relative_gap(model.masses()[vs], interior_mass(silk.density)) < 1e-14);
        assert!(relative_gap(model.masses()[vd], interior_mass(denim.density)) < 1e-14);
        // It simulates: pinned along the silk edge, it hangs without diverging.
        let mut sim = ClothSimulator::from_model(model).unwrap();
        sim.pin(&(0..nx as u32).collect::<Vec<_>>()).unwrap();
        for _ in 0..10 {
            let r = sim.step(1.0 / 30.0, None).unwrap();
            for w in r.newton.energies.windows(2) {
                assert!(w[1] <= w[0] + 1e-12 * w[0].abs().max(1.0));
            }
        }
        assert!(sim.positions()[rest.vertex_count() - 1][1] < -0.05);
    }

    #[test]
    fn bad_input_is_an_error() {
        let rest = grid(3, 3, 0.1);
        let n = rest.vertex_count();
        let o = SimOptions::default();
        let cotton = Material::cotton();
        assert!(ClothModel::from_vertex_materials(&rest, &[cotton; 2], o).is_err());
        let mut materials = vec![cotton; n];
        materials[4].poisson_ratio = 1.2;
        let e = ClothModel::from_vertex_materials(&rest, &materials, o)
            .unwrap_err()
            .to_string();
        assert!(e.contains("vertex 4"), "{e}");
        let bad = SimOptions {
            friction_eps: 0.0,
            ..o
        };
        assert!(ClothModel::uniform(&rest, &cotton, bad).is_err());
        let model = ClothModel::uniform(&rest, &cotton, o).unwrap();
        assert!(model.with_vertex_materials(&materials).is_err());
        let x = rest.positions.clone();
        let pinned = vec![false; n];
        let ok = StepInputs {
            start: &x,
            target: &x,
            dt: 0.1,
            pinned: &pinned,
            body: None,
            collision_stiffness: None,
        };
        assert!(model.step_potential(&ok).is_ok());
        let mut far = x.clone();
        far[2][1] = f64::NAN;
        for step in [
            StepInputs { dt: 0.0, ..ok },
            StepInputs {
                pinned: &pinned[1..],
                ..ok
            },
            StepInputs {
                target: &x[1..],
                ..ok
            },
            StepInputs { start: &far, ..ok },
            StepInputs {
                collision_stiffness: Some(-1.0),
                ..ok
            },
        ] {
            assert!(model.step_potential(&step).is_err(), "{step:?}");
        }
    }
}
