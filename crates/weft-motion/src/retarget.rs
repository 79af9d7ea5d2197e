//! Retargeting a BVH motion of any skeleton onto SMPL's 24 joints.
//!
//! Copying local Euler angles from one skeleton to another is wrong as soon as the two
//! differ in rest pose (a Mixamo A-pose against SMPL's T-pose), in joint count (five
//! MPFB spine bones against SMPL's three) or in how their joint frames are oriented.
//! This module works with **global rotations relative to each skeleton's rest pose**:
//!
//! 1. Every BVH frame is evaluated to world transforms `G_s(t)`. In BVH the rest pose
//!    (all channels zero) has every joint frame aligned with the world, so `G_s(t)` is
//!    already the rotation *from the rest pose*. It is brought into weft's frame
//!    (Y up; `C` turns a Z-up file) as `Q_s(t) = C·G_s(t)·C⁻¹`.
//! 2. For each mapped SMPL joint `j` (source joint `s`), an **alignment** `A_j` is
//!    computed once: the shortest-arc rotation taking SMPL's rest bone direction
//!    (from `j` to the next mapped joint down its chain, e.g. shoulder → elbow) onto the
//!    source's rest bone direction between the corresponding BVH joints. For a T-pose
//!    source `A_j` is the identity; for an A-pose source it lowers SMPL's arm by the
//!    A-pose angle. Joints without a bone direction (pelvis, head, feet, hands) inherit
//!    their parent's alignment; the pelvis keeps the identity, so the facing is the
//!    source's.
//! 3. SMPL's global rotation is `G_j(t) = Q_s(t)·A_j`: at the source's rest SMPL's bone
//!    lies along the source's rest bone, and thereafter it turns with it. Local
//!    rotations follow as `R_j = G_parent(j)⁻¹·G_j`. SMPL joints with no source copy
//!    their parent's global rotation (local identity), so whatever turns in unmapped
//!    source joints in between (CMU's `Neck1`, MPFB's `spine04`) ends up in the next
//!    mapped joint below.
//! 4. The root translation follows the source pelvis, scaled by the ratio of SMPL's leg
//!    length to the source's (so strides and jump heights fit the target's legs and
//!    the feet stay near the floor), minus SMPL's rest pelvis: `trans = λ·p(t) − J₀`.
//!
//! Limits: twist about a bone is copied from the source's frames, and the alignment
//! fixes the rest *direction* only, so a source whose rest pose also twists a limb
//! (palms forward against SMPL's palms down) carries that twist over; bone *lengths*
//! are SMPL's, so end effectors of a differently proportioned source land elsewhere
//! (no inverse kinematics, foot contacts may slide); fingers and toes beyond SMPL's
//! single hand and foot joints are dropped.

use std::path::Path;

use nalgebra::{UnitQuaternion, Vector3};

use super::bvh::Bvh;
use super::error::MotionError;
use super::names::{NameMap, SkeletonPreset};
use super::rest::{check_rest_joints, DEFAULT_REST_JOINTS};
use super::rot::{axis_angle, shortest_arc};
use super::types::{Motion, MAX_FRAMES};
use weft_body::joints::{SMPL_JOINT_COUNT, SMPL_JOINT_NAMES, SMPL_PARENTS};
use weft_body::Pose;

/// Which axis points up in a source file. weft's frame is Y up; a Z-up file is turned
/// by −90° about X, taking (x, y, z) to (x, z, −y).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// Y up (BVH's usual convention, and SMPL's).
    #[default]
    Y,
    /// Z up (AMASS, Blender scenes exported without axis conversion).
    Z,
}

impl UpAxis {
    /// "Y" or "Z".
    pub fn name(self) -> &'static str {
        match self {
            UpAxis::Y => "Y",
            UpAxis::Z => "Z",
        }
    }

    /// The axis named `y` or `z` (any case).
    pub fn parse(name: &str) -> Option<UpAxis> {
        match name.to_ascii_lowercase().as_str() {
            "y" => Some(UpAxis::Y),
            "z" => Some(UpAxis::Z),
            _ => None,
        }
    }

    /// The rotation taking this frame's coordinates to weft's Y-up frame.
    pub fn to_y_up(self) -> UnitQuaternion<f64> {
        match self {
            UpAxis::Y => UnitQuaternion::identity(),
            UpAxis::Z => {
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), -std::f64::consts::FRAC_PI_2)
            }
        }
    }
}

