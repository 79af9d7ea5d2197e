//! `--motion`, `--up` and `--fps`: the arguments of every command that reads a motion
//! (`simulate`, `animate`, `body pose`), so that each reads a file the same way — through
//! [`weft_motion::load_motion`], against the rest joints J(β) of the body it drives —
//! and puts the same body at the same place for the same file.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};
use weft_body::BodyModel;
use weft_motion::{
    body_rest_joints, generate, load_motion, LoadedMotion, Motion, MotionFileOptions, MotionKind,
    MotionSource, ProceduralParams, UpAxis,
};

/// An up axis on the command line.
#[derive(Clone, Copy, ValueEnum)]
pub enum Up {
    Y,
    Z,
}

impl From<Up> for UpAxis {
    fn from(u: Up) -> Self {
        match u {
            Up::Y => UpAxis::Y,
            Up::Z => UpAxis::Z,
        }
    }
}

/// Frame rate of a procedural motion when `--fps` is not given.
pub const DEFAULT_PROCEDURAL_FPS: f64 = 30.0;

/// `--motion FILE|NAME` with `--up`, `--fps` and `--seed`: a motion file or a procedural
/// motion.
#[derive(Args)]
pub struct MotionArgs {
    /// The motion: an .npz (AMASS layout) or .bvh file, or a procedural motion name
    /// (walk, run, jump, dance, kick, raise-arms, twist, bow).
    #[arg(long, value_name = "FILE|NAME")]
    pub motion: String,
    /// Up axis of a motion file (default: the axis a file written by weft records, else
    /// z for .npz as in AMASS, y for .bvh).
    #[arg(long, value_enum)]
    pub up: Option<Up>,
    /// Frames per second. A motion file is resampled to this rate, which is said on
    /// stderr (default: the file's own rate; an .npz recording none runs at this one);
    /// a procedural motion is generated at it (default 30).
    #[arg(long, value_parser = super::frame_rate)]
    pub fps: Option<f64>,
    /// Seed of a procedural motion's variations.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

impl MotionArgs {
    /// Whether `--motion` names a file: an existing path, or one ending in .npz or
    /// .bvh (so that a missing file is reported as such, not as an unknown name).
    pub fn is_file(&self) -> bool {
        let path = Path::new(&self.motion);
        path.exists() || super::has_extension(path, &["npz", "bvh"])
    }

