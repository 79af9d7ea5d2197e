//! A garment on a moving body, ready for HOOD to roll out or to train on: the garment's
//! graph and physics, the posed body at every frame, the garment skinned to the body
//! (where every rollout starts), and the pinned vertices' targets.
//!
//! The garment comes in the rest pose of the body at the clip's shape, as every
//! [`crate::Deformer`] takes it. Its rest shape is that mesh. The start state is the
//! garment skinned to the frame (weights transferred from the body and diffused over
//! the garment, as HOOD's loose garments are; LBS) and pushed
//! 2 mm out of the body (HOOD's push-out). Pinned vertices — the waistband or neckline,
//! the vertices `weft simulate` attaches — follow the skinned garment, as HOOD's do.
//! (The simulator anchors them to body triangles instead; a t-shirt's neckline, which
//! floats centimetres off the neck, then sits 2–6 cm from where the skinned garment
//! around it is, a strain no network step can undo: measured, docs/hood.md.)

use weft_body::joints::smpl_joint_index;
use weft_body::{BodyModel, Pose};
use weft_garment::onbody::push_out;
use weft_mesh::TriMesh;
use weft_sim::{
    check_garment_gap, inertial_target, Attachment, BodyProximity, ClothModel, ClothSimulator,
    IncrementalPotential, Material, MaterialRanges, PosedBody, SimOptions, StepInputs, SweptBody,
};

use super::config::HoodConfig;
use super::features::{BodyStep, GarmentStep, StepGraph};
use super::garment::HoodGarment;
use super::rollout::Advance;
use crate::baseline::SkinnedGarment;
use crate::deformer::Clip;
use crate::error::{body_err, ModelError};

/// HOOD's push-out distance before a rollout starts (m).
pub const PUSH_OUT: f64 = 0.002;

/// Joints whose vertices take no body edges when [`HoodConfig::omit_hands`] is set.
const HAND_JOINTS: [&str; 4] = ["left_wrist", "right_wrist", "left_hand", "right_hand"];

/// What a garment is made of: one material, or one per vertex (a material map).
#[derive(Clone, Debug, PartialEq)]
pub enum Materials {
    /// The same material everywhere.
    Uniform(Material),
    /// A material per garment vertex.
    PerVertex(Vec<Material>),
}

impl Materials {
    /// Each distinct material that lies outside `ranges`, with what lies outside
    /// ([`MaterialRanges::outside`]): `silk: μ 245.5 kPa (trained …), …`.
    pub fn outside(&self, ranges: &MaterialRanges) -> Vec<String> {
        let list: &[Material] = match self {
            Materials::Uniform(m) => std::slice::from_ref(m),
            Materials::PerVertex(m) => m,
        };
        let mut seen: Vec<&Material> = Vec::new();
        let mut notes = Vec::new();
        for m in list {
            if seen.contains(&m) {
                continue;
            }
            seen.push(m);
            let out = ranges.outside(m);
            if !out.is_empty() {
                notes.push(format!("{}: {}", m.name, out.join(", ")));
            }
        }
        notes
    }

    /// The cloth physics of `rest` made of these materials; errors name the count.
    pub fn cloth(&self, rest: &TriMesh) -> Result<ClothModel, ModelError> {
        let sim = |e: weft_sim::SimError| ModelError::Garment(format!("garment physics: {e}"));
        match self {
            Materials::Uniform(m) => ClothModel::uniform(rest, m, SimOptions::default()),
            Materials::PerVertex(m) => {
                if m.len() != rest.vertex_count() {
                    return Err(ModelError::mismatch(
                        "material map",
                        format!("one material per garment vertex ({})", rest.vertex_count()),
                        m.len(),
                    ));
                }
                ClothModel::from_vertex_materials(rest, m, SimOptions::default())
            }
        }
        .map_err(sim)
    }