/// The length unit of a BVH file.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum BvhUnits {
    /// Guess from the rest skeleton's size (see [`detect_units`]).
    #[default]
    Auto,
    /// This many metres per file unit (0.01 for centimetres).
    MetresPerUnit(f64),
}

/// Which joint-name map retargeting uses.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum MapChoice {
    /// The built-in preset that maps the most SMPL joints of this file.
    #[default]
    Auto,
    /// A built-in preset.
    Preset(SkeletonPreset),
    /// A user's map.
    Custom(NameMap),
}

/// Options of [`retarget_bvh`].
#[derive(Clone, Debug, PartialEq)]
pub struct RetargetOptions {
    /// The name map.
    pub map: MapChoice,
    /// The file's length unit.
    pub units: BvhUnits,
    /// The file's up axis.
    pub up: UpAxis,
    /// Rest joints of the target SMPL skeleton (a body's J(β)); bone directions, leg
    /// length and the rest pelvis come from them.
    pub rest_joints: [[f64; 3]; SMPL_JOINT_COUNT],
}

impl Default for RetargetOptions {
    fn default() -> Self {
        RetargetOptions {
            map: MapChoice::Auto,
            units: BvhUnits::Auto,
            up: UpAxis::Y,
            rest_joints: DEFAULT_REST_JOINTS,
        }
    }
}

/// What retargeting did, for the user to check.
#[derive(Clone, Debug, PartialEq)]
pub struct RetargetReport {
    /// The name map used (a preset's name or a map file's path).
    pub map: String,
    /// Metres per file unit.
    pub metres_per_unit: f64,
    /// The unit's name: `m`, `cm`, `mm`, `in`, `CMU` (0.056444 m) or `given`.
    pub unit: &'static str,
    /// The largest extent of the rest skeleton, in metres (about the body height).
    pub rest_extent: f64,
    /// The ratio of SMPL's leg length to the source's, applied to the root path.
    pub root_scale: f64,
    /// `(SMPL joint, BVH joint name)` for every mapped SMPL joint.
    pub mapped: Vec<(usize, String)>,
    /// SMPL joints with no source joint: their local rotation is the identity.
    pub unmapped: Vec<&'static str>,
    /// BVH joints no SMPL joint uses (fingers, helper and end joints).
    pub unused: Vec<String>,
    /// Anything suspicious, one sentence each (a mapping that contradicts the BVH
    /// hierarchy, an implausible body size).
    pub warnings: Vec<String>,
}

/// SMPL joints a retargeted motion cannot do without: the pelvis, both legs to the knee
/// and both arms to the elbow. Others, when missing, stay at their rest rotation.
pub const REQUIRED_JOINTS: [usize; 9] = [0, 1, 2, 4, 5, 16, 17, 18, 19];

/// The next joint down the chain each SMPL joint's bone points to (`None`: no bone
/// direction, the alignment is inherited).
const BONE_CHILD: [Option<usize>; SMPL_JOINT_COUNT] = [
    None,
    Some(4),
    Some(5),
    Some(6),
    Some(7),
    Some(8),
    Some(9),
    Some(10),
    Some(11),
    Some(12),
    None,
    None,
    Some(15),
    Some(16),
    Some(17),
    None,
    Some(18),
    Some(19),
    Some(20),
    Some(21),
    Some(22),
    Some(23),
    None,
    None,
];

/// Candidate units: name, metres per unit. `CMU` is the unit of the CMU database's ASF
/// files and their common BVH conversion (1/0.45 inch).
const UNITS: [(&str, f64); 5] = [
    ("m", 1.0),
    ("cm", 0.01),
    ("mm", 0.001),
    ("in", 0.0254),
    ("CMU", 0.0254 / 0.45),
];

