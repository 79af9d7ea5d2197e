//! AMASS-style `.npz` in and out: round trips, layouts, axis conversion and a malformed
//! corpus generated here.

use std::path::PathBuf;

use nalgebra::{UnitQuaternion, Vector3};
use weft_mesh::io::npz::NpzWriter;
use weft_motion::{
    amass_npz, generate, posed_joints, read_amass, read_motion, write_amass, write_motion,
    AmassOptions, Motion, MotionError, MotionFileOptions, MotionKind, PoseLayout, ProceduralParams,
    UpAxis, DEFAULT_REST_JOINTS,
};

mod motion_common;
use motion_common::TempDir;

fn dance(frames: usize) -> Motion {
    let mut p = ProceduralParams::new(MotionKind::Dance);
    p.frames = frames;
    p.seed = 11;
    generate(&p)
        .unwrap()
        .with_betas(Some(vec![0.5, -1.0, 0.25]))
        .unwrap()
}

#[test]
fn npz_round_trip_is_exact_to_storage_precision() {
    let dir = TempDir::new("npz", "roundtrip");
    let m = dance(30);
    for up in [UpAxis::Z, UpAxis::Y] {
        let options = AmassOptions {
            up: Some(up),
            ..AmassOptions::default()
        };
        let path = dir.path("m.npz");
        write_amass(&path, &m, &options).unwrap();
        let (back, report) = read_amass(&path, &options).unwrap();
        assert_eq!(report.layout, PoseLayout::Smpl);
        assert_eq!(report.frame_rate_key, Some("mocap_framerate"));
        assert_eq!(report.dropped_joints, 0);
        assert!(report.unused_keys.is_empty());
        assert_eq!(back.fps(), m.fps());
        assert_eq!(back.betas(), m.betas());
        let d = back.distance(&m).unwrap();
        assert!(d.rotation < 1e-6 && d.translation < 1e-6, "{up:?}: {d:?}");
        // And again: npz → Motion → npz gives the same arrays.
        let again = dir.path("again.npz");
        write_amass(&again, &back, &options).unwrap();
        let (back2, _) = read_amass(&again, &options).unwrap();
        assert!(back2.distance(&back).unwrap().rotation < 1e-6);
    }
    // Through the extension-dispatching functions too.
    let path = dir.path("x.NPZ");
    write_motion(&path, &m, &MotionFileOptions::default()).unwrap();
    let (back, _) = read_motion(&path, &MotionFileOptions::default()).unwrap();
    assert!(back.distance(&m).unwrap().translation < 1e-6);
}

