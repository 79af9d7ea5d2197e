//! BVH in and out: round trips, retargeting across rest poses, name maps, units, and
//! malformed files.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use weft_body::joints::{smpl_joint_index, SMPL_JOINT_COUNT};
use weft_motion::{
    generate, motion_to_bvh, posed_joints, read_motion, retarget_bvh, write_bvh, Bvh, BvhJoint,
    BvhUnits, Channel, MapChoice, Motion, MotionError, MotionFileOptions, MotionKind, MotionSource,
    NameMap, ProceduralParams, RetargetOptions, SkeletonPreset, UpAxis, DEFAULT_REST_JOINTS,
};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// A fresh directory under the system temp dir, removed on drop.
mod motion_common;
use motion_common::TempDir;

fn walk(frames: usize) -> Motion {
    let mut p = ProceduralParams::new(MotionKind::Walk);
    p.frames = frames;
    p.seed = 3;
    generate(&p).unwrap()
}

#[test]
fn motion_to_bvh_and_back_is_the_same_motion() {
    let dir = TempDir::new("bvh", "roundtrip");
    for kind in MotionKind::ALL {
        let mut p = ProceduralParams::new(kind);
        p.frames = 40;
        p.amplitude = 1.5;
        let m = generate(&p).unwrap();
        let path = dir.path("m.bvh");
        write_bvh(&path, &m, &DEFAULT_REST_JOINTS).unwrap();
        let (back, source) = read_motion(&path, &MotionFileOptions::default()).unwrap();
        let MotionSource::Bvh(report) = source else {
            panic!("not read as BVH")
        };
        assert_eq!(report.map, "smpl");
        assert_eq!(report.unit, "m");
        assert!((report.root_scale - 1.0).abs() < 1e-12);
        assert!(report.unused.is_empty() && report.unmapped.is_empty());
        assert_eq!(back.fps(), m.fps());
        let d = back.distance(&m).unwrap();
        // Six decimals of degrees and metres in the file.
        assert!(d.rotation < 1e-6 && d.translation < 2e-6, "{kind}: {d:?}");
    }
}

#[test]
fn cmu_fixture_round_trips_through_smpl_bvh() {
    let path = fixture("cmu_tiny.bvh");
    let bvh = Bvh::read(&path).unwrap();
    assert_eq!(bvh.joints().len(), 31);
    assert_eq!(bvh.fps(), 120.0);
    let (m1, report) = retarget_bvh(&bvh, &path, &RetargetOptions::default()).unwrap();
    assert_eq!(report.map, "cmu");
    assert_eq!(report.unit, "CMU");
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    for unused in [
        "LHipJoint",
        "RHipJoint",
        "Neck1",
        "LeftHandIndex1",
        "LThumb",
    ] {
        assert!(report.unused.iter().any(|u| u == unused), "{unused}");
    }
    assert!(report.unmapped.is_empty(), "{:?}", report.unmapped);
    // A 1.5 m-ish skeleton, legs a little shorter than the default body's.
    assert!(
        (1.2..2.0).contains(&report.rest_extent),
        "{}",
        report.rest_extent
    );
    assert!(
        (0.8..1.3).contains(&report.root_scale),
        "{}",
        report.root_scale
    );

    let dir = TempDir::new("bvh", "cmu");
    let out = dir.path("smpl.bvh");
    write_bvh(&out, &m1, &DEFAULT_REST_JOINTS).unwrap();
    let (m2, _) = read_motion(&out, &MotionFileOptions::default()).unwrap();
    let d = m2.distance(&m1).unwrap();
    assert!(d.rotation < 1e-6 && d.translation < 2e-6, "{d:?}");
}