/// The unit that makes a rest skeleton of largest extent `extent` (file units) closest,
/// in ratio, to a 1.7 m human: metres, centimetres, millimetres, inches or CMU units.
/// Returns the unit's name and metres per unit.
pub fn detect_units(extent: f64) -> (&'static str, f64) {
    let mut best = UNITS[0];
    let mut best_err = f64::INFINITY;
    for (name, f) in UNITS {
        let err = (extent * f / 1.7).ln().abs();
        if err < best_err {
            best = (name, f);
            best_err = err;
        }
    }
    best
}

/// Maps a BVH motion onto SMPL's 24 joints (see the module documentation for the
/// method). `path` names the file in errors.
///
/// Fails when the file has no frames, a required SMPL joint ([`REQUIRED_JOINTS`]) has
/// no BVH joint, or two BVH joints map to one SMPL joint; each message names the joints
/// and suggests a map file.
pub fn retarget_bvh(
    bvh: &Bvh,
    path: &Path,
    options: &RetargetOptions,
) -> Result<(Motion, RetargetReport), MotionError> {
    let fail = |message: String| MotionError::Retarget {
        path: path.to_path_buf(),
        message,
    };
    check_rest_joints(&options.rest_joints).map_err(MotionError::Parameter)?;
    if bvh.frame_count() == 0 {
        return Err(fail("the file has no frames ('Frames: 0')".into()));
    }
    if bvh.frame_count() > MAX_FRAMES {
        return Err(fail(format!(
            "{} frames; at most {MAX_FRAMES} fit in memory as SMPL poses",
            bvh.frame_count()
        )));
    }
    let map = match &options.map {
        MapChoice::Auto => best_preset(bvh),
        MapChoice::Preset(p) => NameMap::preset(*p),
        MapChoice::Custom(m) => m.clone(),
    };
    let source = assign(bvh, &map).map_err(fail)?;
    let mut warnings = Vec::new();

    // Units and frame change.
    let rest_file = bvh.rest_positions();
    let raw_extent = extent(
        rest_file
            .joints
            .iter()
            .chain(rest_file.end_sites.iter().map(|(_, p)| p)),
    );
    let (unit, k) = match options.units {
        BvhUnits::MetresPerUnit(f) if f.is_finite() && f > 0.0 => ("given", f),
        BvhUnits::MetresPerUnit(f) => {
            return Err(MotionError::Parameter(format!(
                "BVH scale {f}; expected metres per file unit above 0"
            )))
        }
        BvhUnits::Auto => detect_units(raw_extent),
    };
    let rest_extent = raw_extent * k;
    if !(0.5..=3.0).contains(&rest_extent) {
        warnings.push(format!(
            "the rest skeleton is {rest_extent:.2} m across in {unit}; if that is not a human's size, give the scale explicitly"
        ));
    }
    let c = options.up.to_y_up();
    let rest: Vec<Vector3<f64>> = rest_file.joints.iter().map(|p| c * p * k).collect();
    let target = |j: usize| Vector3::from(options.rest_joints[j]);

    // Alignments: SMPL rest bone → source rest bone.
    let mut align = [UnitQuaternion::identity(); SMPL_JOINT_COUNT];
    for j in 1..SMPL_JOINT_COUNT {
        let parent = SMPL_PARENTS[j].unwrap_or(0);
        align[j] = align[parent];
        let Some(s) = source[j] else { continue };
        let mut child = BONE_CHILD[j];
        while let Some(cj) = child {
            if source[cj].is_some() {
                break;
            }
            child = BONE_CHILD[cj];
        }
        if let Some(cj) = child {
            let Some(sc) = source[cj] else { continue };
            let from = target(cj) - target(j);
            let to = rest[sc] - rest[s];
            if from.norm() > 1e-9 && to.norm() > 1e-9 {
                align[j] = shortest_arc(from, to);
            }
        }
    }

    // The mapping should follow the BVH tree: a joint's source below its parent's.
    for j in 1..SMPL_JOINT_COUNT {
        let (Some(s), Some(p)) = (source[j], nearest_mapped_ancestor(j, &source)) else {
            continue;
        };
        if !is_ancestor(bvh, p, s) {
            warnings.push(format!(
                "SMPL joint '{}' is driven by '{}', which is not below '{}' in the BVH hierarchy; check the name map",
                SMPL_JOINT_NAMES[j],
                bvh.joints()[s].name,
                bvh.joints()[p].name
            ));
        }
    }

    // Root scale: SMPL's leg length over the source's.
    let leg =
        |hip: usize, knee: usize, ankle: usize, pos: &dyn Fn(usize) -> Option<Vector3<f64>>| {
            let (h, kn) = (pos(hip)?, pos(knee)?);
            let a = pos(ankle);
            Some((kn - h).norm() + a.map_or(0.0, |a| (a - kn).norm()))
        };
    let src_pos = |j: usize| source[j].map(|s| rest[s]);
    let tgt_pos = |j: usize| {
        // Use the target's ankle only when the source has one, so both legs measure
        // the same segments.
        (j < 7 || source[j].is_some()).then(|| target(j))
    };
    let (src_leg, tgt_leg) = (
        leg(1, 4, 7, &src_pos).unwrap_or(0.0) + leg(2, 5, 8, &src_pos).unwrap_or(0.0),
        leg(1, 4, 7, &tgt_pos).unwrap_or(0.0) + leg(2, 5, 8, &tgt_pos).unwrap_or(0.0),
    );
    let root_scale = if src_leg > 1e-6 && tgt_leg > 1e-6 {
        tgt_leg / src_leg
    } else {
        1.0
    };

    // Frames.
    let frames = bvh.frame_count();
    let mut poses: Vec<Pose> = Vec::with_capacity(frames);
    let mut trans = Vec::with_capacity(frames);
    let c_inv = c.inverse();
    let j0 = target(0);
    let pelvis_source = source[0].unwrap_or(0);
    for f in 0..frames {
        let g = bvh.global_transforms(f);
        let mut global = [UnitQuaternion::identity(); SMPL_JOINT_COUNT];
        let mut pose = [[0.0f32; 3]; SMPL_JOINT_COUNT];
        for j in 0..SMPL_JOINT_COUNT {
            let parent = SMPL_PARENTS[j].map(|p| global[p]);
            global[j] = match source[j] {
                Some(s) => c * g[s].rotation * c_inv * align[j],
                None => parent.unwrap_or_else(UnitQuaternion::identity),
            };
            let local = match parent {
                Some(p) => p.inverse() * global[j],
                None => global[j],
            };
            pose[j] = axis_angle(&local);
        }
        let p = c * g[pelvis_source].translation.vector * k;
        let t = p * root_scale - j0;
        poses.push(pose);
        trans.push([t.x as f32, t.y as f32, t.z as f32]);
    }
    let motion = Motion::new(bvh.fps(), poses, trans, None)?;

    let report = RetargetReport {
        map: map.label().to_owned(),
        metres_per_unit: k,
        unit,
        rest_extent,
        root_scale,
        mapped: (0..SMPL_JOINT_COUNT)
            .filter_map(|j| source[j].map(|s| (j, bvh.joints()[s].name.clone())))
            .collect(),
        unmapped: (0..SMPL_JOINT_COUNT)
            .filter(|&j| source[j].is_none())
            .map(|j| SMPL_JOINT_NAMES[j])
            .collect(),
        unused: bvh
            .joints()
            .iter()
            .enumerate()
            .filter(|(i, _)| !source.contains(&Some(*i)))
            .map(|(_, j)| j.name.clone())
            .collect(),
        warnings,
    };
    Ok((motion, report))
}

