//! [`StandInSimulator`]: a cheap, deterministic stand-in for the cloth simulator, for dry
//! runs of the pipeline (data → training → evaluation) where the real simulator would
//! take minutes — the tests of every pipeline and of the CLI use it. Its figures mean
//! nothing.

use weft_data::{SequenceSimulator, SimInput, SimOutcome};
use weft_models::{Clip, SkinningBaseline};

/// The LBS baseline plus a smooth vertical sag that varies over time, so the ground
/// truth is neither the baseline nor constant.
#[derive(Clone, Copy, Debug, Default)]
pub struct StandInSimulator;

impl SequenceSimulator for StandInSimulator {
    fn simulate(
        &self,
        input: &SimInput<'_>,
        on_frame: &mut dyn FnMut(),
    ) -> Result<SimOutcome, String> {
        let betas: Vec<f32> = input.betas.iter().map(|&b| b as f32).collect();
        let clip = Clip {
            betas: &betas,
            poses: input.motion.poses(),
            trans: input.motion.trans(),
            fps: input.motion.fps(),
        };
        let frames = weft_models::Deformer::animate(
            &SkinningBaseline::LBS,
            input.garment,
            input.body,
            &clip,
        )
        .map_err(|e| e.to_string())?;
        let frames = frames
            .into_iter()
            .enumerate()
            .map(|(t, f)| {
                on_frame();
                let sag = 0.01 * (1.0 + (0.3 * t as f32).sin());
                f.into_iter().map(|p| [p[0], p[1] - sag, p[2]]).collect()
            })
            .collect();
        Ok(SimOutcome::Finished {
            frames,
            stats: serde_json::Value::Null,
        })
    }
}