#[test]
fn retargeted_bones_point_where_the_source_bones_point() {
    // The CMU skeleton's legs form an inverted V at rest, SMPL's hang straight: bone
    // directions must still agree frame by frame.
    let path = fixture("cmu_tiny.bvh");
    let bvh = Bvh::read(&path).unwrap();
    let options = RetargetOptions::default();
    let (m, report) = retarget_bvh(&bvh, &path, &options).unwrap();
    let name = |j: usize| {
        report
            .mapped
            .iter()
            .find(|(k, _)| *k == j)
            .map(|(_, n)| n.clone())
    };
    // SMPL bones whose two ends map to BVH joints that are parent and child.
    let bones = [
        (1, 4),
        (4, 7),
        (7, 10),
        (2, 5),
        (5, 8),
        (16, 18),
        (18, 20),
        (17, 19),
        (3, 6),
        (6, 9),
    ];
    for f in 0..bvh.frame_count() {
        let g = bvh.global_transforms(f);
        let smpl = posed_joints(&m.poses()[f], m.trans()[f], &DEFAULT_REST_JOINTS);
        for (a, b) in bones {
            let (sa, sb) = (name(a).unwrap(), name(b).unwrap());
            let (ia, ib) = (bvh.joint_index(&sa).unwrap(), bvh.joint_index(&sb).unwrap());
            let src = (g[ib].translation.vector - g[ia].translation.vector).normalize();
            let dst = (Vector3::from(smpl[b]) - Vector3::from(smpl[a])).normalize();
            assert!(
                (src - dst).norm() < 1e-5,
                "frame {f}, bone {sa}->{sb}: {src} vs {dst}"
            );
        }
        // The pelvis follows the source root, scaled by the leg-length ratio.
        let p = g[0].translation.vector * report.metres_per_unit * report.root_scale;
        assert!((Vector3::from(smpl[0]) - p).norm() < 1e-5);
    }
}

/// A Mixamo-style skeleton in centimetres with A-pose arms (45° down), "mixamorig:"
/// names, three spine bones and every joint's rotation channels in XYZ order.
fn mixamo_a_pose(frames: &[Vec<f64>]) -> Bvh {
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let spec: Vec<(&str, Option<usize>, [f64; 3])> = vec![
        ("Hips", None, [0.0, 95.0, 0.0]),
        ("Spine", Some(0), [0.0, 10.0, 0.0]),
        ("Spine1", Some(1), [0.0, 12.0, 1.0]),
        ("Spine2", Some(2), [0.0, 13.0, 0.0]),
        ("Neck", Some(3), [0.0, 16.0, -1.0]),
        ("Head", Some(4), [0.0, 10.0, 2.0]),
        ("LeftShoulder", Some(3), [6.0, 11.0, -1.0]),
        ("LeftArm", Some(6), [11.0, 0.0, 0.0]),
        ("LeftForeArm", Some(7), [27.0 * s, -27.0 * s, 0.0]),
        ("LeftHand", Some(8), [25.0 * s, -25.0 * s, 0.0]),
        ("LeftHandMiddle1", Some(9), [9.0 * s, -9.0 * s, 0.0]),
        ("RightShoulder", Some(3), [-6.0, 11.0, -1.0]),
        ("RightArm", Some(11), [-11.0, 0.0, 0.0]),
        ("RightForeArm", Some(12), [-27.0 * s, -27.0 * s, 0.0]),
        ("RightHand", Some(13), [-25.0 * s, -25.0 * s, 0.0]),
        ("RightHandMiddle1", Some(14), [-9.0 * s, -9.0 * s, 0.0]),
        ("LeftUpLeg", Some(0), [9.0, -7.0, 0.0]),
        ("LeftLeg", Some(16), [0.0, -42.0, 0.5]),
        ("LeftFoot", Some(17), [0.0, -40.0, -2.0]),
        ("LeftToeBase", Some(18), [0.0, -6.0, 12.0]),
        ("RightUpLeg", Some(0), [-9.0, -7.0, 0.0]),
        ("RightLeg", Some(20), [0.0, -42.0, 0.5]),
        ("RightFoot", Some(21), [0.0, -40.0, -2.0]),
        ("RightToeBase", Some(22), [0.0, -6.0, 12.0]),
    ];
    let joints = spec
        .iter()
        .map(|(name, parent, offset)| {
            let mut channels = vec![];
            if parent.is_none() {
                channels.extend([Channel::Xposition, Channel::Yposition, Channel::Zposition]);
            }
            channels.extend([Channel::Xrotation, Channel::Yrotation, Channel::Zrotation]);
            BvhJoint {
                name: format!("mixamorig:{name}"),
                parent: *parent,
                offset: *offset,
                channels,
                end_sites: vec![],
                line: 0,
            }
        })
        .collect();
    Bvh::new(joints, 1.0 / 30.0, frames.concat()).unwrap()
}