    /// The network's material inputs of every vertex of a garment of `n` vertices, on
    /// the scale of `ranges` (the run's material space) and clamped to it: a material
    /// outside is read as the nearest one the network was trained on, since beyond the
    /// range its inputs would lie where no training sample did (silk in HOOD's ranges:
    /// μ and λ at 2.0 and 2.3 on a [0, 1] scale; docs/hood.md item 19). Its physics
    /// (the potential, `--refine`, the projection) stays its own.
    pub fn inputs(&self, n: usize, ranges: &MaterialRanges) -> Vec<[f32; 3]> {
        let one = |m: &Material| ranges.inputs(m).map(|x| x.clamp(0.0, 1.0) as f32);
        match self {
            Materials::Uniform(m) => vec![one(m); n],
            Materials::PerVertex(m) => m.iter().map(one).collect(),
        }
    }
}

/// The garment at the start of a step: its positions at t − 1 and t.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Positions at t − 1.
    pub prev: Vec<[f64; 3]>,
    /// Positions at t.
    pub cur: Vec<[f64; 3]>,
}

impl State {
    /// The state borrowed.
    pub fn as_ref(&self) -> StateRef<'_> {
        StateRef {
            prev: &self.prev,
            cur: &self.cur,
        }
    }
}

/// A borrowed [`State`] (a rollout's two last frames).
#[derive(Clone, Copy, Debug)]
pub struct StateRef<'a> {
    /// Positions at t − 1.
    pub prev: &'a [[f64; 3]],
    /// Positions at t.
    pub cur: &'a [[f64; 3]],
}

/// Which step of a scene: from frame `t` to `t + 1`, or the settling step at `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepAt {
    /// The frame the step starts from.
    pub t: usize,
    /// The body held at `t` (HOOD's first step, with a long time step so the garment
    /// drapes).
    pub settle: bool,
    /// The step's length (s).
    pub dt: f64,
    /// Whether the button edges are in the graph.
    pub buttoned: bool,
}

/// A garment on a moving body; see the module documentation.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The garment's graph.
    pub garment: HoodGarment,
    /// The garment's physics (the loss; diagnostics).
    pub cloth: ClothModel,
    /// The body's triangles.
    pub faces: Vec<[u32; 3]>,
    /// The posed body at every frame.
    pub body: Vec<Vec<[f64; 3]>>,
    /// Body vertices that take no body edges.
    pub omit: Vec<bool>,
    /// The garment skinned to every frame (pinned vertices included: their targets).
    pub skinned: Vec<Vec<[f64; 3]>>,
    /// Seconds per frame.
    pub dt: f64,
    /// Frames of the motion the scene was made from: the scene's are that motion
    /// resampled to [`HoodConfig::steps`] steps over its duration.
    pub motion_frames: usize,
    /// The body surface at rest, rebuilt at each step's pose ([`Scene::posed_body`]).
    rest_body: PosedBody,
    /// [`HoodConfig::swept_contacts`].
    swept_contacts: bool,
}

/// A motion's poses, root translations and frame rate.
type Resampled = (Vec<Pose>, Vec<[f32; 3]>, f64);

/// `clip` resampled to `steps` steps over its duration (weft-motion's resampling: a
/// frame that falls on one of the clip's is that frame); `None` when that is a step a
/// frame.
fn at_steps(clip: &Clip, steps: usize) -> Result<Option<Resampled>, ModelError> {
    let intervals = clip.len() - 1;
    if steps == intervals {
        return Ok(None);
    }
    let fps = clip.fps * steps as f64 / intervals as f64;
    let err = |e: weft_motion::MotionError| {
        ModelError::Config(format!(
            "resampling the motion to {fps} fps (network steps): {e}"
        ))
    };
    let motion = weft_motion::Motion::new(clip.fps, clip.poses.to_vec(), clip.trans.to_vec(), None)
        .map_err(err)?;
    let fine = weft_motion::resample(&motion, fps).map_err(err)?;
    if fine.frame_count() != steps + 1 {
        return Err(ModelError::mismatch(
            "resampled motion frames",
            steps + 1,
            fine.frame_count(),
        ));
    }
    Ok(Some((fine.poses().to_vec(), fine.trans().to_vec(), fps)))
}

