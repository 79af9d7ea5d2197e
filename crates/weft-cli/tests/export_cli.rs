//! End-to-end tests of `weft export` through the real binary: every format round-trips,
//! and bad input gives one line on stderr, a non-zero exit and no output file.

use std::path::{Path, PathBuf};
use std::process::Output;

use weft_mesh::export::gltf::read_glb;
use weft_mesh::export::mdd::read_mdd;
use weft_mesh::export::npy::write_npy;
use weft_mesh::export::obj_sequence::read_obj_sequence;
use weft_mesh::export::pc2::read_pc2;
use weft_mesh::export::Frames;
use weft_mesh::io::write_obj;
use weft_mesh::primitives::{cylinder, grid};

mod common;
use common::{s, scratch, stderr, stdout, weft};

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A 6-vertex template and 4 frames of it as `frames.npy`; returns (template, frames).
fn setup(dir: &Path) -> (PathBuf, PathBuf, Frames) {
    let mesh = grid(3, 2, 0.5);
    let template = dir.join("g.obj");
    write_obj(&template, &mesh).unwrap();
    let mut frames = Frames::with_vertex_count(mesh.vertex_count()).unwrap();
    for k in 0..4 {
        let p: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .map(|p| [p[0], p[1] + 0.1 * k as f64 * p[0], p[2] - 0.01 * k as f64])
            .collect();
        frames.push_frame_f64(&p).unwrap();
    }
    let npy = dir.join("frames.npy");
    frames.write_npy(&npy).unwrap();
    (template, npy, frames)
}

/// `weft export --frames FRAMES --faces TEMPLATE --format FORMAT --out OUT EXTRA…`.
fn export(frames: &Path, template: &Path, format: &str, out: &Path, extra: &[&str]) -> Output {
    let mut a = vec!["export", "--frames", s(frames), "--faces", s(template)];
    a.extend_from_slice(&["--format", format, "--out", s(out)]);
    a.extend_from_slice(extra);
    weft(&a)
}

/// One line on stderr starting `error:`, exit status 1, and the line contains `needle`.
fn assert_one_line_error(o: &Output, needle: &str) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.starts_with("error: "), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains(needle), "expected `{needle}` in: {e}");
}

