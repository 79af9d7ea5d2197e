//! AMASS-style `.npz` motions: reading SMPL, SMPL-H and SMPL-X pose arrays into a
//! [`Motion`], and writing any motion back in the same layout.
//!
//! Keys read (others, such as `gender`, `dmpls` or `marker_data`, are reported unused):
//!
//! | key | shape | meaning |
//! |---|---|---|
//! | `poses` | (N, 72), (N, 156) or (N, 165) | axis-angles: SMPL (24 joints), SMPL-H (52), SMPL-X (55) |
//! | `root_orient` + `pose_body` | (N, 3) + (N, 63) | the same split by part (AMASS's SMPL-X release), when `poses` is absent |
//! | `trans` | (N, 3) | root translation, metres |
//! | `mocap_framerate` or `mocap_frame_rate` | () or (1,) | frames per second (SMPL-H and SMPL-X releases name it differently) |
//! | `betas` | (B,) or (1, B), optional | body shape β |
//! | `weft_up_axis` | (3,), optional | the file's up direction, (0, 0, 1) or (0, 1, 0): recorded by weft ([`UP_AXIS_KEY`]) |
//!
//! **Joints.** SMPL, SMPL-H and SMPL-X share their first 22 joints (pelvis to wrists)
//! in the same order. SMPL's joints 22 and 23 (`left_hand`, `right_hand`, a single
//! knuckle joint per hand) have no counterpart: SMPL-H continues with 15 finger joints
//! per hand (22–36 left index1…thumb3, 37–51 right), SMPL-X with jaw and eyes (22–24)
//! before the fingers. Taking "the first 72 numbers" of an SMPL-H or SMPL-X pose would
//! drive SMPL's hands with the left index finger (or the jaw), so weft copies joints
//! 0–21 and leaves both SMPL hand joints at rest, as SNUG and HumanML3D do. Finger poses
//! are dropped (the report counts them).
//!
//! **Axes.** AMASS is Z up (its root orientation includes the turn from SMPL's Y-up
//! model frame to the capture's Z-up world). weft is Y up, so reading turns the world by
//! `C` = −90° about X ((x, y, z) → (x, z, −y)). SMPL rotates the root about the rest
//! pelvis J₀ *in model coordinates* and adds `trans` afterwards, so the posed pelvis
//! lies at `J₀ˢ + trans` in the file's world, J₀ˢ being the pelvis of the body the
//! capture was fitted with (SMPL-H at the file's β). In weft the posed pelvis is
//! `J₀ᵗ + trans'`, J₀ᵗ the pelvis of the body the motion will drive; equating the two
//! positions gives `R₀' = C·R₀` and `trans' = C·(trans + J₀ˢ) − J₀ᵗ`.
//! [`AmassOptions::source_pelvis`] defaults to the built-in SMPL-like skeleton's pelvis
//! (SMPL's own J₀ varies with β by a few centimetres) and
//! [`AmassOptions::target_pelvis`] should be the driven body's (weft's default body has
//! its pelvis at the origin). Writing applies the inverse with the same two, so a round
//! trip is exact. Files already Y up are read with [`UpAxis::Y`].
//!
//! **Which axis is up.** AMASS files record no up axis; they are Z up. Files weft
//! writes record theirs under [`UP_AXIS_KEY`] (Z unless asked otherwise), so they read
//! back the right way up whichever axis they were written with. The axis used is, first
//! to last: [`AmassOptions::up`] when given, the recorded one, Z. When neither was
//! given nor recorded and the body's trunk lies along the other axis in most frames,
//! the report warns that the file may be the other way up.
//!
//! **Size.** The `.npz` reader bounds every member by its archive entry (and at most
//! 8 GiB inflated); poses longer than [`MAX_FRAMES`](super::MAX_FRAMES) are refused.

use std::path::Path;

use nalgebra::Vector3;
use weft_mesh::io::npz::{Npz, NpzError, NpzWriter};

use super::error::MotionError;
use super::rest::DEFAULT_REST_JOINTS;
use super::retarget::UpAxis;
use super::rot::{axis_angle, quat};
use super::types::{Motion, MAX_FPS, MAX_FRAMES};
use weft_body::joints::SMPL_JOINT_COUNT;
use weft_body::Pose;

/// Joints shared by SMPL, SMPL-H and SMPL-X (pelvis to wrists).
const SHARED_JOINTS: usize = 22;

