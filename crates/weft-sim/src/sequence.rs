//! Ground-truth sequences: a garment simulated on a body that follows a motion.
//!
//! [`simulate_sequence`] poses the body for every motion frame, warms the garment up
//! (it is fitted to the body's rest pose; the body blends from there to the motion's
//! first pose while the garment drapes and settles), then produces one output frame per
//! motion frame, each made of `substeps` implicit-Euler steps with the body's vertices
//! interpolated linearly between the two posed frames, so the body moves continuously
//! and a fast limb never jumps through the cloth between frames.
//!
//! Bad input is reported before any work: a garment that starts deeper inside the body
//! than [`SequenceOptions::max_initial_penetration`] is refused, shallower penetrations
//! are pushed out to the surface; a divergent step ends the run with
//! [`SequenceError::Diverged`] naming the frame and keeping the frames finished so far.

use std::time::Instant;

use weft_body::{BodyError, BodyModel, ShapedBody, Skinning};
use weft_mesh::vec3::{add_scaled, dist};
use weft_mesh::TriMesh;
use weft_motion::Motion;

use crate::attachment::{Attachment, SkinAnchors};
use crate::body::{check_garment_gap, Penetration, PosedBody};
use crate::cloth::ClothModel;
use crate::energy::Energy;
use crate::error::SimError;
use crate::material::Material;
use crate::solver::{ClothSimulator, SimOptions};

/// How a sequence is simulated. A TOML table sets any of these; the others keep the
/// defaults stated on each field.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SequenceOptions {
    /// Implicit-Euler steps per output frame (`>= 1`). Default: 4.
    pub substeps: usize,
    /// Frames (at the motion's rate) before the first output frame: the first third
    /// holds the rest pose (the garment drapes under gravity), the rest blends the pose
    /// from rest to the motion's first frame. Default: 15.
    pub warmup_frames: usize,
    /// The simulator's parameters. Default: [`SimOptions::default`] with
    /// `newton.max_iterations` = [`SEQUENCE_NEWTON_BUDGET`] (4). A `[sim]` table in a
    /// file starts from [`SimOptions::default`] itself (50 Newton iterations), so set
    /// `sim.newton.max_iterations` there to keep the sequence budget.
    pub sim: SimOptions,
    /// How the body is posed (in TOML: `lbs`, `dqs`). Default: [`Skinning::Lbs`].
    pub skinning: Skinning,
    /// A garment vertex deeper than this inside the rest-pose body (m) makes the input
    /// invalid; shallower ones are moved out to the surface (plus the collision
    /// threshold) before the simulation starts. Default: 0.02 m.
    pub max_initial_penetration: f64,
    /// Use at most this many motion frames (`None`, or the key left out: all). Default:
    /// `None`.
    pub max_frames: Option<usize>,
    /// Garment vertices that follow the body's skin (default: the top opening, i.e.
    /// the waistband or neckline; see [`crate::attachment`]).
    pub attachment: Attachment,
    /// More garment vertices (0-based indices) that follow the body's skin, beside the
    /// attachment's: straps, a belt, a sewn-on patch, or a whole garment held in place
    /// with `attachment = "none"`. Default: none.
    pub pinned: Vec<u32>,
    /// Where the garment starts on this body in its rest pose, one position per garment
    /// vertex, when that differs from its rest shape: a garment made for another body
    /// (the mesh passed to [`simulate_sequence`] is its pattern, the rest shape its
    /// energies are measured from; these are where it sits on this body, e.g. from
    /// `weft_garment::prepare::fit_onto`). Like the mesh they are in the body's rest
    /// frame: frame 0's root translation is added. Default: `None`, the garment starts
    /// as its rest mesh.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start_positions: Option<Vec<[f64; 3]>>,
    /// Garment vertex pairs (0-based) buttoned together, each a zero-length spring as
    /// stiff as the fabric around it ([`crate::ClothModel::with_buttons`]): a jacket's
    /// front held closed. Default: none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub buttons: Vec<[u32; 2]>,
    /// The output frame from which the buttons are undone (seed 004 Fig. 4); `None`:
    /// buttoned throughout. Default: `None`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unbutton_at: Option<usize>,
}

/// Newton iterations per sub-step in a sequence: a fixed budget (the energy still
/// decreases in every iteration; what is left unconverged is a little extra damping).
/// Measured in `docs/physics.md`: 4 sub-steps × 4 iterations keep the walking skirt
/// penetration-free with mean strain ≈ 0.1 %; fewer sub-steps let fast limbs through.
pub const SEQUENCE_NEWTON_BUDGET: usize = 4;

