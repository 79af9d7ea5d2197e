//! `weft garment resize | drape | prepare` end to end on small garments and the
//! default body: outputs written, UVs kept, weights shaped and normalised, reports
//! consistent, bad input one line of error.

use std::path::Path;

mod common;
use common::{garment, s, scratch, stderr, stdout, weft};

fn ok(args: &[&str]) -> String {
    let out = weft(args);
    assert!(
        out.status.success(),
        "weft {args:?} failed: {}",
        stderr(&out)
    );
    stdout(&out)
}

fn fails(args: &[&str]) -> String {
    let out = weft(args);
    assert!(!out.status.success(), "weft {args:?} should fail");
    let err = stderr(&out);
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// `name` in the scratch directory `dir`, as a command-line argument.
fn file(dir: &Path, name: &str) -> String {
    s(&dir.join(name)).to_owned()
}

fn vt_lines(path: &str) -> Vec<String> {
    std::fs::read_to_string(path)
        .expect("read obj")
        .lines()
        .filter(|l| l.starts_with("vt ") || l.starts_with("f "))
        .map(str::to_owned)
        .collect()
}

fn json(path: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("report")).expect("json")
}

#[test]
fn resize_then_prepare_with_weights() {
    let d = scratch("resize");
    let (g, r, p, w, rep) = (
        file(&d, "g.obj"),
        file(&d, "r.obj"),
        file(&d, "p.obj"),
        file(&d, "w.npy"),
        file(&d, "report.json"),
    );
    garment(Path::new(&g), "tshirt", 400, 0);
    let out = ok(&[
        "garment",
        "resize",
        "--garment",
        &g,
        "--to-betas",
        "1.5,-1",
        "--out",
        &r,
        "--report",
        &rep,
    ]);
    assert!(
        out.contains("resize: moved") && out.contains("wrote"),
        "{out}"
    );
    // Only positions change: UVs and faces are the input's, byte for byte.
    assert_eq!(vt_lines(&g), vt_lines(&r));
    let report = json(&rep);
    assert_eq!(report["resize"]["inside_after"], 0, "{report}");
    assert!(report["resize"]["mean_displacement_m"].as_f64().unwrap() > 0.005);

    // Back to β = 0, draped for a few frames, with weights.
    let out = ok(&[
        "garment",
        "prepare",
        "--garment",
        &r,
        "--from-betas",
        "1.5,-1",
        "--frames",
        "3",
        "--out",
        &p,
        "--weights",
        &w,
        "--report",
        &rep,
    ]);
    assert!(
        out.contains("resize:") && out.contains("drape: 3 frames"),
        "{out}"
    );
    let report = json(&rep);
    assert_eq!(report["drape"]["frames"], 3);
    assert_eq!(
        report["drape"]["deeper_than_threshold_after"], 0,
        "{report}"
    );
    let mesh = weft_mesh::io::read_mesh(Path::new(&p)).expect("prepared mesh");
    let npy = weft_mesh::export::npy::read_npy(Path::new(&w)).expect("weights");
    assert_eq!(npy.shape, vec![mesh.vertex_count(), 24]);
    let weft_mesh::export::npy::NpyData::F32(data) = npy.data else {
        panic!("weights are not float32")
    };
    for row in data.chunks(24) {
        let s: f32 = row.iter().sum();
        assert!(
            (s - 1.0).abs() < 1e-4 && row.iter().all(|&x| x >= 0.0),
            "{row:?}"
        );
    }
}

#[test]
fn drape_writes_ply_and_reports() {
    let d = scratch("drape");
    let (g, out_ply, rep) = (file(&d, "g.obj"), file(&d, "d.ply"), file(&d, "d.json"));
    garment(Path::new(&g), "skirt", 300, 0);
    let out = ok(&[
        "garment",
        "drape",
        "--garment",
        &g,
        "--frames",
        "2",
        "--material",
        "silk",
        "--out",
        &out_ply,
        "--report",
        &rep,
    ]);
    assert!(out.contains("drape: 2 frames"), "{out}");
    let a = weft_mesh::io::read_mesh(Path::new(&g)).unwrap();
    let b = weft_mesh::io::read_mesh(Path::new(&out_ply)).unwrap();
    assert_eq!(a.faces, b.faces);
    assert!(json(&rep)["drape"]["pinned"].as_u64().unwrap() > 0);
}