#[test]
fn every_format_round_trips() {
    let dir = scratch("round_trip");
    let (template, npy, frames) = setup(&dir);
    for (format, out) in [
        ("obj", "seq"),
        ("pc2", "a.pc2"),
        ("mdd", "a.mdd"),
        ("glb", "a.glb"),
        ("usd", "a.usda"),
    ] {
        let out = dir.join(out);
        let o = export(&npy, &template, format, &out, &["--fps", "25", "--json"]);
        assert!(o.status.success(), "{format}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(
            (v["frames"].as_u64(), v["vertices"].as_u64()),
            (Some(4), Some(6))
        );
        assert!(v["bytes"].as_u64().unwrap() > 0);
        match format {
            "obj" => assert_eq!(read_obj_sequence(&out).unwrap(), frames),
            "pc2" => assert_eq!(read_pc2(&out).unwrap().frames, frames),
            "mdd" => {
                let m = read_mdd(&out).unwrap();
                assert_eq!(m.frames, frames);
                assert_eq!(m.times[1], 0.04);
            }
            "usd" => {
                let text = std::fs::read_to_string(&out).unwrap();
                assert!(text.contains("timeCodesPerSecond = 25\n"), "{text}");
                assert!(text.contains("point3f[] points.timeSamples = {"), "{text}");
                assert!(
                    !text.contains("primvars:st"),
                    "the template has no UVs: {text}"
                );
            }
            _ => {
                let g = read_glb(&out).unwrap();
                let back = &g.meshes[0].frames;
                assert_eq!(back.frame_count(), 4);
                for (a, b) in back.as_flat().iter().zip(frames.as_flat()) {
                    assert!((a - b).abs() < 1e-6, "{a} vs {b}");
                }
            }
        }
    }
    // The OBJ sequence reads back as frames for another export.
    let again = dir.join("again.pc2");
    let o = weft(&[
        "export",
        "--frames",
        s(&dir.join("seq")),
        "--faces",
        s(&template),
        "--format",
        "pc2",
        "--out",
        s(&again),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.starts_with("wrote 4 frames × 6 vertices as PC2 to "),
        "{text}"
    );
    assert_eq!(read_pc2(&again).unwrap().frames, frames);
}

#[test]
fn glb_with_a_body() {
    let dir = scratch("body");
    let (template, npy, _) = setup(&dir);
    let body = dir.join("body.obj");
    write_obj(&body, &cylinder(3, 5, 0.2, 0.1)).unwrap();
    let out = dir.join("scene.glb");
    let o = weft(&[
        "export",
        "--frames",
        s(&npy),
        "--faces",
        s(&template),
        "--format",
        "glb",
        "--out",
        s(&out),
        "--body",
        s(&body),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let g = read_glb(&out).unwrap();
    let names: Vec<&str> = g.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["garment", "body"]);
    assert_eq!(g.meshes[1].frames.frame_count(), 1);

    // A body animated with a different frame count is refused.
    let mut bf = Frames::with_vertex_count(15).unwrap();
    bf.push_frame(&[[0.0; 3]; 15]).unwrap();
    bf.push_frame(&[[0.0; 3]; 15]).unwrap();
    let bnpy = dir.join("body.npy");
    bf.write_npy(&bnpy).unwrap();
    let bad = dir.join("bad.glb");
    let o = weft(&[
        "export",
        "--frames",
        s(&npy),
        "--faces",
        s(&template),
        "--format",
        "glb",
        "--out",
        s(&bad),
        "--body",
        s(&body),
        "--body-frames",
        s(&bnpy),
    ]);
    assert_one_line_error(&o, "mesh `body` has 2 frames but `garment` has 4");
    assert!(!bad.exists());

    let o = weft(&[
        "export",
        "--frames",
        s(&npy),
        "--faces",
        s(&template),
        "--format",
        "pc2",
        "--out",
        s(&dir.join("x.pc2")),
        "--body",
        s(&body),
    ]);
    assert_one_line_error(&o, "apply to --format glb and usd only");
}

/// Issue 18: every export keeps the template's UVs (obj, glb, usd); the point caches
/// apply to the template, which keeps its own.
#[test]
fn the_templates_uvs_go_into_obj_glb_and_usd() {
    let dir = scratch("uvs");
    let (_, npy, frames) = setup(&dir);
    // The grid's 6 vertices with a seam: the second column's UVs differ per quad.
    let template = dir.join("uv.obj");
    std::fs::write(
        &template,
        "v 0 0 0\nv 0.5 0 0\nv 1 0 0\nv 0 0 0.5\nv 0.5 0 0.5\nv 1 0 0.5\n\
         vt 0 0\nvt 0.5 0\nvt 0 1\nvt 0.5 1\nvt 2 0\nvt 3 0\nvt 2 1\nvt 3 1\n\
         f 1/1 4/3 5/4\nf 1/1 5/4 2/2\nf 2/5 5/7 6/8\nf 2/5 6/8 3/6\n",
    )
    .unwrap();
    let uvs = weft_mesh::io::load_obj(&template)
        .unwrap()
        .corner_uvs
        .unwrap();
    for (format, out) in [("obj", "seq"), ("glb", "a.glb"), ("usd", "a.usda")] {
        let out = dir.join(out);
        let o = export(&npy, &template, format, &out, &["--json"]);
        assert!(o.status.success(), "{format}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["uvs"], true, "{format}");
        match format {
            "obj" => {
                let r = weft_mesh::io::load_obj(&out.join("frame_00003.obj")).unwrap();
                assert_eq!(r.corner_uvs.unwrap(), uvs);
                assert_eq!(read_obj_sequence(&out).unwrap(), frames);
            }
            "glb" => {
                let g = read_glb(&out).unwrap();
                // Vertices 1 and 4 sit on the seam: 6 + 2 glTF vertices.
                assert_eq!(g.meshes[0].frames.vertex_count(), 8);
                let t = g.meshes[0].texcoords.as_ref().unwrap();
                let corner = g.meshes[0].faces[2][0] as usize;
                assert_eq!(t[corner], [2.0, 1.0]); // (2, 0) with V flipped
            }
            _ => {
                let text = std::fs::read_to_string(&out).unwrap();
                assert!(
                    text.contains(
                        "int[] primvars:st:indices = [0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7]"
                    ),
                    "{text}"
                );
            }
        }
    }
}

#[test]
fn bad_input_is_one_line_and_leaves_nothing() {
    let dir = scratch("bad");
    let (template, npy, _) = setup(&dir);
    let out_dir = dir.join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let out = out_dir.join("a.pc2");
    let run = |frames: &Path, format: &str, out: &Path, fps: &str| {
        weft(&[
            "export",
            "--frames",
            s(frames),
            "--faces",
            s(&template),
            "--format",
            format,
            "--fps",
            fps,
            "--out",
            s(out),
        ])
    };

    // Vertex count mismatch names both files and both counts.
    let other = dir.join("other.npy");
    write_npy(&other, &[2, 5, 3], &[0.0f32; 30]).unwrap();
    let o = run(&other, "pc2", &out, "30");
    assert_one_line_error(&o, "has 5 vertices per frame but the template");
    let e = stderr(&o);
    assert!(e.contains("other.npy") && e.contains("g.obj has 6"), "{e}");

    // NaN: frame and vertex named, nothing written.
    let mut v = vec![0.0f32; 2 * 6 * 3];
    v[(6 + 4) * 3 + 1] = f32::NAN;
    let nan = dir.join("nan.npy");
    write_npy(&nan, &[2, 6, 3], &v).unwrap();
    for format in ["obj", "pc2", "mdd", "glb", "usd"] {
        let o = run(&nan, format, &out, "30");
        assert_one_line_error(&o, "frame 1, vertex 4: the y coordinate is NaN");
    }

    // Unknown format, bad fps.
    assert_one_line_error(
        &run(&npy, "fbx", &out, "30"),
        "unknown export format `fbx`; expected one of obj, pc2, mdd, glb, usd",
    );
    assert_one_line_error(
        &run(&npy, "usd", &out_dir.join("a.usdc"), "30"),
        "weft writes USD as text (.usda or .usd)",
    );
    assert_one_line_error(
        &run(&npy, "pc2", &out, "0"),
        "frame rate 0 is not a positive",
    );

    // Missing parent directories are created (issue 17 item 12).
    let o = run(&npy, "glb", &dir.join("no/such/dir/a.glb"), "30");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.join("no/such/dir/a.glb").is_file());
    let o = run(&npy, "obj", &dir.join("new/parent/seq"), "30");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.join("new/parent/seq/frame_00000.obj").is_file());

    // Unwritable outputs: a path under a file.
    let o = run(&npy, "mdd", &template.join("a.mdd"), "30");
    assert_one_line_error(&o, "cannot write ");
    assert_eq!(stderr(&o).matches("os error").count(), 1, "{}", stderr(&o));
    let o = run(&npy, "obj", &template.join("seq"), "30");
    assert_one_line_error(&o, "cannot write ");

    // An OBJ sequence never replaces a directory of other files.
    let o = run(&npy, "obj", &dir, "30");
    assert_one_line_error(&o, "which is not a frame of a previous export");

    // Broken frame inputs.
    std::fs::write(dir.join("junk.npy"), b"not numpy").unwrap();
    assert_one_line_error(
        &run(&dir.join("junk.npy"), "pc2", &out, "30"),
        "not a .npy file",
    );
    let o = run(&dir.join("missing.npy"), "pc2", &out, "30");
    assert_one_line_error(&o, "cannot read ");
    assert_eq!(stderr(&o).matches("os error").count(), 1, "{}", stderr(&o));
    let o = weft(&[
        "export",
        "--frames",
        s(&npy),
        "--faces",
        s(&dir.join("missing.obj")),
        "--format",
        "pc2",
        "--out",
        s(&out),
    ]);
    assert_one_line_error(&o, "missing.obj: ");
    assert_eq!(stderr(&o).matches("os error").count(), 1, "{}", stderr(&o));

    assert!(entries(&out_dir).is_empty(), "{:?}", entries(&out_dir));
}