#[test]
fn a_pose_sources_map_onto_the_t_pose_by_bone_direction() {
    let channels = 3 + 3 * 24;
    // Frame 0: the rest pose. Others: pseudo-random rotations on every joint.
    let mut frames = vec![{
        let mut v = vec![0.0; channels];
        v[..3].copy_from_slice(&[0.0, 95.0, 0.0]);
        v
    }];
    let mut state = 12345u64;
    for f in 1..6 {
        let mut v = vec![0.0; channels];
        v[..3].copy_from_slice(&[3.0 * f as f64, 95.0 + f as f64, 10.0 * f as f64]);
        for x in v[3..].iter_mut() {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            *x = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 80.0;
        }
        frames.push(v);
    }
    let bvh = mixamo_a_pose(&frames);
    let (m, report) =
        retarget_bvh(&bvh, Path::new("mixamo.bvh"), &RetargetOptions::default()).unwrap();
    assert_eq!(report.map, "mixamo");
    assert_eq!(report.unit, "cm");
    assert!(report.unmapped.is_empty(), "{:?}", report.unmapped);

    // At the source's rest the SMPL arms hang 45° down like the source's.
    let rest = posed_joints(&m.poses()[0], m.trans()[0], &DEFAULT_REST_JOINTS);
    let upper_arm = (Vector3::from(rest[18]) - Vector3::from(rest[16])).normalize();
    let expected = Vector3::new(1.0, -1.0, 0.0).normalize();
    assert!((upper_arm - expected).norm() < 1e-6, "{upper_arm}");
    // ... and its legs hang straight.
    let shin = (Vector3::from(rest[7]) - Vector3::from(rest[4])).normalize();
    let src_shin = Vector3::new(0.0, -40.0, -2.0).normalize();
    assert!((shin - src_shin).norm() < 1e-6, "{shin}");

    // Every mapped bone follows its source bone in every frame.
    let bones = [
        (1, 4),
        (4, 7),
        (7, 10),
        (2, 5),
        (5, 8),
        (8, 11),
        (3, 6),
        (6, 9),
        (9, 12),
        (12, 15),
        (13, 16),
        (16, 18),
        (18, 20),
        (20, 22),
        (14, 17),
        (17, 19),
        (19, 21),
        (21, 23),
    ];
    let source = |j: usize| {
        let n = &report.mapped.iter().find(|(k, _)| *k == j).unwrap().1;
        bvh.joint_index(n).unwrap()
    };
    for f in 0..frames.len() {
        let g = bvh.global_transforms(f);
        let smpl = posed_joints(&m.poses()[f], m.trans()[f], &DEFAULT_REST_JOINTS);
        for (a, b) in bones {
            let src =
                (g[source(b)].translation.vector - g[source(a)].translation.vector).normalize();
            let dst = (Vector3::from(smpl[b]) - Vector3::from(smpl[a])).normalize();
            assert!(
                (src - dst).norm() < 1e-5,
                "frame {f} bone {a}->{b}: {src} vs {dst}"
            );
        }
    }
}

