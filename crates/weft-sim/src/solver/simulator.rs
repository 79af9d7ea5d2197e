//! The time loop of the cloth simulator: one implicit-Euler step per call, minimising
//! the incremental potential (seed 004 eq. 5) with [`super::minimize`].
//!
//! Per step: the inertial target `x̂ = x_t + h v_t`; the step's potential from the
//! garment's [`ClothModel`] ([`ClothModel::step_potential`], the same potential a
//! network's loss uses), with body contacts from the start-of-step positions (HOOD: the
//! closest body point of each garment vertex at the start of the step, with the body at
//! its end-of-step state), each vertex within `contact_radius` of the body getting a
//! cubic collision contact and, within HOOD's friction radius, a friction contact with
//! HOOD's lagged normal force `m g`; pinned vertices held at their targets; the new
//! velocity `(x_{t+1} − x_t)/h`. A step that produces non-finite positions or an absurd
//! speed is reported as [`SimError::Diverged`] and leaves the state as it was.

use weft_mesh::TriMesh;

use crate::bending::{BendingScale, RestAngle};
use crate::cloth::{ClothModel, StepInputs};
use crate::collision::{HOOD_COLLISION_EPS, HOOD_COLLISION_STIFFNESS};
use crate::contact::{BodyProximity, Clearance};
use crate::error::{check_len, check_nonneg, check_vertex, SimError};
use crate::friction::{DEFAULT_FRICTION_EPS, HOOD_FRICTION_RADIUS};
use crate::gravity::STANDARD_GRAVITY;
use crate::material::Material;
use crate::math::{finite3, v3};
use crate::potential::IncrementalPotential;
use crate::solver::newton::{minimize, NewtonOptions, NewtonReport};
use crate::sparse::BlockCsr;

/// Simulator parameters (defaults: HOOD's contact parameters, standard gravity). A TOML
/// table sets any of them; the others keep the defaults stated on each field.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimOptions {
    /// Gravitational acceleration, m/s². Default: [`STANDARD_GRAVITY`], `[0, -9.81, 0]`.
    pub gravity: [f64; 3],
    /// Cubic collision stiffness `k_c`, J/m³ (energy `k_c (ε − d)³` per vertex).
    /// Default: [`HOOD_COLLISION_STIFFNESS`], 5·10⁵.
    pub collision_stiffness: f64,
    /// Collision threshold ε, m. Default: [`HOOD_COLLISION_EPS`], 2 mm.
    pub collision_eps: f64,
    /// Vertices closer than this to the body get a collision contact, m. Default: 2 cm.
    pub contact_radius: f64,
    /// Vertices closer than this get a friction contact, m. Default:
    /// [`HOOD_FRICTION_RADIUS`], 3 mm.
    pub friction_radius: f64,
    /// Friction mollifier slip length, m. Default: [`DEFAULT_FRICTION_EPS`], 0.1 mm.
    pub friction_eps: f64,
    /// Bending weight form. Default: [`BendingScale::Hood`].
    pub bending_scale: BendingScale,
    /// Bending rest angle. Default: [`RestAngle::Flat`].
    pub rest_angle: RestAngle,
    /// Newton parameters (a `[newton]` table). Default: [`NewtonOptions::default`].
    pub newton: NewtonOptions,
    /// A step whose largest vertex speed exceeds this (m/s) is reported as diverged.
    /// Default: 100 m/s.
    pub max_speed: f64,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            gravity: STANDARD_GRAVITY,
            collision_stiffness: HOOD_COLLISION_STIFFNESS,
            collision_eps: HOOD_COLLISION_EPS,
            contact_radius: 2e-2,
            friction_radius: HOOD_FRICTION_RADIUS,
            friction_eps: DEFAULT_FRICTION_EPS,
            bending_scale: BendingScale::Hood,
            rest_angle: RestAngle::Flat,
            newton: NewtonOptions::default(),
            max_speed: 100.0,
        }
    }
}

/// What one step did.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    /// The Newton solve.
    pub newton: NewtonReport,
    /// Collision contacts used.
    pub contacts: usize,
    /// Friction contacts used.
    pub friction_contacts: usize,
    /// Largest vertex speed after the step, m/s.
    pub max_speed: f64,
}

