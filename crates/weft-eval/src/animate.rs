//! `weft animate`: a trained model drives any garment (unseen topology included) on any
//! body shape and motion, and the frames are written in a format graphics tools read.
//!
//! Motions come from a file (AMASS `.npz`, `.bvh`, read by [`weft_motion::load_motion`]
//! against the body's own rest joints `J(β)`, as every command reads motion files) or
//! from weft's procedural library by name. Export goes through weft-mesh's writers (atomic: a failure leaves nothing).

use std::path::Path;

use weft_body::query::MovingSurface;
use weft_body::{BodyError, BodyModel, PosedSequence};
use weft_mesh::export::{
    check_template, validate_fps, write_scene, AnimatedMesh, CornerUvs, ExportFormat, Frames,
    BODY_COLOR, GARMENT_COLOR,
};
use weft_mesh::TriMesh;
use weft_models::{Clip, Deformer};
use weft_motion::{
    body_rest_joints, generate, load_motion, Motion, MotionFileOptions, MotionKind,
    ProceduralParams, UpAxis,
};

use crate::error::EvalError;

/// Where a motion comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum MotionSpec {
    /// An AMASS `.npz` or `.bvh` file.
    File {
        /// The file.
        path: std::path::PathBuf,
        /// Its up axis; `None`: as the file records, else the format's convention.
        up: Option<UpAxis>,
        /// The frame rate to resample to; `None`: the file's own.
        fps: Option<f64>,
    },
    /// A procedural motion.
    Procedural {
        /// walk, run, jump, dance, …
        kind: MotionKind,
        /// Number of frames.
        frames: usize,
        /// Seed of its variations.
        seed: u64,
        /// Frames per second.
        fps: f64,
    },
}

impl MotionSpec {
    /// `spec` is an existing file (read at its own rate and up axis), or a procedural
    /// motion name (`walk`, `dance`, …) with `frames`, `seed` and `fps`.
    pub fn parse(spec: &str, frames: usize, seed: u64, fps: f64) -> Result<Self, EvalError> {
        let path = Path::new(spec);
        if path.exists() {
            return Ok(MotionSpec::File {
                path: path.to_path_buf(),
                up: None,
                fps: None,
            });
        }
        match MotionKind::parse(spec) {
            Some(kind) => Ok(MotionSpec::Procedural {
                kind,
                frames,
                seed,
                fps,
            }),
            None => Err(EvalError::Invalid(format!(
                "motion {spec:?} is neither an existing .npz/.bvh file nor a procedural motion name (see `weft motion generate --help`)"
            ))),
        }
    }

    /// Reads or generates the motion for `body` at shape `betas`.
    pub fn load(&self, body: &BodyModel, betas: &[f32]) -> Result<Motion, EvalError> {
        match self {
            MotionSpec::File { path, up, fps } => {
                let betas: Vec<f64> = betas.iter().map(|&b| f64::from(b)).collect();
                let invalid = |e: weft_motion::MotionError| EvalError::Invalid(e.to_string());
                let rest = body_rest_joints(body, &betas).map_err(invalid)?;
                let options = MotionFileOptions::for_body(rest, *up);
                let read = load_motion(path, &options, *fps)
                    .map_err(|e| EvalError::Invalid(format!("{}: {e}", path.display())))?;
                Ok(read.motion)
            }
            MotionSpec::Procedural {
                kind,
                frames,
                seed,
                fps,
            } => {
                let mut p = ProceduralParams::new(*kind);
                p.frames = *frames;
                p.seed = *seed;
                p.fps = *fps;
                generate(&p).map_err(|e| EvalError::Invalid(format!("motion {kind}: {e}")))
            }
        }
    }
}

/// A body to export with the garment: its faces and its vertices per frame.
pub type BodyFrames<'a> = (&'a [[u32; 3]], &'a [Vec<[f32; 3]>]);

/// The garment animated by `deformer` on `body` at `betas` through `motion`.
pub fn animate(
    deformer: &dyn Deformer,
    garment: &TriMesh,
    body: &BodyModel,
    betas: &[f32],
    motion: &Motion,
) -> Result<Vec<Vec<[f32; 3]>>, EvalError> {
    let clip = Clip {
        betas,
        poses: motion.poses(),
        trans: motion.trans(),
        fps: motion.fps(),
    };
    Ok(deformer.animate(garment, body, &clip)?)
}