/// The key under which weft records a file's up axis: the up direction in the file's
/// coordinates as three `float64`, (0, 0, 1) for Z up and (0, 1, 0) for Y up. AMASS has
/// no such key; a reader that does not know it skips it as it skips `gender` or `dmpls`
/// (NumPy loads it as a plain array, without pickles).
pub const UP_AXIS_KEY: &str = "weft_up_axis";

/// Where the up axis a file was read with came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpFrom {
    /// Given by the caller ([`AmassOptions::up`], `--up`).
    Given,
    /// Recorded in the file ([`UP_AXIS_KEY`]).
    Recorded,
    /// Neither: AMASS's Z.
    Default,
}

impl UpFrom {
    /// A short phrase for reports: "given", "recorded in the file", "AMASS default".
    pub fn phrase(self) -> &'static str {
        match self {
            UpFrom::Given => "given",
            UpFrom::Recorded => "recorded in the file",
            UpFrom::Default => "AMASS default",
        }
    }
}

/// Options of [`read_amass`] and [`write_amass`].
#[derive(Clone, Debug, PartialEq)]
pub struct AmassOptions {
    /// The file's up axis. Reading: `None` takes the axis the file records under
    /// [`UP_AXIS_KEY`], else Z as in AMASS; a given axis overrides a recorded one.
    /// Writing: the axis to write (`None`: Z), recorded in the file.
    pub up: Option<UpAxis>,
    /// The rest pelvis J₀ˢ of the body the file's parameters belong to (metres, SMPL's
    /// Y-up model frame): SMPL's, for AMASS.
    pub source_pelvis: [f64; 3],
    /// The rest pelvis J₀ᵗ of the body the motion drives.
    pub target_pelvis: [f64; 3],
    /// Frames per second to use when the file records none; `None` makes a missing
    /// frame rate an error.
    pub fps_if_missing: Option<f64>,
}

impl Default for AmassOptions {
    fn default() -> Self {
        AmassOptions {
            up: None,
            source_pelvis: DEFAULT_REST_JOINTS[0],
            target_pelvis: DEFAULT_REST_JOINTS[0],
            fps_if_missing: None,
        }
    }
}

/// Which pose layout a file had.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoseLayout {
    /// `poses` (N, 72): SMPL's 24 joints.
    Smpl,
    /// `poses` (N, 156): SMPL-H's 52 joints.
    SmplH,
    /// `poses` (N, 165): SMPL-X's 55 joints.
    SmplX,
    /// `root_orient` (N, 3) and `pose_body` (N, 63): the 22 body joints.
    Parts,
}

impl PoseLayout {
    /// A short name for reports.
    pub fn name(self) -> &'static str {
        match self {
            PoseLayout::Smpl => "SMPL (72)",
            PoseLayout::SmplH => "SMPL-H (156)",
            PoseLayout::SmplX => "SMPL-X (165)",
            PoseLayout::Parts => "root_orient + pose_body",
        }
    }

    /// Joints in the file's poses.
    pub fn joints(self) -> usize {
        match self {
            PoseLayout::Smpl => 24,
            PoseLayout::SmplH => 52,
            PoseLayout::SmplX => 55,
            PoseLayout::Parts => 22,
        }
    }
}

/// What reading an AMASS file found.
#[derive(Clone, Debug, PartialEq)]
pub struct AmassReport {
    /// The pose layout.
    pub layout: PoseLayout,
    /// The key the frame rate came from, `None` when [`AmassOptions::fps_if_missing`]
    /// supplied it.
    pub frame_rate_key: Option<&'static str>,
    /// Joints of the file's poses beyond SMPL's 22 body joints that were not used
    /// (fingers, jaw, eyes).
    pub dropped_joints: usize,
    /// Keys weft does not read.
    pub unused_keys: Vec<String>,
    /// The up axis the file was read with.
    pub up: UpAxis,
    /// Where that axis came from.
    pub up_from: UpFrom,
    /// What looks wrong but was read anyway (a recorded axis overridden, a body that
    /// lies down in most frames with the default axis), one sentence each.
    pub warnings: Vec<String>,
}

const FRAME_RATE_KEYS: [&str; 2] = ["mocap_framerate", "mocap_frame_rate"];
const READ_KEYS: [&str; 8] = [
    "poses",
    "root_orient",
    "pose_body",
    "trans",
    "betas",
    "mocap_framerate",
    "mocap_frame_rate",
    UP_AXIS_KEY,
];

/// Reads an AMASS-style `.npz` motion (see the module documentation).
pub fn read_amass(
    path: &Path,
    options: &AmassOptions,
) -> Result<(Motion, AmassReport), MotionError> {
    let mut npz = Npz::open(path)?;
    amass_from_npz(&mut npz, options)
}