fn f64s(frame: &[[f32; 3]]) -> Vec<[f64; 3]> {
    frame.iter().map(|p| p.map(f64::from)).collect()
}

impl Scene {
    /// `garment` (rest pose of `body` at `clip.betas`) made of `materials`, on `body`
    /// moving through `clip`, its `attachment` pinned.
    pub fn new(
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        materials: &Materials,
        attachment: Attachment,
        config: &HoodConfig,
    ) -> Result<Self, ModelError> {
        clip.check()?;
        if clip.len() < 2 {
            return Err(ModelError::mismatch(
                "motion frames",
                "at least 2 for a rollout",
                clip.len(),
            ));
        }
        let motion_frames = clip.len();
        let steps = config.steps(motion_frames, clip.fps);
        let fine = at_steps(clip, steps)?;
        let clip = match &fine {
            Some((poses, trans, fps)) => &Clip {
                poses,
                trans,
                fps: *fps,
                ..*clip
            },
            None => clip,
        };
        let cloth = materials.cloth(garment)?;
        let pinned = attachment.vertices(garment);
        let n = garment.vertex_count();
        let hood = HoodGarment::new(
            garment,
            config.levels,
            &pinned,
            cloth.masses().to_vec(),
            materials.inputs(n, &config.materials),
        )?;
        let posed = weft_body::PosedSequence::new(body, clip.betas, clip.poses, clip.trans)
            .map_err(body_err("posing the body"))?;
        let frames: Vec<Vec<[f64; 3]>> = posed.frames().map(f64s).collect();
        // A garment nowhere near the body (another frame or unit) would fall beside it.
        let rest_body = body
            .shape(&clip.betas.iter().map(|&b| f64::from(b)).collect::<Vec<_>>())
            .map_err(body_err("shaping the body"))?;
        let on_rest = |e: weft_sim::SimError| {
            ModelError::Garment(format!("the garment on the rest body: {e}"))
        };
        let rest_surface =
            PosedBody::new(&rest_body.positions, &rest_body.faces).map_err(on_rest)?;
        rest_surface
            .signed_distances(&garment.positions)
            .and_then(check_garment_gap)
            .map_err(on_rest)?;
        let skinned: Vec<Vec<[f64; 3]>> = SkinnedGarment::diffused(garment, body, clip.betas)?
            .animate(body, clip, weft_body::Skinning::Lbs)?
            .iter()
            .map(|f| f64s(f))
            .collect();
        Ok(Scene {
            garment: hood,
            cloth,
            faces: body.faces().to_vec(),
            body: frames,
            omit: if config.omit_hands {
                hand_vertices(body)
            } else {
                Vec::new()
            },
            skinned,
            dt: 1.0 / clip.fps,
            motion_frames,
            rest_body: rest_surface,
            swept_contacts: config.swept_contacts,
        })
    }

    /// Frames of the clip.
    pub fn frames(&self) -> usize {
        self.body.len()
    }

    /// Network steps per frame of the motion the scene was made from (1: the motion's
    /// own frames).
    pub fn steps_per_frame(&self) -> f64 {
        (self.frames() - 1) as f64 / (self.motion_frames - 1) as f64
    }

    /// The skinned garment at frame `t`: where the pinned vertices go in a step that
    /// ends at `t`.
    pub fn pin_targets(&self, t: usize) -> Vec<[f64; 3]> {
        self.skinned[t].clone()
    }

