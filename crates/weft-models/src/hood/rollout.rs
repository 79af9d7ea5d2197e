//! From the network's output to the garment at t + 1 (seed 004 §3.3; hood-reference
//! §1.6): the decoder's acceleration `a` (scaled back by the output normaliser, metres
//! per frame²) gives `x_{t+1} = x_t + (x_t − x_{t−1}) + a` for free vertices; pinned
//! vertices go to their targets. The same tensor expression serves training (the loss
//! differentiates through it) and inference, so they cannot drift apart.

use burn::tensor::{Device, Tensor, TensorData};
use weft_garment::onbody::push_out;
use weft_mesh::vec3;
use weft_sim::{project_contacts, FaceContact, StrainBounds, StrainLimit};

use super::config::HoodConfig;
use super::features::GarmentStep;
use super::garment::HoodGarment;
use super::model::{HoodBatch, InferHood};
use super::scene::{Scene, StateRef, StepAt};
use super::stats::HoodStats;
use crate::error::ModelError;

/// What a step adds the acceleration to: `x_t + v_t` (free) or the target (pinned), and
/// which vertices take the acceleration.
#[derive(Clone, Debug, PartialEq)]
pub struct Advance {
    /// `x_t + (x_t − x_{t−1})` for free vertices, the target for pinned ones, flattened.
    pub base: Vec<f32>,
    /// 1 for free vertices, 0 for pinned ones.
    pub free: Vec<f32>,
}

impl Advance {
    /// The advance of `garment` from `state`.
    pub fn new(garment: &HoodGarment, state: &GarmentStep) -> Self {
        let n = garment.vertex_count();
        let mut base = Vec::with_capacity(3 * n);
        let mut free = Vec::with_capacity(n);
        for i in 0..n {
            if garment.pinned[i] {
                base.extend(state.pin_targets[i].map(|x| x as f32));
                free.push(0.0);
            } else {
                let (c, p) = (state.cur[i], state.prev[i]);
                base.extend((0..3).map(|k| (2.0 * c[k] - p[k]) as f32));
                free.push(1.0);
            }
        }
        Advance { base, free }
    }

    /// The inertial target `x̂ = x_t + v_t` of the incremental potential (the base, with
    /// pinned vertices at their targets), in f64.
    pub fn inertial_target(&self) -> Vec<[f64; 3]> {
        self.base
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]].map(f64::from))
            .collect()
    }
}

/// `x_{t+1}` of every garment of a batch, `[Σ N, 3]`, from the network's normalised
/// output `out` (rows in the same order as `advances`).
pub fn next_positions(
    out: Tensor<2>,
    advances: &[&Advance],
    stats: &HoodStats,
    device: &Device,
) -> Result<Tensor<2>, ModelError> {
    let rows: usize = advances.iter().map(|a| a.free.len()).sum();
    if out.dims() != [rows, 3] {
        return Err(ModelError::mismatch(
            "HOOD output",
            format!("[{rows}, 3]"),
            format!("{:?}", out.dims()),
        ));
    }
    let base: Vec<f32> = advances
        .iter()
        .flat_map(|a| a.base.iter().copied())
        .collect();
    let free: Vec<f32> = advances
        .iter()
        .flat_map(|a| a.free.iter().copied())
        .collect();
    let base = Tensor::<2>::from_data(TensorData::new(base, [rows, 3]), device);
    let free = Tensor::<2>::from_data(TensorData::new(free, [rows, 1]), device);
    let std = Tensor::<2>::from_data(TensorData::new(stats.output.std.clone(), [1, 3]), device);
    let mean = Tensor::<2>::from_data(TensorData::new(stats.output.mean.clone(), [1, 3]), device);
    let a = out * std + mean;
    Ok(base + a * free)
}

/// How a rollout runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RolloutOptions {
    /// Button edges are removed from this frame on (`None`: kept throughout).
    pub unbutton_at: Option<usize>,
    /// A step that moves a vertex faster than this (m/s), or to a non-finite position,
    /// stops that rollout: the finished frames are kept.
    pub max_speed: f64,
    /// Run-time strain limiting: after every step, edges longer than `1 + stretch` rest
    /// lengths are shortened to it, and edges shorter than `1 − compression` lengthened
    /// to it ([`StrainLimit`], [`STRAIN_LIMIT_SWEEPS`] sweeps). Unbounded both ways
    /// (the default): the network's step as it is (HOOD).
    pub strain_limit: StrainBounds,
    /// Run-time contact projection: after every step (and after the strain limit),
    /// vertices nearer than this (m) to the collision term's contact planes, or behind
    /// them, move onto them at this distance ([`project_contacts`], with the friction
    /// of the garment's material against the body points they touched), the faces that
    /// a body vertex came through in the step are pushed off it ([`FaceContact`]), and
    /// free vertices still inside the body or nearer to it then move to its closest
    /// point plus this distance. `None`: off (HOOD).
    pub contact_margin: Option<f64>,
    /// Whether a bound left unset above takes the model's own step projection
    /// ([`HoodConfig::project_stretch`] and its siblings; on by default, so a run
    /// trained with a projection rolls out with it). Off (`--no-projection`): only the
    /// bounds set here.
    pub projection: bool,
    /// Newton iterations of the step's incremental potential (the objective the
    /// network is trained to minimise) after every network step, started from the
    /// network's prediction, before the corrections ([`Scene::refine_step`]). 0 (the
    /// default): the network's step as it is (HOOD).
    pub refine: usize,
    /// Roll out the run's objective instead of its network: every step is weft-sim's
    /// implicit Euler step of the incremental potential the network is trained on (up
    /// to [`OBJECTIVE_ITERATIONS`] Newton iterations from inertia), then the same
    /// corrections. What the network would give were it exact, from the same start.
    pub objective: bool,
}

