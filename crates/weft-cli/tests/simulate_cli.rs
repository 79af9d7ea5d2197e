//! End-to-end tests of `weft simulate` through the real binary: a small skirt on the
//! default body, walking, a few frames (kept small so the test profile runs it in
//! seconds).

use std::path::{Path, PathBuf};

mod common;
use common::{garment, s, scratch, stderr, stdout, weft};

/// A 300-vertex skirt fitted to the default body.
fn skirt(dir: &Path) -> PathBuf {
    let g = dir.join("skirt.obj");
    garment(&g, "skirt", 300, 1);
    g
}

fn vertex_count(obj: &Path) -> usize {
    std::fs::read_to_string(obj)
        .expect("obj")
        .lines()
        .filter(|l| l.starts_with("v "))
        .count()
}

#[test]
fn simulate_writes_frames_npy_pc2_obj_and_stats() {
    let dir = scratch("walk");
    let g = skirt(&dir);
    let n = vertex_count(&g);
    let out = dir.join("out");
    let o = weft(&[
        "simulate",
        "--garment",
        s(&g),
        "--motion",
        "walk",
        "--frames",
        "3",
        "--warmup",
        "2",
        "--substeps",
        "2",
        "--material",
        "silk",
        "--out",
        s(&out),
        "--obj",
        "--usd",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("3 frames of"), "{}", stdout(&o));
    // The garment's UVs (weft garment generate writes them) survive into obj/ and USD;
    // the USD scene holds the garment and the walking body, 3 time samples each.
    let uvs = weft_mesh::io::load_obj(&g).unwrap().corner_uvs.unwrap();
    let first = weft_mesh::io::load_obj(&out.join("obj/frame_00000.obj")).unwrap();
    assert_eq!(first.corner_uvs.unwrap(), uvs);
    let usd = std::fs::read_to_string(out.join("scene.usda")).expect("usd");
    assert_eq!(usd.matches("points.timeSamples = {").count(), 2, "{usd}");
    assert!(usd.contains("def Mesh \"garment\"") && usd.contains("def Mesh \"body\""));
    assert!(usd.contains("primvars:st:indices") && usd.contains("endTimeCode = 2\n"));
    // PC2: 32-byte header, then frames × vertices × 3 f32.
    let pc2 = std::fs::metadata(out.join("frames.pc2"))
        .expect("pc2")
        .len();
    assert_eq!(pc2, 32 + 3 * n as u64 * 12);
    // .npy of shape (3, n, 3), little-endian f32.
    let npy = std::fs::read(out.join("frames.npy")).expect("npy");
    let head = String::from_utf8_lossy(&npy[..128.min(npy.len())]).into_owned();
    assert!(head.contains("'<f4'"), "{head}");
    assert!(head.contains(&format!("(3, {n}, 3)")), "{head}");
    // One OBJ per frame.
    let objs = std::fs::read_dir(out.join("obj")).expect("obj dir").count();
    assert_eq!(objs, 3);
    // stats.json: per-frame statistics and totals.
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("stats.json")).expect("stats"))
            .expect("json");
    let frames = stats["frames"].as_array().expect("frames");
    assert_eq!(frames.len(), 3);
    for (k, f) in frames.iter().enumerate() {
        assert_eq!(f["frame"].as_u64(), Some(k as u64));
        for key in [
            "energy",
            "max_edge_strain",
            "mean_edge_strain",
            "max_penetration",
            "seconds",
        ] {
            assert!(f[key].as_f64().is_some_and(f64::is_finite), "{key}: {f}");
        }
        assert!(f["newton_iterations"].as_u64().unwrap_or(0) > 0);
        // Within the collision threshold (2 mm) of the body surface.
        assert!(f["max_penetration"].as_f64().unwrap_or(1.0) <= 2e-3, "{f}");
    }
    assert_eq!(stats["material"], "silk");
    assert!(stats["diverged"].is_null());
    assert_eq!(stats["totals"]["frames"].as_u64(), Some(3));
}