    /// The start state at frame `t`: the skinned garment at `t − 1` and `t` (or at `t`
    /// twice, at rest, when `at_rest` or `t = 0`), pushed out of the body at `t`.
    pub fn start(&self, t: usize, at_rest: bool) -> Result<State, ModelError> {
        let surface = weft_body::query::BodySurface::new(&self.body[t], &self.faces)
            .map_err(|e| ModelError::Body(e.to_string()))?;
        let mut cur = self.pin_targets(t);
        let mut prev = if at_rest || t == 0 {
            cur.clone()
        } else {
            self.pin_targets(t - 1)
        };
        for x in [&mut cur, &mut prev] {
            push_out(&surface, x, PUSH_OUT).map_err(|e| {
                ModelError::Garment(format!("pushing the garment out of the body: {e}"))
            })?;
        }
        Ok(State { prev, cur })
    }

    /// The graph and the advance of the step `at` from `state`.
    pub fn step(
        &self,
        state: StateRef,
        at: StepAt,
        config: &HoodConfig,
    ) -> Result<(StepGraph, Advance), ModelError> {
        let t = at.t;
        let next = if at.settle { t } else { t + 1 };
        if next >= self.frames() {
            return Err(ModelError::mismatch(
                "rollout frame",
                format!("below {}", self.frames()),
                next,
            ));
        }
        let targets = self.pin_targets(next);
        let garment = GarmentStep {
            prev: state.prev,
            cur: state.cur,
            pin_targets: &targets,
            buttoned: at.buttoned,
        };
        let body_prev = if at.settle { t } else { t.saturating_sub(1) };
        let body = BodyStep {
            prev: &self.body[body_prev],
            cur: &self.body[t],
            next: &self.body[next],
            faces: &self.faces,
            omit: &self.omit,
        };
        let graph = StepGraph::build(&self.garment, &garment, &body, at.dt, config)?;
        Ok((graph, Advance::new(&self.garment, &garment)))
    }
}

impl Scene {
    /// This scene with `pairs` of garment vertices buttoned: extra mesh edges in the
    /// graph ([`HoodGarment::with_buttons`]) and zero-length springs in the potential
    /// ([`ClothModel::with_buttons`]), both while a step is buttoned.
    pub fn with_buttons(mut self, pairs: &[[u32; 2]]) -> Result<Self, ModelError> {
        self.garment = self.garment.with_buttons(pairs)?;
        self.cloth = self
            .cloth
            .with_buttons(pairs)
            .map_err(|e| ModelError::Garment(format!("the buttons: {e}")))?;
        Ok(self)
    }