impl Default for SequenceOptions {
    fn default() -> Self {
        let mut sim = SimOptions::default();
        sim.newton.max_iterations = SEQUENCE_NEWTON_BUDGET;
        SequenceOptions {
            substeps: 4,
            warmup_frames: 15,
            sim,
            skinning: Skinning::Lbs,
            max_initial_penetration: 0.02,
            max_frames: None,
            attachment: Attachment::TopOpening,
            pinned: Vec::new(),
            start_positions: None,
            buttons: Vec::new(),
            unbutton_at: None,
        }
    }
}

/// The most warm-up frames a sequence may ask for: 10 000 frames is over five minutes
/// at 30 fps of draping before the motion starts, far past what any garment needs to
/// settle; more is a typo that would run for hours.
pub const MAX_WARMUP_FRAMES: usize = 10_000;

/// The most implicit-Euler sub-steps per frame: 100 is 25 times the default and a
/// 0.3 ms step at 30 fps, finer than any cloth preset needs to stay stable; more is a
/// typo that would run for days.
pub const MAX_SUBSTEPS: usize = 100;

/// What [`simulate_sequence`] reports as it goes, for progress bars.
#[derive(Clone, Copy, Debug)]
pub enum SequenceProgress<'a> {
    /// Warm-up frame `done` of `total` is finished (no output frame yet).
    Warmup {
        /// Warm-up frames finished.
        done: usize,
        /// Warm-up frames in all.
        total: usize,
    },
    /// An output frame is finished.
    Frame(&'a FrameStats),
}

/// What one output frame looked like and cost.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// Output frame index (= motion frame index).
    pub frame: usize,
    /// Potential energy of the garment at the end of the frame: stretching + bending +
    /// gravity (J; gravity measured from y = 0).
    pub energy: f64,
    /// Largest `|l/l̄ − 1|` over the garment's edges.
    pub max_edge_strain: f64,
    /// Mean `|l/l̄ − 1|` over the garment's edges.
    pub mean_edge_strain: f64,
    /// Garment vertices inside the body at the end of the frame.
    pub penetrations: usize,
    /// Depth of the deepest of them, m (0 when none).
    pub max_penetration: f64,
    /// Newton iterations over the frame's sub-steps.
    pub newton_iterations: usize,
    /// PCG iterations over the frame's sub-steps.
    pub cg_iterations: usize,
    /// Wall time of the frame, s (frame 0: the whole warm-up).
    pub seconds: f64,
}

/// A simulated garment sequence.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SimulatedSequence {
    /// Garment positions per output frame (`f32`, the precision of datasets).
    pub frames: Vec<Vec<[f32; 3]>>,
    /// Statistics per output frame.
    pub stats: Vec<FrameStats>,
    /// Garment vertices found inside the rest-pose body and pushed out before the run.
    pub pushed_out: usize,
}

/// Why a sequence could not be (fully) simulated.
#[derive(Debug, thiserror::Error)]
pub enum SequenceError {
    /// A step diverged; `finished` holds the frames before `frame`.
    #[error("the simulation diverged at frame {frame}: {message} ({} frames finished)", finished.frames.len())]
    Diverged {
        /// The output frame being simulated (0 during the warm-up).
        frame: usize,
        /// What was detected.
        message: String,
        /// The frames finished before it.
        finished: SimulatedSequence,
    },
    /// The garment, material or options are invalid.
    #[error(transparent)]
    Input(#[from] SimError),
    /// The body or the motion could not be posed.
    #[error("the body could not be posed")]
    Body(#[from] BodyError),
    /// The garment starts too deep inside the body.
    #[error("the garment starts inside the body: {count} vertices inside, the deepest {max_depth:.4} m (more than {limit} m); fit the garment to this body shape and its rest pose")]
    StartsInside {
        /// Vertices inside the body.
        count: usize,
        /// The deepest, m.
        max_depth: f64,
        /// The accepted depth, m.
        limit: f64,
    },
    /// A posed body frame is not finite (a motion with NaN, a broken model).
    #[error("motion frame {frame}: the posed body has a non-finite vertex")]
    NonFiniteBody {
        /// The motion frame.
        frame: usize,
    },
}

/// Edge rest lengths and the strain statistics of a garment.
struct EdgeStrain {
    edges: Vec<[u32; 2]>,
    rest: Vec<f64>,
}

impl EdgeStrain {
    fn new(mesh: &TriMesh) -> Self {
        let edges = mesh.edges();
        let rest = edges
            .iter()
            .map(|&[a, b]| dist(mesh.positions[a as usize], mesh.positions[b as usize]))
            .collect();
        EdgeStrain { edges, rest }
    }

    /// `(max, mean)` of `|l/l̄ − 1|`.
    fn of(&self, x: &[[f64; 3]]) -> (f64, f64) {
        let mut max: f64 = 0.0;
        let mut sum = 0.0;
        for (&[a, b], &l0) in self.edges.iter().zip(&self.rest) {
            let s = (dist(x[a as usize], x[b as usize]) / l0 - 1.0).abs();
            max = max.max(s);
            sum += s;
        }
        (max, sum / self.edges.len().max(1) as f64)
    }
}

/// The body at the key frames of the timeline: warm-up poses, then the motion frames.
struct Timeline<'a> {
    model: &'a BodyModel,
    shaped: ShapedBody,
    motion: &'a Motion,
    warmup: usize,
    frames: usize,
    skinning: Skinning,
}

impl Timeline<'_> {
    /// Number of key frames.
    fn len(&self) -> usize {
        self.warmup + self.frames
    }

