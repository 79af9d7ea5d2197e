//! Motion files by extension: `.npz` (AMASS layout) and `.bvh`, in and out, with one
//! set of options for both; and [`load_motion`], the one way weft's commands read a
//! motion file for the body it drives.

use std::path::Path;

use super::amass::{read_amass, write_amass, AmassOptions, AmassReport};
use super::bvh::Bvh;
use super::error::MotionError;
use super::resample::resample;
use super::rest::DEFAULT_REST_JOINTS;
use super::retarget::{retarget_bvh, BvhUnits, MapChoice, RetargetOptions, RetargetReport, UpAxis};
use super::smpl_bvh::write_bvh;
use super::types::Motion;
use weft_body::joints::SMPL_JOINT_COUNT;
use weft_body::BodyModel;

/// A motion file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionFormat {
    /// AMASS-style `.npz`.
    Npz,
    /// Biovision `.bvh`.
    Bvh,
}

impl MotionFormat {
    /// The format a path's extension names (`.npz` or `.bvh`, any case).
    pub fn from_path(path: &Path) -> Result<Self, MotionError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("npz") => Ok(MotionFormat::Npz),
            Some("bvh") => Ok(MotionFormat::Bvh),
            _ => Err(MotionError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Options of [`read_motion`] and [`write_motion`].
#[derive(Clone, Debug, PartialEq)]
pub struct MotionFileOptions {
    /// Rest joints of the body the motion drives (J(β)): the pelvis places AMASS's
    /// root translation on it, all of them shape the BVH skeleton written and the
    /// retargeting target read.
    pub rest_joints: [[f64; 3]; SMPL_JOINT_COUNT],
    /// Up axis of `.npz` files: `None` reads the axis a file records (weft's own files,
    /// see [`UP_AXIS_KEY`](super::UP_AXIS_KEY)), else Z as in AMASS; writes Z.
    ///
    /// The rest pelvis `.npz` parameters belong to ([`AmassOptions::source_pelvis`]) is
    /// not an option here: it is a property of the files (AMASS's, and weft's, which
    /// write with the same one), not of the body read for, and every reader uses the
    /// default so that every command places a body at the same place.
    pub npz_up: Option<UpAxis>,
    /// Frame rate for `.npz` files that record none.
    pub fps_if_missing: Option<f64>,
    /// Joint-name map for `.bvh` files.
    pub bvh_map: MapChoice,
    /// Length unit of `.bvh` files.
    pub bvh_units: BvhUnits,
    /// Up axis of `.bvh` files (usually Y).
    pub bvh_up: UpAxis,
}

impl Default for MotionFileOptions {
    fn default() -> Self {
        MotionFileOptions {
            rest_joints: DEFAULT_REST_JOINTS,
            npz_up: None,
            fps_if_missing: None,
            bvh_map: MapChoice::Auto,
            bvh_units: BvhUnits::Auto,
            bvh_up: UpAxis::Y,
        }
    }
}

impl MotionFileOptions {
    /// Options for reading a file that drives the body with rest joints `rest_joints`
    /// (see [`body_rest_joints`]), the file being `up` up when given (else as recorded or
    /// by its format's convention: Z for `.npz`, Y for `.bvh`).
    pub fn for_body(rest_joints: [[f64; 3]; SMPL_JOINT_COUNT], up: Option<UpAxis>) -> Self {
        let default = MotionFileOptions::default();
        MotionFileOptions {
            rest_joints,
            npz_up: up,
            bvh_up: up.unwrap_or(default.bvh_up),
            ..default
        }
    }

    /// The AMASS options these imply.
    pub fn amass(&self) -> AmassOptions {
        AmassOptions {
            up: self.npz_up,
            source_pelvis: AmassOptions::default().source_pelvis,
            target_pelvis: self.rest_joints[0],
            fps_if_missing: self.fps_if_missing,
        }
    }

    /// The retargeting options these imply.
    pub fn retarget(&self) -> RetargetOptions {
        RetargetOptions {
            map: self.bvh_map.clone(),
            units: self.bvh_units,
            up: self.bvh_up,
            rest_joints: self.rest_joints,
        }
    }
}

/// What reading a motion file did.
#[derive(Clone, Debug, PartialEq)]
pub enum MotionSource {
    /// Read from an AMASS-style `.npz`.
    Amass(AmassReport),
    /// Read from a `.bvh` and retargeted to SMPL.
    Bvh(RetargetReport),
}

/// Reads a `.npz` or `.bvh` motion by extension.
pub fn read_motion(
    path: &Path,
    options: &MotionFileOptions,
) -> Result<(Motion, MotionSource), MotionError> {
    match MotionFormat::from_path(path)? {
        MotionFormat::Npz => {
            read_amass(path, &options.amass()).map(|(m, r)| (m, MotionSource::Amass(r)))
        }
        MotionFormat::Bvh => {
            let bvh = Bvh::read(path)?;
            retarget_bvh(&bvh, path, &options.retarget()).map(|(m, r)| (m, MotionSource::Bvh(r)))
        }
    }
}

/// A motion file as [`load_motion`] read it.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedMotion {
    /// The motion, at the frame rate asked for.
    pub motion: Motion,
    /// What reading the file did.
    pub source: MotionSource,
    /// `(frame rate, frames)` of the file when it was resampled to the rate asked for;
    /// `None` when the motion is at the file's own rate.
    pub resampled_from: Option<(f64, usize)>,
}

/// Reads a motion file the way every weft command that takes one does (`simulate`,
/// `body pose`, `animate`, `motion info`, the file motions of `data generate`): by
/// extension with `options` — whose [`rest_joints`](MotionFileOptions::rest_joints)
/// are the driven body's J(β) ([`body_rest_joints`], [`MotionFileOptions::for_body`]) —
/// and then, when `fps` is given, at that rate: a file recording another rate is
/// resampled to it ([`resample`]; [`LoadedMotion::resampled_from`] says so), an `.npz`
/// recording none is taken to run at it. A rate is never ignored.
pub fn load_motion(
    path: &Path,
    options: &MotionFileOptions,
    fps: Option<f64>,
) -> Result<LoadedMotion, MotionError> {
    let mut options = options.clone();
    if fps.is_some() {
        options.fps_if_missing = fps;
    }
    let (motion, source) = read_motion(path, &options)?;
    match fps {
        Some(f) if motion.fps() != f => {
            let from = (motion.fps(), motion.frame_count());
            let motion = resample(&motion, f)?;
            Ok(LoadedMotion {
                motion,
                source,
                resampled_from: Some(from),
            })
        }
        _ => Ok(LoadedMotion {
            motion,
            source,
            resampled_from: None,
        }),
    }
}

/// The rest joints J(β) of `body` at shape `betas`: what a motion file is read against
/// for that body (the BVH retargeting target, where AMASS's root translation puts the
/// pelvis). Fails for a body without SMPL's 24 joints.
pub fn body_rest_joints(
    body: &BodyModel,
    betas: &[f64],
) -> Result<[[f64; 3]; SMPL_JOINT_COUNT], MotionError> {
    let joints = body
        .joints(betas)
        .map_err(|e| MotionError::Parameter(format!("{}: rest joints: {e}", body.source())))?;
    joints.try_into().map_err(|j: Vec<[f64; 3]>| {
        MotionError::Parameter(format!(
            "{}: the body has {} joints; motions drive SMPL's {SMPL_JOINT_COUNT}",
            body.source(),
            j.len()
        ))
    })
}

/// Writes a motion as `.npz` (AMASS layout) or `.bvh` (SMPL skeleton) by extension,
/// atomically.
pub fn write_motion(
    path: &Path,
    motion: &Motion,
    options: &MotionFileOptions,
) -> Result<(), MotionError> {
    match MotionFormat::from_path(path)? {
        MotionFormat::Npz => write_amass(path, motion, &options.amass()),
        MotionFormat::Bvh => write_bvh(path, motion, &options.rest_joints),
    }
}