/// A garment simulated with implicit Euler. Its physics is a [`ClothModel`], and each
/// step minimises the model's [`ClothModel::step_potential`].
#[derive(Debug)]
pub struct ClothSimulator {
    model: ClothModel,
    potential: IncrementalPotential,
    hess: BlockCsr,
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    pinned: Vec<bool>,
    pin_targets: Vec<[f64; 3]>,
    /// What the last step's contact search learned about the vertices far from the
    /// body, so this step's can skip them.
    clearance: Clearance,
}

impl ClothSimulator {
    /// A simulator for the garment `rest` (rest shape = initial state, at rest) made of
    /// `material`.
    pub fn new(rest: &TriMesh, material: &Material, options: SimOptions) -> Result<Self, SimError> {
        Self::from_model(ClothModel::uniform(rest, material, options)?)
    }

    /// A simulator for the garment of `model` (e.g. one material per vertex), starting
    /// at its rest shape, at rest.
    pub fn from_model(model: ClothModel) -> Result<Self, SimError> {
        let n = model.vertex_count();
        let x = model.rest().positions.clone();
        let pinned = vec![false; n];
        let potential = model.step_potential(&StepInputs {
            start: &x,
            target: &x,
            dt: 1.0 / 30.0,
            pinned: &pinned,
            body: None,
            collision_stiffness: None,
        })?;
        let hess = potential.hessian_pattern(model.options().newton.hessian);
        Ok(ClothSimulator {
            model,
            potential,
            hess,
            pin_targets: x.clone(),
            x,
            v: vec![[0.0; 3]; n],
            pinned,
            clearance: Clearance::default(),
        })
    }

    /// The garment's physics.
    pub fn model(&self) -> &ClothModel {
        &self.model
    }