/// Newton iterations of a step of [`RolloutOptions::objective`]: weft-sim's own budget
/// for one implicit step ([`weft_sim::NewtonOptions`]' default).
pub const OBJECTIVE_ITERATIONS: usize = 50;

impl Default for RolloutOptions {
    fn default() -> Self {
        RolloutOptions {
            unbutton_at: None,
            max_speed: 50.0,
            strain_limit: StrainBounds::default(),
            contact_margin: None,
            projection: true,
            refine: 0,
            objective: false,
        }
    }
}

impl RolloutOptions {
    /// These options over the step projection of a model of `config`: a bound set here
    /// wins, one left unset takes the model's (while [`RolloutOptions::projection`]).
    pub fn over(&self, config: &HoodConfig) -> Self {
        if !self.projection {
            return *self;
        }
        let bounds = &self.strain_limit;
        RolloutOptions {
            strain_limit: StrainBounds {
                stretch: bounds.stretch.or(config.project_stretch),
                compression: bounds.compression.or(config.project_compression),
            },
            contact_margin: self.contact_margin.or(config.project_margin),
            ..*self
        }
    }

    /// Whether any correction runs after a step.
    pub fn corrects(&self) -> bool {
        self.strain_limit.any() || self.contact_margin.is_some()
    }
}

/// Gauss–Seidel sweeps of [`RolloutOptions::strain_limit`] at most per step (they stop
/// when no edge is over the limit). A chain of edges from a pinned waist to a hem needs
/// many: with a 10 % limit, a skirt falling at 1 cm per frame² (the test below) ends
/// five steps with its longest edge 33 % over its rest length after 20 sweeps a step,
/// 12 % after 100. A few milliseconds a frame on a 1 000-vertex garment.
pub const STRAIN_LIMIT_SWEEPS: usize = 100;

/// Rounds of strain limiting ([`ROUND_SWEEPS`] sweeps) and contact projection after
/// the first of each, when a rollout has both. A vertex the projection moves then
/// drags its neighbours along instead of stretching the edges to them: with one pass
/// of each, a sleeve's edges next to a contact ended steps 7 rest lengths over
/// (docs/hood.md item 11).
pub const CONTACT_ROUNDS: usize = 5;

/// Passes of the face contacts ([`FaceContact`]) after the last round (one in each
/// round): a moved face can uncover the next body vertex.
pub const FACE_PASSES: usize = 3;

/// Gauss–Seidel sweeps of the strain limit in each of [`CONTACT_ROUNDS`].
pub const ROUND_SWEEPS: usize = 10;

/// What the run-time corrections of a rollout did, summed over its steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Corrections {
    /// Edges outside [`RolloutOptions::strain_limit`] after the network's step, before
    /// they were corrected (not counted again in [`CONTACT_ROUNDS`]).
    pub edges_limited: usize,
    /// Vertex positions moved onto a contact plane or out of the body by
    /// [`RolloutOptions::contact_margin`] (the first projection and the push-out; not
    /// counted again in [`CONTACT_ROUNDS`]).
    pub vertices_projected: usize,
}

/// One scene's rollout: the garment at every frame it reached, and why it stopped early
/// if it did.
#[derive(Clone, Debug, PartialEq)]
pub struct Rollout {
    /// Garment positions per frame (frame 0: the settled garment).
    pub frames: Vec<Vec<[f64; 3]>>,
    /// The frame at which the rollout diverged, with what happened.
    pub stopped: Option<(usize, String)>,
    /// What [`RolloutOptions`]' run-time corrections did.
    pub corrections: Corrections,
}

/// One HOOD step of several states at once (one disjoint graph): `x_{t+1}` of each.
pub fn step_batch(
    model: &InferHood,
    stats: &HoodStats,
    steps: &[(&super::features::StepGraph, &Advance)],
    device: &Device,
) -> Result<Vec<Vec<[f64; 3]>>, ModelError> {
    let graphs: Vec<_> = steps.iter().map(|s| s.0).collect();
    let advances: Vec<_> = steps.iter().map(|s| s.1).collect();
    let out = model.forward(&HoodBatch::new(&graphs, stats)?)?;
    let rows = out.len() / 3;
    let out = Tensor::<2>::from_data(TensorData::new(out, [rows, 3]), device);
    let x = next_positions(out, &advances, stats, device)?;
    let mut rows = host_positions(&x)?.into_iter();
    Ok(advances
        .iter()
        .map(|a| rows.by_ref().take(a.free.len()).collect())
        .collect())
}

/// The rows of a `[N, 3]` positions tensor on the host, in f64.
pub fn host_positions(x: &Tensor<2>) -> Result<Vec<[f64; 3]>, ModelError> {
    let flat: Vec<f32> = x
        .to_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .map_err(|e| ModelError::Config(format!("HOOD output: {e:?}")))?;
    Ok(flat
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]].map(f64::from))
        .collect())
}

/// Why `next` is not an acceptable step from `cur` over `dt` seconds, if it is not.
fn diverged(cur: &[[f64; 3]], next: &[[f64; 3]], dt: f64, max_speed: f64) -> Option<String> {
    let mut fastest = (0.0f64, 0usize);
    for (i, (a, b)) in cur.iter().zip(next).enumerate() {
        if !b.iter().all(|x| x.is_finite()) {
            return Some(format!("vertex {i} has a non-finite position"));
        }
        let d = vec3::dist(*a, *b) / dt;
        if d > fastest.0 {
            fastest = (d, i);
        }
    }
    (fastest.0 > max_speed).then(|| {
        format!(
            "vertex {} moved at {:.1} m/s (limit {max_speed} m/s)",
            fastest.1, fastest.0
        )
    })
}

