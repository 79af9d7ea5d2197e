//! Motion files by extension: `.npz` (AMASS layout) and `.bvh`, in and out, with one
//! set of options for both.

use std::path::Path;

use super::amass::{read_amass, write_amass, AmassOptions, AmassReport};
use super::bvh::Bvh;
use super::error::MotionError;
use super::rest::DEFAULT_REST_JOINTS;
use super::retarget::{retarget_bvh, BvhUnits, MapChoice, RetargetOptions, RetargetReport, UpAxis};
use super::smpl_bvh::write_bvh;
use super::types::Motion;
use weft_body::joints::SMPL_JOINT_COUNT;

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
    /// Up axis of `.npz` files (AMASS: Z).
    pub npz_up: UpAxis,
    /// Rest pelvis of the body `.npz` parameters belong to (see
    /// [`AmassOptions::source_pelvis`]); SMPL-like by default.
    pub npz_source_pelvis: [f64; 3],
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
            npz_up: UpAxis::Z,
            npz_source_pelvis: DEFAULT_REST_JOINTS[0],
            fps_if_missing: None,
            bvh_map: MapChoice::Auto,
            bvh_units: BvhUnits::Auto,
            bvh_up: UpAxis::Y,
        }
    }
}

impl MotionFileOptions {
    /// The AMASS options these imply.
    pub fn amass(&self) -> AmassOptions {
        AmassOptions {
            up: self.npz_up,
            source_pelvis: self.npz_source_pelvis,
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