    /// Posed body vertices at key frame `k` (`k = warmup` is motion frame 0).
    fn body(&self, k: usize) -> Result<Vec<[f64; 3]>, SequenceError> {
        let (frame, blend) = if k >= self.warmup {
            (k - self.warmup, 1.0)
        } else {
            // Hold the rest pose for the first third, then ease into frame 0.
            let hold = self.warmup / 3;
            let t = if k < hold {
                0.0
            } else {
                (k - hold) as f64 / (self.warmup - hold) as f64
            };
            (0, t * t * (3.0 - 2.0 * t))
        };
        let pose: Vec<[f64; 3]> = self.motion.poses()[frame]
            .iter()
            .map(|w| w.map(|c| f64::from(c) * blend))
            .collect();
        // The root translation of frame 0 through the warm-up: the garment is moved
        // there at the start, so only the pose blends.
        let t = self.motion.trans()[frame].map(f64::from);
        let v = self
            .model
            .pose_vertices(&self.shaped, &pose, t, self.skinning)?;
        if v.iter().flatten().any(|c| !c.is_finite()) {
            return Err(SequenceError::NonFiniteBody { frame });
        }
        Ok(v)
    }
}

fn lerp_into(a: &[[f64; 3]], b: &[[f64; 3]], t: f64, out: &mut Vec<[f64; 3]>) {
    out.clear();
    out.extend(
        a.iter()
            .zip(b)
            .map(|(p, q)| std::array::from_fn(|k| p[k] + t * (q[k] - p[k]))),
    );
}

/// Potential energy (stretching + bending + gravity) of the simulator's state.
fn potential_energy(sim: &ClothSimulator) -> Result<f64, SimError> {
    let p = sim.potential();
    let x = sim.positions();
    let mut e = 0.0;
    if let Some(s) = p.stretch() {
        e += s.value(x)?;
    }
    if let Some(b) = p.bending() {
        e += b.value(x)?;
    }
    if let Some(g) = p.gravity() {
        e += g.value(x)?;
    }
    Ok(e)
}