#[test]
fn bad_input_is_one_line_of_error() {
    let d = scratch("bad");
    let g = file(&d, "g.obj");
    garment(Path::new(&g), "skirt", 300, 0);
    let out = file(&d, "o.obj");
    let e = fails(&[
        "garment",
        "drape",
        "--garment",
        &g,
        "--material",
        "tweed",
        "--out",
        &out,
    ]);
    assert!(e.contains("tweed"), "{e}");
    let e = fails(&[
        "garment",
        "resize",
        "--garment",
        &g,
        "--to-betas",
        "1,x",
        "--out",
        &out,
    ]);
    assert!(e.contains("--to-betas"), "{e}");
    let e = fails(&[
        "garment",
        "drape",
        "--garment",
        &g,
        "--frames",
        "0",
        "--out",
        &out,
    ]);
    assert!(e.contains("--frames 0"), "{e}");
    let e = fails(&[
        "garment",
        "resize",
        "--garment",
        &file(&d, "missing.obj"),
        "--to-betas",
        "1",
        "--out",
        &out,
    ]);
    assert!(e.contains("missing.obj"), "{e}");
    assert!(!Path::new(&out).exists());
}

/// Issue 17 item 12: when the weights cannot be written, no prepared mesh is left.
#[test]
fn prepare_writes_nothing_when_the_weights_fail() {
    let d = scratch("prepare_all_or_nothing");
    let g = file(&d, "g.obj");
    garment(Path::new(&g), "skirt", 300, 0);
    let out = file(&d, "prepared.obj");
    let report = file(&d, "report.json");
    // The weights' parent is a file: the write fails after the mesh is computed.
    let e = fails(&[
        "garment",
        "prepare",
        "--garment",
        &g,
        "--no-drape",
        "--out",
        &out,
        "--report",
        &report,
        "--weights",
        &format!("{g}/w.npy"),
    ]);
    assert!(e.contains("w.npy"), "{e}");
    assert!(!Path::new(&out).exists(), "a mesh without its weights");
    assert!(!Path::new(&report).exists());
}

/// `weft garment generate --open-front N --buttons PAIRS.json`: the top comes out cut
/// down the front (more vertices, the same faces and UVs), with N button pairs of
/// distinct, in-range vertices at the same position; either flag alone is refused.
#[test]
fn generate_opens_a_top_down_the_front() {
    let dir = scratch("open-front");
    let (closed, open, pairs) = (
        file(&dir, "closed.obj"),
        file(&dir, "open.obj"),
        file(&dir, "pairs.json"),
    );
    let base = [
        "garment",
        "generate",
        "--kind",
        "tshirt",
        "--vertices",
        "800",
    ];
    ok(&[&base[..], &["--out", &closed]].concat());
    let said = ok(&[
        &base[..],
        &["--out", &open, "--open-front", "4", "--buttons", &pairs],
    ]
    .concat());
    assert!(said.contains("4 button pairs"), "{said}");
    let a = weft_mesh::io::load_obj(Path::new(&closed)).unwrap();
    let b = weft_mesh::io::load_obj(Path::new(&open)).unwrap();
    assert!(b.mesh.vertex_count() > a.mesh.vertex_count());
    assert_eq!(b.mesh.face_count(), a.mesh.face_count());
    assert_eq!(b.corner_uvs, a.corner_uvs);
    let list: Vec<[u32; 2]> =
        serde_json::from_str(&std::fs::read_to_string(&pairs).unwrap()).unwrap();
    assert_eq!(list.len(), 4);
    for [p, q] in list {
        assert!(p != q && (q as usize) < b.mesh.vertex_count());
        assert_eq!(b.mesh.positions[p as usize], b.mesh.positions[q as usize]);
    }
    // Buttons that cannot be written (their directory is a file) take the garment back.
    let blocked = file(&dir, "blocked.obj");
    let e = fails(
        &[
            &base[..],
            &[
                "--out",
                &blocked,
                "--open-front",
                "4",
                "--buttons",
                &format!("{closed}/pairs.json"),
            ],
        ]
        .concat(),
    );
    assert!(e.contains("--buttons"), "{e}");
    assert!(!Path::new(&blocked).exists());
    let e = fails(&[&base[..], &["--out", &open, "--open-front", "4"]].concat());
    assert!(e.contains("--buttons"), "{e}");
    let e = fails(&[&base[..], &["--out", &open, "--buttons", &pairs]].concat());
    assert!(e.contains("--open-front"), "{e}");
}
