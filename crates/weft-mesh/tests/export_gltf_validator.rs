//! The `.glb` files weft writes pass the Khronos glTF validator with no errors.
//!
//! Runs `node tools/gltf-validator/validate.js` (the npm package `gltf-validator`, pinned
//! in `tools/gltf-validator/package-lock.json`; install it with
//! `npm ci --prefix tools/gltf-validator`). When `node` or the package is missing the test
//! prints why and passes, so a machine without Node still runs the rest of the suite.

use std::path::{Path, PathBuf};
use std::process::Command;

use weft_mesh::export::gltf::{write_glb, GlbMesh, GlbOptions, BODY_COLOR, GARMENT_COLOR};
use weft_mesh::export::Frames;
use weft_mesh::primitives::{builtin_garment, cylinder};
use weft_mesh::TriMesh;

fn validator() -> Option<(PathBuf, PathBuf)> {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/gltf-validator");
    let script = tools.join("validate.js");
    let package = tools.join("node_modules/gltf-validator/package.json");
    let node_ok = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !node_ok {
        eprintln!("SKIPPED glTF validation: `node` is not on PATH (install Node.js to run it)");
        return None;
    }
    if !package.is_file() {
        eprintln!(
            "SKIPPED glTF validation: the validator is not installed; run `npm ci --prefix {}`",
            tools.display()
        );
        return None;
    }
    Some((PathBuf::from("node"), script))
}

fn frames_of(mesh: &TriMesh, t: usize, amplitude: f64) -> Frames {
    let mut f = Frames::with_vertex_count(mesh.vertex_count()).unwrap();
    for k in 0..t {
        let phase = k as f64 * 0.2;
        let p: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .map(|p| {
                let s = 1.0 + amplitude * (phase + 8.0 * p[1]).sin();
                [p[0] * s, p[1] + 0.01 * phase.sin(), p[2] * s]
            })
            .collect();
        f.push_frame_f64(&p).unwrap();
    }
    f
}

fn validate(node: &Path, script: &Path, glb: &Path) {
    let out = Command::new(node)
        .arg(script)
        .arg(glb)
        .output()
        .expect("run node");
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "the glTF validator found errors in {}",
        glb.display()
    );
    assert!(text.contains(" 0 errors, 0 warnings"), "{text}");
}

#[test]
fn glb_files_pass_the_khronos_validator() {
    let Some((node, script)) = validator() else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("weft-gltf-validator-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    // The built-in garment animated over 24 frames, over a body animated with it.
    let garment = builtin_garment();
    let body = cylinder(30, 40, 0.25, 0.05);
    let gf = frames_of(&garment, 24, 0.05);
    let bf = frames_of(&body, 24, 0.01);
    let both = dir.join("garment_body.glb");
    write_glb(
        &both,
        &[
            GlbMesh {
                name: "garment",
                faces: &garment.faces,
                frames: &gf,
                color: GARMENT_COLOR,
            },
            GlbMesh {
                name: "body",
                faces: &body.faces,
                frames: &bf,
                color: BODY_COLOR,
            },
        ],
        GlbOptions {
            fps: 30.0,
            normals: true,
        },
    )
    .unwrap();
    validate(&node, &script, &both);

    // Without normals, with a static body, and a single static frame.
    let still = frames_of(&body, 1, 0.0);
    let variants = dir.join("static_body.glb");
    write_glb(
        &variants,
        &[
            GlbMesh {
                name: "garment",
                faces: &garment.faces,
                frames: &gf,
                color: GARMENT_COLOR,
            },
            GlbMesh {
                name: "body",
                faces: &body.faces,
                frames: &still,
                color: BODY_COLOR,
            },
        ],
        GlbOptions {
            fps: 24.0,
            normals: false,
        },
    )
    .unwrap();
    validate(&node, &script, &variants);
    let single = dir.join("single.glb");
    write_glb(
        &single,
        &[GlbMesh {
            name: "body",
            faces: &body.faces,
            frames: &still,
            color: BODY_COLOR,
        }],
        GlbOptions::default(),
    )
    .unwrap();
    validate(&node, &script, &single);

    let _ = std::fs::remove_dir_all(&dir);
}
