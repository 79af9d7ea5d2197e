//! Draping: settling a garment on the body in rest pose with the simulator, so its
//! shape has gravity's folds and rests on the body instead of floating at a fixed ease.
//!
//! 1. **Check.** Signed distances of every vertex to the body. A vertex deeper than
//!    [`DrapeOptions::max_start_depth`] (3 cm by default) is an error
//!    ([`PrepareError::DeeplyInside`]): its closest body point may be on the far side of
//!    a limb, and pushing it there drags the cloth through the body. Such a garment was
//!    made for another body and should be resized first ([`super::resize`]).
//! 2. **Push-out.** Vertices inside or closer than the collision threshold ε move to
//!    their closest body point plus ε along the outward direction, the displacement is
//!    spread to the neighbourhood (a smooth bump, not folded triangles) and the push-out
//!    repeated ([`FitBody::push_out`], as for templates). The number moved is reported.
//!    The simulator starts collision-free: its cubic penalty only acts within ε, so a
//!    vertex starting deeper would be pushed by an enormous force in the first step.
//! 3. **Gravity ramp.** Gravity grows linearly from `1/ramp_frames` of its value to the
//!    full value over the first `ramp_frames` frames, so the cloth is not jerked down
//!    before the contacts have formed. The simulator fixes gravity at construction, so
//!    each ramp frame continues the state in a simulator built with that frame's
//!    gravity (a few milliseconds against a step's tens to hundreds).
//! 4. **Settle.** Frames of the implicit-Euler simulator against the rest body, with a
//!    fraction [`DrapeOptions::damping`] of every velocity removed after each frame (a
//!    drape wants the rest state, not the swing), until the largest vertex speed is
//!    below [`DrapeOptions::settle_speed`] after the ramp, or the frame budget is spent.
//!
//! **Pinning.** Templates are sized with an ease of 1.5–4 cm everywhere, waistbands too,
//! and a real waistband is elastic or buttoned tight: on weft's default body a skirt
//! whose waistband is 2 cm looser than the waist slides over the hips and falls to the
//! feet (measured: 0.7 m down in 25 frames). So by default the top opening is held where
//! it is ([`DrapeOptions::pin_top_opening`]), standing in for the waistband (or, for a
//! top, the neckline, which the shoulders would hold anyway); the rest of the garment
//! settles under gravity. Garments without an opening (closed surfaces) pin nothing.
//!
//! The garment's input shape is the rest shape of the cloth (its sewing pattern): the
//! membrane and bending energies are measured from it, push-out included.
//! [`drape_from`] separates the two: a pattern, and start positions (the pattern moved
//! onto another body, [`super::fit_onto`]) that the checks, push-out and pins apply to.

use std::time::Instant;

use weft_mesh::TriMesh;
use weft_sim::{ClothSimulator, Material, Penetration, PosedBody, SimOptions};

use super::resize::check_finite;
use super::PrepareError;
use crate::onbody::spread_displacements;
use crate::FitBody;

/// Parameters of [`drape`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrapeOptions {
    /// Time step per frame, s.
    pub dt: f64,
    /// Frame budget.
    pub max_frames: usize,
    /// Frames over which gravity ramps up to its full value (≥ 1).
    pub ramp_frames: usize,
    /// Settled when the largest vertex speed is below this after the ramp, m/s.
    pub settle_speed: f64,
    /// Fraction of each vertex velocity removed after every frame, in [0, 1).
    pub damping: f64,
    /// A vertex starting deeper inside the body than this is an error, m.
    pub max_start_depth: f64,
    /// Hold the garment's top opening (the boundary loop highest up: a skirt's or a
    /// pair of pants' waist, a top's neckline) where it is.
    pub pin_top_opening: bool,
    /// Simulator options (gravity, collision threshold ε, Newton).
    pub sim: SimOptions,
}

impl Default for DrapeOptions {
    /// 30 fps, at most 120 frames (4 s), a 10-frame gravity ramp, settled below 2 cm/s,
    /// 20% damping per frame, 3 cm start-depth limit, top opening pinned, the simulator's
    /// defaults.
    fn default() -> Self {
        DrapeOptions {
            dt: 1.0 / 30.0,
            max_frames: 120,
            ramp_frames: 10,
            settle_speed: 0.02,
            damping: 0.2,
            max_start_depth: 0.03,
            pin_top_opening: true,
            sim: SimOptions::default(),
        }
    }
}

impl DrapeOptions {
    fn check(&self) -> Result<(), PrepareError> {
        let bad = |name, value, expected| PrepareError::Option {
            name,
            value,
            expected,
        };
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return Err(bad("dt", self.dt, "a positive time step in seconds"));
        }
        if self.max_frames == 0 {
            return Err(bad("max_frames", 0.0, "at least 1 frame"));
        }
        if self.ramp_frames == 0 {
            return Err(bad("ramp_frames", 0.0, "at least 1 frame"));
        }
        if !(self.settle_speed.is_finite() && self.settle_speed > 0.0) {
            return Err(bad(
                "settle_speed",
                self.settle_speed,
                "a positive speed (m/s)",
            ));
        }
        if !(self.damping.is_finite() && (0.0..1.0).contains(&self.damping)) {
            return Err(bad("damping", self.damping, "0 <= damping < 1"));
        }
        if !(self.max_start_depth.is_finite() && self.max_start_depth >= 0.0) {
            return Err(bad("max_start_depth", self.max_start_depth, "0 m or more"));
        }
        if !(self.sim.collision_eps.is_finite() && self.sim.collision_eps > 0.0) {
            return Err(bad(
                "sim.collision_eps",
                self.sim.collision_eps,
                "a positive length (m)",
            ));
        }
        Ok(())
    }
}