#[test]
fn z_up_files_and_explicit_scales_are_converted() {
    // The walk written as BVH, then rewritten Z up in centimetres by hand.
    let m = walk(20);
    let b = motion_to_bvh(&m, &DEFAULT_REST_JOINTS).unwrap();
    let c =
        nalgebra::UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2);
    let joints: Vec<BvhJoint> = b
        .joints()
        .iter()
        .map(|j| {
            let o = c * Vector3::from(j.offset) * 100.0;
            BvhJoint {
                offset: [o.x, o.y, o.z],
                end_sites: j
                    .end_sites
                    .iter()
                    .map(|e| (c * Vector3::from(*e) * 100.0).into())
                    .collect(),
                ..j.clone()
            }
        })
        .collect();
    // Channels: root position turned and scaled; rotations Z·Y·X of the turned frame:
    // express each local rotation as C·R·C⁻¹ and re-decompose.
    let mut values = Vec::new();
    for f in 0..b.frame_count() {
        let g0 = b.local_transform(f, 0);
        let p = c * g0.translation.vector * 100.0;
        values.extend([p.x, p.y, p.z]);
        for j in 0..24 {
            let r = c * b.local_transform(f, j).rotation * c.inverse();
            let (x, y, z) = r.euler_angles();
            values.extend([z.to_degrees(), y.to_degrees(), x.to_degrees()]);
        }
    }
    let zup = Bvh::new(joints, b.frame_time(), values).unwrap();
    let options = RetargetOptions {
        up: UpAxis::Z,
        ..RetargetOptions::default()
    };
    let (back, report) = retarget_bvh(&zup, Path::new("z.bvh"), &options).unwrap();
    assert_eq!(report.unit, "cm");
    let d = back.distance(&m).unwrap();
    assert!(d.rotation < 1e-6 && d.translation < 1e-5, "{d:?}");
    // The same with the scale given.
    let options = RetargetOptions {
        up: UpAxis::Z,
        units: BvhUnits::MetresPerUnit(0.01),
        ..RetargetOptions::default()
    };
    let (back, report) = retarget_bvh(&zup, Path::new("z.bvh"), &options).unwrap();
    assert_eq!(report.unit, "given");
    assert!(back.distance(&m).unwrap().translation < 1e-5);
}

#[test]
fn user_name_maps_in_toml_and_json() {
    let dir = TempDir::new("bvh", "maps");
    // The SMPL BVH with renamed joints.
    let m = walk(10);
    let b = motion_to_bvh(&m, &DEFAULT_REST_JOINTS).unwrap();
    let joints: Vec<BvhJoint> = b
        .joints()
        .iter()
        .map(|j| BvhJoint {
            name: format!("Bip01 {}", j.name.replace('_', " ")),
            ..j.clone()
        })
        .collect();
    let renamed = Bvh::new(
        joints,
        b.frame_time(),
        (0..b.frame_count())
            .flat_map(|f| b.frame(f).to_vec())
            .collect(),
    )
    .unwrap();
    let renamed_path = dir.path("bip.bvh");
    renamed.write(&renamed_path).unwrap();

    // Auto detection finds no preset that maps the required joints.
    let e = read_motion(&renamed_path, &MotionFileOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.starts_with(&format!(
            "{}: no BVH joint maps to SMPL joint 'pelvis'",
            renamed_path.display()
        )),
        "{msg}"
    );
    assert!(msg.contains("--map"), "{msg}");

    let toml_path = dir.path("map.toml");
    let mut toml = String::from("# BVH joint = SMPL joint\n");
    for name in weft_body::joints::SMPL_JOINT_NAMES {
        toml.push_str(&format!(
            "\"Bip01 {}\" = \"{name}\"\n",
            name.replace('_', " ")
        ));
    }
    std::fs::write(&toml_path, toml).unwrap();
    let json_path = dir.path("map.json");
    let json: serde_json::Map<String, serde_json::Value> = weft_body::joints::SMPL_JOINT_NAMES
        .iter()
        .map(|n| {
            (
                format!("Bip01 {}", n.replace('_', " ")),
                serde_json::Value::from(*n),
            )
        })
        .collect();
    std::fs::write(&json_path, serde_json::to_string(&json).unwrap()).unwrap();
    for map_path in [&toml_path, &json_path] {
        let options = MotionFileOptions {
            bvh_map: MapChoice::Custom(NameMap::read(map_path).unwrap()),
            ..MotionFileOptions::default()
        };
        let (back, source) = read_motion(&renamed_path, &options).unwrap();
        let MotionSource::Bvh(r) = source else {
            panic!()
        };
        assert_eq!(r.map, map_path.display().to_string());
        assert!(back.distance(&m).unwrap().rotation < 1e-6);
    }

    // Bad map files name the file and the problem.
    let bad = dir.path("bad.toml");
    std::fs::write(&bad, "Hips = \"hip\"\n").unwrap();
    let e = NameMap::read(&bad).unwrap_err().to_string();
    assert!(
        e.contains("bad.toml: 'Hips' maps to 'hip', which is no SMPL joint"),
        "{e}"
    );
    std::fs::write(&bad, "Hips = 3\n").unwrap();
    assert!(NameMap::read(&bad)
        .unwrap_err()
        .to_string()
        .contains("expected an SMPL joint name"));
    std::fs::write(&bad, "Hips = \n").unwrap();
    assert!(NameMap::read(&bad)
        .unwrap_err()
        .to_string()
        .contains("not valid TOML"));
    let bad_json = dir.path("bad.json");
    std::fs::write(&bad_json, "[1, 2]").unwrap();
    assert!(NameMap::read(&bad_json)
        .unwrap_err()
        .to_string()
        .contains("expected one JSON object"));
    let e = NameMap::read(&dir.path("map.yaml")).unwrap_err();
    assert!(matches!(e, MotionError::Io { .. }), "{e}");
}