/// A post-process for predicted frames: every vertex inside the posed body, or closer
/// to it than `margin` (m), moves to the closest body surface point plus `margin`
/// outwards (weft-garment's push-out, as when a garment is fitted). The network has no
/// hard contact constraint: legs can pass through a predicted skirt. Returns how many
/// vertices moved over all frames. `posed` holds the body at each of the frames.
pub fn push_out_of_body(
    frames: &mut [Vec<[f32; 3]>],
    posed: &PosedSequence,
    margin: f64,
) -> Result<usize, EvalError> {
    if posed.len() != frames.len() {
        return Err(EvalError::Count {
            what: "posed body frames vs garment frames",
            expected: frames.len(),
            found: posed.len(),
        });
    }
    let mut moved = 0;
    posed.for_each_surface(|t, surface| {
        let frame = &mut frames[t];
        let mut points: Vec<[f64; 3]> = frame.iter().map(|p| p.map(f64::from)).collect();
        moved += weft_garment::onbody::push_out(surface, &mut points, margin)
            .map_err(|e| EvalError::Invalid(format!("push-out of frame {t}: {e}")))?;
        for (dst, src) in frame.iter_mut().zip(&points) {
            *dst = src.map(|x| x as f32);
        }
        Ok::<_, EvalError>(())
    })?;
    Ok(moved)
}

/// What an animation without ground truth is checked for, over all its frames: how far
/// it stretches the cloth and how much of it is inside the body (a rollout's strain and
/// penetration over the whole sequence; legs through a skirt).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct AnimationCheck {
    /// Frames checked.
    pub frames: usize,
    /// Mean `|l / l₀ − 1|` over every edge of every frame, against the garment as given.
    pub strain_mean: f64,
    /// The largest.
    pub strain_max: f64,
    /// Share of the vertices, over every frame, inside the posed body.
    pub inside: f64,
    /// The deepest of them, mm (0 when none is inside).
    pub deepest_mm: f64,
    /// The frame with the largest share of its vertices inside the body: where to look
    /// in the pictures (0 when none is inside).
    pub worst_frame: usize,
    /// That frame's share.
    pub worst_frame_inside: f64,
    /// Vertex positions that were not finite (left out of the figures above).
    pub nonfinite: usize,
}

/// [`AnimationCheck`] of `frames` of `garment`; `posed` holds the body at each frame.
pub fn check_animation(
    garment: &TriMesh,
    frames: &[Vec<[f32; 3]>],
    posed: &PosedSequence,
) -> Result<AnimationCheck, EvalError> {
    if posed.len() < frames.len() {
        return Err(EvalError::Count {
            what: "posed body frames vs garment frames",
            expected: frames.len(),
            found: posed.len(),
        });
    }
    let topology = crate::metrics::GarmentTopology::new(garment)?;
    let (mut strain_sum, mut strain_count, mut strain_max) = (0.0, 0usize, 0.0f64);
    let (mut inside, mut checked, mut deepest, mut nonfinite) = (0usize, 0usize, 0.0f64, 0);
    let (mut worst_frame, mut worst_frame_inside) = (0, 0.0f64);
    // `posed` may run past the frames (a rollout that diverged): follow the body only
    // as far as they go.
    let mut body = MovingSurface::new(posed.faces());
    for (t, (frame, body_frame)) in frames.iter().zip(posed.frames()).enumerate() {
        let surface = body.frame(body_frame).map_err(BodyError::from)?;
        for e in crate::metrics::edge_strains(&topology.edges, &topology.rest_lengths, frame)? {
            if e.is_finite() {
                strain_sum += e;
                strain_count += 1;
                strain_max = strain_max.max(e);
            }
        }
        let finite: Vec<[f32; 3]> = frame
            .iter()
            .copied()
            .filter(|p| p.iter().all(|x| x.is_finite()))
            .collect();
        nonfinite += frame.len() - finite.len();
        let mut frame_inside = 0usize;
        for d in crate::metrics::body_signed_distances(surface, &finite)? {
            checked += 1;
            if d < 0.0 {
                frame_inside += 1;
                deepest = deepest.max(-d);
            }
        }
        inside += frame_inside;
        let share = frame_inside as f64 / finite.len().max(1) as f64;
        if share > worst_frame_inside {
            (worst_frame, worst_frame_inside) = (t, share);
        }
    }
    Ok(AnimationCheck {
        frames: frames.len(),
        strain_mean: strain_sum / strain_count.max(1) as f64,
        strain_max,
        inside: inside as f64 / checked.max(1) as f64,
        deepest_mm: 1e3 * deepest,
        worst_frame,
        worst_frame_inside,
        nonfinite,
    })
}

impl std::fmt::Display for AnimationCheck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "over {} frames: edge strain mean {:.2} %, max {:.1} %; {:.2} % of the vertices inside the body, deepest {:.1} mm",
            self.frames,
            100.0 * self.strain_mean,
            100.0 * self.strain_max,
            100.0 * self.inside,
            self.deepest_mm
        )?;
        if self.inside > 0.0 {
            write!(
                f,
                " (most in frame {}: {:.2} %)",
                self.worst_frame,
                100.0 * self.worst_frame_inside
            )?;
        }
        if self.nonfinite > 0 {
            write!(f, "; {} non-finite vertex positions", self.nonfinite)?;
        }
        Ok(())
    }
}