/// Reads an AMASS-style motion from an opened archive.
pub fn amass_from_npz(
    npz: &mut Npz,
    options: &AmassOptions,
) -> Result<(Motion, AmassReport), MotionError> {
    let path = npz.path().to_path_buf();
    let bad = |key: &str, message: String| MotionError::npz(&path, key, message);
    check_pelvis(options)?;

    // Poses.
    let (layout, n, poses_flat, stride) = if npz.contains("poses") || !npz.contains("pose_body") {
        let a = match npz.floats("poses", &[None, None]) {
            Err(NpzError::Shape { found, .. }) => {
                return Err(bad("poses", format!(
                    "has shape {found:?}; expected (N, 72) for SMPL, (N, 156) for SMPL-H or (N, 165) for SMPL-X"
                )))
            }
            r => r?,
        };
        let (n, d) = (a.shape[0], a.shape[1]);
        let layout = match d {
            72 => PoseLayout::Smpl,
            156 => PoseLayout::SmplH,
            165 => PoseLayout::SmplX,
            _ => {
                return Err(bad("poses", format!(
                    "has shape ({n}, {d}); expected (N, 72) for SMPL, (N, 156) for SMPL-H or (N, 165) for SMPL-X"
                )))
            }
        };
        (layout, n, a.data, d)
    } else {
        let body = npz.floats("pose_body", &[None, Some(3 * (SHARED_JOINTS - 1))])?;
        let n = body.shape[0];
        let root = npz.floats("root_orient", &[Some(n), Some(3)])?;
        let mut flat = Vec::with_capacity(n * 3 * SHARED_JOINTS);
        for t in 0..n {
            flat.extend_from_slice(&root.data[3 * t..3 * t + 3]);
            flat.extend_from_slice(&body.data[63 * t..63 * t + 63]);
        }
        (PoseLayout::Parts, n, flat, 3 * SHARED_JOINTS)
    };
    let pose_key = if layout == PoseLayout::Parts {
        "pose_body"
    } else {
        "poses"
    };
    if n == 0 {
        return Err(bad(
            pose_key,
            "has no frames (N = 0); expected at least one".into(),
        ));
    }
    if n > MAX_FRAMES {
        return Err(bad(
            pose_key,
            format!("has {n} frames; at most {MAX_FRAMES} fit in memory"),
        ));
    }
    if let Some(i) = poses_flat.iter().position(|x| !x.is_finite()) {
        return Err(bad(
            pose_key,
            format!(
                "frame {}, value {} is {}; expected finite axis-angles",
                i / stride,
                i % stride,
                poses_flat[i]
            ),
        ));
    }

    // Translation, frame rate, shape.
    let trans = npz.floats("trans", &[Some(n), Some(3)])?;
    if let Some(i) = trans.data.iter().position(|x| !x.is_finite()) {
        return Err(bad(
            "trans",
            format!(
                "frame {}, coordinate {} is {}; expected finite metres",
                i / 3,
                i % 3,
                trans.data[i]
            ),
        ));
    }
    let (fps, frame_rate_key) = match FRAME_RATE_KEYS.iter().find(|k| npz.contains(k)) {
        Some(&key) => (scalar(npz, key)?, Some(key)),
        None => match options.fps_if_missing {
            Some(f) => (f, None),
            None => {
                return Err(bad("", format!(
                    "no frame rate: expected `mocap_framerate` or `mocap_frame_rate` (the file has: {})",
                    npz.keys().join(", ")
                )))
            }
        },
    };
    if !(fps.is_finite() && fps > 0.0 && fps <= MAX_FPS) {
        return Err(bad(
            frame_rate_key.unwrap_or(""),
            format!("frame rate {fps}; expected frames per second above 0 and at most {MAX_FPS}"),
        ));
    }
    let betas = if npz.contains("betas") {
        let b = match npz.floats("betas", &[None]) {
            Err(NpzError::Shape { found, .. }) if found.len() == 2 && found[0] == 1 => {
                npz.floats("betas", &[Some(1), None])?
            }
            r => r?,
        };
        if let Some(i) = b.data.iter().position(|x| !x.is_finite()) {
            return Err(bad(
                "betas",
                format!("beta {i} is {}; expected finite numbers", b.data[i]),
            ));
        }
        Some(b.data.iter().map(|&x| x as f32).collect())
    } else {
        None
    };

    // Up axis: given, recorded, or AMASS's.
    let recorded = if npz.contains(UP_AXIS_KEY) {
        let v = npz.floats(UP_AXIS_KEY, &[Some(3)])?.data;
        let axis = [UpAxis::Y, UpAxis::Z].into_iter().find(|&a| {
            up_vector(a)
                .iter()
                .zip(&v)
                .all(|(x, y)| (x - y).abs() < 1e-6)
        });
        match axis {
            Some(a) => Some(a),
            None => {
                return Err(bad(
                    UP_AXIS_KEY,
                    format!("is {v:?}; expected [0, 1, 0] for Y up or [0, 0, 1] for Z up"),
                ))
            }
        }
    } else {
        None
    };
    let mut warnings = Vec::new();
    let (up, up_from) = match (options.up, recorded) {
        (Some(given), rec) => {
            if let Some(rec) = rec.filter(|&r| r != given) {
                warnings.push(format!(
                    "the file records {} up ({UP_AXIS_KEY}); read {} up as asked",
                    rec.name(),
                    given.name()
                ));
            }
            (given, UpFrom::Given)
        }
        (None, Some(rec)) => (rec, UpFrom::Recorded),
        (None, None) => (UpAxis::Z, UpFrom::Default),
    };
    if up_from == UpFrom::Default {
        warnings.extend(lying_down_warning(&poses_flat, stride, up));
    }

    // Convert.
    let c = up.to_y_up();
    let (j0s, j0t) = (
        Vector3::from(options.source_pelvis),
        Vector3::from(options.target_pelvis),
    );
    let shared = if layout == PoseLayout::Smpl {
        SMPL_JOINT_COUNT
    } else {
        SHARED_JOINTS
    };
    let mut poses: Vec<Pose> = Vec::with_capacity(n);
    let mut out_trans = Vec::with_capacity(n);
    for t in 0..n {
        let row = &poses_flat[t * stride..(t + 1) * stride];
        let mut pose = [[0.0f32; 3]; SMPL_JOINT_COUNT];
        for (j, r) in pose.iter_mut().enumerate().take(shared) {
            *r = [
                row[3 * j] as f32,
                row[3 * j + 1] as f32,
                row[3 * j + 2] as f32,
            ];
        }
        pose[0] = axis_angle(&(c * quat(pose[0])));
        let tr = Vector3::new(
            trans.data[3 * t],
            trans.data[3 * t + 1],
            trans.data[3 * t + 2],
        );
        let p = c * (tr + j0s) - j0t;
        poses.push(pose);
        out_trans.push([p.x as f32, p.y as f32, p.z as f32]);
    }
    let motion =
        Motion::new(fps, poses, out_trans, betas).map_err(|e| bad(pose_key, e.to_string()))?;
    let report = AmassReport {
        layout,
        frame_rate_key,
        dropped_joints: layout.joints().saturating_sub(shared),
        unused_keys: npz
            .keys()
            .into_iter()
            .filter(|k| !READ_KEYS.contains(&k.as_str()))
            .collect(),
        up,
        up_from,
        warnings,
    };
    Ok((motion, report))
}