    /// The motion for `model` at shape `betas`: the file read for that body (see
    /// [`read_motion_file`]), or the procedural motion generated with `frames` frames.
    pub fn load(&self, model: &BodyModel, betas: &[f64], frames: usize) -> Result<Motion> {
        if self.is_file() {
            let read = read_motion_file(Path::new(&self.motion), self.up, self.fps, model, betas)?;
            return Ok(read.motion);
        }
        let Some(kind) = MotionKind::parse(&self.motion) else {
            bail!(
                "--motion {:?} is neither an existing motion file (.npz, .bvh) nor a procedural motion (walk, run, jump, dance, kick, raise-arms, twist, bow)",
                self.motion
            );
        };
        if self.up.is_some() {
            bail!("--up applies to motion files; {kind} is a procedural motion, generated Y up");
        }
        // Procedural motions pose SMPL's joints: a body with another skeleton is
        // refused here, naming its file, rather than when the first frame is posed.
        body_rest_joints(model, betas)?;
        let params = ProceduralParams {
            frames,
            fps: self.fps.unwrap_or(DEFAULT_PROCEDURAL_FPS),
            seed: self.seed,
            ..ProceduralParams::new(kind)
        };
        generate(&params).with_context(|| format!("generating {kind}"))
    }
}

/// `--motion FILE` with `--up` and `--fps`: a motion file only.
#[derive(Args)]
pub struct MotionFileArgs {
    /// The motion: an .npz (AMASS layout) or .bvh file (see `weft motion`).
    #[arg(long, value_name = "FILE")]
    pub motion: PathBuf,
    /// Up axis of the file (default: the axis a file written by weft records, else z for
    /// .npz as in AMASS, y for .bvh).
    #[arg(long, value_enum)]
    pub up: Option<Up>,
    /// Resample the motion to this many frames per second, said on stderr (default: the
    /// file's own rate; an .npz recording none runs at this one).
    #[arg(long, value_parser = super::frame_rate)]
    pub fps: Option<f64>,
}

impl MotionFileArgs {
    /// The file read for `model` at shape `betas` (see [`read_motion_file`]).
    pub fn load(&self, model: &BodyModel, betas: &[f64]) -> Result<LoadedMotion> {
        read_motion_file(&self.motion, self.up, self.fps, model, betas)
    }
}

/// Reads the motion file at `path` for `model` at shape `betas`, `up` up when given, at
/// `fps` when given (resampling is reported on stderr), with the BVH name map and units
/// detected. Every command's motion file goes through here.
pub fn read_motion_file(
    path: &Path,
    up: Option<Up>,
    fps: Option<f64>,
    model: &BodyModel,
    betas: &[f64],
) -> Result<LoadedMotion> {
    let rest = body_rest_joints(model, betas)?;
    let options = MotionFileOptions::for_body(rest, up.map(UpAxis::from));
    let read = load_motion(path, &options, fps)
        .with_context(|| format!("reading the motion {}", path.display()))?;
    report(path, &read);
    Ok(read)
}

/// Says on stderr what reading a motion file changed or doubted: resampling, and the
/// reader's warnings (an overridden up axis, a body lying down, BVH mapping doubts).
pub fn report(path: &Path, read: &LoadedMotion) {
    if let Some((fps, frames)) = read.resampled_from {
        eprintln!(
            "note: {}: resampled from {fps} fps ({frames} frames) to {} fps ({} frames)",
            path.display(),
            read.motion.fps(),
            read.motion.frame_count()
        );
    }
    let warnings = match &read.source {
        MotionSource::Amass(r) => &r.warnings,
        MotionSource::Bvh(r) => &r.warnings,
    };
    for w in warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_data::{
        generate as generate_dataset, DataConfig, Dataset, GarmentSpec, GenerateOptions,
        MotionSpec as DataMotion, SequenceSimulator, Silent, SimInput, SimOutcome, SplitConfig,
    };
    use weft_eval::animate::MotionSpec;
    use weft_motion::{write_motion, MotionKind};

    /// The rest garment, one frame per motion frame: only the motion matters here.
    struct Still;

    impl SequenceSimulator for Still {
        fn simulate(
            &self,
            input: &SimInput<'_>,
            on_frame: &mut dyn FnMut(),
        ) -> Result<SimOutcome, String> {
            let rest: Vec<[f32; 3]> = input
                .garment
                .positions
                .iter()
                .map(|p| p.map(|x| x as f32))
                .collect();
            let frames = (0..input.motion.frame_count())
                .map(|_| {
                    on_frame();
                    rest.clone()
                })
                .collect();
            Ok(SimOutcome::Finished {
                frames,
                stats: serde_json::json!([]),
            })
        }
    }

    /// Where the body stands at each frame: the posed pelvis (SMPL rotates the root about
    /// the rest pelvis, so it is J₀(β) + trans) and the root's axis-angle.
    fn placement(j0: [f64; 3], motion: (&[weft_motion::Pose], &[[f32; 3]])) -> Vec<[f64; 6]> {
        let (poses, trans) = motion;
        poses
            .iter()
            .zip(trans)
            .map(|(p, t)| {
                let r = p[0].map(f64::from);
                [
                    j0[0] + f64::from(t[0]),
                    j0[1] + f64::from(t[1]),
                    j0[2] + f64::from(t[2]),
                    r[0],
                    r[1],
                    r[2],
                ]
            })
            .collect()
    }

    fn assert_same(what: &str, a: &[[f64; 6]], b: &[[f64; 6]]) {
        assert_eq!(a.len(), b.len(), "{what}: frame counts");
        for (t, (x, y)) in a.iter().zip(b).enumerate() {
            let pelvis = (0..3).map(|k| (x[k] - y[k]).abs()).fold(0.0, f64::max);
            let root = (3..6).map(|k| (x[k] - y[k]).abs()).fold(0.0, f64::max);
            assert!(
                pelvis < 1e-3 && root < 1e-5,
                "{what}, frame {t}: pelvis {:?} vs {:?} ({:.1} mm apart), root {:?} vs {:?}",
                &x[..3],
                &y[..3],
                1e3 * pelvis,
                &x[3..],
                &y[3..]
            );
        }
    }

    /// Issue 17 item 9: `weft animate` read .npz files with its body's pelvis as the
    /// file's source pelvis and put body and garment about 22 cm back and 2 cm down from
    /// where `weft simulate` and `weft body pose` put them; datasets (what `weft eval`
    /// evaluates on) read file motions for the zero shape whatever the sequence's body.
    /// The same file through each must place the same body (β ≠ 0) at the same place.
    #[test]
    fn simulate_body_pose_animate_and_eval_place_the_same_body_alike() {
        let dir = std::env::temp_dir().join(format!("weft-cli-placement-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let model = weft_body::default_body().unwrap();
        let betas = model.betas(&[1.5, -1.0]).unwrap();
        let betas32: Vec<f32> = betas.iter().map(|&b| b as f32).collect();
        let j0 = model.joints(&betas).unwrap()[0];
        let mut p = ProceduralParams::new(MotionKind::Walk);
        p.frames = 6;
        let walk = generate(&p).unwrap();
        for name in ["walk.npz", "walk.bvh"] {
            let file = dir.join(name);
            write_motion(&file, &walk, &MotionFileOptions::default()).unwrap();
            let text = file.to_str().unwrap().to_string();

            // weft simulate and weft animate (--motion FILE).
            let args = MotionArgs {
                motion: text.clone(),
                up: None,
                fps: None,
                seed: 0,
            };
            let m = args.load(&model, &betas, 60).unwrap();
            let simulate = placement(j0, (m.poses(), m.trans()));

            // weft body pose.
            let m = MotionFileArgs {
                motion: file.clone(),
                up: None,
                fps: None,
            }
            .load(&model, &betas)
            .unwrap()
            .motion;
            assert_same(
                &format!("{name}: body pose vs simulate"),
                &placement(j0, (m.poses(), m.trans())),
                &simulate,
            );

            // weft-eval's motion spec (weft demo, weft attribute).
            let m = MotionSpec::parse(&text, 0, 0, 30.0)
                .unwrap()
                .load(&model, &betas32)
                .unwrap();
            assert_same(
                &format!("{name}: weft-eval's MotionSpec vs simulate"),
                &placement(j0, (m.poses(), m.trans())),
                &simulate,
            );

            // weft eval: a dataset whose training sequence performs the file on this
            // body (the other splits, which must differ, are procedural and small).
            let other = |seed: u64, kind: &str| SplitConfig {
                betas: vec![vec![seed as f64 / 4.0]],
                random_bodies: 0,
                motions_per_pair: 0,
                garments: vec![GarmentSpec {
                    kind: "skirt".into(),
                    vertices: 300,
                    seed: Some(seed),
                    material: None,
                    length: None,
                }],
                motions: vec![DataMotion {
                    kind: Some(kind.into()),
                    frames: Some(2),
                    ..DataMotion::default()
                }],
            };
            let split = SplitConfig {
                betas: vec![vec![1.5, -1.0]],
                random_bodies: 0,
                motions_per_pair: 0,
                garments: vec![GarmentSpec {
                    kind: "skirt".into(),
                    vertices: 300,
                    seed: Some(1),
                    material: None,
                    length: None,
                }],
                motions: vec![DataMotion {
                    file: Some(file.clone()),
                    frames: Some(4),
                    ..DataMotion::default()
                }],
            };
            let config = DataConfig {
                fps: walk.fps(),
                warmup_frames: 0,
                train: split,
                validation: other(2, "kick"),
                test: other(3, "twist"),
                ..DataConfig::default()
            };
            let out = dir.join(format!("data-{name}"));
            generate_dataset(&config, &out, &GenerateOptions::default(), &Still, &Silent).unwrap();
            let ds = Dataset::open(&out).unwrap();
            let record = ds.records_in(weft_data::Split::Train)[0].clone();
            assert_eq!(record.betas, betas32);
            let seq = ds.load(&record).unwrap();
            assert_same(
                &format!("{name}: dataset (weft eval) vs simulate"),
                &placement(j0, (&seq.poses, &seq.trans)),
                &simulate[..4],
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
