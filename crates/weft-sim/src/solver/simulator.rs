//! The time loop of the cloth simulator: one implicit-Euler step per call, minimising
//! the incremental potential (seed 004 eq. 5) with [`super::minimize`].
//!
//! Per step: the inertial target `x̂ = x_t + h v_t`; body contacts refreshed from the
//! start-of-step positions (HOOD: the closest body point of each garment vertex at the
//! start of the step, with the body at its end-of-step state), each vertex within
//! `contact_radius` of the body getting a cubic collision contact and, within HOOD's
//! friction radius, a friction contact with HOOD's lagged normal force `m g`; pinned
//! vertices held at their targets; the new velocity `(x_{t+1} − x_t)/h`. A step that
//! produces non-finite positions or an absurd speed is reported as
//! [`SimError::Diverged`] and leaves the state as it was.

use weft_mesh::TriMesh;

use crate::bending::{Bending, BendingScale, RestAngle};
use crate::collision::{CubicCollision, HOOD_COLLISION_EPS, HOOD_COLLISION_STIFFNESS};
use rayon::prelude::*;

use crate::contact::{BodyContact, BodyProximity, VertexContact};
use crate::error::{check_len, check_nonneg, check_vertex, SimError};
use crate::friction::{Friction, FrictionContact, DEFAULT_FRICTION_EPS, HOOD_FRICTION_RADIUS};
use crate::gravity::{lumped_masses, Gravity, STANDARD_GRAVITY};
use crate::inertia::Inertia;
use crate::material::Material;
use crate::math::{finite3, v3};
use crate::potential::{IncrementalPotential, Term};
use crate::solver::newton::{minimize, NewtonOptions, NewtonReport};
use crate::sparse::BlockCsr;
use crate::stretch::Stretch;

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

/// A garment simulated with implicit Euler.
#[derive(Debug)]
pub struct ClothSimulator {
    potential: IncrementalPotential,
    hess: BlockCsr,
    masses: Vec<f64>,
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    pinned: Vec<bool>,
    pin_targets: Vec<[f64; 3]>,
    options: SimOptions,
    material: Material,
}

impl ClothSimulator {
    /// A simulator for the garment `rest` (rest shape = initial state, at rest) made of
    /// `material`.
    pub fn new(rest: &TriMesh, material: &Material, options: SimOptions) -> Result<Self, SimError> {
        material.validate()?;
        let n = rest.vertex_count();
        let masses = lumped_masses(rest, &vec![material.density; rest.face_count()])?;
        let potential = IncrementalPotential::new(n)
            .with(
                1.0,
                Term::Stretch(Stretch::uniform(rest, material.stretch_params())?),
            )?
            .with(
                1.0,
                Term::Bending(Bending::uniform(
                    rest,
                    material.bending_stiffness,
                    options.bending_scale,
                    options.rest_angle,
                )?),
            )?
            .with(
                1.0,
                Term::Gravity(Gravity::new(masses.clone(), options.gravity)?),
            )?
            .with(
                1.0,
                Term::Inertia(Inertia::new(
                    masses.clone(),
                    1.0 / 30.0,
                    rest.positions.clone(),
                )?),
            )?
            .with(
                1.0,
                Term::Collision(CubicCollision::new(
                    n,
                    options.collision_stiffness,
                    options.collision_eps,
                    Vec::new(),
                )?),
            )?
            .with(
                1.0,
                Term::Friction(Friction::new(n, options.friction_eps, Vec::new())?),
            )?;
        let hess = potential.hessian_pattern();
        Ok(ClothSimulator {
            potential,
            hess,
            masses,
            x: rest.positions.clone(),
            v: vec![[0.0; 3]; n],
            pinned: vec![false; n],
            pin_targets: rest.positions.clone(),
            options,
            material: *material,
        })
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
        &self.masses
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

    /// Advances by `dt` seconds against `body` (at its end-of-step state; `None`: no body).
    pub fn step(
        &mut self,
        dt: f64,
        body: Option<&(dyn BodyProximity + Sync)>,
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
        let (contacts, friction, moved) = self.contacts(body);
        let (nc, nf) = (contacts.len(), friction.len());
        if let Some(inertia) = self.potential.inertia_mut() {
            inertia.set_dt(dt)?;
            inertia.set_target(target.clone())?;
        }
        if let Some(c) = self.potential.collision_mut() {
            c.set_contacts(contacts)?;
        }
        if let Some(f) = self.potential.friction_mut() {
            f.set_contacts(friction)?;
        }
        // Start from the inertial target; where it lies closer to the body than ε
        // (along the contact's normal), from its projection to ε instead. Keeping the
        // tangential part keeps the start free of the stretch a jump between contact
        // and free vertices would cause.
        let _ = moved;
        let mut x = target;
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
            &self.options.newton,
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
        if max_speed > self.options.max_speed {
            return Err(SimError::Diverged {
                message: format!(
                    "largest vertex speed {max_speed:.3e} m/s exceeds {:.3e} m/s",
                    self.options.max_speed
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

    /// Collision and friction contacts of the free vertices at the start of the step
    /// (queried in parallel: with a refit per sub-step this is a large share of a
    /// step's cost), and each contact's body displacement over the step.
    fn contacts(
        &self,
        body: Option<&(dyn BodyProximity + Sync)>,
    ) -> (Vec<VertexContact>, Vec<FrictionContact>, Vec<[f64; 3]>) {
        let Some(body) = body else {
            return (Vec::new(), Vec::new(), Vec::new());
        };
        let g = v3(self.options.gravity).norm();
        let found: Vec<(u32, BodyContact, [f64; 3])> = self
            .x
            .par_iter()
            .enumerate()
            .filter(|(i, _)| !self.pinned[*i])
            .filter_map(|(i, &p)| {
                let (c, moved) = body.closest_moving(p)?;
                (finite3(c.point) && finite3(c.normal) && finite3(moved))
                    .then_some((i as u32, c, moved))
            })
            .collect();
        let mut contacts = Vec::new();
        let mut friction = Vec::new();
        let mut moved = Vec::new();
        for (i, c, m) in found {
            let p = self.x[i as usize];
            let d = c.signed_distance(p);
            if d < self.options.contact_radius {
                contacts.push(VertexContact {
                    vertex: i,
                    contact: c,
                });
                moved.push(m);
            }
            if d < self.options.friction_radius && self.material.friction > 0.0 {
                let before: [f64; 3] = std::array::from_fn(|k| c.point[k] - m[k]);
                friction.push(FrictionContact::hood(
                    i,
                    p,
                    before,
                    c.point,
                    c.normal,
                    c.normal,
                    self.masses[i as usize],
                    g,
                    self.material.friction,
                ));
            }
        }
        (contacts, friction, moved)
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