/// A draped garment and what the drape did.
#[derive(Clone, Debug, PartialEq)]
pub struct DrapeReport {
    /// The draped vertex positions (same order and faces as the input).
    pub positions: Vec<[f64; 3]>,
    /// Vertices inside the body as given.
    pub before: Penetration,
    /// Vertices moved by the initial push-out (inside or within ε of the body).
    pub pushed_out: usize,
    /// Vertices inside the body at the end (`beyond_tolerance`: deeper than ε).
    pub after: Penetration,
    /// Frames simulated.
    pub frames: usize,
    /// Whether the speed criterion was met within the budget.
    pub settled: bool,
    /// Largest vertex speed of each frame, m/s.
    pub max_speeds: Vec<f64>,
    /// Newton iterations over all frames.
    pub newton_iterations: usize,
    /// Vertices held in place (the top opening).
    pub pinned: usize,
    /// Wall-clock time of the simulation, s.
    pub seconds: f64,
}

/// Drapes `garment` (its shape is also the cloth's rest shape) on `body` at rest, made
/// of `material`. See the module docs. The same as [`drape_from`] with the garment as
/// both pattern and start.
pub fn drape(
    garment: &TriMesh,
    body: &FitBody,
    material: &Material,
    options: &DrapeOptions,
) -> Result<DrapeReport, PrepareError> {
    drape_from(garment, &garment.positions, body, material, options)
}

/// Drapes a garment whose rest shape (sewing pattern) is `pattern` from the positions
/// `start` (one per pattern vertex, e.g. the pattern resized onto another body) on
/// `body` at rest, made of `material`. The membrane and bending energies are measured
/// from `pattern`, so a start stretched past the pattern pulls tight against the body
/// and a start compressed below it relaxes outwards. The checks, push-out, pinning and
/// settling are [`drape`]'s (module docs), applied to `start`; the report's
/// `positions` are in `pattern`'s vertex order and faces.
pub fn drape_from(
    pattern: &TriMesh,
    start: &[[f64; 3]],
    body: &FitBody,
    material: &Material,
    options: &DrapeOptions,
) -> Result<DrapeReport, PrepareError> {
    options.check()?;
    check_finite(&pattern.positions)?;
    if start.len() != pattern.vertex_count() {
        return Err(PrepareError::StartPositions {
            given: start.len(),
            expected: pattern.vertex_count(),
        });
    }
    check_finite(start)?;
    let eps = options.sim.collision_eps;
    let posed = PosedBody::new(&body.mesh.positions, &body.mesh.faces)?
        .with_query_radius(options.sim.contact_radius.max(options.sim.friction_radius))?;

    let signed = posed.signed_distances(start)?;
    weft_sim::check_garment_gap(signed.iter().copied())?;
    let before = posed.penetration(start, eps)?;
    let too_deep: Vec<usize> = (0..signed.len())
        .filter(|&i| signed[i] < -options.max_start_depth)
        .collect();
    if let Some(&vertex) = too_deep
        .iter()
        .min_by(|&&a, &&b| signed[a].total_cmp(&signed[b]))
    {
        return Err(PrepareError::DeeplyInside {
            count: too_deep.len(),
            vertex,
            deepest_mm: -signed[vertex] * 1e3,
            limit_mm: options.max_start_depth * 1e3,
        });
    }

    let mut moved = TriMesh::new(start.to_vec(), pattern.faces.clone());
    body.push_out(&mut moved.positions, eps)?;
    spread_displacements(&mut moved, start, 20);
    body.push_out(&mut moved.positions, eps)?;
    let pushed_out = moved
        .positions
        .iter()
        .zip(start)
        .filter(|(p, q)| p != q)
        .count();

    let clock = Instant::now();
    let mut x = moved.positions;
    let mut v = vec![[0.0; 3]; x.len()];
    let pins = if options.pin_top_opening {
        weft_sim::attachment::top_opening(pattern)
    } else {
        Vec::new()
    };
    // The simulator with `scale` times the gravity, continuing the state `x`, `v`.
    let build = |scale: f64, x: &[[f64; 3]], v: &[[f64; 3]]| {
        let mut sim_options = options.sim;
        sim_options.gravity = options.sim.gravity.map(|g| g * scale);
        let mut s = ClothSimulator::new(pattern, material, sim_options)?;
        s.set_state(x.to_vec(), v.to_vec())?;
        s.pin(&pins)?;
        Ok::<_, PrepareError>(s)
    };
    let ramp = |frame: usize| ((frame + 1) as f64 / options.ramp_frames as f64).min(1.0);
    let mut s = build(ramp(0), &x, &v)?;
    let mut max_speeds = Vec::new();
    let mut newton_iterations = 0;
    let mut settled = false;
    for frame in 0..options.max_frames {
        let ramping = frame < options.ramp_frames;
        if frame > 0 && ramping {
            s = build(ramp(frame), &x, &v)?;
        }
        let report = s
            .step(options.dt, Some(&posed))
            .map_err(|source| PrepareError::Simulation { frame, source })?;
        newton_iterations += report.newton.iterations;
        max_speeds.push(report.max_speed);
        let keep = 1.0 - options.damping;
        x = s.positions().to_vec();
        v = s.velocities().iter().map(|u| u.map(|c| c * keep)).collect();
        s.set_state(x.clone(), v.clone())?;
        if !ramping && report.max_speed < options.settle_speed {
            settled = true;
            break;
        }
    }
    let after = posed.penetration(&x, eps)?;
    Ok(DrapeReport {
        positions: x,
        before,
        pushed_out,
        after,
        frames: max_speeds.len(),
        settled,
        max_speeds,
        newton_iterations,
        pinned: pins.len(),
        seconds: clock.elapsed().as_secs_f64(),
    })
}