/// Writes `frames` of `garment` (with its corner `uvs`, when it has them) to `out` in
/// `format` at `fps`; for the scene formats (glb, usd), `body` (faces and frames) is
/// added as a second animated mesh.
pub fn write_animation(
    format: ExportFormat,
    garment: &TriMesh,
    uvs: Option<&CornerUvs>,
    frames: &[Vec<[f32; 3]>],
    fps: f64,
    body: Option<BodyFrames<'_>>,
    out: &Path,
) -> Result<(), EvalError> {
    let export_err = |e: weft_mesh::export::ExportError| EvalError::Invalid(format!("export: {e}"));
    let g = Frames::from_frames(frames).map_err(export_err)?;
    check_template(garment, &g).map_err(export_err)?;
    validate_fps(fps as f32).map_err(export_err)?;
    let b = match body {
        Some((_, body_frames)) if format.holds_scene() => {
            Some(Frames::from_frames(body_frames).map_err(export_err)?)
        }
        _ => None,
    };
    let mut meshes = vec![AnimatedMesh {
        name: "garment",
        faces: &garment.faces,
        uvs,
        frames: &g,
        color: GARMENT_COLOR,
    }];
    if let (Some((faces, _)), Some(b)) = (body, &b) {
        meshes.push(AnimatedMesh {
            name: "body",
            faces,
            uvs: None,
            frames: b,
            color: BODY_COLOR,
        });
    }
    write_scene(format, &meshes, fps as f32, out).map_err(export_err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn motion_specs() {
        let body = weft_body::default_body().unwrap();
        let m = MotionSpec::parse("walk", 12, 3, 30.0).unwrap();
        let motion = m.load(&body, &[]).unwrap();
        assert_eq!(motion.frame_count(), 12);
        assert!(MotionSpec::parse("no-such-motion-or-file", 12, 0, 30.0).is_err());
        assert!(MotionSpec::parse("walk", 0, 0, 30.0)
            .unwrap()
            .load(&body, &[])
            .is_err());
    }

    #[test]
    fn push_out_moves_only_vertices_inside_the_body_of_their_frame() {
        let body = weft_body::default_body().unwrap();
        let pelvis = body.joints(&vec![0.0; body.num_betas()]).unwrap()[0];
        let trans = [[0.0f32; 3], [0.0, 0.3, 0.0]];
        let posed = PosedSequence::new(&body, &[], &[[[0.0f32; 3]; 24]; 2], &trans).unwrap();
        let far = [0.0f32, 0.0, 2.0];
        // The pelvis joint is inside the body in both frames, the far point outside.
        let mut frames: Vec<Vec<[f32; 3]>> = trans
            .iter()
            .map(|t| {
                let inside = [0, 1, 2].map(|c| pelvis[c] as f32 + t[c]);
                vec![inside, far]
            })
            .collect();
        let margin = 0.004;
        let moved = push_out_of_body(&mut frames, &posed, margin).unwrap();
        assert_eq!(moved, 2);
        posed
            .for_each_surface(|t, surface| {
                assert_eq!(frames[t][1], far);
                let d = surface
                    .signed_distance(frames[t][0].map(f64::from))
                    .unwrap();
                // Outside; at most `margin` out (concave parts of the body, here the
                // crotch, can leave it nearer than `margin` to another triangle).
                assert!(
                    d > 0.0 && d <= margin + 1e-6,
                    "frame {t}: signed distance {d}"
                );
                Ok::<_, EvalError>(())
            })
            .unwrap();
        assert!(push_out_of_body(&mut frames[..1], &posed, margin).is_err());
    }

    #[test]
    fn check_counts_vertices_inside_and_names_the_worst_frame() {
        let body = weft_body::default_body().unwrap();
        let pelvis = body.joints(&vec![0.0; body.num_betas()]).unwrap()[0];
        let inside = pelvis.map(|x| x as f32);
        let far = [0.0f32, 0.0, 2.0];
        let posed =
            PosedSequence::new(&body, &[], &[[[0.0f32; 3]; 24]; 3], &[[0.0; 3]; 3]).unwrap();
        // A one-triangle "garment", moved about whole.
        let garment = TriMesh {
            positions: vec![[0.0, 0.0, 2.0], [0.0, 0.1, 2.0], [0.1, 0.0, 2.0]],
            faces: vec![[0, 1, 2]],
        };
        let frames = vec![
            vec![far, far, far],
            vec![inside, inside, far],
            vec![inside, far, far],
        ];
        let check = check_animation(&garment, &frames, &posed).unwrap();
        assert_eq!(check.frames, 3);
        assert!((check.inside - 3.0 / 9.0).abs() < 1e-12, "{}", check.inside);
        assert_eq!(check.worst_frame, 1);
        assert!((check.worst_frame_inside - 2.0 / 3.0).abs() < 1e-12);
        assert!(check.deepest_mm > 10.0, "{}", check.deepest_mm);
        assert!(check.to_string().contains("most in frame 1"), "{check}");
    }
}