/// The up direction of `up` in that file's own coordinates.
fn up_vector(up: UpAxis) -> [f64; 3] {
    match up {
        UpAxis::Y => [0.0, 1.0, 0.0],
        UpAxis::Z => [0.0, 0.0, 1.0],
    }
}

/// A warning when, read `up` up, the body lies down in most frames but would stand along
/// the other axis: the mean over frames of how far the trunk (the root's rotation of
/// SMPL's model Y) points along each axis of the file. Capture of someone lying down
/// exists, so this only warns.
fn lying_down_warning(poses_flat: &[f64], stride: usize, up: UpAxis) -> Option<String> {
    let other = match up {
        UpAxis::Y => UpAxis::Z,
        UpAxis::Z => UpAxis::Y,
    };
    let (u, o) = (
        Vector3::from(up_vector(up)),
        Vector3::from(up_vector(other)),
    );
    let (mut along_up, mut along_other, mut n) = (0.0, 0.0, 0usize);
    for row in poses_flat.chunks_exact(stride) {
        let root = quat([row[0] as f32, row[1] as f32, row[2] as f32]);
        let trunk = root * Vector3::y();
        along_up += trunk.dot(&u);
        along_other += trunk.dot(&o);
        n += 1;
    }
    let n = n.max(1) as f64;
    let (along_up, along_other) = (along_up / n, along_other / n);
    (along_up < 0.5 && along_other > 0.8).then(|| {
        format!(
            "read {} up (AMASS's axis; the file records none), the body lies down: its trunk points along the file's {} axis (mean {:.2}) rather than {} (mean {:.2}); if the file is {} up, read it with --up {}",
            up.name(),
            other.name(),
            along_other,
            up.name(),
            along_up,
            other.name(),
            other.name().to_ascii_lowercase()
        )
    })
}

