//! End-to-end tests of `weft motion …` through the real binary.

use std::path::Path;

mod common;
use common::{garment, s, scratch, stderr, stdout, weft};

#[test]
fn generate_then_info_in_both_formats() {
    let dir = scratch("generate");
    for ext in ["npz", "bvh"] {
        let out = dir.join(format!("walk.{ext}"));
        let o = weft(&[
            "motion",
            "generate",
            "--kind",
            "walk",
            "--frames",
            "120",
            "--fps",
            "30",
            "--seed",
            "0",
            "--speed",
            "1.0",
            "--amplitude",
            "1.0",
            "--out",
            s(&out),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            stdout(&o).contains("walk, 120 frames at 30 fps"),
            "{}",
            stdout(&o)
        );
        let o = weft(&["motion", "info", s(&out), "--json"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("one JSON object");
        assert_eq!(v["frames"], 120);
        assert_eq!(v["fps"], 30.0);
        assert_eq!(v["joint_count"], 24);
        let d = v["duration_s"].as_f64().unwrap();
        assert!((d - 119.0 / 30.0).abs() < 1e-9);
        // 1 m/s for 3.97 s along +Z, plus a little sway and bob.
        let z = v["root_displacement_m"][2].as_f64().unwrap();
        assert!((z - d).abs() < 1e-3, "{z}");
        let path = v["root_path_length_m"].as_f64().unwrap();
        assert!(path >= z && path < 1.2 * z, "{path}");
        let knee = &v["joints"][4];
        assert_eq!(knee["name"], "left_knee");
        assert!(knee["max_deg"][0].as_f64().unwrap() > 30.0);
        assert_eq!(v["source"]["format"], ext);

        let o = weft(&["motion", "info", s(&out)]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = stdout(&o);
        assert!(text.contains("120 frames at 30 fps, 3.967 s"), "{text}");
        assert!(text.contains("left_knee"), "{text}");
    }
}

#[test]
fn same_seed_same_bytes() {
    let dir = scratch("seed");
    let run = |name: &str, seed: &str| {
        let out = dir.join(name);
        let o = weft(&[
            "motion",
            "generate",
            "--kind",
            "dance",
            "--frames",
            "50",
            "--seed",
            seed,
            "--out",
            s(&out),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read(out).unwrap()
    };
    assert_eq!(run("a.npz", "4"), run("b.npz", "4"));
    assert_ne!(run("a.npz", "4"), run("c.npz", "5"));
    assert_eq!(run("a.bvh", "4"), run("b.bvh", "4"));
}

#[test]
fn bad_arguments_and_files_fail_with_one_line() {
    let dir = scratch("bad");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "generate".into(),
                "--kind".into(),
                "moonwalk".into(),
                "--out".into(),
                "x.npz".into(),
            ],
            "unknown motion 'moonwalk'",
        ),
        (
            vec![
                "generate".into(),
                "--kind".into(),
                "walk".into(),
                "--frames".into(),
                "99999999999".into(),
                "--out".into(),
                s(&dir.join("x.npz")).into(),
            ],
            "expected 1 to 10000000",
        ),
        (
            vec![
                "generate".into(),
                "--kind".into(),
                "run".into(),
                "--speed".into(),
                "40".into(),
                "--out".into(),
                s(&dir.join("x.npz")).into(),
            ],
            "speed 40 for run",
        ),
        (
            vec![
                "generate".into(),
                "--kind".into(),
                "walk".into(),
                "--out".into(),
                s(&dir.join("x.fbx")).into(),
            ],
            "unknown motion format",
        ),
        (
            vec!["info".into(), s(&dir.join("missing.npz")).into()],
            "missing.npz",
        ),
    ];
    for (args, expected) in cases {
        let mut all = vec!["motion".to_string()];
        all.extend(args);
        let refs: Vec<&str> = all.iter().map(String::as_str).collect();
        let o = weft(&refs);
        assert!(!o.status.success(), "{refs:?}");
        let err = stderr(&o);
        assert!(err.contains(expected), "{refs:?}: {err}");
        // One error line (clap adds a hint line after its own argument errors).
        let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
        assert!(lines[0].starts_with("error: "), "{refs:?}: {err}");
        assert!(
            lines.len() == 1 || lines[1].starts_with("For more information"),
            "{refs:?}: {err}"
        );
    }
    assert!(!dir.join("x.npz").exists());

    // A truncated BVH names the file and line.
    let bvh = dir.join("t.bvh");
    std::fs::write(&bvh, "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n").unwrap();
    let o = weft(&["motion", "info", s(&bvh)]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.starts_with(&format!(
            "error: {}:6: the file ends here, truncated",
            s(&bvh)
        )),
        "{err}"
    );
}

#[test]
fn bvh_maps_and_scales_from_the_command_line() {
    let dir = scratch("map");
    let out = dir.join("bow.bvh");
    let o = weft(&[
        "motion",
        "generate",
        "--kind",
        "bow",
        "--frames",
        "10",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = weft(&["motion", "info", s(&out), "--map", "smpl", "--scale", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("with the smpl map, units given (1 m)"),
        "{}",
        stdout(&o)
    );
    // The Mixamo map finds none of SMPL's names.
    let o = weft(&["motion", "info", s(&out), "--map", "mixamo"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o)
            .contains("no BVH joint maps to SMPL joint 'pelvis' (the mixamo map looks for Hips)"),
        "{}",
        stderr(&o)
    );
    let o = weft(&[
        "motion",
        "info",
        s(&out),
        "--map",
        s(&dir.join("none.toml")),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("none.toml"), "{}", stderr(&o));
}

/// A minimal body in the SMPL `.npz` layout: one vertex at each rest joint (of the
/// built-in skeleton scaled by `scale`), each vertex its own joint's.
fn tiny_body(path: &Path, scale: f64) {
    use weft_body::joints::SMPL_PARENTS;
    use weft_mesh::io::npz::NpzWriter;
    use weft_motion::DEFAULT_REST_JOINTS;
    let n = 24;
    let v: Vec<f64> = DEFAULT_REST_JOINTS
        .iter()
        .flat_map(|p| p.map(|x| x * scale))
        .collect();
    let mut eye = vec![0.0f64; n * n];
    for i in 0..n {
        eye[i * n + i] = 1.0;
    }
    let mut kintree = Vec::new();
    kintree.extend(SMPL_PARENTS.iter().map(|p| p.map_or(-1, |p| p as i64)));
    kintree.extend(0..n as i64);
    let mut w = NpzWriter::new(false);
    w.add("v_template", &[n, 3], &v).unwrap();
    w.add("shapedirs", &[n, 3, 1], &vec![0.0f64; n * 3])
        .unwrap();
    w.add("J_regressor", &[n, n], &eye).unwrap();
    w.add("weights", &[n, n], &eye).unwrap();
    w.add("kintree_table", &[2, n], &kintree).unwrap();
    w.add("f", &[2, 3], &[0i64, 1, 2, 0, 2, 3]).unwrap();
    w.write(path).unwrap();
}

#[test]
fn a_body_file_shapes_the_bvh_skeleton() {
    let dir = scratch("body");
    let body = dir.join("body.npz");
    tiny_body(&body, 1.1);
    let out = dir.join("walk.bvh");
    let o = weft(&[
        "motion",
        "generate",
        "--kind",
        "walk",
        "--frames",
        "5",
        "--body",
        s(&body),
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).unwrap();
    // left_hip → left_knee is (0.03, −0.39, −0.005) on the built-in skeleton.
    assert!(text.contains("OFFSET 0.033 -0.429 -0.0055"), "{text}");
    // Reading it back against the same body gives a root scale of 1.
    let o = weft(&["motion", "info", s(&out), "--json", "--body", s(&body)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!((v["source"]["root_scale"].as_f64().unwrap() - 1.0).abs() < 1e-9);
    let o = weft(&[
        "motion",
        "info",
        s(&out),
        "--body",
        s(&dir.join("nobody.npz")),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("nobody.npz"), "{}", stderr(&o));
}

/// The vertical (Y) and largest horizontal extent of an OBJ's vertices, metres.
fn obj_extents(path: &Path) -> (f64, f64) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for line in std::fs::read_to_string(path).unwrap().lines() {
        if let Some(rest) = line.strip_prefix("v ") {
            for (k, x) in rest.split_whitespace().take(3).enumerate() {
                let x: f64 = x.parse().unwrap();
                lo[k] = lo[k].min(x);
                hi[k] = hi[k].max(x);
            }
        }
    }
    (hi[1] - lo[1], (hi[0] - lo[0]).max(hi[2] - lo[2]))
}

fn generate_walk(out: &Path, extra: &[&str]) {
    let mut args = vec!["motion", "generate", "--kind", "walk", "--out", s(out)];
    args.extend_from_slice(extra);
    let o = weft(&args);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Issue 17 item 10: `motion generate --npz-up y` wrote a file that `body pose`,
/// `simulate` and `animate` read back lying on its back. Files record their up axis;
/// `--up` overrides it wherever a motion is read.
#[test]
fn a_y_up_npz_reads_back_upright_and_up_overrides() {
    let dir = scratch("up");
    let walk = dir.join("walk_y.npz");
    generate_walk(&walk, &["--frames", "3", "--npz-up", "y"]);

    let upright = dir.join("upright.obj");
    let o = weft(&["body", "pose", "--motion", s(&walk), "--out", s(&upright)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (height, _) = obj_extents(&upright);
    assert!(height > 1.4, "standing body {height:.2} m tall");

    // --up z says otherwise: the body lies down, and the override is pointed out.
    let lying = dir.join("lying.obj");
    let o = weft(&[
        "body",
        "pose",
        "--motion",
        s(&walk),
        "--up",
        "z",
        "--out",
        s(&lying),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (height, across) = obj_extents(&lying);
    assert!(
        height < 1.0 && across > 1.4,
        "{height:.2} m tall, {across:.2} m long"
    );
    assert!(stderr(&o).contains("records Y up"), "{}", stderr(&o));

    // motion info says where the axis came from.
    let o = weft(&["motion", "info", s(&walk), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["source"]["up"], "Y");
    assert_eq!(v["source"]["up_from"], "recorded in the file");
    let o = weft(&["motion", "info", s(&walk)]);
    assert!(
        stdout(&o).contains("file Y up (recorded in the file; read as Y up)"),
        "{}",
        stdout(&o)
    );

    // A procedural motion has no file axis: --up with one is refused, not ignored.
    let o = weft(&[
        "simulate",
        "--garment",
        s(&upright),
        "--motion",
        "walk",
        "--up",
        "y",
        "--out",
        s(&dir.join("sim")),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--up applies to motion files"),
        "{}",
        stderr(&o)
    );
}

/// Issue 17 item 11: `--fps` with a motion file was silently ignored (a 120 fps file
/// with `--fps 30` gave 120 fps). The file is resampled, and stderr says so.
#[test]
fn fps_with_a_motion_file_resamples_and_says_so() {
    let dir = scratch("fps");
    let walk = dir.join("walk120.npz");
    generate_walk(&walk, &["--frames", "25", "--fps", "120"]);
    let said = "resampled from 120 fps (25 frames) to 30 fps (7 frames)";

    let frames = dir.join("frames");
    let o = weft(&[
        "body",
        "pose",
        "--motion",
        s(&walk),
        "--fps",
        "30",
        "--all-frames",
        "--out",
        s(&frames),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains(said), "{}", stderr(&o));
    assert!(stdout(&o).contains("7 frames at 30 fps"), "{}", stdout(&o));
    assert_eq!(std::fs::read_dir(&frames).unwrap().count(), 7);

    let o = weft(&["motion", "info", s(&walk), "--fps", "30", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains(said), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(
        (v["fps"].as_f64(), v["frames"].as_u64()),
        (Some(30.0), Some(7))
    );

    // weft simulate: the frames written are at 30 fps.
    let skirt = dir.join("skirt.obj");
    garment(&skirt, "skirt", 300, 1);
    let out = dir.join("sim");
    let o = weft(&[
        "simulate",
        "--garment",
        s(&skirt),
        "--motion",
        s(&walk),
        "--fps",
        "30",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--substeps",
        "1",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains(said), "{}", stderr(&o));
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("stats.json")).unwrap()).unwrap();
    assert_eq!(stats["fps"].as_f64(), Some(30.0));
}

/// `weft motion info --json` of `file`: (frames, fps, per-joint largest angle in degrees,
/// root displacement).
fn info_json(file: &Path) -> serde_json::Value {
    let o = weft(&["motion", "info", s(file), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

/// Issue 18 item 3: `weft motion convert` between AMASS-style .npz and BVH, either up
/// axis, any frame rate; a round trip keeps the motion.
#[test]
fn convert_between_npz_and_bvh_keeps_the_motion() {
    let dir = scratch("convert");
    let npz = dir.join("walk.npz");
    generate_walk(&npz, &["--frames", "40", "--fps", "30"]);
    let bvh = dir.join("walk.bvh");
    let back = dir.join("back.npz");
    let o = weft(&["motion", "convert", s(&npz), s(&bvh)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).starts_with(&format!(
            "wrote {} (bvh, SMPL skeleton, Y up): 40 frames at 30 fps",
            bvh.display()
        )),
        "{}",
        stdout(&o)
    );
    let o = weft(&[
        "motion",
        "convert",
        s(&bvh),
        s(&back),
        "--npz-up",
        "y",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(
        (v["format"].as_str(), v["npz_up"].as_str()),
        (Some("npz"), Some("Y"))
    );

    let (a, b) = (info_json(&npz), info_json(&back));
    assert_eq!(
        (b["frames"].as_u64(), b["fps"].as_f64()),
        (Some(40), Some(30.0))
    );
    assert_eq!(b["source"]["up"], "Y");
    for (ja, jb) in a["joints"]
        .as_array()
        .unwrap()
        .iter()
        .zip(b["joints"].as_array().unwrap())
    {
        let (x, y) = (
            ja["max_angle_deg"].as_f64().unwrap(),
            jb["max_angle_deg"].as_f64().unwrap(),
        );
        assert!((x - y).abs() < 0.05, "{}: {x} vs {y}", ja["name"]);
    }
    for k in 0..3 {
        let (x, y) = (
            a["root_displacement_m"][k].as_f64().unwrap(),
            b["root_displacement_m"][k].as_f64().unwrap(),
        );
        assert!((x - y).abs() < 1e-4, "root displacement {k}: {x} vs {y}");
    }

    // Resampled on the way: 40 frames at 30 fps are 20 at 15.
    let slow = dir.join("slow.bvh");
    let o = weft(&["motion", "convert", s(&npz), s(&slow), "--fps", "15"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("resampled from 30 fps (40 frames) to 15 fps (20 frames)"),
        "{}",
        stderr(&o)
    );
    assert_eq!(info_json(&slow)["frames"].as_u64(), Some(20));

    // Bad input: one line naming the problem, nothing written.
    let o = weft(&["motion", "convert", s(&npz), s(&dir.join("walk.fbx"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).starts_with("error: OUT: ") && stderr(&o).trim_end().lines().count() == 1,
        "{}",
        stderr(&o)
    );
    let o = weft(&[
        "motion",
        "convert",
        s(&dir.join("missing.npz")),
        s(&dir.join("x.bvh")),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("missing.npz"), "{}", stderr(&o));
    assert!(!dir.join("walk.fbx").exists() && !dir.join("x.bvh").exists());
}