#[test]
fn ambiguous_and_missing_joints_are_errors_naming_them() {
    let m = walk(5);
    let b = motion_to_bvh(&m, &DEFAULT_REST_JOINTS).unwrap();
    let values: Vec<f64> = (0..b.frame_count())
        .flat_map(|f| b.frame(f).to_vec())
        .collect();

    // Two joints normalising to one name: `L_Elbow` and `left_elbow` both drive SMPL's
    // left elbow under the SMPL preset.
    let mut joints = b.joints().to_vec();
    joints[16].name = "L_Elbow".into(); // was left_shoulder
    let ambiguous = Bvh::new(joints, b.frame_time(), values.clone()).unwrap();
    let options = RetargetOptions {
        map: MapChoice::Preset(SkeletonPreset::Smpl),
        ..RetargetOptions::default()
    };
    let e = retarget_bvh(&ambiguous, Path::new("a.bvh"), &options)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "'L_Elbow' (line 0) and 'left_elbow' (line 0) both map to SMPL joint 'left_elbow'"
        ),
        "{e}"
    );

    // A missing knee.
    let mut joints = b.joints().to_vec();
    joints[4].name = "knee_thing".into();
    let missing = Bvh::new(joints, b.frame_time(), values.clone()).unwrap();
    let e = retarget_bvh(&missing, Path::new("k.bvh"), &options)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("k.bvh: no BVH joint maps to SMPL joint 'left_knee' (the smpl map looks for left_knee or L_Knee)"), "{e}");

    // Unknown extra joints and a missing optional joint are reported, not errors.
    let mut joints = b.joints().to_vec();
    joints[22].name = "left_hand_helper".into();
    let extra = Bvh::new(joints, b.frame_time(), values).unwrap();
    let (_, r) = retarget_bvh(&extra, Path::new("x.bvh"), &options).unwrap();
    assert_eq!(r.unused, vec!["left_hand_helper".to_string()]);
    assert_eq!(r.unmapped, vec!["left_hand"]);
}