/// A number stored as a 0-d or one-element array, float or integer.
fn scalar(npz: &mut Npz, key: &str) -> Result<f64, MotionError> {
    let wrong = |npz: &Npz, found: &[usize]| {
        MotionError::npz(
            npz.path(),
            key,
            format!("has shape {found:?}; expected a single number, shape () or (1,)"),
        )
    };
    let data: Vec<f64> = match npz.floats(key, &[]) {
        Ok(a) => a.data,
        Err(NpzError::Shape { found, .. }) if found == [1] => npz.floats(key, &[Some(1)])?.data,
        Err(NpzError::Shape { found, .. }) => return Err(wrong(npz, &found)),
        Err(NpzError::Dtype { .. }) => {
            let ints = match npz.ints(key, &[]) {
                Err(NpzError::Shape { found, .. }) if found == [1] => npz.ints(key, &[Some(1)])?,
                Err(NpzError::Shape { found, .. }) => return Err(wrong(npz, &found)),
                r => r?,
            };
            ints.data.iter().map(|&x| x as f64).collect()
        }
        Err(e) => return Err(e.into()),
    };
    data.first().copied().ok_or_else(|| wrong(npz, &[0]))
}

fn check_pelvis(options: &AmassOptions) -> Result<(), MotionError> {
    for (which, p) in [
        ("source", options.source_pelvis),
        ("target", options.target_pelvis),
    ] {
        if !p.iter().all(|x| x.is_finite()) {
            return Err(MotionError::Parameter(format!(
                "{which} rest pelvis {p:?}; expected finite coordinates"
            )));
        }
    }
    Ok(())
}

/// The AMASS-style arrays of a motion: `poses` (N, 72) in SMPL's layout, `trans`
/// (N, 3), `mocap_framerate` (a 0-d array) and, when the motion records a shape,
/// `betas` (B,), all `float64` as AMASS stores them, converted to `options.up` (Z when
/// `None`), and that axis under [`UP_AXIS_KEY`] so that weft reads the file back the
/// right way up.
pub fn amass_npz(motion: &Motion, options: &AmassOptions) -> Result<NpzWriter, MotionError> {
    check_pelvis(options)?;
    let up = options.up.unwrap_or(UpAxis::Z);
    let c_inv = up.to_y_up().inverse();
    let (j0s, j0t) = (
        Vector3::from(options.source_pelvis),
        Vector3::from(options.target_pelvis),
    );
    let n = motion.frame_count();
    let mut poses = Vec::with_capacity(n * 3 * SMPL_JOINT_COUNT);
    let mut trans = Vec::with_capacity(n * 3);
    for (pose, t) in motion.poses().iter().zip(motion.trans()) {
        let root = axis_angle(&(c_inv * quat(pose[0])));
        poses.extend(root.iter().map(|&x| f64::from(x)));
        for r in &pose[1..] {
            poses.extend(r.iter().map(|&x| f64::from(x)));
        }
        let tr = Vector3::new(f64::from(t[0]), f64::from(t[1]), f64::from(t[2]));
        let p = c_inv * (tr + j0t) - j0s;
        trans.extend([p.x, p.y, p.z]);
    }
    let mut w = NpzWriter::new(false);
    let add_err = |e: std::io::Error| MotionError::Invalid(e.to_string());
    w.add("poses", &[n, 3 * SMPL_JOINT_COUNT], &poses)
        .map_err(add_err)?;
    w.add("trans", &[n, 3], &trans).map_err(add_err)?;
    w.add("mocap_framerate", &[], &[motion.fps()])
        .map_err(add_err)?;
    if let Some(b) = motion.betas() {
        let b: Vec<f64> = b.iter().map(|&x| f64::from(x)).collect();
        w.add("betas", &[b.len()], &b).map_err(add_err)?;
    }
    w.add(UP_AXIS_KEY, &[3], &up_vector(up)).map_err(add_err)?;
    Ok(w)
}

/// Writes a motion as an AMASS-style `.npz` (see [`amass_npz`]), atomically.
pub fn write_amass(
    path: &Path,
    motion: &Motion,
    options: &AmassOptions,
) -> Result<(), MotionError> {
    amass_npz(motion, options)?.write(path)?;
    Ok(())
}