#[test]
fn bad_input_is_one_clear_error() {
    let dir = scratch("bad");
    let g = skirt(&dir);
    let out = dir.join("out");
    let run = |extra: &[&str]| {
        let mut a = vec!["simulate", "--garment", s(&g), "--out", s(&out)];
        a.extend_from_slice(extra);
        weft(&a)
    };
    let o = run(&["--motion", "moonwalk"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("moonwalk"), "{}", stderr(&o));
    let o = run(&["--motion", "walk", "--material", "tinfoil"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("tinfoil"), "{}", stderr(&o));
    let o = run(&["--motion", "walk", "--substeps", "0"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--substeps"), "{}", stderr(&o));
    let o = run(&["--motion", "missing.npz"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("missing.npz"), "{}", stderr(&o));

    // The skirt shrunk towards the body's axis starts deep inside the hips: refused,
    // with the count and the depth.
    let text = std::fs::read_to_string(&g).expect("obj");
    let shrunk: String = text
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            if f.first() == Some(&"v") && f.len() >= 4 {
                let c: Vec<f64> = f[1..4].iter().map(|x| x.parse().expect("float")).collect();
                format!("v {} {} {}\n", 0.5 * c[0], c[1], 0.5 * c[2])
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let inside = dir.join("inside.obj");
    std::fs::write(&inside, shrunk).expect("write");
    let o = weft(&[
        "simulate",
        "--garment",
        s(&inside),
        "--motion",
        "walk",
        "--frames",
        "2",
        "--out",
        s(&out),
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("starts inside the body") && e.contains("vertices inside"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1, "{e}");
}

/// Issue 17 items 6, 8 and 12: a failed run leaves no directory; a warm-up past the
/// bound and a garment a kilometre away are refused before any work; a run without
/// `--obj` into an earlier run's directory removes its stale `obj/`; missing parents of
/// `--out` are created.
#[test]
fn outputs_are_all_or_nothing_and_bounds_hold() {
    let dir = scratch("hygiene");
    let g = skirt(&dir);
    let out = dir.join("a/b/out");
    let run = |garment: &Path, extra: &[&str]| {
        let mut a = vec!["simulate", "--garment", s(garment), "--motion", "walk"];
        a.extend_from_slice(&["--frames", "2", "--out", s(&out)]);
        a.extend_from_slice(extra);
        weft(&a)
    };
    let o = run(&g, &["--warmup", "1000000000"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("--warmup") && err.contains("0 to 10000"),
        "{err}"
    );
    assert!(!dir.join("a").exists(), "a failed run left a directory");

    let text = std::fs::read_to_string(&g).expect("obj");
    let far: String = text
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(rest) => {
                let c: Vec<f64> = rest
                    .split_whitespace()
                    .map(|x| x.parse().unwrap())
                    .collect();
                format!("v {} {} {}\n", c[0] + 1000.0, c[1], c[2])
            }
            None => format!("{l}\n"),
        })
        .collect();
    let far_path = dir.join("far.obj");
    std::fs::write(&far_path, far).expect("write");
    let o = run(&far_path, &[]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("m from the body") && e.lines().count() == 1,
        "{e}"
    );
    assert!(!dir.join("a").exists(), "a failed run left a directory");

    let o = run(&g, &["--obj", "--usd"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("obj/frame_00000.obj").is_file());
    assert!(out.join("scene.usda").is_file());
    let o = run(&g, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !out.join("obj").exists(),
        "stale obj/ left beside new frames"
    );
    assert!(!out.join("scene.usda").exists(), "stale scene.usda left");
    assert!(stderr(&o).contains("removed"), "{}", stderr(&o));
}

/// Issue 18 item 3: the material from a TOML file of its fields, and pinned vertices from
/// the command line or a file; mistakes name the file, the key or the index.
#[test]
fn material_files_and_pinned_vertices() {
    let dir = scratch("material_pin");
    let g = skirt(&dir);
    let out = dir.join("out");
    let run = |extra: &[&str]| {
        let mut a = vec!["simulate", "--garment", s(&g), "--motion", "walk"];
        a.extend_from_slice(&["--frames", "2", "--warmup", "1", "--substeps", "2"]);
        a.extend_from_slice(&["--out", s(&out)]);
        a.extend_from_slice(extra);
        weft(&a)
    };
    let fabric = dir.join("fabric.toml");
    std::fs::write(
        &fabric,
        "density = 0.15\nyoung_modulus = 5e4\nfriction = 0.3\n",
    )
    .unwrap();
    let pins = dir.join("pins.txt");
    std::fs::write(&pins, "# a vertex group\n0 1 2\n3-5\n").unwrap();
    let o = run(&[
        "--material",
        s(&fabric),
        "--attach",
        "none",
        "--pin",
        s(&pins),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("stats.json")).unwrap()).unwrap();
    assert_eq!(stats["material"], "custom");
    // That pins hold exactly like the attachment is weft-sim's
    // `pinned_vertices_follow_the_skin_like_the_attachment`.
    assert_eq!(stats["totals"]["frames"].as_u64(), Some(2));

    let o = run(&["--pin", "0-3"]);
    assert!(o.status.success(), "{}", stderr(&o));

    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "densty = 0.15\n").unwrap();
    for (extra, needle) in [
        (vec!["--material", s(&bad)], "densty"),
        (vec!["--material", s(&dir.join("none.toml"))], "none.toml"),
        (vec!["--pin", "0,x"], "`x` is not a vertex index"),
        (vec!["--pin", "99999"], "pinned vertex (the garment has"),
    ] {
        let o = run(&extra);
        assert_eq!(o.status.code(), Some(1), "{extra:?}");
        let e = stderr(&o);
        assert!(
            e.contains(needle) && e.trim_end().lines().count() == 1,
            "{extra:?}: {e}"
        );
    }
    std::fs::write(&bad, "density = -1\n").unwrap();
    let o = run(&["--material", s(&bad)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("bad.toml"), "{}", stderr(&o));
}

/// `--buttons`: two hem vertices on opposite sides of the skirt buttoned together come
/// close; with `--unbutton-at 1` they are apart again by the last frame. A pair out of
/// range or a file that is not pairs is refused, naming the file.
#[test]
fn buttons_hold_a_pair_until_unbuttoned() {
    let dir = scratch("buttons");
    let g = skirt(&dir);
    let mesh = weft_mesh::io::load_obj(&g).unwrap().mesh;
    // The lowest vertex and the lowest one farthest from it: across the hem.
    let low = |v: &usize| mesh.positions[*v][1];
    let a = (0..mesh.vertex_count())
        .min_by(|x, y| low(x).total_cmp(&low(y)))
        .unwrap();
    let dist = |v: usize| weft_mesh::vec3::dist(mesh.positions[a], mesh.positions[v]);
    let b = (0..mesh.vertex_count())
        .filter(|&v| (low(&v) - low(&a)).abs() < 0.01)
        .max_by(|&x, &y| dist(x).total_cmp(&dist(y)))
        .unwrap();
    let pairs = dir.join("pairs.json");
    std::fs::write(&pairs, format!("[[{a}, {b}]]")).unwrap();
    let gap = |out: &Path, frame: usize| {
        let x = weft_mesh::export::npy::read_npy(&out.join("frames.npy")).unwrap();
        let v: Vec<f64> = match x.data {
            weft_mesh::export::npy::NpyData::F32(v) => v.into_iter().map(f64::from).collect(),
            weft_mesh::export::npy::NpyData::F64(v) => v,
            _ => panic!("frames.npy holds floats"),
        };
        let n = mesh.vertex_count();
        let p = |i: usize| -> [f64; 3] { std::array::from_fn(|k| v[3 * (frame * n + i) + k]) };
        weft_mesh::vec3::dist(p(a), p(b))
    };
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "simulate",
            "--garment",
            s(&g),
            "--motion",
            "walk",
            "--frames",
            "4",
            "--warmup",
            "6",
            "--substeps",
            "2",
            "--material",
            "silk",
            "--out",
            s(out),
        ];
        args.extend_from_slice(extra);
        weft(&args)
    };
    let held = dir.join("held");
    let o = run(&held, &["--buttons", s(&pairs)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let open = dist(b);
    assert!(gap(&held, 0) < 0.5 * open, "{} of {open}", gap(&held, 0));
    let undone = dir.join("undone");
    let o = run(&undone, &["--buttons", s(&pairs), "--unbutton-at", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        gap(&undone, 3) > 1.5 * gap(&held, 3),
        "{} vs {}",
        gap(&undone, 3),
        gap(&held, 3)
    );

    let bad = dir.join("bad.json");
    for (text, want) in [
        (format!("[[{a}, 99999]]"), "pair 0"),
        ("{\"a\": 1}".to_string(), "JSON list of vertex pairs"),
    ] {
        std::fs::write(&bad, text).unwrap();
        let o = run(&dir.join("never"), &["--buttons", s(&bad)]);
        assert!(!o.status.success());
        let e = stderr(&o);
        assert!(e.contains("bad.json") && e.contains(want), "{e}");
        assert!(!dir.join("never").exists());
    }
}
