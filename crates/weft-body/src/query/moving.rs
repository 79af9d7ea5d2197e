//! [`MovingSurface`]: the query surface of a body that moves frame by frame (same
//! faces), built once and refit for the next frames — the per-frame loop that the
//! collision metric, the animation check, the push-out post-process and the model's
//! contact input all share.

use super::error::QueryError;
use super::surface::BodySurface;

/// Frames between fresh tree builds: a refit keeps the tree's topology, so its boxes
/// overlap more the further the pose moves from the one it was built on (queries stay
/// exact, only slower); a walk of a second or two stays tight, a long rollout is rebuilt.
pub const REBUILD_EVERY: usize = 64;

/// A body surface following its frames in order.
///
/// Building a [`BodySurface`] numbers the edges (a sort of every half-edge) and builds a
/// tree: on the default body that is several times a refit, and it was most of a
/// training step when done per frame. Results are those of a fresh build (the queries
/// are exact whatever the tree).
#[derive(Clone, Debug)]
pub struct MovingSurface {
    faces: Vec<[u32; 3]>,
    surface: Option<BodySurface>,
    since_build: usize,
    scratch: Vec<[f64; 3]>,
}

impl MovingSurface {
    /// A surface over `faces`, built on the first frame given to [`MovingSurface::frame`].
    pub fn new(faces: &[[u32; 3]]) -> Self {
        MovingSurface {
            faces: faces.to_vec(),
            surface: None,
            since_build: 0,
            scratch: Vec::new(),
        }
    }

    /// The surface at the next frame's `positions` (the vertex count must stay that of
    /// the first frame; non-finite positions are refused).
    pub fn frame(&mut self, positions: &[[f32; 3]]) -> Result<&BodySurface, QueryError> {
        self.scratch.clear();
        self.scratch
            .extend(positions.iter().map(|p| p.map(f64::from)));
        match &mut self.surface {
            Some(s) if self.since_build < REBUILD_EVERY => {
                s.refit(&self.scratch)?;
                self.since_build += 1;
            }
            Some(s) => {
                s.rebuild(&self.scratch)?;
                self.since_build = 1;
            }
            None => {
                self.surface = Some(BodySurface::new(&self.scratch, &self.faces)?);
                self.since_build = 1;
            }
        }
        Ok(self.surface.as_ref().expect("set above"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra(shift: f32) -> Vec<[f32; 3]> {
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]
        .map(|p: [f32; 3]| [p[0] + shift, p[1] - 0.5 * shift, p[2]])
        .to_vec()
    }

    const FACES: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

    #[test]
    fn every_frame_answers_as_a_fresh_surface() {
        let mut moving = MovingSurface::new(&FACES);
        let probe = [[0.2, 0.1, 0.3], [2.0, -1.0, 0.5], [0.9, 0.9, 0.9]];
        for t in 0..(2 * REBUILD_EVERY + 3) {
            let frame = tetra(0.05 * t as f32);
            let fresh: Vec<[f64; 3]> = frame.iter().map(|p| p.map(f64::from)).collect();
            let fresh = BodySurface::new(&fresh, &FACES).unwrap();
            let s = moving.frame(&frame).unwrap();
            for p in probe {
                assert_eq!(
                    s.signed_distance(p).unwrap(),
                    fresh.signed_distance(p).unwrap(),
                    "frame {t}"
                );
            }
        }
    }

    #[test]
    fn refuses_another_vertex_count_and_nan() {
        let mut moving = MovingSurface::new(&FACES);
        moving.frame(&tetra(0.0)).unwrap();
        assert!(matches!(
            moving.frame(&tetra(0.0)[..3]),
            Err(QueryError::CountMismatch { .. })
        ));
        let mut bad = tetra(0.0);
        bad[2][1] = f32::NAN;
        assert!(moving.frame(&bad).is_err());
        assert!(MovingSurface::new(&[]).frame(&tetra(0.0)).is_err());
    }
}
