//! What the refinement benches (`weft bench densegats`, `weft bench multiresgnet`) share:
//! the character (the benchmark skirt bound to the body as `weft animate --character`
//! binds any mesh), the timed pose, the pose inputs, and the timings around the
//! network's own stages (the reference forward and the whole frame).

use burn::tensor::{Device, Tensor, TensorData};
use weft_body::{BodyModel, Pose};
use weft_models::refine::{Character, CharacterRig, InputSpec, RefineNet};
use weft_nn::infer::Features;

use crate::timing::try_median_ms;
use crate::{skirt, BenchError};

/// A bound character in the timed pose, with its normalised-width node features.
pub(crate) struct Setup {
    /// The character.
    pub character: Character,
    /// The timed pose: the left elbow bent.
    pub pose: Pose,
    /// How the model reads the pose.
    pub inputs: InputSpec,
    /// The pose's node features.
    pub x: Features,
    /// Coarse skinning, normals and node features (host), ms.
    pub inputs_ms: f64,
}

impl Setup {
    /// The benchmark skirt of about `vertices` vertices bound to `body` with
    /// `influences` weights per vertex, its inputs timed over `reps` runs.
    pub fn new(
        body: &BodyModel,
        vertices: usize,
        influences: usize,
        inputs: InputSpec,
        reps: usize,
    ) -> Result<Self, BenchError> {
        let mesh = skirt(body, vertices)?;
        let n = mesh.positions.len();
        let weights = weft_garment::FitBody::new(body, &[])
            .and_then(|fit| fit.weights_at(body, &mesh.positions))
            .map_err(BenchError::stage("binding the character"))?;
        let joints = body.joints(&[]).map_err(BenchError::stage("rest joints"))?;
        let character = Character::new(
            CharacterRig {
                mesh,
                weights: weights.to_f32(),
                joints,
                parents: body.skeleton().parents().to_vec(),
                // The network's cost does not depend on the distances' values.
                joint_distances: vec![0.5; n * body.joint_count()],
            },
            influences,
        )
        .map_err(BenchError::stage("the character"))?;
        let mut pose = [[0.0f32; 3]; 24];
        pose[18] = [0.0, -1.2, 0.0];
        let inputs_ms = try_median_ms(reps, || {
            character.pose_input(&pose, [0.0; 3], inputs).map(drop)
        })
        .map_err(BenchError::stage("pose inputs"))?;
        let features = character
            .pose_input(&pose, [0.0; 3], inputs)
            .map_err(BenchError::stage("pose inputs"))?
            .features;
        let x = Features::new(features, character.feature_width())
            .map_err(BenchError::stage("pose inputs"))?;
        Ok(Setup {
            character,
            pose,
            inputs,
            x,
            inputs_ms,
        })
    }

    /// The network whole by its reference forward (`reference`, burn layers as training
    /// runs them) and one frame (inputs and the inference form `fast`), ms.
    pub fn whole_ms(
        &self,
        reps: usize,
        reference: &dyn RefineNet,
        fast: &dyn RefineNet,
        device: &Device,
    ) -> Result<(f64, f64), BenchError> {
        let batch = self.character.batch();
        let tensor = self.x.clone().into_tensor(device);
        let reference_ms = try_median_ms(reps, || {
            reference
                .forward(tensor.clone(), batch)
                .map(|t| drop(t.into_data()))
        })
        .map_err(BenchError::stage("reference network"))?;
        let shape = [self.character.vertex_count(), self.x.width()];
        let frame_ms = try_median_ms(reps, || {
            let input = self
                .character
                .pose_input(&self.pose, [0.0; 3], self.inputs)?;
            let x = Tensor::<2>::from_data(TensorData::new(input.features, shape), device);
            fast.forward(x, batch).map(|t| drop(t.into_data()))
        })
        .map_err(BenchError::stage("frame"))?;
        Ok((reference_ms, frame_ms))
    }
}