/// Simulates `garment` (its rest mesh, fitted to `body` with `betas` in the body's rest
/// pose, as weft_garment's generators make them) made of `material` on the body
/// following `motion` at the motion's frame rate. With
/// [`SequenceOptions::start_positions`] the garment starts there instead (a garment made
/// for another body, fitted onto this one), and `garment` stays its rest shape: strains
/// and energies are measured from it.
///
/// The first `warmup_frames` blend from the rest pose to the motion's first frame
/// (draping the garment and letting it settle); then one output frame per motion frame
/// (output frame 0 is the state after the warm-up), each made of `opts.substeps`
/// implicit-Euler steps with the body interpolated continuously in between. `progress`
/// is told of each warm-up frame and each output frame (progress bars). At most
/// [`MAX_WARMUP_FRAMES`] warm-up frames and 1 to [`MAX_SUBSTEPS`] sub-steps.
pub fn simulate_sequence(
    garment: &TriMesh,
    material: &Material,
    body: &BodyModel,
    betas: &[f64],
    motion: &Motion,
    opts: &SequenceOptions,
    progress: &mut dyn FnMut(SequenceProgress<'_>),
) -> Result<SimulatedSequence, SequenceError> {
    if !(1..=MAX_SUBSTEPS).contains(&opts.substeps) {
        return Err(SimError::InvalidParameter {
            what: "sub-steps per frame".into(),
            value: opts.substeps as f64,
            expected: "expected 1 to 100 (MAX_SUBSTEPS)",
        }
        .into());
    }
    if opts.warmup_frames > MAX_WARMUP_FRAMES {
        return Err(SimError::InvalidParameter {
            what: "warm-up frames".into(),
            value: opts.warmup_frames as f64,
            expected: "expected at most 10000 (MAX_WARMUP_FRAMES)",
        }
        .into());
    }
    if let Some(&v) = opts
        .pinned
        .iter()
        .find(|&&v| v as usize >= garment.vertex_count())
    {
        return Err(SimError::InvalidParameter {
            what: format!("pinned vertex (the garment has {})", garment.vertex_count()),
            value: f64::from(v),
            expected: "expected 0-based garment vertex indices",
        }
        .into());
    }
    crate::error::check_nonneg(
        || "maximum initial penetration".into(),
        opts.max_initial_penetration,
        false,
    )?;
    if let Some(i) = garment
        .positions
        .iter()
        .position(|p| !weft_mesh::vec3::is_finite(*p))
    {
        return Err(SimError::InvalidVector {
            what: format!("garment vertex {i}"),
            message: "not finite",
        }
        .into());
    }
    if let Some(start) = &opts.start_positions {
        if start.len() != garment.vertex_count() {
            return Err(SimError::InvalidParameter {
                what: format!(
                    "start_positions: number of positions (the garment has {} vertices)",
                    garment.vertex_count()
                ),
                value: start.len() as f64,
                expected: "expected one start position per garment vertex",
            }
            .into());
        }
        if let Some(i) = start.iter().position(|p| !weft_mesh::vec3::is_finite(*p)) {
            return Err(SimError::InvalidVector {
                what: format!("start_positions[{i}]"),
                message: "not finite",
            }
            .into());
        }
    }
    let frames = opts
        .max_frames
        .map_or(motion.frame_count(), |m| m.min(motion.frame_count()));
    if frames == 0 {
        return Ok(SimulatedSequence::default());
    }
    let timeline = Timeline {
        model: body,
        shaped: body.shaped(betas)?,
        motion,
        warmup: opts.warmup_frames,
        frames,
        skinning: opts.skinning,
    };
    let dt = 1.0 / (motion.fps() * opts.substeps as f64);
    let eps = opts.sim.collision_eps;

    // The garment at the start: the rest mesh (or the start positions) carried to frame
    // 0's root translation, checked against (and pushed out of) the body at key frame 0.
    let mut body_prev = timeline.body(0)?;
    let mut posed = PosedBody::new(&body_prev, body.faces())?
        .with_query_radius(opts.sim.contact_radius.max(opts.sim.friction_radius))?;
    let t0 = motion.trans()[0].map(f64::from);
    let mut start = garment.clone();
    if let Some(p) = &opts.start_positions {
        start.positions.clone_from(p);
    }
    for p in &mut start.positions {
        *p = add_scaled(*p, t0, 1.0);
    }
    check_garment_gap(posed.signed_distances(&start.positions)?)?;
    let pushed_out = push_out(
        &posed,
        &mut start.positions,
        eps,
        opts.max_initial_penetration,
    )?;
    // The rest shape stays the garment as given (translation does not change it).
    let model = ClothModel::uniform(garment, material, opts.sim)?.with_buttons(&opts.buttons)?;
    let mut sim = ClothSimulator::from_model(model)?;
    let zero = vec![[0.0; 3]; start.positions.len()];
    sim.set_state(start.positions.clone(), zero)?;
    let mut held = opts.attachment.vertices(garment);
    held.extend_from_slice(&opts.pinned);
    held.sort_unstable();
    held.dedup();
    let anchors = SkinAnchors::new(posed.surface(), &start.positions, &held)?;
    sim.pin(anchors.vertices())?;
    let strain = EdgeStrain::new(garment);

    let mut out = SimulatedSequence {
        frames: Vec::with_capacity(frames),
        stats: Vec::with_capacity(frames),
        pushed_out,
    };
    let mut frame_stats = FrameStats::default();
    let mut clock = Instant::now();
    let mut body_now = Vec::new();
    // Key frame `warmup` is output frame 0; with no warm-up it is the start state.
    let first_output = timeline.warmup;
    if first_output == 0 {
        finish_frame(
            &sim,
            &posed,
            &strain,
            eps,
            0,
            &mut frame_stats,
            clock,
            &mut out,
        )?;
        progress(SequenceProgress::Frame(&frame_stats));
        frame_stats = FrameStats::default();
        clock = Instant::now();
    }
    for k in 1..timeline.len() {
        let output = k.saturating_sub(first_output);
        let buttoned = sim.model().buttons().is_some();
        if buttoned && k >= first_output && opts.unbutton_at.is_some_and(|f| output >= f) {
            sim.unbutton();
        }
        let body_next = timeline.body(k)?;
        for s in 1..=opts.substeps {
            lerp_into(
                &body_prev,
                &body_next,
                s as f64 / opts.substeps as f64,
                &mut body_now,
            );
            posed.refit(&body_now)?;
            for (&v, t) in anchors
                .vertices()
                .iter()
                .zip(anchors.targets(&body_now, body.faces()))
            {
                sim.move_pin(v, t)?;
            }
            match sim.step(dt, Some(&posed)) {
                Ok(r) => {
                    frame_stats.newton_iterations += r.newton.iterations;
                    frame_stats.cg_iterations += r.newton.cg_iterations;
                }
                Err(SimError::Diverged { message }) => {
                    let message = if k < first_output {
                        format!("warm-up frame {k} of {first_output}, sub-step {s}: {message}")
                    } else {
                        format!("sub-step {s}: {message}")
                    };
                    return Err(SequenceError::Diverged {
                        frame: output,
                        message,
                        finished: out,
                    });
                }
                Err(e) => return Err(e.into()),
            }
        }
        body_prev = body_next;
        if k >= first_output {
            finish_frame(
                &sim,
                &posed,
                &strain,
                eps,
                output,
                &mut frame_stats,
                clock,
                &mut out,
            )?;
            progress(SequenceProgress::Frame(&frame_stats));
            frame_stats = FrameStats::default();
            clock = Instant::now();
        } else {
            progress(SequenceProgress::Warmup {
                done: k,
                total: first_output,
            });
        }
    }
    Ok(out)
}

/// Records the state as output frame `frame`.
#[allow(clippy::too_many_arguments)]
fn finish_frame(
    sim: &ClothSimulator,
    posed: &PosedBody,
    strain: &EdgeStrain,
    eps: f64,
    frame: usize,
    stats: &mut FrameStats,
    clock: Instant,
    out: &mut SimulatedSequence,
) -> Result<(), SimError> {
    let x = sim.positions();
    let (max, mean) = strain.of(x);
    let pen: Penetration = posed.penetration(x, eps)?;
    stats.frame = frame;
    stats.energy = potential_energy(sim)?;
    stats.max_edge_strain = max;
    stats.mean_edge_strain = mean;
    stats.penetrations = pen.count;
    stats.max_penetration = pen.max_depth;
    stats.seconds = clock.elapsed().as_secs_f64();
    out.frames
        .push(x.iter().map(|p| p.map(|c| c as f32)).collect());
    out.stats.push(stats.clone());
    Ok(())
}

/// Moves garment vertices that are inside the body out to the surface plus `eps` along
/// the contact normal; refuses (before moving anything) if one is deeper than `limit`.
/// Returns how many were moved.
fn push_out(
    body: &PosedBody,
    x: &mut [[f64; 3]],
    eps: f64,
    limit: f64,
) -> Result<usize, SequenceError> {
    let pen = body.penetration(x, limit)?;
    if pen.beyond_tolerance > 0 {
        return Err(SequenceError::StartsInside {
            count: pen.count,
            max_depth: pen.max_depth,
            limit,
        });
    }
    if pen.count == 0 {
        return Ok(0);
    }
    let surface = body.surface();
    let mut moved = 0;
    for p in x.iter_mut() {
        let c = surface.closest_point(*p).map_err(SimError::from)?;
        if c.signed_distance < 0.0 {
            *p = add_scaled(c.point, c.normal, eps);
            moved += 1;
        }
    }
    Ok(moved)
}

/// A cone skirt around the hips of a body, for tests and benchmarks of this crate
/// (weft-garment's generators sit above weft-sim): each ring a circle around the
/// body's cross-section at its height, 1 cm clear of it, flaring out below the waist.
#[doc(hidden)]
pub fn test_skirt(body_rest: &[[f64; 3]], around: usize, rings: usize) -> TriMesh {
    let (top, bottom) = (0.08, -0.32);
    let slab = |y: f64| {
        let pts: Vec<[f64; 3]> = body_rest
            .iter()
            .copied()
            .filter(|p| (p[1] - y).abs() < 0.015 && p[0].abs() < 0.3)
            .collect();
        let n = pts.len().max(1) as f64;
        let cx = pts.iter().map(|p| p[0]).sum::<f64>() / n;
        let cz = pts.iter().map(|p| p[2]).sum::<f64>() / n;
        let r = pts
            .iter()
            .map(|p| ((p[0] - cx).powi(2) + (p[2] - cz).powi(2)).sqrt())
            .fold(0.0, f64::max);
        (cx, cz, r)
    };
    let (cx, cz, r_top) = slab(top);
    let mut positions = Vec::with_capacity(rings * around);
    for i in 0..rings {
        let y = top + (bottom - top) * i as f64 / (rings - 1) as f64;
        let (_, _, rb) = slab(y);
        let r = (r_top + 0.01 + 0.25 * (top - y)).max(rb + 0.01);
        for k in 0..around {
            let phi = std::f64::consts::TAU * k as f64 / around as f64;
            positions.push([cx + r * phi.cos(), y, cz - r * phi.sin()]);
        }
    }
    let id = |r: usize, k: usize| (r * around + k % around) as u32;
    let mut faces = Vec::new();
    for r in 0..rings - 1 {
        for k in 0..around {
            faces.push([id(r, k), id(r + 1, k), id(r + 1, k + 1)]);
            faces.push([id(r, k), id(r + 1, k + 1), id(r, k + 1)]);
        }
    }
    TriMesh::new(positions, faces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_motion::{generate, MotionKind, ProceduralParams};

    fn walk(frames: usize) -> Motion {
        let mut p = ProceduralParams::new(MotionKind::Walk);
        p.frames = frames;
        generate(&p).unwrap()
    }

    /// Issue 4 item 7 on a small garment (CI-sized): a silk skirt on the walking default
    /// body ends every frame with no vertex deeper inside the body than the collision
    /// threshold, and a mean |edge strain| below 1 %. The 4 000-vertex figures are in
    /// docs/benchmarks.md (`weft simulate`).
    /// Issue 11: the simulator's parameters go in TOML like every other config.
    #[test]
    fn options_round_trip_through_toml_and_refuse_unknown_keys() {
        let mut o = SequenceOptions {
            skinning: Skinning::Dqs,
            max_frames: Some(7),
            attachment: Attachment::None,
            ..SequenceOptions::default()
        };
        o.sim.bending_scale = crate::BendingScale::DiscreteShells;
        o.sim.newton.hessian = crate::HessianKind::Projected;
        let text = toml::to_string(&o).unwrap();
        assert_eq!(
            toml::from_str::<SequenceOptions>(&text).unwrap(),
            o,
            "{text}"
        );
        let d = SequenceOptions::default();
        assert_eq!(
            toml::from_str::<SequenceOptions>(&toml::to_string(&d).unwrap()).unwrap(),
            d
        );

        // A partial file: what it names changes, everything else keeps its default.
        let partial: SequenceOptions = toml::from_str(
            "substeps = 2\nskinning = \"dqs\"\n[sim]\ncontact_radius = 0.01\n[sim.newton]\nmax_iterations = 4\n",
        )
        .unwrap();
        let mut want = SequenceOptions {
            substeps: 2,
            skinning: Skinning::Dqs,
            ..d
        };
        want.sim.contact_radius = 0.01;
        assert_eq!(partial, want);
        assert_eq!(
            toml::from_str::<SimOptions>("").unwrap(),
            SimOptions::default()
        );

        for (text, key) in [
            ("substep = 2", "substep"),
            ("[sim]\ncontact_radus = 0.01", "contact_radus"),
            ("[sim.newton]\ntolerence = 1e-6", "tolerence"),
        ] {
            let e = toml::from_str::<SequenceOptions>(text)
                .unwrap_err()
                .to_string();
            assert!(e.contains(&format!("unknown field `{key}`")), "{text}: {e}");
        }
        let e = toml::from_str::<SequenceOptions>("skinning = \"lbd\"")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown variant `lbd`"), "{e}");
    }

    #[test]
    fn silk_skirt_walks_without_penetration_or_stretch() {
        let body = weft_body::default_body().unwrap();
        let rest = body.shaped(&[]).unwrap().vertices;
        let skirt = test_skirt(&rest, 32, 10);
        let opts = SequenceOptions {
            warmup_frames: 3,
            ..SequenceOptions::default()
        };
        let mut seen = Vec::new();
        let seq = simulate_sequence(
            &skirt,
            &Material::silk(),
            &body,
            &[],
            &walk(5),
            &opts,
            &mut |p| match p {
                SequenceProgress::Warmup { done, total } => seen.push(format!("w{done}/{total}")),
                SequenceProgress::Frame(s) => seen.push(format!("f{}", s.frame)),
            },
        )
        .unwrap();
        assert_eq!(seen, ["w1/3", "w2/3", "f0", "f1", "f2", "f3", "f4"]);
        assert_eq!(seq.frames.len(), 5);
        assert_eq!(seq.frames[0].len(), skirt.vertex_count());
        for s in &seq.stats {
            if std::env::var_os("WEFT_SIM_TRACE").is_some() {
                eprintln!("{s:?}");
            }
            assert!(s.max_penetration <= opts.sim.collision_eps, "{s:?}");
            assert!(s.mean_edge_strain < 0.01, "{s:?}");
            assert!(s.newton_iterations > 0 && s.energy.is_finite());
        }
        // The skirt moves with the body (walking forward along +Z).
        let z = |f: &Vec<[f32; 3]>| f.iter().map(|p| p[2]).sum::<f32>() / f.len() as f32;
        assert!(z(&seq.frames[4]) > z(&seq.frames[0]) + 0.05);
    }

    /// What `simulate_sequence` refuses a small skirt on the default body with, before
    /// any frame starts (`edit` changes the skirt).
    fn refusal(edit: impl FnOnce(&mut TriMesh), opts: &SequenceOptions) -> String {
        let body = weft_body::default_body().unwrap();
        let rest = body.shaped(&[]).unwrap().vertices;
        let mut skirt = test_skirt(&rest, 8, 3);
        edit(&mut skirt);
        simulate_sequence(
            &skirt,
            &Material::cotton(),
            &body,
            &[],
            &walk(2),
            opts,
            &mut |_| panic!("no frame may start"),
        )
        .unwrap_err()
        .to_string()
    }

    /// Issue 17 item 6: a garment a kilometre from the body is refused, not simulated
    /// falling beside it.
    #[test]
    fn a_garment_far_from_the_body_is_refused() {
        let far = |skirt: &mut TriMesh| {
            for p in &mut skirt.positions {
                p[0] += 1000.0;
            }
        };
        let e = refusal(far, &SequenceOptions::default());
        assert!(
            e.contains("nearest vertex is 99") && e.contains("m from the body"),
            "{e}"
        );
    }

    /// Issue 17 item 8: a warm-up or sub-steps past their bounds are refused before any
    /// work.
    #[test]
    fn an_endless_warm_up_or_substepping_is_refused() {
        let opts = SequenceOptions {
            warmup_frames: 1_000_000_000,
            ..SequenceOptions::default()
        };
        let e = refusal(|_| {}, &opts);
        assert!(
            e.contains("warm-up frames") && e.contains("at most 10000"),
            "{e}"
        );
        let opts = SequenceOptions {
            substeps: 1_000_000,
            ..SequenceOptions::default()
        };
        let e = refusal(|_| {}, &opts);
        assert!(e.contains("sub-steps") && e.contains("1 to 100"), "{e}");
    }

    /// Issue 18 item 3: pinned vertices follow the skin exactly as the attachment's do
    /// (pinning the top opening by hand gives the attachment's frames bit for bit), and
    /// an index past the garment is refused before any frame.
    #[test]
    fn pinned_vertices_follow_the_skin_like_the_attachment() {
        let body = weft_body::default_body().unwrap();
        let rest = body.shaped(&[]).unwrap().vertices;
        let skirt = test_skirt(&rest, 16, 4);
        let run = |opts: &SequenceOptions| {
            simulate_sequence(
                &skirt,
                &Material::cotton(),
                &body,
                &[],
                &walk(3),
                opts,
                &mut |_| {},
            )
            .unwrap()
            .frames
        };
        let attached = SequenceOptions {
            warmup_frames: 1,
            substeps: 2,
            ..SequenceOptions::default()
        };
        let pinned = SequenceOptions {
            attachment: Attachment::None,
            pinned: crate::attachment::top_opening(&skirt),
            ..attached.clone()
        };
        assert!(!pinned.pinned.is_empty());
        assert_eq!(run(&attached), run(&pinned));
        let free = SequenceOptions {
            attachment: Attachment::None,
            ..attached.clone()
        };
        assert_ne!(run(&attached), run(&free));

        let bad = SequenceOptions {
            pinned: vec![0, skirt.vertex_count() as u32],
            ..SequenceOptions::default()
        };
        let e = refusal(|_| {}, &bad);
        assert!(e.contains("pinned vertex (the garment has"), "{e}");
        let text = "attachment = \"none\"\npinned = [3, 1, 2]\n";
        let o: SequenceOptions = toml::from_str(text).unwrap();
        assert_eq!((o.attachment, o.pinned), (Attachment::None, vec![3, 1, 2]));
    }

    /// Issue 14: a garment started from other positions than its rest shape (here its
    /// rest shape scaled by 1.03 about its centre, as a garment made for a slimmer body
    /// sits on a fuller one) keeps its rest shape: frame 0 (no warm-up: the start state)
    /// measures about 3 % strain against it, and the cloth relaxes back toward its rest
    /// edge lengths. `None` and the rest mesh itself give the same frames; a wrong count
    /// or a non-finite start position is refused naming the field.
    #[test]
    fn start_positions_start_the_garment_away_from_its_rest_shape() {
        let body = weft_body::default_body().unwrap();
        let rest = body.shaped(&[]).unwrap().vertices;
        let skirt = test_skirt(&rest, 16, 4);
        let n = skirt.vertex_count() as f64;
        let centre = skirt
            .positions
            .iter()
            .fold([0.0; 3], |s, p| add_scaled(s, *p, 1.0 / n));
        let scaled: Vec<[f64; 3]> = skirt
            .positions
            .iter()
            .map(|p| std::array::from_fn(|k| centre[k] + 1.03 * (p[k] - centre[k])))
            .collect();
        let base = SequenceOptions {
            warmup_frames: 0,
            substeps: 2,
            ..SequenceOptions::default()
        };
        let run = |start: Option<Vec<[f64; 3]>>| {
            let opts = SequenceOptions {
                start_positions: start,
                ..base.clone()
            };
            simulate_sequence(
                &skirt,
                &Material::cotton(),
                &body,
                &[],
                &walk(8),
                &opts,
                &mut |_| {},
            )
        };
        let seq = run(Some(scaled)).unwrap();
        let strain: Vec<f64> = seq.stats.iter().map(|s| s.mean_edge_strain).collect();
        assert!((strain[0] - 0.03).abs() < 1e-3, "{strain:?}");
        assert!(strain[7] < 0.5 * strain[0], "{strain:?}");
        assert!(seq.stats.iter().all(|s| s.energy.is_finite()));

        let plain = run(None).unwrap();
        assert!(
            plain.stats[0].mean_edge_strain < 0.1 * strain[0],
            "{:?}",
            plain.stats[0]
        );
        assert_eq!(
            plain.frames,
            run(Some(skirt.positions.clone())).unwrap().frames
        );

        let e = run(Some(vec![[0.0; 3]; 3])).unwrap_err().to_string();
        assert!(
            e.contains("start_positions") && e.contains("one start position per garment vertex"),
            "{e}"
        );
        let mut nan = skirt.positions.clone();
        nan[5][1] = f64::NAN;
        let e = run(Some(nan)).unwrap_err().to_string();
        assert!(e.contains("start_positions[5]: not finite"), "{e}");
    }

    /// A step that diverges ends the run with the frame named and the finished frames
    /// kept.
    #[test]
    fn divergence_keeps_finished_frames() {
        let body = weft_body::default_body().unwrap();
        let rest = body.shaped(&[]).unwrap().vertices;
        let skirt = test_skirt(&rest, 16, 4);
        let mut opts = SequenceOptions {
            warmup_frames: 0,
            substeps: 1,
            ..SequenceOptions::default()
        };
        // Any motion at all counts as divergence.
        opts.sim.max_speed = 1e-9;
        let r = simulate_sequence(
            &skirt,
            &Material::cotton(),
            &body,
            &[],
            &walk(3),
            &opts,
            &mut |_| {},
        );
        match r {
            Err(SequenceError::Diverged {
                frame,
                message,
                finished,
            }) => {
                assert_eq!(frame, 1);
                assert_eq!(finished.frames.len(), 1);
                assert!(message.contains("speed"), "{message}");
            }
            other => panic!("expected divergence, got {other:?}"),
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let body = weft_body::default_body().unwrap();
        let rest = body.shaped(&[]).unwrap().vertices;
        let skirt = test_skirt(&rest, 16, 4);
        let motion = walk(2);
        let run = |g: &TriMesh, m: &Material, o: &SequenceOptions| {
            simulate_sequence(g, m, &body, &[], &motion, o, &mut |_| {})
        };
        let opts = SequenceOptions::default();
        // Degenerate triangle.
        let mut degenerate = skirt.clone();
        let [a, b, _] = degenerate.faces[5];
        degenerate.positions[b as usize] = degenerate.positions[a as usize];
        assert!(matches!(
            run(&degenerate, &Material::silk(), &opts),
            Err(SequenceError::Input(SimError::DegenerateTriangle { .. }))
        ));
        // Zero and negative material values.
        for (density, young) in [(0.0, 1e6), (0.1, -1e6)] {
            let m = Material {
                density,
                young_modulus: young,
                ..Material::silk()
            };
            assert!(matches!(
                run(&skirt, &m, &opts),
                Err(SequenceError::Input(SimError::InvalidParameter { .. }))
            ));
        }
        // No sub-steps, or more than MAX_SUBSTEPS; non-finite garment.
        for substeps in [0, MAX_SUBSTEPS + 1] {
            let bad = SequenceOptions {
                substeps,
                ..opts.clone()
            };
            assert!(matches!(
                run(&skirt, &Material::silk(), &bad),
                Err(SequenceError::Input(SimError::InvalidParameter { .. }))
            ));
        }
        let mut nan = skirt.clone();
        nan.positions[3][0] = f64::NAN;
        assert!(matches!(
            run(&nan, &Material::silk(), &opts),
            Err(SequenceError::Input(SimError::InvalidVector { .. }))
        ));
        // Starting inside the body: refused beyond the limit, pushed out below it.
        let mut inside = skirt.clone();
        for p in &mut inside.positions {
            p[0] *= 0.5;
            p[2] *= 0.5;
        }
        let e = run(&inside, &Material::silk(), &opts).unwrap_err();
        assert!(
            matches!(e, SequenceError::StartsInside { count, .. } if count > 0),
            "{e}"
        );
        assert!(e.to_string().contains("inside the body"));
        let lenient = SequenceOptions {
            max_initial_penetration: 1.0,
            max_frames: Some(1),
            warmup_frames: 0,
            ..opts
        };
        let seq = run(&inside, &Material::silk(), &lenient).unwrap();
        assert!(seq.pushed_out > 0);
        assert!(seq.stats[0].max_penetration <= 1e-9, "{:?}", seq.stats[0]);
    }
}