#[test]
fn z_up_files_are_turned_y_up_about_the_rest_pelvis() {
    // One frame, written by hand the way AMASS stores it: the body stands upright in a
    // Z-up world, so its root orientation is +90° about X, and the pelvis is 0.95 m
    // above the floor.
    let dir = TempDir::new("npz", "zup");
    let path = dir.path("amass.npz");
    let j0 = DEFAULT_REST_JOINTS[0];
    let mut poses = vec![0.0f64; 156];
    poses[0] = std::f64::consts::FRAC_PI_2;
    // SMPL-H: joints 22.. are fingers; put something in the left index finger.
    poses[66..69].copy_from_slice(&[0.3, 0.2, 0.1]);
    poses[12..15].copy_from_slice(&[0.4, 0.0, 0.0]); // left knee (joint 4)
                                                     // The pelvis at world (0.1, 0.2, 0.95) means trans = that − J0 (J0 in model coords).
    let trans = [0.1 - j0[0], 0.2 - j0[1], 0.95 - j0[2]];
    let mut w = NpzWriter::new(true);
    w.add("poses", &[1, 156], &poses).unwrap();
    w.add("trans", &[1, 3], &trans).unwrap();
    w.add("mocap_framerate", &[], &[120.0f64]).unwrap();
    w.add("betas", &[16], &[0.0f64; 16]).unwrap();
    w.add("gender", &[1], &[1u8]).unwrap();
    w.add("dmpls", &[1, 8], &[0.0f64; 8]).unwrap();
    w.write(&path).unwrap();

    let (m, report) = read_amass(&path, &AmassOptions::default()).unwrap();
    assert_eq!(report.layout, PoseLayout::SmplH);
    assert_eq!(report.dropped_joints, 30);
    assert_eq!(
        report.unused_keys,
        vec!["dmpls".to_string(), "gender".to_string()]
    );
    assert_eq!(m.fps(), 120.0);
    assert_eq!(m.betas().unwrap().len(), 16);
    let pose = m.poses()[0];
    // Upright in Y-up: no root rotation left.
    assert!(pose[0].iter().all(|x| x.abs() < 1e-6), "{:?}", pose[0]);
    assert_eq!(pose[4], [0.4, 0.0, 0.0]);
    // SMPL's hand joints stay at rest; the finger rotation is not copied into them.
    assert_eq!(pose[22], [0.0; 3]);
    assert_eq!(pose[23], [0.0; 3]);
    // The pelvis: Z-up (0.1, 0.2, 0.95) is Y-up (0.1, 0.95, −0.2).
    let joints = posed_joints(&pose, m.trans()[0], &DEFAULT_REST_JOINTS);
    let p = Vector3::from(joints[0]);
    assert!((p - Vector3::new(0.1, 0.95, -0.2)).norm() < 1e-6, "{p}");
    // The head is above the pelvis: the body stands up in Y-up.
    assert!(joints[15][1] > p.y + 0.4);

    // Driving a body whose pelvis is elsewhere (weft's default body has it at the
    // origin) puts that body's pelvis at the same place in the world.
    let other = AmassOptions {
        target_pelvis: [0.0; 3],
        ..AmassOptions::default()
    };
    let (m0, _) = read_amass(&path, &other).unwrap();
    let t0 = m0.trans()[0];
    let p0 = Vector3::new(f64::from(t0[0]), f64::from(t0[1]), f64::from(t0[2]));
    assert!((p0 - Vector3::new(0.1, 0.95, -0.2)).norm() < 1e-6, "{p0}");
    let back0 = dir.path("back0.npz");
    write_amass(&back0, &m0, &other).unwrap();
    let (again, _) = read_amass(&back0, &other).unwrap();
    assert!(again.distance(&m0).unwrap().translation < 1e-6);

    // Written back Z up, the root orientation and translation are AMASS's again.
    let out = dir.path("back.npz");
    write_amass(&out, &m, &AmassOptions::default()).unwrap();
    let mut npz = weft_mesh::io::npz::Npz::open(&out).unwrap();
    let back = npz.floats("poses", &[Some(1), Some(72)]).unwrap().data;
    let q = UnitQuaternion::from_scaled_axis(Vector3::new(back[0], back[1], back[2]));
    assert!(
        q.angle_to(&UnitQuaternion::from_axis_angle(
            &Vector3::x_axis(),
            std::f64::consts::FRAC_PI_2
        )) < 1e-6
    );
    let t = npz.floats("trans", &[Some(1), Some(3)]).unwrap().data;
    for k in 0..3 {
        assert!((t[k] - trans[k]).abs() < 1e-6, "{t:?} vs {trans:?}");
    }
}

