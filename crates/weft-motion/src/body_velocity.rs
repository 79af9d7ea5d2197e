//! Seed 000's body-vertex velocities `V^t` for a [`Motion`]: the body posed at the
//! frames a window needs, then the slice-based
//! [`weft_body::features::velocity_window`], which stays the reference.

use weft_body::features::{velocity_window, FeatureError, VelocityWindow};
use weft_body::{BodyModel, ShapedBody, Skinning};

use crate::types::Motion;

impl Motion {
    /// Seed 000's `V^t` for frame `t` of this motion on `body` at shape `shaped`: the
    /// window of `m` body-vertex velocity frames, current first. Poses only the
    /// `m + 1` frames the window needs.
    pub fn velocity_window(
        &self,
        body: &BodyModel,
        shaped: &ShapedBody,
        t: usize,
        m: usize,
        method: Skinning,
    ) -> Result<VelocityWindow, FeatureError> {
        if t >= self.frame_count() {
            return Err(FeatureError::FrameOutOfRange {
                frame: t,
                frames: self.frame_count(),
            });
        }
        let first = t.saturating_sub(m);
        let frames = (first..=t)
            .map(|k| {
                let pose: Vec<[f64; 3]> =
                    self.poses()[k].iter().map(|w| w.map(f64::from)).collect();
                body.pose_vertices(shaped, &pose, self.trans()[k].map(f64::from), method)
                    .map_err(|e| FeatureError::Posing(e.to_string()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        velocity_window(&frames, self.fps(), t - first, m)
    }
}
