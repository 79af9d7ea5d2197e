//! A body posed at every frame of a motion: the one place that turns a shape and a
//! motion into posed body meshes and query surfaces (evaluation's collision metric,
//! training's physics terms and the model's body features all start here).

use weft_mesh::TriMesh;

use crate::error::BodyError;
use crate::model::BodyModel;
use crate::query::{BodySurface, MovingSurface};
use crate::skinning::Skinning;

/// The body at shape `betas`, posed frame by frame (LBS with the model's pose blend
/// shapes, as the simulator saw it), in f32 as motions and datasets store it.
#[derive(Clone, Debug)]
pub struct PosedSequence {
    frames: Vec<Vec<[f32; 3]>>,
    faces: Vec<[u32; 3]>,
}

impl PosedSequence {
    /// Poses `body` at shape `betas` for each of `poses` (one axis-angle per joint) and
    /// root translations `trans`; the counts must agree and every value be finite.
    pub fn new<P>(
        body: &BodyModel,
        betas: &[f32],
        poses: &[P],
        trans: &[[f32; 3]],
    ) -> Result<Self, BodyError>
    where
        P: AsRef<[[f32; 3]]> + Sync,
    {
        if let Some(i) = trans.iter().flatten().position(|x| !x.is_finite()) {
            return Err(BodyError::NonFinite {
                what: "root translation value",
                index: i,
                value: f64::from(trans[i / 3][i % 3]),
            });
        }
        let betas: Vec<f64> = betas.iter().map(|&b| f64::from(b)).collect();
        let shaped = body.shaped(&betas)?;
        let frames = body.pose_frames(&shaped, poses, trans, Skinning::Lbs)?;
        Ok(PosedSequence {
            frames,
            faces: body.faces().to_vec(),
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether there are no frames.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The body's triangles (the model's faces).
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// The posed vertices of frame `t`.
    pub fn frame(&self, t: usize) -> Option<&[[f32; 3]]> {
        self.frames.get(t).map(Vec::as_slice)
    }

    /// The posed vertices of every frame, in order.
    pub fn frames(&self) -> impl ExactSizeIterator<Item = &[[f32; 3]]> {
        self.frames.iter().map(Vec::as_slice)
    }

    /// The posed vertices of every frame, without a copy.
    pub fn into_frames(self) -> Vec<Vec<[f32; 3]>> {
        self.frames
    }

    /// Calls `visit(t, surface)` with the closest-point and signed-distance surface of
    /// every frame in order (built on the first, refit for the next: [`MovingSurface`]).
    pub fn for_each_surface<E: From<BodyError>>(
        &self,
        mut visit: impl FnMut(usize, &BodySurface) -> Result<(), E>,
    ) -> Result<(), E> {
        let mut moving = MovingSurface::new(&self.faces);
        for (t, frame) in self.frames().enumerate() {
            let surface = moving.frame(frame).map_err(BodyError::from)?;
            visit(t, surface)?;
        }
        Ok(())
    }

    /// The posed body mesh of frame `t` (for pictures and exports).
    pub fn mesh(&self, t: usize) -> Option<TriMesh> {
        self.frames.get(t).map(|f| {
            TriMesh::new(
                f.iter().map(|v| v.map(f64::from)).collect(),
                self.faces.clone(),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_every_frame_and_refuses_bad_input() {
        let body = crate::default_body().unwrap();
        let mut bent = [[0.0f32; 3]; 24];
        bent[18] = [0.0, 0.0, 1.2]; // left elbow
        let poses = vec![[[0.0f32; 3]; 24], bent];
        let trans = vec![[0.0, 0.0, 0.0], [0.0, 0.5, 0.0]];
        let posed = PosedSequence::new(&body, &[0.5], &poses, &trans).unwrap();
        assert_eq!(posed.len(), 2);
        let (a, b) = (posed.frame(0).unwrap(), posed.frame(1).unwrap());
        // The translation moves every vertex; the elbow bends some of them further.
        let moved = a
            .iter()
            .zip(b)
            .filter(|(p, q)| (q[1] - p[1] - 0.5).abs() > 1e-3);
        assert!(moved.count() > 0);
        let mut visited = 0;
        posed
            .for_each_surface(|t, s| {
                assert_eq!(s.positions().len(), a.len(), "frame {t}");
                visited += 1;
                Ok::<_, BodyError>(())
            })
            .unwrap();
        assert_eq!(visited, 2);
        assert_eq!(posed.mesh(0).unwrap().faces.len(), body.faces().len());
        // Counts that disagree, and NaN, are errors.
        assert!(PosedSequence::new(&body, &[], &poses, &trans[..1]).is_err());
        let nan = vec![[f32::NAN, 0.0, 0.0]; 2];
        assert!(PosedSequence::new(&body, &[], &poses, &nan).is_err());
        let mut bad = poses.clone();
        bad[1][3][0] = f32::NAN;
        assert!(PosedSequence::new(&body, &[], &bad, &trans).is_err());
    }
}
