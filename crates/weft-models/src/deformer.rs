//! [`Deformer`]: the one interface every system implements — given a garment (or a whole
//! character mesh) in the rest pose of a body, the body model, a shape and a motion
//! clip, produce the garment's vertices at every frame.
//!
//! The evaluator, `weft animate` and the demo see systems only through this trait, so a
//! learned model, a no-learning baseline and (later) a physics rollout are scored and
//! exported by the same code. Speed is part of the interface because what a system can
//! cache (Multilevel's pair encoding, HOOD's graph) decides how it should be timed.

use std::collections::BTreeMap;

use weft_body::{BodyModel, Pose};
use weft_mesh::TriMesh;

use crate::error::ModelError;
use crate::kind::ModelKind;

/// A motion applied to one body shape: `poses[t]` (one axis-angle per SMPL joint) and
/// `trans[t]` (root translation, metres) at `fps`, for the body at shape `betas`.
#[derive(Clone, Copy, Debug)]
pub struct Clip<'a> {
    /// Shape coefficients β (fewer than the model has: the rest are zero).
    pub betas: &'a [f32],
    /// One pose per frame.
    pub poses: &'a [Pose],
    /// One root translation per frame.
    pub trans: &'a [[f32; 3]],
    /// Frames per second (velocities and histories depend on it).
    pub fps: f64,
}

impl Clip<'_> {
    /// Frames in the clip.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether the clip has no frame.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// Checks the counts, the frame rate and that every number is finite.
    pub fn check(&self) -> Result<(), ModelError> {
        if self.poses.len() != self.trans.len() {
            return Err(ModelError::mismatch(
                "root translations",
                format!("one per pose ({})", self.poses.len()),
                self.trans.len(),
            ));
        }
        if !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(ModelError::mismatch(
                "frame rate",
                "a positive number",
                self.fps,
            ));
        }
        let flat = |v: &[[f32; 3]]| v.iter().flatten().position(|x| !x.is_finite());
        if let Some(index) = self
            .poses
            .iter()
            .flatten()
            .flatten()
            .position(|x| !x.is_finite())
        {
            return Err(ModelError::NonFinite {
                what: "poses",
                index,
            });
        }
        if let Some(index) = flat(self.trans) {
            return Err(ModelError::NonFinite {
                what: "root translations",
                index,
            });
        }
        if let Some(index) = self.betas.iter().position(|x| !x.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "shape coefficients",
                index,
            });
        }
        Ok(())
    }
}

/// Garment vertices per frame: `frames[t][i]`.
pub type Frames = Vec<Vec<[f32; 3]>>;

/// Inference speed at one batch size (frames per forward pass).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Timing {
    /// Frames per forward pass (HOOD: garments per pass, one frame each).
    pub batch: usize,
    /// Garment vertices.
    pub vertices: usize,
    /// Frames per second of the network alone.
    pub network_fps: f64,
    /// Frames per second including the per-frame inputs.
    pub end_to_end_fps: f64,
    /// Frames timed.
    pub frames: usize,
}

/// The physics the steps of any method's frames are scored by (seed 004's objective):
/// how far above its minimiser each step's incremental potential is.
pub trait StepJudge: Sync {
    /// For each step `t → t + 1` of `frames` from `t = 1` (the state `frames[t − 1]`,
    /// `frames[t]`, the garment made of the preset `material`): the step's incremental
    /// potential at `frames[t + 1]` less its minimum (J), the minimiser found by
    /// weft-sim's implicit Euler from the same state. Zero for a method whose every step
    /// is that minimiser.
    fn potential_gaps(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        material: &str,
        frames: &Frames,
    ) -> Result<Vec<f64>, ModelError>;
}

/// A system that deforms a garment with a body; see the module documentation.
pub trait Deformer: Sync {
    /// The name in tables and pictures (e.g. "Multilevel", "LBS only").
    fn name(&self) -> String;

    /// The learned system it is, or `None` for a no-learning baseline.
    fn kind(&self) -> Option<ModelKind>;

    /// Its variant settings (preset, pooling, skinning method, checkpoint, …), for
    /// reports.
    fn variant(&self) -> BTreeMap<String, String>;

    /// `garment` (in the rest pose of `body` at `clip.betas`) at every frame of `clip`.
    fn animate(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Frames, ModelError>;

    /// [`Deformer::animate`] for a garment made of `material` (a weft-sim preset name, as
    /// a dataset records what it simulated): a system that takes its material at run
    /// time (HOOD) rolls out in it; the others learnt their data's and ignore it.
    fn animate_in(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        _material: &str,
    ) -> Result<Frames, ModelError> {
        self.animate(garment, body, clip)
    }

    /// Frames per second at each of `batches` frames per pass over `frames` frames of
    /// `clip`, timed the way the system is meant to run; `None` when there is nothing
    /// worth timing apart from [`Deformer::animate`] (the baselines).
    fn time(
        &self,
        _garment: &TriMesh,
        _body: &BodyModel,
        _clip: &Clip,
        _batches: &[usize],
        _frames: usize,
    ) -> Result<Option<Vec<Timing>>, ModelError> {
        Ok(None)
    }
}