#[test]
fn smplx_and_split_layouts_read() {
    let dir = TempDir::new("npz", "layouts");
    let n = 4;
    let mut poses = vec![0.0f64; n * 165];
    for t in 0..n {
        poses[t * 165 + 3] = 0.1 * t as f64; // left hip x
        poses[t * 165 + 66] = 0.7; // jaw: must not reach SMPL's left hand
    }
    let trans = vec![0.0f64; n * 3];
    let path = dir.path("smplx.npz");
    let mut w = NpzWriter::new(false);
    w.add("poses", &[n, 165], &poses).unwrap();
    w.add("trans", &[n, 3], &trans).unwrap();
    w.add("mocap_frame_rate", &[1], &[60i64]).unwrap();
    w.add("betas", &[1, 10], &[0.1f32; 10]).unwrap();
    w.write(&path).unwrap();
    let options = AmassOptions {
        up: Some(UpAxis::Y),
        ..AmassOptions::default()
    };
    let (m, r) = read_amass(&path, &options).unwrap();
    assert_eq!(
        (r.layout, r.dropped_joints, r.frame_rate_key),
        (PoseLayout::SmplX, 33, Some("mocap_frame_rate"))
    );
    assert_eq!(m.fps(), 60.0);
    assert_eq!(m.betas().unwrap().len(), 10);
    assert_eq!(m.poses()[3][1][0], 0.3f64 as f32);
    assert_eq!(m.poses()[3][22], [0.0; 3]);

    let path = dir.path("parts.npz");
    let mut w = NpzWriter::new(false);
    w.add("root_orient", &[n, 3], &vec![0.0f64; n * 3]).unwrap();
    let mut body = vec![0.0f64; n * 63];
    body[63 * 2 + 9] = -0.5; // frame 2, joint 4 (left knee) x
    w.add("pose_body", &[n, 63], &body).unwrap();
    w.add("trans", &[n, 3], &trans).unwrap();
    w.write(&path).unwrap();
    let e = read_amass(&path, &options).unwrap_err().to_string();
    assert!(
        e.contains("no frame rate: expected `mocap_framerate` or `mocap_frame_rate`"),
        "{e}"
    );
    let options = AmassOptions {
        fps_if_missing: Some(30.0),
        ..options
    };
    let (m, r) = read_amass(&path, &options).unwrap();
    assert_eq!((r.layout, r.frame_rate_key), (PoseLayout::Parts, None));
    assert_eq!(m.poses()[2][4], [-0.5, 0.0, 0.0]);
}

/// An `.npz` from `(key, shape, data)` arrays.
fn npz(dir: &TempDir, name: &str, arrays: &[(&str, Vec<usize>, Vec<f64>)]) -> PathBuf {
    let mut w = NpzWriter::new(false);
    for (k, shape, data) in arrays {
        w.add(k, shape, data).unwrap();
    }
    let path = dir.path(name);
    w.write(&path).unwrap();
    path
}

fn good(n: usize) -> Vec<(&'static str, Vec<usize>, Vec<f64>)> {
    vec![
        ("poses", vec![n, 72], vec![0.0; n * 72]),
        ("trans", vec![n, 3], vec![0.0; n * 3]),
        ("mocap_framerate", vec![], vec![30.0]),
    ]
}