/// The preset mapping the most SMPL joints of this file; ties go to the earlier preset
/// in [`SkeletonPreset::ALL`], and a preset whose mapping is ambiguous loses to one that
/// is not.
fn best_preset(bvh: &Bvh) -> NameMap {
    let mut best: Option<(usize, NameMap)> = None;
    for p in SkeletonPreset::ALL {
        let map = NameMap::preset(p);
        let score = match assign(bvh, &map) {
            Ok(s) => 2 * s.iter().filter(|s| s.is_some()).count() + 1,
            Err(_) => {
                let hits: std::collections::BTreeSet<usize> = bvh
                    .joints()
                    .iter()
                    .filter_map(|j| map.lookup(&j.name))
                    .collect();
                2 * hits.len()
            }
        };
        match &best {
            Some((b, _)) if *b >= score => {}
            _ => best = Some((score, map)),
        }
    }
    best.map_or_else(|| NameMap::preset(SkeletonPreset::Smpl), |(_, m)| m)
}

/// The BVH joint of each SMPL joint under `map`; fails naming an ambiguous or missing
/// required joint.
fn assign(bvh: &Bvh, map: &NameMap) -> Result<[Option<usize>; SMPL_JOINT_COUNT], String> {
    let mut source: [Option<usize>; SMPL_JOINT_COUNT] = [None; SMPL_JOINT_COUNT];
    for (i, joint) in bvh.joints().iter().enumerate() {
        let Some(j) = map.lookup(&joint.name) else {
            continue;
        };
        if let Some(other) = source[j] {
            let o = &bvh.joints()[other];
            return Err(format!(
                "BVH joints '{}' (line {}) and '{}' (line {}) both map to SMPL joint '{}' under the {} map; give a map file (--map FILE.toml) that names only one of them",
                o.name, o.line, joint.name, joint.line, SMPL_JOINT_NAMES[j], map.label()
            ));
        }
        source[j] = Some(i);
    }
    for j in REQUIRED_JOINTS {
        if source[j].is_none() {
            let mut names: Vec<&str> = bvh.joints().iter().map(|j| j.name.as_str()).collect();
            let more = names.len().saturating_sub(40);
            names.truncate(40);
            return Err(format!(
                "no BVH joint maps to SMPL joint '{}' (the {} map looks for {}); the file's joints are {}{}; give a map file (--map FILE.toml) naming the joint to use",
                SMPL_JOINT_NAMES[j],
                map.label(),
                map.sources_of(j).join(" or "),
                names.join(", "),
                if more > 0 { format!(" and {more} more") } else { String::new() }
            ));
        }
    }
    Ok(source)
}