    /// The garment's physics at step `at`: without its buttons once unbuttoned.
    pub fn cloth_at(&self, at: StepAt) -> std::borrow::Cow<'_, ClothModel> {
        if at.buttoned || self.cloth.buttons().is_none() {
            std::borrow::Cow::Borrowed(&self.cloth)
        } else {
            std::borrow::Cow::Owned(self.cloth.without_buttons())
        }
    }

    /// The body as the step `at` sees it: at its end-of-step state, having moved there
    /// from frame `at.t` (the settling step: still at `at.t`).
    pub fn posed_body(&self, at: StepAt) -> Result<PosedBody, ModelError> {
        let sim = |e: weft_sim::SimError| ModelError::Body(format!("the posed body: {e}"));
        let mut body = self.rest_body.clone();
        body.rebuild(&self.body[at.t]).map_err(sim)?;
        if !at.settle {
            body.refit(&self.body[at.t + 1]).map_err(sim)?;
        }
        Ok(body)
    }

    /// The body that step `at`'s contacts are found against: [`Scene::posed_body`]
    /// (HOOD), or with [`HoodConfig::swept_contacts`] the body swept from frame `at.t`
    /// to its end-of-step state ([`SweptBody`]), so a limb that moves through the cloth
    /// in one frame pushes it back to the side it was on.
    pub fn contact_body(&self, at: StepAt) -> Result<Box<dyn BodyProximity + Sync>, ModelError> {
        if !self.swept_contacts || at.settle {
            return Ok(Box::new(self.posed_body(at)?));
        }
        Ok(Box::new(self.swept_body(at)?))
    }

    /// [`Scene::contact_body`], the body at the start of step `at` and
    /// [`Scene::posed_body`] from one build (a swept body starts at the first and ends
    /// at the last): the run-time corrections need all three every step.
    pub fn step_bodies(&self, at: StepAt) -> Result<StepBodies, ModelError> {
        if !self.swept_contacts || at.settle {
            let start = self.posed_body(StepAt { settle: true, ..at })?;
            let mut end = start.clone();
            if !at.settle {
                end.refit(&self.body[at.t + 1])
                    .map_err(|e| ModelError::Body(format!("the posed body: {e}")))?;
            }
            return Ok(StepBodies {
                contact: Box::new(end.clone()),
                start,
                end,
            });
        }
        let swept = self.swept_body(at)?;
        let (start, end) = (swept.before().clone(), swept.after().clone());
        Ok(StepBodies {
            contact: Box::new(swept),
            start,
            end,
        })
    }

    /// The body swept from frame `at.t` to its state at the end of step `at`.
    fn swept_body(&self, at: StepAt) -> Result<SweptBody, ModelError> {
        let sim = |e: weft_sim::SimError| ModelError::Body(format!("the swept body: {e}"));
        let before = self.posed_body(StepAt { settle: true, ..at })?;
        let mut after = before.clone();
        after.refit(&self.body[at.t + 1]).map_err(sim)?;
        SweptBody::new(before, after).map_err(sim)
    }

    /// The step `at` from `state` as weft-sim's implicit Euler takes it (Newton on the
    /// same incremental potential HOOD is trained on, the pinned vertices at their
    /// targets): the reference a HOOD step is measured against. `body` is the step's
    /// [`Scene::contact_body`], which a caller that also builds the step's potential
    /// builds once for both.
    pub fn implicit_step(
        &self,
        state: StateRef,
        at: StepAt,
        body: &(dyn BodyProximity + Sync),
    ) -> Result<Vec<[f64; 3]>, ModelError> {
        self.solve_step(state, at, body, None)
    }

    /// The incremental potential of step `at` from `state` (HOOD's loss, weft-sim's
    /// objective): inertial target `x_t + (x_t − x_{t−1})`, pinned vertices at their
    /// targets, contacts against the step's [`Scene::contact_body`] `body`.
    pub fn step_potential(
        &self,
        state: StateRef,
        at: StepAt,
        body: &(dyn BodyProximity + Sync),
    ) -> Result<IncrementalPotential, ModelError> {
        let failed =
            |e: weft_sim::SimError| ModelError::Garment(format!("the step's potential: {e}"));
        let next = if at.settle { at.t } else { at.t + 1 };
        let mut target = inertial_target(state.cur, state.prev, 1.0).map_err(failed)?;
        for (i, _) in self.garment.pinned.iter().enumerate().filter(|(_, &p)| p) {
            target[i] = self.skinned[next][i];
        }
        self.cloth_at(at)
            .step_potential(&StepInputs {
                start: state.cur,
                target: &target,
                dt: at.dt,
                pinned: &self.garment.pinned,
                body: Some(body),
                collision_stiffness: None,
            })
            .map_err(failed)
    }

    /// The step `at` from `state` refined from `predicted` (a network's step) by at most
    /// `iterations` Newton iterations on the same incremental potential: the
    /// [`Scene::implicit_step`] started from the prediction instead of inertia and cut
    /// short ([`RolloutOptions::refine`](super::RolloutOptions::refine)).
    pub fn refine_step(
        &self,
        state: StateRef,
        at: StepAt,
        body: &(dyn BodyProximity + Sync),
        predicted: &[[f64; 3]],
        iterations: usize,
    ) -> Result<Vec<[f64; 3]>, ModelError> {
        self.solve_step(state, at, body, Some((predicted, iterations)))
    }

    fn solve_step(
        &self,
        state: StateRef,
        at: StepAt,
        body: &(dyn BodyProximity + Sync),
        from: Option<(&[[f64; 3]], usize)>,
    ) -> Result<Vec<[f64; 3]>, ModelError> {
        let what = match from {
            Some(_) => "the Newton refinement",
            None => "the implicit step",
        };
        let sim = |e: weft_sim::SimError| ModelError::Garment(format!("{what}: {e}"));
        let mut solver = ClothSimulator::from_model(self.cloth_at(at).into_owned()).map_err(sim)?;
        let v = state
            .cur
            .iter()
            .zip(state.prev)
            .map(|(c, p)| std::array::from_fn(|k| (c[k] - p[k]) / at.dt))
            .collect();
        solver.set_state(state.cur.to_vec(), v).map_err(sim)?;
        let next = if at.settle { at.t } else { at.t + 1 };
        let targets = &self.skinned[next];
        for (i, _) in self.garment.pinned.iter().enumerate().filter(|(_, &p)| p) {
            solver.move_pin(i as u32, targets[i]).map_err(sim)?;
        }
        match from {
            Some((start, iterations)) => solver.step_from(at.dt, Some(body), start, iterations),
            None => solver.step(at.dt, Some(body)),
        }
        .map_err(sim)?;
        Ok(solver.positions().to_vec())
    }
}