#[test]
fn mapping_against_the_hierarchy_is_warned_about() {
    let m = walk(3);
    let b = motion_to_bvh(&m, &DEFAULT_REST_JOINTS).unwrap();
    let values: Vec<f64> = (0..b.frame_count())
        .flat_map(|f| b.frame(f).to_vec())
        .collect();
    let mut joints = b.joints().to_vec();
    // Swap the names of the two elbows: each elbow's source is under the other arm.
    joints[18].name = "right_elbow".into();
    joints[19].name = "left_elbow".into();
    let swapped = Bvh::new(joints, b.frame_time(), values).unwrap();
    let (_, r) = retarget_bvh(&swapped, Path::new("s.bvh"), &RetargetOptions::default()).unwrap();
    assert!(
        r.warnings.iter().any(|w| w.contains(
            "'left_elbow' is driven by 'left_elbow', which is not below 'left_shoulder'"
        )),
        "{:?}",
        r.warnings
    );
}

#[test]
fn malformed_bvh_corpus_gives_one_line_errors() {
    let good = std::fs::read_to_string(fixture("cmu_tiny.bvh")).unwrap();
    let dir = TempDir::new("bvh", "corpus");
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "truncated-hierarchy",
            good[..good.len() / 3].to_string(),
            "truncated",
        ),
        (
            "truncated-frames",
            good[..good.len() - 200].to_string(),
            "values; the CHANNELS declare 96 per frame",
        ),
        (
            "missing-last-frame",
            good.trim_end().rsplit_once('\n').unwrap().0.to_string(),
            "after 3 of the 4 frames",
        ),
        (
            "absurd-frames",
            good.replace("Frames: 4", "Frames: 4000000000000"),
            "declares 4000000000000 frames of 96 channels",
        ),
        (
            "bad-channel-count",
            good.replacen(
                "CHANNELS 3 Zrotation Yrotation Xrotation",
                "CHANNELS 4 Zrotation Yrotation Xrotation",
                1,
            ),
            "declares 4 channels but channel 4 is 'JOINT'",
        ),
        (
            "bad-channel-name",
            good.replacen(
                "CHANNELS 3 Zrotation Yrotation Xrotation",
                "CHANNELS 3 Zrotation Yrotation Wrotation",
                1,
            ),
            "channel 3 is 'Wrotation'",
        ),
        (
            "nan",
            {
                let (head, frames) = good.split_at(good.find("Frame Time").unwrap());
                format!("{head}{}", frames.replacen(" 0.0000", " nan", 1))
            },
            "expected a finite number, found 'nan'",
        ),
        ("empty", String::new(), "truncated; expected 'HIERARCHY'"),
        ("binary", "\u{0}\u{1}garbage".into(), "expected 'HIERARCHY'"),
    ];
    for (name, text, expected) in cases {
        let path = dir.path(&format!("{name}.bvh"));
        std::fs::write(&path, &text).unwrap();
        let e = read_motion(&path, &MotionFileOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&path.display().to_string()), "{name}: {e}");
        assert!(e.contains(expected), "{name}: {e}");
        assert!(!e.contains('\n'), "{name}: {e}");
    }
    let e = read_motion(&dir.path("none.bvh"), &MotionFileOptions::default()).unwrap_err();
    assert!(matches!(e, MotionError::Io { .. }));
    let e = read_motion(&dir.path("m.fbx"), &MotionFileOptions::default()).unwrap_err();
    assert!(e.to_string().contains("unknown motion format"), "{e}");
}

#[test]
fn smpl_skeleton_offsets_come_from_the_rest_joints() {
    let mut rest = DEFAULT_REST_JOINTS;
    for p in rest.iter_mut() {
        p[1] *= 1.1;
    }
    let b = motion_to_bvh(&walk(2), &rest).unwrap();
    let knee = smpl_joint_index("left_knee").unwrap();
    let hip = smpl_joint_index("left_hip").unwrap();
    assert!(
        (b.joints()[knee].offset[1]
            - 1.1 * (DEFAULT_REST_JOINTS[knee][1] - DEFAULT_REST_JOINTS[hip][1]))
            .abs()
            < 1e-12
    );
    assert_eq!(b.joints().len(), SMPL_JOINT_COUNT);
    let mut bad = rest;
    bad[3][0] = f64::NAN;
    assert!(motion_to_bvh(&walk(2), &bad).is_err());
}