/// `options`' run-time corrections of one scene's steps (its strain limiter built once):
/// what a rollout does after each network step, and what training does after each step
/// of a model whose step ends in a projection.
pub struct Corrector<'a> {
    scene: &'a Scene,
    limiter: Option<StrainLimit>,
    /// The limiter with the garment's button pairs held closed, for buttoned steps.
    buttoned: Option<StrainLimit>,
    faces: Option<FaceContact>,
    options: RolloutOptions,
}

impl<'a> Corrector<'a> {
    /// The corrections `options` asks for on `scene`'s garment.
    pub fn new(scene: &'a Scene, options: &RolloutOptions) -> Result<Self, ModelError> {
        let g = &scene.garment;
        let limiter = match options.strain_limit.any() {
            true => Some(
                StrainLimit::new(&g.rest, &g.masses, &g.pinned)
                    .map_err(|e| ModelError::Garment(format!("the strain limit: {e}")))?,
            ),
            false => None,
        };
        // The strain limit holds the buttons as stiff as the fabric, as the simulator's
        // buttons are (weft-sim's `StrainLimit::with_buttons`): a buttoned front stays
        // closed where the network alone leaves its pairs centimetres apart.
        // (The garment's button edges run both ways; the limiter takes each pair once.)
        let pairs: Vec<[u32; 2]> = g.buttons.iter().filter(|p| p[0] < p[1]).copied().collect();
        let buttoned = match (&limiter, pairs.is_empty()) {
            (Some(limiter), false) => Some(
                limiter
                    .with_buttons(&pairs)
                    .map_err(|e| ModelError::Garment(format!("the strain limit: {e}")))?,
            ),
            _ => None,
        };
        let faces = match options.contact_margin {
            Some(_) => Some(
                FaceContact::new(&g.rest, &g.pinned, &scene.omit)
                    .map_err(|e| ModelError::Garment(format!("the face contacts: {e}")))?,
            ),
            None => None,
        };
        Ok(Corrector {
            scene,
            limiter,
            buttoned,
            faces,
            options: *options,
        })
    }

    /// The corrections of the step `at` from `cur` to `next`: the strain limit (holding
    /// the button pairs closed while `at` is buttoned), then
    /// the contact projection against the planes the collision term uses (found from
    /// `cur`, on the swept body when the run uses swept contacts, so a limb that passed
    /// through the cloth in the step pushes it back to its side, and the material's
    /// friction carries it on with the limb), with both given [`CONTACT_ROUNDS`] rounds
    /// of the two (and of the face contacts) and a last limit, then the face contacts
    /// ([`FACE_PASSES`]) and the push-out of what is still inside. The rollout goes on
    /// from the corrected positions.
    pub fn correct(
        &self,
        cur: &[[f64; 3]],
        at: StepAt,
        next: &mut [[f64; 3]],
    ) -> Result<Corrections, ModelError> {
        let (scene, options) = (self.scene, &self.options);
        let mut done = Corrections::default();
        let failed = |what: &str, e: weft_sim::SimError| {
            ModelError::Garment(format!("{what} of frame {}: {e}", at.t + 1))
        };
        let limiter = match at.buttoned {
            true => self.buttoned.as_ref().or(self.limiter.as_ref()),
            false => self.limiter.as_ref(),
        };
        let limit = |x: &mut [[f64; 3]], sweeps: usize| match limiter {
            Some(limiter) => limiter
                .apply(x, options.strain_limit, sweeps)
                .map(|report| report.edges_outside)
                .map_err(|e| failed("the strain limit", e)),
            None => Ok(0),
        };
        done.edges_limited = limit(next, STRAIN_LIMIT_SWEEPS)?;
        if let Some(margin) = options.contact_margin {
            let bodies = scene.step_bodies(at)?;
            let end = &bodies.end;
            let contacts = scene
                .cloth_at(at)
                .contacts(cur, &scene.garment.pinned, Some(bodies.contact.as_ref()))
                .map_err(|e| failed("the contacts", e))?;
            let project = |x: &mut [[f64; 3]]| {
                project_contacts(x, &contacts.collision, &contacts.grips, margin)
                    .map_err(|e| failed("the contact projection", e))
            };
            // What came through the cloth between its vertices (a knee through a
            // triangle whose corners are all outside): its faces pushed off the body.
            let step = match &self.faces {
                Some(faces) => {
                    let step = faces.step(cur, bodies.start.surface(), end.surface());
                    Some(step.map_err(|e| failed("the face contacts", e))?)
                }
                None => None,
            };
            let faces = |x: &mut [[f64; 3]], passes: usize| match (&self.faces, &step) {
                (Some(faces), Some(step)) => faces
                    .apply(step, x, end.surface(), margin, passes)
                    .map_err(|e| failed("the face contacts", e)),
                _ => Ok(0),
            };
            done.vertices_projected = project(next)?;
            if self.limiter.is_some() {
                for _ in 0..CONTACT_ROUNDS {
                    limit(next, ROUND_SWEEPS)?;
                    project(next)?;
                    faces(next, 1)?;
                }
                // The limit has the last word before the push-out: ending the rounds on
                // the projection left a hem vertex that rested on a foot held to it by
                // its grip, 3.5 rest lengths from its neighbours (docs/hood.md item 12).
                limit(next, ROUND_SWEEPS)?;
            }
            // The faces once more before the push-out, which moves out any corner they
            // pushed into another part of the body (a thigh into the other in a crouch).
            done.vertices_projected += faces(next, FACE_PASSES)?;
            // What no plane reached (a vertex farther than the contact radius at t that
            // the step, the strain limit or the faces moved into the body): the closest
            // surface point at t + 1. Pinned vertices keep their targets.
            let free: Vec<usize> = (0..next.len())
                .filter(|&i| !scene.garment.pinned[i])
                .collect();
            let mut points: Vec<[f64; 3]> = free.iter().map(|&i| next[i]).collect();
            done.vertices_projected +=
                push_out(end.surface(), &mut points, margin).map_err(|e| {
                    ModelError::Garment(format!("pushing frame {} out of the body: {e}", at.t + 1))
                })?;
            for (&i, p) in free.iter().zip(points) {
                next[i] = p;
            }
        }
        Ok(done)
    }
}

