//! Motions: what a body does over time, as SMPL poses (work in progress).

mod bvh;
mod error;
mod fk;
mod names;
mod rest;
mod retarget;
mod rot;
mod smpl_bvh;
mod types;

pub use bvh::{Bvh, BvhJoint, Channel};
pub use error::MotionError;
pub use fk::posed_joints;
pub use names::{normalize_joint_name, NameMap, SkeletonPreset};
pub use rest::DEFAULT_REST_JOINTS;
pub use retarget::{
    detect_units, retarget_bvh, BvhUnits, MapChoice, RetargetOptions, RetargetReport, UpAxis,
    REQUIRED_JOINTS,
};
pub use smpl_bvh::{motion_to_bvh, smpl_bvh_skeleton, write_bvh};
pub use types::{Motion, MotionDistance, Pose, MAX_FRAMES};