/// The source joint of the nearest SMPL ancestor of `j` that has one.
fn nearest_mapped_ancestor(j: usize, source: &[Option<usize>; SMPL_JOINT_COUNT]) -> Option<usize> {
    let mut a = SMPL_PARENTS[j];
    while let Some(p) = a {
        if let Some(s) = source[p] {
            return Some(s);
        }
        a = SMPL_PARENTS[p];
    }
    None
}

/// Whether BVH joint `a` is a proper ancestor of `b`.
fn is_ancestor(bvh: &Bvh, a: usize, b: usize) -> bool {
    let mut x = bvh.joints()[b].parent;
    while let Some(p) = x {
        if p == a {
            return true;
        }
        x = bvh.joints()[p].parent;
    }
    false
}

/// The largest extent along any axis of a point set.
fn extent<'a>(points: impl Iterator<Item = &'a Vector3<f64>>) -> f64 {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (hi - lo).max().max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_are_detected_from_a_human_sized_skeleton() {
        assert_eq!(detect_units(1.75).0, "m");
        assert_eq!(detect_units(172.0).0, "cm");
        assert_eq!(detect_units(1690.0).0, "mm");
        assert_eq!(detect_units(67.0).0, "in");
        assert_eq!(detect_units(30.5).0, "CMU");
    }

    #[test]
    fn a_file_without_frames_is_an_error() {
        let joints = crate::smpl_bvh::smpl_bvh_skeleton(&DEFAULT_REST_JOINTS);
        let bvh = Bvh::new(joints, 0.1, vec![]).unwrap();
        let e = retarget_bvh(&bvh, Path::new("e.bvh"), &RetargetOptions::default()).unwrap_err();
        assert_eq!(e.to_string(), "e.bvh: the file has no frames ('Frames: 0')");
    }

    #[test]
    fn z_up_turns_into_y_up() {
        let v = UpAxis::Z.to_y_up() * Vector3::new(1.0, 2.0, 3.0);
        assert!((v - Vector3::new(1.0, 3.0, -2.0)).norm() < 1e-12, "{v}");
    }
}