/// HOOD rolled out over every frame of each scene, the scenes advanced together (one
/// forward pass per frame for the whole batch).
///
/// Frame 0 is the skinned, pushed-out garment after the settling step (as it is, when
/// [`HoodConfig::settle_dt`] is 0); frame `t + 1`
/// comes from frames `t − 1` and `t` and the body at `t − 1`, `t`, `t + 1`. After the
/// settling step the garment starts at rest (zero velocity): HOOD's code feeds the
/// settling displacement, taken over 1/3 s, in as the next step's per-frame velocity,
/// ten times too fast for a 1/30 s step. Without one it starts with the skinned
/// garment's velocity from frame 0 to 1: a motion that starts mid-stride would
/// otherwise meet a garment at rest with a body moving at full speed, and a run's
/// thighs go through the front of a skirt in the first step (docs/hood.md item 9).
pub fn roll_out(
    model: &InferHood,
    stats: &HoodStats,
    config: &HoodConfig,
    scenes: &[&Scene],
    options: &RolloutOptions,
    device: &Device,
) -> Result<Vec<Rollout>, ModelError> {
    let options = &options.over(config);
    // Whether the step that ends at frame `t` of scene `k` is buttoned: `unbutton_at`
    // counts the motion's frames, the first step that ends at or after it is not.
    let buttoned = |k: usize, t: usize| {
        options
            .unbutton_at
            .is_none_or(|f| (t as f64) < f as f64 * scenes[k].steps_per_frame() - 1e-9)
    };
    // The step's prediction: the network's, or inertia's for the objective (whose
    // Newton iterations then take the whole step).
    let predict = |steps: &[(super::features::StepGraph, Advance)]| match options.objective {
        true => Ok(steps.iter().map(|(_, a)| a.inertial_target()).collect()),
        false => {
            let pairs: Vec<_> = steps.iter().map(|(g, a)| (g, a)).collect();
            step_batch(model, stats, &pairs, device)
        }
    };
    let iterations = match options.objective {
        true => OBJECTIVE_ITERATIONS.max(options.refine),
        false => options.refine,
    };
    let mut starts = Vec::with_capacity(scenes.len());
    for s in scenes {
        starts.push(s.start(0, true)?);
    }
    let settled = if config.settle_dt > 0.0 {
        let at = StepAt {
            t: 0,
            settle: true,
            dt: config.settle_dt,
            buttoned: true,
        };
        let states = scenes
            .iter()
            .zip(&starts)
            .enumerate()
            .map(|(k, (s, start))| {
                let buttoned = buttoned(k, 0);
                s.step(start.as_ref(), StepAt { buttoned, ..at }, config)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let predicted = predict(&states)?;
        let mut settled = Vec::with_capacity(scenes.len());
        for (k, ((s, start), x)) in scenes.iter().zip(&starts).zip(predicted).enumerate() {
            settled.push(match iterations {
                0 => x,
                n => {
                    let at = StepAt {
                        buttoned: buttoned(k, 0),
                        ..at
                    };
                    let body = s.contact_body(at)?;
                    s.refine_step(start.as_ref(), at, body.as_ref(), &x, n)?
                }
            });
        }
        settled
    } else {
        starts.into_iter().map(|s| s.cur).collect()
    };
    // Frame -1 of each scene: frame 0 less the skinned garment's first displacement.
    let before: Vec<Vec<[f64; 3]>> = scenes
        .iter()
        .zip(&settled)
        .map(|(s, x)| {
            if config.settle_dt > 0.0 {
                return x.clone();
            }
            let (s0, s1) = (s.pin_targets(0), s.pin_targets(1));
            x.iter()
                .zip(s0.iter().zip(&s1))
                .map(|(p, (a, b))| std::array::from_fn(|k| p[k] - (b[k] - a[k])))
                .collect()
        })
        .collect();
    let mut out: Vec<Rollout> = settled
        .into_iter()
        .map(|x| Rollout {
            frames: vec![x],
            stopped: None,
            corrections: Corrections::default(),
        })
        .collect();
    let correctors = scenes
        .iter()
        .map(|s| Corrector::new(s, options))
        .collect::<Result<Vec<_>, _>>()?;
    // Scene k's step from frame t, for its graph and for its corrections alike.
    let step_at = |k: usize, t: usize| StepAt {
        t,
        settle: false,
        dt: scenes[k].dt,
        buttoned: buttoned(k, t + 1),
    };
    let longest = scenes.iter().map(|s| s.frames()).max().unwrap_or(0);
    for t in 0..longest.saturating_sub(1) {
        let active: Vec<usize> = (0..scenes.len())
            .filter(|&k| out[k].stopped.is_none() && t + 1 < scenes[k].frames())
            .collect();
        if active.is_empty() {
            break;
        }
        let mut steps = Vec::with_capacity(active.len());
        for &k in &active {
            let state = state_at(&before[k], &out[k].frames, t);
            steps.push(scenes[k].step(state, step_at(k, t), config)?);
        }
        let next = predict(&steps)?;
        for (&k, x) in active.iter().zip(next) {
            let mut x = match iterations {
                0 => x,
                iterations => {
                    let state = state_at(&before[k], &out[k].frames, t);
                    let at = step_at(k, t);
                    let body = scenes[k].contact_body(at)?;
                    match scenes[k].refine_step(state, at, body.as_ref(), &x, iterations) {
                        Ok(x) => x,
                        Err(e) => {
                            out[k].stopped = Some((t + 1, e.to_string()));
                            continue;
                        }
                    }
                }
            };
            match diverged(&out[k].frames[t], &x, scenes[k].dt, options.max_speed) {
                Some(why) => out[k].stopped = Some((t + 1, why)),
                None => {
                    let done = correctors[k].correct(&out[k].frames[t], step_at(k, t), &mut x)?;
                    out[k].corrections.edges_limited += done.edges_limited;
                    out[k].corrections.vertices_projected += done.vertices_projected;
                    out[k].frames.push(x);
                }
            }
        }
    }
    Ok(out
        .into_iter()
        .zip(scenes)
        .map(|(r, s)| r.motion_frames(s.steps_per_frame(), s.motion_frames))
        .collect())
}

/// A rollout's state at step `t`: its frames `t − 1` and `t`, with `before` (frame −1)
/// for the first step.
fn state_at<'a>(before: &'a [[f64; 3]], frames: &'a [Vec<[f64; 3]>], t: usize) -> StateRef<'a> {
    StateRef {
        prev: if t == 0 { before } else { &frames[t - 1] },
        cur: &frames[t],
    }
}

impl Rollout {
    /// The first `frames` frames of the motion from a rollout of `per_frame` steps a
    /// motion frame: a frame that falls on a step's end is that step's, one between two
    /// steps is interpolated linearly; a divergence is named at the first motion frame
    /// it kept from being reached.
    fn motion_frames(self, per_frame: f64, frames: usize) -> Rollout {
        if per_frame == 1.0 {
            return self;
        }
        let reached = self.frames.len();
        let mut out = Vec::with_capacity(frames);
        for i in 0..frames {
            let at = i as f64 * per_frame;
            let j = at.round() as usize;
            // Within rounding of a step's end: that step's frame.
            if (at - j as f64).abs() < 1e-9 {
                match self.frames.get(j) {
                    Some(x) => out.push(x.clone()),
                    None => break,
                }
                continue;
            }
            let j = at.floor() as usize;
            if j + 1 >= reached {
                break;
            }
            let w = at - j as f64;
            let (a, b) = (&self.frames[j], &self.frames[j + 1]);
            out.push(
                a.iter()
                    .zip(b)
                    .map(|(&a, &b)| vec3::add_scaled(a, vec3::sub(b, a), w))
                    .collect(),
            );
        }
        Rollout {
            stopped: self.stopped.map(|(_, why)| (out.len(), why)),
            frames: out,
            corrections: self.corrections,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deformer::Clip;
    use weft_mesh::primitives::grid;
    use weft_nn::backend::cpu;
    use weft_nn::FeatureNormalizer;

    /// An untrained network predicts no acceleration, so frame 1 shows the velocity the
    /// rollout starts with: the skinned garment's without a settling step, none after
    /// one.
    #[test]
    fn without_a_settling_step_the_garment_starts_with_the_body() {
        use crate::hood::{HoodStats, Materials, Scene};
        use weft_sim::{Attachment, Material};
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let (poses, mut trans) = crate::hood::testutil::still(3);
        for (t, x) in trans.iter_mut().enumerate() {
            x[2] = 0.05 * t as f32;
        }
        let clip = crate::hood::testutil::clip(&poses, &trans);
        let device = cpu();
        let hood = Materials::Uniform(Material::hood());
        for (settle_dt, want) in [(0.0, 0.05), (1.0 / 3.0, 0.0)] {
            let config = HoodConfig::preset("cpu").unwrap().with_settle_dt(settle_dt);
            let model = InferHood::from(&config.init(&device).unwrap());
            let stats = HoodStats::identity(config.levels);
            let scene =
                Scene::new(&skirt, &body, &clip, &hood, Attachment::TopOpening, &config).unwrap();
            let options = RolloutOptions::default();
            let r = roll_out(&model, &stats, &config, &[&scene], &options, &device).unwrap();
            let free = scene.garment.pinned.iter().position(|&p| !p).unwrap();
            let moved = r[0].frames[1][free][2] - r[0].frames[0][free][2];
            assert!(
                (moved - want).abs() < 1e-4,
                "settle_dt {settle_dt}: {moved}"
            );
        }
    }

    /// A rollout steps at the network's rate whatever the motion's and returns the
    /// motion's frames: the untrained network keeps the skinned garment's velocity, so
    /// on a body moving at a constant 1.5 m/s every motion frame has the skirt moved by
    /// the body's displacement, at two steps a frame (30 fps, step_fps 60) and at a
    /// step every four frames (120 fps, step_fps 30) alike.
    #[test]
    fn rollouts_step_at_the_networks_rate_and_return_the_motions_frames() {
        use crate::hood::Materials;
        use weft_sim::{Attachment, Material};
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let device = cpu();
        let hood = Materials::Uniform(Material::hood());
        let free = (0..skirt.vertex_count())
            .min_by(|&a, &b| skirt.positions[a][1].total_cmp(&skirt.positions[b][1]))
            .unwrap();
        for (fps, step_fps, steps) in [(30.0, 30.0, 3), (30.0, 60.0, 6), (120.0, 30.0, 3)] {
            let frames = (0.1 * fps) as usize + 1;
            let (poses, mut trans) = crate::hood::testutil::still(frames);
            for (t, x) in trans.iter_mut().enumerate() {
                x[2] = (1.5 * t as f64 / fps) as f32;
            }
            let clip = Clip {
                fps,
                ..crate::hood::testutil::clip(&poses, &trans)
            };
            let config = HoodConfig::preset("cpu").unwrap().with_step_fps(step_fps);
            let model = InferHood::from(&config.init(&device).unwrap());
            let stats = HoodStats::identity(config.levels);
            let scene =
                Scene::new(&skirt, &body, &clip, &hood, Attachment::TopOpening, &config).unwrap();
            assert_eq!(scene.frames(), steps + 1, "{fps} fps, step_fps {step_fps}");
            assert!((scene.dt - 1.0 / step_fps).abs() < 1e-9);
            let options = RolloutOptions::default();
            let r = roll_out(&model, &stats, &config, &[&scene], &options, &device).unwrap();
            let r = &r[0];
            assert_eq!(r.frames.len(), frames);
            assert!(r.stopped.is_none());
            for t in 1..frames {
                let moved = r.frames[t][free][2] - r.frames[0][free][2];
                let want = 1.5 * t as f64 / fps;
                assert!(
                    (moved - want).abs() < 1e-4,
                    "{fps} fps, step_fps {step_fps}, frame {t}: {moved} for {want}"
                );
            }
        }
    }

    /// The `cpu` preset without its step projection: the network's steps as they are.
    fn unprojected_cpu() -> HoodConfig {
        HoodConfig {
            project_stretch: None,
            project_compression: None,
            project_margin: None,
            ..HoodConfig::preset("cpu").unwrap()
        }
    }

    /// `refine` Newton iterations after each network step: the untrained network
    /// coasts (the skirt hangs where it was skinned, gravity or not), one iteration
    /// lowers it under gravity, and enough of them give weft-sim's implicit step, which
    /// the objective's rollout gives whatever the network.
    #[test]
    fn refined_steps_go_to_the_implicit_step() {
        use crate::hood::{HoodStats, Materials, Scene};
        use weft_sim::{Attachment, Material};
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let (poses, trans) = crate::hood::testutil::still(2);
        let clip = crate::hood::testutil::clip(&poses, &trans);
        let device = cpu();
        let config = unprojected_cpu().with_settle_dt(0.0);
        let model = InferHood::from(&config.init(&device).unwrap());
        let stats = HoodStats::identity(config.levels);
        let hood = Materials::Uniform(Material::hood());
        let scene =
            Scene::new(&skirt, &body, &clip, &hood, Attachment::TopOpening, &config).unwrap();
        let frame_1 = |refine: usize| {
            let options = RolloutOptions {
                refine,
                ..RolloutOptions::default()
            };
            let r = roll_out(&model, &stats, &config, &[&scene], &options, &device).unwrap();
            r[0].frames[1].clone()
        };
        let start = scene.start(0, true).unwrap().cur;
        let at = StepAt {
            t: 0,
            settle: false,
            dt: scene.dt,
            buttoned: true,
        };
        let state = StateRef {
            prev: &start,
            cur: &start,
        };
        let body = scene.contact_body(at).unwrap();
        let implicit = scene.implicit_step(state, at, body.as_ref()).unwrap();
        // The free vertices' mean drop from the start, and the largest distance from
        // the implicit step.
        let free: Vec<usize> = (0..start.len())
            .filter(|&i| !scene.garment.pinned[i])
            .collect();
        let drop = |x: &[[f64; 3]]| {
            free.iter().map(|&i| start[i][1] - x[i][1]).sum::<f64>() / free.len() as f64
        };
        let off = |x: &[[f64; 3]]| {
            free.iter()
                .map(|&i| weft_mesh::vec3::dist(x[i], implicit[i]))
                .fold(0.0, f64::max)
        };
        let (coast, once, solved) = (frame_1(0), frame_1(1), frame_1(50));
        let sag = drop(&implicit);
        assert!(sag > 1e-4, "the implicit step lowers the skirt: {sag}");
        assert!(drop(&coast).abs() < 1e-9, "{}", drop(&coast));
        assert!(drop(&once) > 0.5 * sag, "{} of {sag}", drop(&once));
        assert!(off(&solved) < 1e-5, "{}", off(&solved));
        // The objective: the implicit step whatever the network (here one that would
        // push every vertex a centimetre sideways).
        let mut pushing = stats.clone();
        pushing.output.mean = vec![0.01, 0.0, 0.0];
        let options = RolloutOptions {
            objective: true,
            ..RolloutOptions::default()
        };
        let r = roll_out(&model, &pushing, &config, &[&scene], &options, &device).unwrap();
        assert!(off(&r[0].frames[1]) < 1e-5, "{}", off(&r[0].frames[1]));
        // A prediction the solver cannot start from stops the rollout at that frame,
        // keeping the frames before it.
        let mut broken = stats.clone();
        broken.output.mean = vec![f32::NAN, 0.0, 0.0];
        let options = RolloutOptions {
            refine: 2,
            ..RolloutOptions::default()
        };
        let r = roll_out(&model, &broken, &config, &[&scene], &options, &device).unwrap();
        assert_eq!(r[0].frames.len(), 1);
        let (frame, why) = r[0].stopped.clone().unwrap();
        assert_eq!(frame, 1);
        assert!(why.contains("the Newton refinement"), "{why}");
    }

    #[test]
    fn a_divergence_is_named_at_the_motion_frame_it_kept_from_being_reached() {
        let at = |t: f64| vec![[t; 3]];
        // Steps reached 0..=3, the step to 4 diverged.
        let r = Rollout {
            frames: (0..4).map(|t| at(t as f64)).collect(),
            stopped: Some((4, "fast".into())),
            corrections: Corrections::default(),
        };
        // Two steps a frame: frames 0 and 1 (steps 0 and 2); frame 2 is step 4.
        let m = r.clone().motion_frames(2.0, 5);
        assert_eq!(m.frames, vec![at(0.0), at(2.0)]);
        assert_eq!(m.stopped, Some((2, "fast".into())));
        // A step every two frames: frames between steps interpolated, up to step 3.
        let m = r.clone().motion_frames(0.5, 11);
        let want: Vec<_> = (0..7).map(|i| at(0.5 * i as f64)).collect();
        assert_eq!(m.frames, want);
        assert_eq!(m.stopped, Some((7, "fast".into())));
        assert_eq!(r.clone().motion_frames(1.0, 5), r);
        // A finished rollout keeps every frame of the motion.
        let done = Rollout { stopped: None, ..r };
        assert_eq!(done.motion_frames(0.5, 7).frames.len(), 7);
    }

    #[test]
    fn free_vertices_take_the_acceleration_and_pins_their_target() {
        let g = grid(2, 2, 1.0);
        let garment = HoodGarment::new(&g, 1, &[3], vec![1.0; 4], vec![[0.5; 3]; 4]).unwrap();
        let cur = g.positions.clone();
        let prev: Vec<[f64; 3]> = cur.iter().map(|p| [p[0] - 0.1, p[1], p[2]]).collect();
        let targets = vec![[7.0, 8.0, 9.0]; 4];
        let adv = Advance::new(
            &garment,
            &GarmentStep {
                prev: &prev,
                cur: &cur,
                pin_targets: &targets,
                buttoned: false,
            },
        );
        let norm = FeatureNormalizer {
            mean: vec![0.0, -1.0, 0.0],
            std: vec![2.0, 1.0, 1.0],
        };
        let stats = HoodStats {
            node: norm.clone(),
            mesh: norm.clone(),
            body: norm.clone(),
            output: norm,
        };
        let device = cpu();
        let out = Tensor::<2>::ones([4, 3], &device);
        let x = next_positions(out, &[&adv], &stats, &device).unwrap();
        let x: Vec<f32> = x.into_data().convert::<f32>().try_into_vec().unwrap();
        // Vertex 0: x_t + v_t = (0.1, 0, 0); a = (2, 0, 1).
        let expect0 = [cur[0][0] + 0.1 + 2.0, cur[0][1], cur[0][2] + 1.0];
        for k in 0..3 {
            assert!((f64::from(x[k]) - expect0[k]).abs() < 1e-5, "{x:?}");
        }
        assert_eq!(&x[9..12], &[7.0, 8.0, 9.0]);
        assert_eq!(adv.inertial_target()[3], [7.0, 8.0, 9.0]);
        let bad = next_positions(Tensor::<2>::ones([3, 3], &device), &[&adv], &stats, &device);
        assert!(bad.is_err());
    }

    /// An untrained network predicts no acceleration, so the output normaliser's mean is
    /// the acceleration of every free vertex: here 1 cm per frame² down and forwards,
    /// which stretches a skirt pinned at the waist (its longest edge 5.4 times its rest
    /// length after five steps) and drives its back into the body. The strain limit
    /// holds every edge near it (Gauss–Seidel does not converge fully in
    /// [`STRAIN_LIMIT_SWEEPS`] sweeps on a stretch this large); the contact projection
    /// keeps the skirt out of the body; neither is on for a model without a step
    /// projection.
    #[test]
    fn the_run_time_corrections_hold_a_skirt_driven_into_the_body() {
        use crate::hood::{HoodStats, Materials, Scene};
        use weft_sim::{Attachment, Material, PosedBody};
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let (poses, trans) = crate::hood::testutil::still(6);
        let clip = crate::hood::testutil::clip(&poses, &trans);
        let device = cpu();
        let config = unprojected_cpu();
        let model = InferHood::from(&config.init(&device).unwrap());
        let mut stats = HoodStats::identity(config.levels);
        stats.output.mean = vec![0.0, -0.01, 0.01];
        let hood = Materials::Uniform(Material::hood());
        let scene =
            Scene::new(&skirt, &body, &clip, &hood, Attachment::TopOpening, &config).unwrap();
        let run = |options: RolloutOptions| {
            roll_out(&model, &stats, &config, &[&scene], &options, &device)
                .unwrap()
                .remove(0)
        };
        let edges = skirt.edges();
        let strains = |x: &[[f64; 3]]| -> Vec<f64> {
            edges
                .iter()
                .map(|&[a, b]| {
                    let (a, b) = (a as usize, b as usize);
                    weft_mesh::vec3::dist(x[a], x[b])
                        / weft_mesh::vec3::dist(skirt.positions[a], skirt.positions[b])
                        - 1.0
                })
                .collect()
        };
        let max_strain = |x: &[[f64; 3]]| strains(x).into_iter().fold(f64::NEG_INFINITY, f64::max);
        let min_strain = |x: &[[f64; 3]]| strains(x).into_iter().fold(f64::INFINITY, f64::min);
        let surface = PosedBody::new(&scene.body[5], &scene.faces).unwrap();
        let inside = |x: &[[f64; 3]]| {
            let d = surface.signed_distances(x).unwrap();
            (0..x.len())
                .filter(|&i| !scene.garment.pinned[i] && d[i] < 0.0)
                .count()
        };
        let plain = run(RolloutOptions::default());
        assert_eq!(plain.corrections, Corrections::default());
        let last = |r: &Rollout| r.frames.last().unwrap().clone();
        assert_eq!(plain.frames.len(), 6);
        assert!(
            max_strain(&last(&plain)) > 0.3,
            "{}",
            max_strain(&last(&plain))
        );
        assert!(inside(&last(&plain)) > 10, "{}", inside(&last(&plain)));

        let limited = run(RolloutOptions {
            strain_limit: StrainBounds::stretch(0.1),
            ..Default::default()
        });
        assert!(limited.corrections.edges_limited > 0);
        for x in &limited.frames[1..] {
            assert!(max_strain(x) < 0.15, "{}", max_strain(x));
        }

        // Bounded both ways, the edges the fall shortens are lengthened back as well.
        assert!(
            min_strain(&last(&limited)) < -0.15,
            "{}",
            min_strain(&last(&limited))
        );
        let both_ways = run(RolloutOptions {
            strain_limit: StrainBounds {
                stretch: Some(0.1),
                compression: Some(0.1),
            },
            ..Default::default()
        });
        for x in &both_ways.frames[1..] {
            assert!(max_strain(x) < 0.15, "{}", max_strain(x));
            assert!(min_strain(x) > -0.15, "{}", min_strain(x));
        }

        let projected = run(RolloutOptions {
            contact_margin: Some(0.002),
            ..Default::default()
        });
        assert!(projected.corrections.vertices_projected > 0);
        assert!(
            inside(&last(&projected)) * 10 < inside(&last(&plain)),
            "{} inside with the projection, {} without",
            inside(&last(&projected)),
            inside(&last(&plain))
        );

        // Both: the projection's moves are handed on to the neighbours (the rounds),
        // so the edges stay near the limit with the skirt out of the body. One pass of
        // each (no rounds) left an edge 0.198 over its rest length, the rounds 0.162,
        // the rounds and a last limit 0.151; the push-out after them is what stretches
        // beyond 0.1.
        let both = run(RolloutOptions {
            strain_limit: StrainBounds::stretch(0.1),
            contact_margin: Some(0.002),
            ..Default::default()
        });
        for x in &both.frames[1..] {
            assert!(max_strain(x) < 0.16, "{}", max_strain(x));
        }
        assert!(inside(&last(&both)) * 10 < inside(&last(&plain)));

        // A model whose step ends in a projection (`[model] project_*`) rolls out with it
        // unless told not to, and a bound given at run time wins over the model's.
        let projecting = HoodConfig {
            project_stretch: Some(0.1),
            ..config.clone()
        };
        let run_on = |options: RolloutOptions| {
            roll_out(&model, &stats, &projecting, &[&scene], &options, &device)
                .unwrap()
                .remove(0)
        };
        assert_eq!(run_on(RolloutOptions::default()), limited);
        let off = RolloutOptions {
            projection: false,
            ..Default::default()
        };
        assert_eq!(run_on(off), plain);
        let looser = RolloutOptions {
            strain_limit: StrainBounds::stretch(0.2),
            ..Default::default()
        };
        assert_eq!(run_on(looser), run(looser));
        assert_ne!(run(looser), limited);
    }

    /// The strain limit holds a buttoned pair closed and lets it go once unbuttoned: two
    /// free vertices of the skirt a few centimetres apart, buttoned, meet after the
    /// first step and stay together; the step that ends at `unbutton_at` is the first
    /// the limiter no longer joins them in.
    #[test]
    fn the_strain_limit_holds_buttons_until_unbuttoned() {
        use crate::hood::{HoodStats, Materials, Scene};
        use weft_mesh::vec3::dist;
        use weft_sim::{Attachment, Material};
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let (poses, trans) = crate::hood::testutil::still(8);
        let clip = crate::hood::testutil::clip(&poses, &trans);
        let device = cpu();
        let config = HoodConfig {
            project_stretch: Some(0.1),
            ..HoodConfig::preset("cpu").unwrap()
        };
        let model = InferHood::from(&config.init(&device).unwrap());
        let stats = HoodStats::identity(config.levels);
        let hood = Materials::Uniform(Material::hood());
        let plain =
            Scene::new(&skirt, &body, &clip, &hood, Attachment::TopOpening, &config).unwrap();
        // Two free vertices nearest each other that no edge joins, 1–6 cm apart.
        let free: Vec<usize> = (0..skirt.vertex_count())
            .filter(|&i| !plain.garment.pinned[i])
            .collect();
        let edges = skirt.edges();
        let x0 = &skirt.positions;
        let (a, b) = free
            .iter()
            .flat_map(|&a| free.iter().map(move |&b| (a, b)))
            .filter(|&(a, b)| a < b && !edges.contains(&[a as u32, b as u32]))
            .map(|(a, b)| (a, b, dist(x0[a], x0[b])))
            .filter(|&(_, _, d)| (0.01..0.06).contains(&d))
            .min_by(|p, q| p.2.total_cmp(&q.2))
            .map(|(a, b, _)| (a, b))
            .unwrap();
        let buttoned = plain.clone().with_buttons(&[[a as u32, b as u32]]).unwrap();
        let run = |scene: &Scene, unbutton_at: Option<usize>| {
            let options = RolloutOptions {
                unbutton_at,
                ..Default::default()
            };
            roll_out(&model, &stats, &config, &[scene], &options, &device)
                .unwrap()
                .remove(0)
        };
        let gap = |r: &Rollout, t: usize| dist(r.frames[t][a], r.frames[t][b]);
        let held = run(&buttoned, None);
        let released = run(&buttoned, Some(4));
        let never = run(&plain, None);
        for t in 1..8 {
            assert!(gap(&held, t) < 1e-3, "frame {t}: {} m", gap(&held, t));
            assert!(gap(&never, t) > 0.01, "frame {t}: {} m", gap(&never, t));
        }
        assert_eq!(released.frames[..4], held.frames[..4]);
        assert_ne!(released.frames[4], held.frames[4]);
    }
}
