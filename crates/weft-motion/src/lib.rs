//! Motions: what a body does over time, as SMPL poses.
//!
//! A [`Motion`] is a frame rate, one pose per frame — an axis-angle rotation for each of
//! SMPL's 24 joints, in SMPL's order ([`weft_body::joints::SMPL_JOINT_NAMES`]) — and one root
//! translation per frame, in SMPL's own frame: right-handed, Y up, metres, the rest body
//! facing +Z with its left on +X.
//!
//! Where motions come from and go to, one concept per module:
//!
//! - [`amass`](read_amass): AMASS-style `.npz` (SMPL, SMPL-H, SMPL-X poses; Z up,
//!   converted on load and back on write);
//! - [`Bvh`]: BVH files of any skeleton, parsed with errors naming file and line;
//!   [`retarget_bvh`] maps them onto SMPL by joint names ([`NameMap`]: built-in maps
//!   for SMPL, CMU, Mixamo, MPFB, or a user's TOML/JSON file) with rest-pose-aware
//!   global rotations; [`motion_to_bvh`] writes any motion back on the SMPL skeleton;
//! - [`generate`]: the seeded procedural library (walk, run, jump, dance, kick, raise
//!   arms, twist, bow), within [`JOINT_LIMITS_DEG`];
//! - [`resample`] to another frame rate, [`pose_history`] for seed 000's Θᵗ,
//!   [`motion_stats`] for summaries;
//! - [`read_motion`] / [`write_motion`] pick the format by extension; [`load_motion`] is
//!   how every command reads a motion file for the body it drives (up axis, frame rate).
//!
//! See `docs/motions.md` for the formats, conventions and methods in one place.

mod amass;
mod body_velocity;
mod bvh;
mod error;
mod file;
mod fk;
mod history;
mod limits;
mod names;
mod procedural;
mod resample;
mod rest;
mod retarget;
mod rot;
mod smpl_bvh;
mod stats;
mod types;

pub use amass::{
    amass_from_npz, amass_npz, read_amass, write_amass, AmassOptions, AmassReport, PoseLayout,
    UpFrom, UP_AXIS_KEY,
};
pub use bvh::{Bvh, BvhJoint, Channel, RestPositions};
pub use error::MotionError;
pub use file::{
    body_rest_joints, load_motion, read_motion, write_motion, LoadedMotion, MotionFileOptions,
    MotionFormat, MotionSource,
};
pub use fk::posed_joints;
pub use history::{
    pose_features, pose_histories, pose_history, HISTORY_FEATURES, MAX_HISTORY_VALUES,
};
pub use limits::{clamp_pose, limit_violation, JOINT_LIMITS_DEG};
pub use names::{normalize_joint_name, NameMap, SkeletonPreset};
pub use procedural::{generate, MotionKind, ProceduralParams, MAX_AMPLITUDE};
pub use resample::resample;
pub use rest::DEFAULT_REST_JOINTS;
pub use retarget::{
    detect_units, retarget_bvh, BvhUnits, MapChoice, RetargetOptions, RetargetReport, UpAxis,
    REQUIRED_JOINTS,
};
pub use smpl_bvh::{motion_to_bvh, smpl_bvh_skeleton, write_bvh};
pub use stats::{motion_stats, JointRange, MotionStats};
pub use types::{Motion, MotionDistance, MAX_FPS, MAX_FRAMES};
pub use weft_body::Pose;