fn with(
    mut arrays: Vec<(&'static str, Vec<usize>, Vec<f64>)>,
    key: &'static str,
    shape: Vec<usize>,
    data: Vec<f64>,
) -> Vec<(&'static str, Vec<usize>, Vec<f64>)> {
    arrays.retain(|a| a.0 != key);
    arrays.push((key, shape, data));
    arrays
}

fn without(
    mut arrays: Vec<(&'static str, Vec<usize>, Vec<f64>)>,
    key: &str,
) -> Vec<(&'static str, Vec<usize>, Vec<f64>)> {
    arrays.retain(|a| a.0 != key);
    arrays
}

/// Named arrays of an .npz under test: (key, shape, values).
type Arrays = Vec<(&'static str, Vec<usize>, Vec<f64>)>;

#[test]
fn malformed_npz_corpus_gives_one_line_errors_naming_file_and_key() {
    let dir = TempDir::new("npz", "corpus");
    let mut nan_poses = vec![0.0; 5 * 72];
    nan_poses[2 * 72 + 7] = f64::NAN;
    let mut inf_trans = vec![0.0; 15];
    inf_trans[4] = f64::INFINITY;
    let cases: Vec<(&str, Arrays, &str)> = vec![
        ("poses-wrong-width", with(good(5), "poses", vec![5, 50], vec![0.0; 250]), "`poses`: has shape (5, 50); expected (N, 72) for SMPL, (N, 156) for SMPL-H or (N, 165) for SMPL-X"),
        ("poses-3d", with(good(5), "poses", vec![5, 24, 3], vec![0.0; 360]), "`poses`: has shape [5, 24, 3]; expected (N, 72)"),
        ("poses-empty", with(with(good(5), "poses", vec![0, 72], vec![]), "trans", vec![0, 3], vec![]), "`poses`: has no frames"),
        ("poses-nan", with(good(5), "poses", vec![5, 72], nan_poses), "`poses`: frame 2, value 7 is NaN; expected finite"),
        ("trans-short", with(good(5), "trans", vec![4, 3], vec![0.0; 12]), "`trans` has shape (4, 3); expected (5, 3)"),
        ("trans-inf", with(good(5), "trans", vec![5, 3], inf_trans), "`trans`: frame 1, coordinate 1 is inf"),
        ("no-poses", without(good(5), "poses"), "no array `poses`"),
        ("no-trans", without(good(5), "trans"), "no array `trans`"),
        ("no-framerate", without(good(5), "mocap_framerate"), "no frame rate"),
        ("framerate-zero", with(good(5), "mocap_framerate", vec![], vec![0.0]), "`mocap_framerate`: frame rate 0; expected frames per second above 0"),
        ("framerate-array", with(good(5), "mocap_framerate", vec![2], vec![30.0, 60.0]), "`mocap_framerate`: has shape [2]; expected a single number"),
        ("betas-nan", with(good(5), "betas", vec![3], vec![0.0, f64::NAN, 0.0]), "`betas`: beta 1 is NaN"),
        ("betas-2d", with(good(5), "betas", vec![5, 10], vec![0.0; 50]), "`betas` has shape (5, 10)"),
    ];
    for (name, arrays, expected) in cases {
        let path = npz(&dir, &format!("{name}.npz"), &arrays);
        let e = read_motion(&path, &MotionFileOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&path.display().to_string()), "{name}: {e}");
        assert!(e.contains(expected), "{name}: {e}");
        assert!(!e.contains('\n'), "{name}: {e}");
    }

    // Not a zip at all, and a truncated archive.
    let path = dir.path("text.npz");
    std::fs::write(&path, "poses = [1, 2, 3]").unwrap();
    let e = read_motion(&path, &MotionFileOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a readable .npz (zip) archive"), "{e}");
    let full = std::fs::read(npz(&dir, "full.npz", &good(50))).unwrap();
    let path = dir.path("cut.npz");
    std::fs::write(&path, &full[..full.len() / 2]).unwrap();
    let e = read_motion(&path, &MotionFileOptions::default()).unwrap_err();
    assert!(matches!(e, MotionError::NpzFile(_)), "{e}");
}

/// CRC-32 (IEEE), to patch the archive after editing a member's bytes.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = (crc >> 1) ^ (0xedb8_8320 & (!(crc & 1)).wrapping_add(1));
        }
    }
    !crc
}