    /// Current positions.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.x
    }

    /// Current velocities.
    pub fn velocities(&self) -> &[[f64; 3]] {
        &self.v
    }

    /// Lumped vertex masses.
    pub fn masses(&self) -> &[f64] {
        self.model.masses()
    }

    /// The incremental potential (with the last step's inertial target and contacts).
    pub fn potential(&self) -> &IncrementalPotential {
        &self.potential
    }

    /// Replaces positions and velocities.
    pub fn set_state(&mut self, x: Vec<[f64; 3]>, v: Vec<[f64; 3]>) -> Result<(), SimError> {
        check_len("positions", self.x.len(), x.len())?;
        check_len("velocities", self.x.len(), v.len())?;
        if let Some(i) = x.iter().chain(&v).position(|p| !finite3(*p)) {
            return Err(SimError::InvalidVector {
                what: format!("state entry {i}"),
                message: "not finite",
            });
        }
        self.x = x;
        self.v = v;
        Ok(())
    }

    /// Pins `vertices` at their current positions.
    pub fn pin(&mut self, vertices: &[u32]) -> Result<(), SimError> {
        for (i, &v) in vertices.iter().enumerate() {
            check_vertex("pin", i, v, self.x.len())?;
        }
        for &v in vertices {
            self.pinned[v as usize] = true;
            self.pin_targets[v as usize] = self.x[v as usize];
            self.v[v as usize] = [0.0; 3];
        }
        Ok(())
    }

    /// Moves the target of a pinned vertex (it reaches it at the end of the next step).
    pub fn move_pin(&mut self, vertex: u32, target: [f64; 3]) -> Result<(), SimError> {
        check_vertex("pin", 0, vertex, self.x.len())?;
        if !finite3(target) {
            return Err(SimError::InvalidVector {
                what: format!("pin target of vertex {vertex}"),
                message: "not finite",
            });
        }
        self.pinned[vertex as usize] = true;
        self.pin_targets[vertex as usize] = target;
        Ok(())
    }

    /// Unbuttons the garment from the next step on (seed 004 Fig. 4). The Hessian's
    /// pattern keeps the pairs' blocks, which are zero from then on.
    pub fn unbutton(&mut self) {
        self.model = self.model.without_buttons();
    }

    /// Advances by `dt` seconds against `body` (at its end-of-step state; `None`: no body).
    pub fn step(
        &mut self,
        dt: f64,
        body: Option<&(dyn BodyProximity + Sync)>,
    ) -> Result<StepReport, SimError> {
        let newton = self.model.options().newton;
        self.advance(dt, body, None, &newton)
    }

    /// Advances by `dt` like [`ClothSimulator::step`], with Newton started from
    /// `start` (a predicted end of the step, such as a learned model's) instead of the
    /// inertial target, and at most `max_iterations` iterations: a few iterations
    /// refine a good prediction towards the step's minimiser at a fraction of a full
    /// solve. Pinned vertices start at their targets.
    pub fn step_from(
        &mut self,
        dt: f64,
        body: Option<&(dyn BodyProximity + Sync)>,
        start: &[[f64; 3]],
        max_iterations: usize,
    ) -> Result<StepReport, SimError> {
        check_len("start positions", self.x.len(), start.len())?;
        let newton = NewtonOptions {
            max_iterations,
            ..self.model.options().newton
        };
        self.advance(dt, body, Some(start), &newton)
    }

    fn advance(
        &mut self,
        dt: f64,
        body: Option<&(dyn BodyProximity + Sync)>,
        start: Option<&[[f64; 3]]>,
        newton: &NewtonOptions,
    ) -> Result<StepReport, SimError> {
        check_nonneg(|| "time step".into(), dt, true)?;
        let n = self.x.len();
        let target: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                if self.pinned[i] {
                    self.pin_targets[i]
                } else {
                    std::array::from_fn(|k| self.x[i][k] + dt * self.v[i][k])
                }
            })
            .collect();
        let contacts =
            self.model
                .contacts_with(&self.x, &self.pinned, body, &mut self.clearance)?;
        self.potential = self.model.potential_with_contacts(
            &StepInputs {
                start: &self.x,
                target: &target,
                dt,
                pinned: &self.pinned,
                body,
                collision_stiffness: None,
            },
            contacts,
        )?;
        let nc = self.potential.collision().map_or(0, |c| c.contacts().len());
        let nf = self.potential.friction().map_or(0, |f| f.contacts().len());
        // Start from the inertial target (or the given start); where it lies closer to
        // the body than ε (along the contact's normal), from its projection to ε
        // instead. Keeping the tangential part keeps the start free of the stretch a
        // jump between contact and free vertices would cause.
        let mut x = match start {
            Some(start) => (0..n)
                .map(|i| if self.pinned[i] { target[i] } else { start[i] })
                .collect(),
            None => target,
        };
        if let Some(c) = self.potential.collision() {
            let eps = c.eps();
            for vc in c.contacts() {
                let i = vc.vertex as usize;
                let d = vc.contact.signed_distance(x[i]);
                if d < eps {
                    x[i] = std::array::from_fn(|k| x[i][k] + (eps - d) * vc.contact.normal[k]);
                }
            }
        }
        let report = minimize(
            &self.potential,
            &mut x,
            &self.pinned,
            &mut self.hess,
            newton,
        )?;
        let mut max_speed: f64 = 0.0;
        let mut v = vec![[0.0; 3]; n];
        for i in 0..n {
            if !finite3(x[i]) {
                return Err(SimError::Diverged {
                    message: format!("vertex {i} has non-finite position"),
                });
            }
            v[i] = std::array::from_fn(|k| (x[i][k] - self.x[i][k]) / dt);
            max_speed = max_speed.max(v3(v[i]).norm());
        }
        let limit = self.model.options().max_speed;
        if max_speed > limit {
            return Err(SimError::Diverged {
                message: format!(
                    "largest vertex speed {max_speed:.3e} m/s exceeds {limit:.3e} m/s"
                ),
            });
        }
        self.x = x;
        self.v = v;
        Ok(StepReport {
            newton: report,
            contacts: nc,
            friction_contacts: nf,
            max_speed,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::Sphere;
    use weft_mesh::primitives::grid;
    use weft_mesh::TriMesh;

    /// A 0.5 m square of cotton, pinned at the two corners of one edge, falls from
    /// horizontal and swings down: every Newton iteration decreases the potential, the
    /// state stays finite and bounded, and the swing dies out (implicit Euler's numerical
    /// damping is the only damping: the pendulum mode, about 1 Hz, loses roughly 1.5%
    /// of its amplitude per 1/30 s step).
    #[test]
    fn hanging_cloth_falls_and_settles() {
        let (nx, h) = (11, 0.05);
        let rest = grid(nx, nx, h);
        let mut sim =
            ClothSimulator::new(&rest, &Material::cotton(), SimOptions::default()).unwrap();
        sim.pin(&[0, (nx - 1) as u32]).unwrap();
        let dt = 1.0 / 30.0;
        let mut speeds = Vec::new();
        for frame in 0..90 {
            let r = sim.step(dt, None).unwrap();
            let e = &r.newton.energies;
            for w in e.windows(2) {
                assert!(
                    w[1] <= w[0] + 1e-12 * w[0].abs().max(1.0),
                    "frame {frame}: energy rose {w:?}"
                );
            }
            assert!(r.newton.iterations <= 50);
            speeds.push(r.max_speed);
            if std::env::var_os("WEFT_SIM_TRACE").is_some() {
                eprintln!(
                    "frame {frame}: iters {} converged {} cg {} speed {:.4} E {:.6e} grad {:.2e}",
                    r.newton.iterations,
                    r.newton.converged,
                    r.newton.cg_iterations,
                    r.max_speed,
                    e.last().copied().unwrap_or(0.0),
                    r.newton.gradient_max
                );
            }
        }
        let x = sim.positions();
        assert!(x.iter().flatten().all(|c| c.is_finite() && c.abs() < 2.0));
        // Pins held.
        assert_eq!(x[0], rest.positions[0]);
        assert_eq!(x[nx - 1], rest.positions[nx - 1]);
        // It hangs: the free edge is about a cloth length below the pins.
        let bottom = x[nx * nx - nx / 2 - 1][1];
        assert!(bottom < -0.3 && bottom > -0.7, "{bottom}");
        // And settles: the swing in the third second is well below the first.
        let window_max = |r: std::ops::Range<usize>| speeds[r].iter().copied().fold(0.0, f64::max);
        let (first, third) = (window_max(0..30), window_max(60..90));
        assert!(
            third < 0.5 * first,
            "max speed {first} in the first second, {third} in the third"
        );
        // Edges are not much stretched under its own weight.
        let strain = rest
            .edges()
            .iter()
            .map(|&[a, b]| {
                let l0 = (v3(rest.positions[a as usize]) - v3(rest.positions[b as usize])).norm();
                let l = (v3(x[a as usize]) - v3(x[b as usize])).norm();
                (l / l0 - 1.0).abs()
            })
            .fold(0.0, f64::max);
        assert!(strain < 0.05, "max edge strain {strain}");
    }

    /// The hanging square of the test above with its two free corners buttoned together:
    /// they close up as it falls; unbuttoned after a second, they part again, while the
    /// same square never buttoned keeps them a cloth width apart throughout.
    #[test]
    fn buttons_hold_two_corners_together_until_unbuttoned() {
        let (nx, h) = (11, 0.05);
        let rest = grid(nx, nx, h);
        let model = ClothModel::uniform(&rest, &Material::cotton(), SimOptions::default()).unwrap();
        let corners = [(nx * nx - nx) as u32, (nx * nx - 1) as u32];
        let buttoned = model.with_buttons(&[corners]).unwrap();
        // The stiffness is the fabric's E t: 1 050 N/m for cotton.
        let cotton = Material::cotton();
        let k = buttoned.buttons().unwrap().stiffness()[0];
        let et = cotton.young_modulus * cotton.thickness;
        assert!((k - et).abs() < 1e-9 * et, "{k} vs {et}");
        assert!(buttoned
            .with_buttons(&[[0, nx as u32 * nx as u32]])
            .is_err());
        // A material change keeps the pairs and rescales the stiffness.
        let silk = buttoned.with_material(&Material::silk()).unwrap();
        assert_eq!(silk.buttons().unwrap().pairs(), &[corners]);
        let silk_et = Material::silk().young_modulus * Material::silk().thickness;
        assert!((silk.buttons().unwrap().stiffness()[0] - silk_et).abs() < 1e-9 * silk_et);
        let gap = |sim: &ClothSimulator| {
            let x = sim.positions();
            (v3(x[corners[0] as usize]) - v3(x[corners[1] as usize])).norm()
        };
        let run = |model: ClothModel, unbutton_at: Option<usize>| {
            let mut sim = ClothSimulator::from_model(model).unwrap();
            sim.pin(&[0, (nx - 1) as u32]).unwrap();
            let mut gaps = Vec::new();
            for frame in 0..60 {
                if Some(frame) == unbutton_at {
                    sim.unbutton();
                }
                sim.step(1.0 / 30.0, None).unwrap();
                gaps.push(gap(&sim));
            }
            gaps
        };
        let open = run(model.clone(), None);
        let closed = run(buttoned.clone(), Some(30));
        let width = (nx - 1) as f64 * h;
        assert!(open.iter().all(|&g| g > 0.9 * width), "{open:?}");
        assert!(closed[29] < 0.1 * width, "buttoned gap {}", closed[29]);
        assert!(closed[59] > 0.5 * width, "unbuttoned gap {}", closed[59]);
        // The button is a term of the potential while buttoned, and only then.
        let names = |sim: &ClothSimulator| -> Vec<&'static str> {
            sim.potential()
                .terms()
                .iter()
                .map(|t| t.term.energy().name())
                .collect()
        };
        let mut sim = ClothSimulator::from_model(buttoned).unwrap();
        sim.step(1.0 / 30.0, None).unwrap();
        assert_eq!(names(&sim).last(), Some(&"buttons"));
        sim.unbutton();
        sim.step(1.0 / 30.0, None).unwrap();
        assert!(!names(&sim).contains(&"buttons"));
    }

    /// A square dropped on a sphere drapes over it without passing through.
    #[test]
    fn cloth_drapes_on_a_sphere() {
        let (nx, h) = (13, 0.05);
        let mut rest = grid(nx, nx, h);
        for p in &mut rest.positions {
            p[0] -= 0.3;
            p[2] -= 0.3;
            p[1] = 0.25;
        }
        let body = Sphere {
            center: [0.0, 0.0, 0.0],
            radius: 0.2,
        };
        let mut sim =
            ClothSimulator::new(&rest, &Material::cotton(), SimOptions::default()).unwrap();
        let mut had_contact = false;
        for _ in 0..40 {
            let r = sim.step(1.0 / 30.0, Some(&body)).unwrap();
            had_contact |= r.contacts > 0;
            for w in r.newton.energies.windows(2) {
                assert!(w[1] <= w[0] + 1e-12 * w[0].abs().max(1.0));
            }
        }
        assert!(had_contact);
        let min_d = sim
            .positions()
            .iter()
            .map(|&p| v3(p).norm() - body.radius)
            .fold(f64::INFINITY, f64::min);
        assert!(min_d > -HOOD_COLLISION_EPS, "deepest penetration {min_d}");
        // The centre rests on top of the sphere.
        let c = sim.positions()[nx * nx / 2];
        assert!((c[1] - body.radius).abs() < 0.01, "{c:?}");
    }

    /// A strip pinned along its top edge hangs straight down and stretches under its own
    /// weight to the analytic static rest: with ν = 0 (no lateral contraction) and StVK,
    /// the first Piola stress per rest width at arc length `s` from the top carries the
    /// weight below, `(1 + ε) E h ((1 + ε)² − 1)/2 = ρ g (L − s)`, and the bottom edge
    /// drops by `∫₀ᴸ ε(s) ds` beyond the rest length. Large implicit-Euler steps
    /// (0.1 s) damp the motion so the state settles on the static equilibrium.
    #[test]
    fn hanging_strip_reaches_the_analytic_elongation() {
        let (w, l, nx, ny) = (0.1, 0.5, 5, 21);
        let flat = grid(nx, ny, l / (ny - 1) as f64);
        let rest = TriMesh::new(
            flat.positions.iter().map(|p| [p[0], -p[2], 0.0]).collect(),
            flat.faces.clone(),
        );
        assert!((rest.positions[nx - 1][0] - w).abs() < 1e-12);
        let material = Material {
            name: "test",
            density: 0.2,
            young_modulus: 7.0e4,
            poisson_ratio: 0.0,
            thickness: 4.7e-4,
            bending_stiffness: 0.0,
            friction: 0.0,
        };
        let mut sim = ClothSimulator::new(&rest, &material, SimOptions::default()).unwrap();
        let top: Vec<u32> = (0..nx as u32).collect();
        sim.pin(&top).unwrap();
        for _ in 0..80 {
            let r = sim.step(0.1, None).unwrap();
            for e in r.newton.energies.windows(2) {
                assert!(e[1] <= e[0] + 1e-12 * e[0].abs().max(1.0));
            }
        }
        // Analytic: solve for ε(s) by Newton, integrate by the midpoint rule.
        let (eh, load) = (
            material.young_modulus * material.thickness,
            material.density * 9.81,
        );
        let strain = |s: f64| {
            let target = load * (l - s) / eh;
            let mut e: f64 = target;
            for _ in 0..50 {
                let f = (1.0 + e) * ((1.0 + e).powi(2) - 1.0) / 2.0 - target;
                let df = ((1.0 + e).powi(2) - 1.0) / 2.0 + (1.0 + e).powi(2);
                e -= f / df;
            }
            e
        };
        let m = 10_000;
        let elongation: f64 = (0..m)
            .map(|k| strain((k as f64 + 0.5) * l / m as f64) * l / m as f64)
            .sum();
        let bottom: Vec<f64> = (0..nx)
            .map(|i| sim.positions()[(ny - 1) * nx + i][1])
            .collect();
        if std::env::var_os("WEFT_SIM_TRACE").is_some() {
            eprintln!("analytic elongation {elongation:.6} m, bottom edge {bottom:?}");
        }
        for b in &bottom {
            let got = -b - l;
            assert!(
                (got - elongation).abs() < 0.03 * elongation,
                "bottom dropped {got:.6} m beyond the rest length, analytic {elongation:.6} m"
            );
        }
        assert!(
            elongation > 5e-3,
            "the check must see a real stretch: {elongation}"
        );
        // Hangs straight: no sideways or out-of-plane drift.
        for p in sim.positions() {
            assert!(
                p[2].abs() < 1e-6 && p[0] > -1e-3 && p[0] < w + 1e-3,
                "{p:?}"
            );
        }
    }

    /// Newton started from a prediction ([`ClothSimulator::step_from`]): from the
    /// step's own minimiser it stays there, from a coasting guess one iteration lowers
    /// the potential and enough of them reach the step [`ClothSimulator::step`] takes.
    #[test]
    fn a_step_from_a_prediction_refines_it_to_the_implicit_step() {
        let (nx, h) = (7, 0.05);
        let rest = grid(nx, nx, h);
        let fresh = || {
            let mut sim =
                ClothSimulator::new(&rest, &Material::cotton(), SimOptions::default()).unwrap();
            sim.pin(&[0, (nx - 1) as u32]).unwrap();
            sim
        };
        let dt = 1.0 / 30.0;
        let mut reference = fresh();
        reference.step(dt, None).unwrap();
        let want = reference.positions().to_vec();
        let gap = |x: &[[f64; 3]]| {
            x.iter()
                .zip(&want)
                .map(|(a, b)| v3(*a).metric_distance(&v3(*b)))
                .fold(0.0, f64::max)
        };
        let mut from_answer = fresh();
        let r = from_answer.step_from(dt, None, &want, 50).unwrap();
        assert!(r.newton.iterations <= 1, "{:?}", r.newton);
        // Within Newton's tolerance (1e-5 m) of where it started.
        let stayed = gap(from_answer.positions());
        assert!(stayed < 1e-5, "{stayed}");
        // The coasting guess: the rest shape, where gravity has not acted.
        let mut once = fresh();
        let r = once.step_from(dt, None, &rest.positions, 1).unwrap();
        assert_eq!(r.newton.iterations, 1);
        let e = &r.newton.energies;
        assert!(e.last().unwrap() < &e[0], "{e:?}");
        assert!(gap(once.positions()) < gap(&rest.positions));
        let mut full = fresh();
        full.step_from(dt, None, &rest.positions, 50).unwrap();
        assert!(gap(full.positions()) < 1e-4, "{}", gap(full.positions()));
        assert!(fresh().step_from(dt, None, &want[1..], 4).is_err());
    }

    #[test]
    fn bad_input_is_an_error() {
        let rest = grid(3, 3, 0.1);
        let mut sim = ClothSimulator::new(&rest, &Material::silk(), SimOptions::default()).unwrap();
        assert!(sim.step(0.0, None).is_err());
        assert!(sim.pin(&[9]).is_err());
        assert!(sim.move_pin(0, [f64::NAN, 0.0, 0.0]).is_err());
        assert!(sim.set_state(vec![[0.0; 3]; 2], vec![[0.0; 3]; 2]).is_err());
        let mut m = Material::silk();
        m.density = -1.0;
        assert!(ClothSimulator::new(&rest, &m, SimOptions::default()).is_err());
    }
}