/// The bodies of one step ([`Scene::step_bodies`]).
pub struct StepBodies {
    /// What the step's contacts are found against ([`Scene::contact_body`]).
    pub contact: Box<dyn BodyProximity + Sync>,
    /// The body at the start of the step.
    pub start: PosedBody,
    /// The body at the end of the step ([`Scene::posed_body`]).
    pub end: PosedBody,
}

/// Body vertices bound mostly (weight > 0.5) to the wrists and hands.
fn hand_vertices(body: &BodyModel) -> Vec<bool> {
    let hands: Vec<usize> = HAND_JOINTS
        .iter()
        .filter_map(|n| smpl_joint_index(n))
        .collect();
    let w = body.weights();
    (0..w.vertex_count())
        .map(|v| {
            w.influences(v)
                .filter(|(j, _)| hands.contains(j))
                .map(|(_, x)| x)
                .sum::<f64>()
                > 0.5
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A material outside the run's space is read as the nearest one inside (silk in
    /// HOOD's ranges: stiffest μ and λ, its own bending), one inside as itself; the
    /// report names each distinct material outside once.
    #[test]
    fn materials_outside_the_space_are_clamped_and_named() {
        let ranges = MaterialRanges::hood();
        let silk = Materials::Uniform(Material::silk());
        let x = silk.inputs(2, &ranges);
        let own = ranges.inputs(&Material::silk());
        assert_eq!(x[0], [own[0] as f32, 1.0, 1.0]);
        assert!(own[1] > 1.5 && own[2] > 1.5, "{own:?}");
        let hood = Materials::Uniform(Material::hood());
        assert_eq!(
            hood.inputs(1, &ranges)[0],
            ranges.inputs(&Material::hood()).map(|v| v as f32)
        );
        assert!(hood.outside(&ranges).is_empty());
        let map = Materials::PerVertex(vec![
            Material::silk(),
            Material::hood(),
            Material::silk(),
            Material::denim(),
        ]);
        let notes = map.outside(&ranges);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(
            notes[0].starts_with("silk: μ") && notes[1].starts_with("denim: μ"),
            "{notes:?}"
        );
        let inputs = map.inputs(4, &ranges);
        assert!(
            inputs.iter().flatten().all(|v| (0.0..=1.0).contains(v)),
            "{inputs:?}"
        );
    }

    /// A body that moves farther in a frame than it is deep sweeps the front of the
    /// skirt to its back: HOOD's contact at t + 1 lets it go, the swept body holds it
    /// in front.
    #[test]
    fn swept_contacts_keep_the_cloth_on_its_side_of_a_fast_body() {
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let (poses, mut trans) = crate::hood::testutil::still(3);
        trans[1] = [0.0, 0.0, 0.35];
        let clip = Clip {
            betas: &[],
            poses: &poses,
            trans: &trans,
            fps: 30.0,
        };
        let hood = Materials::Uniform(Material::hood());
        let scene = |swept| {
            let cfg = HoodConfig::preset("cpu")
                .unwrap()
                .with_swept_contacts(swept);
            Scene::new(&skirt, &body, &clip, &hood, Attachment::TopOpening, &cfg).unwrap()
        };
        let at = StepAt {
            t: 0,
            settle: false,
            dt: 1.0 / 30.0,
            buttoned: true,
        };
        let front = (0..skirt.vertex_count())
            .max_by(|&a, &b| skirt.positions[a][2].total_cmp(&skirt.positions[b][2]))
            .unwrap();
        let x = skirt.positions[front];
        let plain = scene(false).contact_body(at).unwrap().closest(x);
        assert!(plain.is_none_or(|c| c.normal[2] < 0.0), "{plain:?}");
        let swept = scene(true).contact_body(at).unwrap().closest(x).unwrap();
        assert!(swept.normal[2] > 0.5, "{swept:?}");
        assert!(swept.signed_distance(x) < 0.0, "{swept:?}");
    }

    #[test]
    fn scenes_refuse_a_garment_off_the_body_and_a_bad_material_map() {
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let (poses, trans) = crate::hood::testutil::still(3);
        let clip = Clip {
            betas: &[],
            poses: &poses,
            trans: &trans,
            fps: 30.0,
        };
        let cfg = HoodConfig::preset("cpu").unwrap();
        let hood = Materials::Uniform(Material::hood());
        let scene = Scene::new(&skirt, &body, &clip, &hood, Attachment::TopOpening, &cfg).unwrap();
        assert_eq!(scene.frames(), 3);
        // Pinned vertices (the waistband) follow the skinned garment exactly.
        let pinned = scene.garment.pinned.iter().position(|&p| p).unwrap();
        assert_eq!(scene.pin_targets(2)[pinned], scene.skinned[2][pinned]);
        let mut far = skirt.clone();
        for p in &mut far.positions {
            p[0] += 3.0;
        }
        let e = Scene::new(&far, &body, &clip, &hood, Attachment::TopOpening, &cfg)
            .unwrap_err()
            .to_string();
        assert!(e.contains("rest body"), "{e}");
        let short = Materials::PerVertex(vec![Material::silk(); 5]);
        let e = Scene::new(&skirt, &body, &clip, &short, Attachment::TopOpening, &cfg)
            .unwrap_err()
            .to_string();
        assert!(e.contains("material map"), "{e}");
        // Buttons join the graph and the potential while a step is buttoned.
        let buttoned = scene.clone().with_buttons(&[[0, 5]]).unwrap();
        assert_eq!(buttoned.garment.buttons, vec![[0, 5], [5, 0]]);
        let at = |buttoned| StepAt {
            t: 0,
            settle: false,
            dt: 1.0 / 30.0,
            buttoned,
        };
        assert_eq!(
            buttoned
                .cloth_at(at(true))
                .buttons()
                .map(|b| b.pairs().to_vec()),
            Some(vec![[0, 5]])
        );
        assert!(buttoned.cloth_at(at(false)).buttons().is_none());
        assert!(scene.clone().with_buttons(&[[3, 3]]).is_err());
        let nan = vec![[[f32::NAN; 3]; 24]; 3];
        let bad = Clip {
            poses: &nan,
            ..clip
        };
        assert!(Scene::new(&skirt, &body, &bad, &hood, Attachment::TopOpening, &cfg).is_err());
    }
}