#[test]
fn an_absurd_frame_count_in_the_header_is_refused_without_allocating() {
    // A stored archive whose `poses` header claims 10¹⁵ frames over 5 frames of data:
    // the reader must compare the claim with the bytes present, not allocate for it.
    let dir = TempDir::new("npz", "absurd");
    let mut w = NpzWriter::new(false);
    w.add("poses", &[5, 72], &vec![0.0f64; 360]).unwrap();
    w.add("trans", &[5, 3], &[0.0f64; 15]).unwrap();
    w.add("mocap_framerate", &[], &[30.0f64]).unwrap();
    let mut bytes = w.to_bytes().unwrap();
    // The poses member: magic, version, header length, header, 360 doubles.
    let header_at = bytes.windows(6).position(|x| x == b"\x93NUMPY").unwrap();
    let header_len = usize::from(u16::from_le_bytes([
        bytes[header_at + 8],
        bytes[header_at + 9],
    ]));
    let member_len = 10 + header_len + 360 * 8;
    let old_crc = crc32(&bytes[header_at..header_at + member_len]);
    let text = std::str::from_utf8(&bytes[header_at + 10..header_at + 10 + header_len])
        .unwrap()
        .to_owned();
    // Same header length: the longer shape eats into the space padding.
    let grown = text.replacen("(5, 72)", "(1000000000000000, 72)", 1);
    let extra = grown.len() - text.len();
    let body = grown.trim_end_matches('\n');
    assert!(
        body.ends_with(&" ".repeat(extra)),
        "not enough padding to patch in place"
    );
    let new_header = format!("{}\n", &body[..body.len() - extra]);
    assert_eq!(new_header.len(), header_len);
    bytes[header_at + 10..header_at + 10 + header_len].copy_from_slice(new_header.as_bytes());
    let new_crc = crc32(&bytes[header_at..header_at + member_len]);
    let (old, new) = (old_crc.to_le_bytes(), new_crc.to_le_bytes());
    let mut patched_crcs = 0;
    let mut i = 0;
    while i + 4 <= bytes.len() {
        if bytes[i..i + 4] == old {
            bytes[i..i + 4].copy_from_slice(&new);
            patched_crcs += 1;
        }
        i += 1;
    }
    assert!(patched_crcs >= 2, "local and central CRC");
    let path = dir.path("absurd.npz");
    std::fs::write(&path, &bytes).unwrap();
    let e = read_motion(&path, &MotionFileOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`poses`: the data has 2880 bytes but shape (1000000000000000, 72)"),
        "{e}"
    );
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn the_writer_stores_amass_keys_and_dtypes() {
    let m = dance(3);
    let w = amass_npz(&m, &AmassOptions::default()).unwrap();
    let dir = TempDir::new("npz", "keys");
    let path = dir.path("k.npz");
    w.write(&path).unwrap();
    let mut npz = weft_mesh::io::npz::Npz::open(&path).unwrap();
    assert_eq!(
        npz.keys(),
        vec!["betas", "mocap_framerate", "poses", "trans", "weft_up_axis"]
    );
    for key in ["betas", "mocap_framerate", "poses", "trans", "weft_up_axis"] {
        assert_eq!(npz.describe(key).unwrap().0, "<f8", "{key}");
    }
    // The up axis is recorded as a plain float64 direction: Z, as AMASS.
    assert_eq!(
        npz.floats("weft_up_axis", &[Some(3)]).unwrap().data,
        vec![0.0, 0.0, 1.0]
    );
    assert_eq!(npz.describe("poses").unwrap().1, vec![3, 72]);
    assert_eq!(
        npz.describe("mocap_framerate").unwrap().1,
        Vec::<usize>::new()
    );
}

/// Issue 17 item 10: `weft motion generate --npz-up y` wrote a file that every reader
/// took for Z up, so the body came back lying on its back. Files record their axis now.
#[test]
fn a_file_records_its_up_axis_and_reads_back_upright() {
    use weft_motion::{UpFrom, UP_AXIS_KEY};
    let dir = TempDir::new("npz", "up");
    let m = dance(12);
    for up in [UpAxis::Y, UpAxis::Z] {
        let path = dir.path("m.npz");
        write_motion(
            &path,
            &m,
            &MotionFileOptions {
                npz_up: Some(up),
                ..MotionFileOptions::default()
            },
        )
        .unwrap();
        // Read without saying which axis: the recorded one.
        let (back, report) = read_amass(&path, &AmassOptions::default()).unwrap();
        assert_eq!((report.up, report.up_from), (up, UpFrom::Recorded));
        assert!(report.unused_keys.is_empty(), "{:?}", report.unused_keys);
        assert!(report.warnings.is_empty(), "{:?}", report.warnings);
        let d = back.distance(&m).unwrap();
        assert!(d.rotation < 1e-6 && d.translation < 1e-6, "{up:?}: {d:?}");
        // A given axis overrides the recorded one, with a warning.
        let other = if up == UpAxis::Y {
            UpAxis::Z
        } else {
            UpAxis::Y
        };
        let (turned, report) = read_amass(
            &path,
            &AmassOptions {
                up: Some(other),
                ..AmassOptions::default()
            },
        )
        .unwrap();
        assert_eq!((report.up, report.up_from), (other, UpFrom::Given));
        assert!(report.warnings[0].contains("read"), "{:?}", report.warnings);
        assert!(turned.distance(&m).unwrap().rotation > 1.0);
    }

    // A Y-up file that records nothing (another tool's) is read Z up, as AMASS, and
    // the report says the body lies down and how to read it.
    let y_up = amass_npz(
        &m,
        &AmassOptions {
            up: Some(UpAxis::Y),
            ..AmassOptions::default()
        },
    )
    .unwrap()
    .to_bytes()
    .unwrap();
    let path = dir.path("y.npz");
    std::fs::write(&path, &y_up).unwrap();
    let mut src = weft_mesh::io::npz::Npz::open(&path).unwrap();
    let mut w = NpzWriter::new(false);
    for key in src.keys() {
        if key != UP_AXIS_KEY {
            let shape: Vec<Option<usize>> = src
                .describe(&key)
                .unwrap()
                .1
                .into_iter()
                .map(Some)
                .collect();
            let a = src.floats(&key, &shape).unwrap();
            w.add(&key, &a.shape, &a.data).unwrap();
        }
    }
    let bare = dir.path("bare.npz");
    w.write(&bare).unwrap();
    let (_, report) = read_amass(&bare, &AmassOptions::default()).unwrap();
    assert_eq!((report.up, report.up_from), (UpAxis::Z, UpFrom::Default));
    assert!(
        report.warnings.len() == 1 && report.warnings[0].contains("--up y"),
        "{:?}",
        report.warnings
    );
    // A Z-up capture (the dance written as AMASS is) draws no such warning.
    let z = dir.path("z.npz");
    write_amass(&z, &m, &AmassOptions::default()).unwrap();
    assert!(read_amass(&z, &AmassOptions::default())
        .unwrap()
        .1
        .warnings
        .is_empty());

    // A recorded axis that is neither Y nor Z is refused, naming the key.
    let mut w = NpzWriter::new(false);
    w.add("poses", &[1, 72], &[0.0f64; 72]).unwrap();
    w.add("trans", &[1, 3], &[0.0f64; 3]).unwrap();
    w.add("mocap_framerate", &[], &[30.0f64]).unwrap();
    w.add(UP_AXIS_KEY, &[3], &[1.0f64, 0.0, 0.0]).unwrap();
    let odd = dir.path("odd.npz");
    w.write(&odd).unwrap();
    let e = read_amass(&odd, &AmassOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("weft_up_axis") && e.contains("[0, 1, 0] for Y up"),
        "{e}"
    );
}

/// Issue 17 item 11: a frame rate given with a motion file was silently ignored. The
/// one reading path resamples to it, and says so.
#[test]
fn load_motion_resamples_to_the_rate_asked_for() {
    use weft_motion::load_motion;
    let dir = TempDir::new("npz", "fps");
    let mut p = ProceduralParams::new(MotionKind::Walk);
    p.frames = 25;
    p.fps = 120.0;
    let m = generate(&p).unwrap();
    let path = dir.path("walk120.npz");
    write_motion(&path, &m, &MotionFileOptions::default()).unwrap();
    let options = MotionFileOptions::default();
    let kept = load_motion(&path, &options, None).unwrap();
    assert_eq!((kept.motion.fps(), kept.resampled_from), (120.0, None));
    let same = load_motion(&path, &options, Some(120.0)).unwrap();
    assert_eq!(same.resampled_from, None);
    let at30 = load_motion(&path, &options, Some(30.0)).unwrap();
    assert_eq!(at30.motion.fps(), 30.0);
    assert_eq!(at30.motion.frame_count(), 7); // 24/120 s = 0.2 s: frames at 0…6/30
    assert_eq!(at30.resampled_from, Some((120.0, 25)));
    // Frame 1 at 30 fps is frame 4 at 120 (the root went through the Z-up file).
    assert_eq!(at30.motion.poses()[1][1..], m.poses()[4][1..]);
    // A file without a frame rate is taken to run at the rate given.
    let mut w = NpzWriter::new(false);
    w.add("poses", &[2, 72], &[0.0f64; 144]).unwrap();
    w.add("trans", &[2, 3], &[0.0f64; 6]).unwrap();
    let bare = dir.path("no-rate.npz");
    w.write(&bare).unwrap();
    let got = load_motion(&bare, &options, Some(50.0)).unwrap();
    assert_eq!((got.motion.fps(), got.resampled_from), (50.0, None));
    assert!(load_motion(&bare, &options, None).is_err());
}
