//! End-to-end tests of `weft render` through the real binary.

use std::path::{Path, PathBuf};

use weft_mesh::io::write_obj;
use weft_mesh::primitives::cylinder;

mod common;
use common::{s, scratch, stderr, stdout, weft};

/// A 1-D little-endian float32 `.npy` file.
fn write_npy_f32(path: &Path, values: &[f32]) {
    write_npy_f32_shaped(path, &format!("({},)", values.len()), values);
}

/// A little-endian float32 `.npy` file of the given shape (a Python tuple).
fn write_npy_f32_shaped(path: &Path, shape: &str, values: &[f32]) {
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).expect("write npy");
}

/// garment.obj (a 20 × 40 tube, 800 vertices) and body.obj (a thinner tube) in `dir`.
fn meshes(dir: &Path) -> (PathBuf, PathBuf) {
    let g = dir.join("garment.obj");
    let b = dir.join("body.obj");
    write_obj(&g, &cylinder(20, 40, 0.3, 0.03)).expect("write garment");
    write_obj(&b, &cylinder(20, 40, 0.2, 0.03)).expect("write body");
    (g, b)
}

fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).expect("png written");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    (w, h)
}

#[test]
fn renders_a_garment_over_a_body_coloured_by_values() {
    let dir = scratch("render_color");
    let (g, b) = meshes(&dir);
    let npy = dir.join("error_mm.npy");
    write_npy_f32(&npy, &(0..800).map(|i| i as f32 * 0.01).collect::<Vec<_>>());
    let out = dir.join("out.png");
    let o = weft(&[
        "render",
        s(&g),
        "--body",
        s(&b),
        "--color-by",
        s(&npy),
        "--size",
        "256",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(png_size(&out), (256, 256));
    let text = stdout(&o);
    assert!(
        text.contains("wrote") && text.contains("800 vertices"),
        "{text}"
    );
    assert!(text.contains("viridis, 0 to 7.99"), "{text}");
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    // Same input, same bytes.
    let first = std::fs::read(&out).unwrap();
    let o = weft(&[
        "render",
        s(&g),
        "--body",
        s(&b),
        "--color-by",
        s(&npy),
        "--size",
        "256",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success());
    assert_eq!(std::fs::read(&out).unwrap(), first);
}

#[test]
fn the_default_body_is_built_in() {
    let dir = scratch("render_default_body");
    let (g, _) = meshes(&dir);
    let out = dir.join("out.png");
    let o = weft(&[
        "render",
        s(&g),
        "--default-body",
        "--camera",
        "front",
        "--size",
        "128",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("over the default body"),
        "{}",
        stdout(&o)
    );
    assert_eq!(png_size(&out), (128, 128));
}

#[test]
fn a_count_mismatch_names_both_files_and_writes_nothing() {
    let dir = scratch("render_mismatch");
    let (g, _) = meshes(&dir);
    let npy = dir.join("short.npy");
    write_npy_f32(&npy, &[1.0; 799]);
    let out = dir.join("out.png");
    let o = weft(&["render", s(&g), "--color-by", s(&npy), "--out", s(&out)]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("short.npy holds 799 values"), "{err}");
    assert!(err.contains("garment.obj has 800 vertices"), "{err}");
    assert!(!out.exists());
}

#[test]
fn nan_values_are_drawn_and_reported_as_a_warning() {
    let dir = scratch("render_nan");
    let (g, _) = meshes(&dir);
    let npy = dir.join("err.npy");
    let mut v = vec![1.0f32; 800];
    v[10] = f32::NAN;
    v[11] = f32::INFINITY;
    write_npy_f32(&npy, &v);
    let out = dir.join("out.png");
    let o = weft(&[
        "render",
        s(&g),
        "--color-by",
        s(&npy),
        "--size",
        "128",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.starts_with("warning: "), "{err}");
    assert!(
        err.contains("2 values of") && err.contains("magenta"),
        "{err}"
    );
    assert!(out.exists());
}

#[test]
fn unwritable_output_is_one_clear_line_and_no_file() {
    let dir = scratch("render_unwritable");
    let (g, _) = meshes(&dir);
    // Missing parents are created (issue 17 item 12); a parent that is a file is not.
    let out = g.join("out.png");
    let o = weft(&["render", s(&g), "--size", "64", "--out", s(&out)]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("cannot write the picture") && err.contains("out.png"),
        "{err}"
    );
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 2, "{leftovers:?}");
    // A non-PNG output name is refused before anything is drawn.
    let o = weft(&["render", s(&g), "--out", s(&dir.join("x.jpg"))]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("must be a .png file"), "{}", stderr(&o));
}

#[test]
fn bad_inputs_are_one_line_errors() {
    let dir = scratch("render_bad");
    let (g, _) = meshes(&dir);
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec![s(&dir.join("missing.obj")).into()], "missing.obj"),
        (
            vec![s(&g).into(), "--color-by".into(), s(&g).into()],
            "not a .npy file",
        ),
        (
            vec![s(&g).into(), "--range".into(), "5:1".into()],
            "expected MIN:MAX",
        ),
        (
            vec![s(&g).into(), "--animate".into()],
            "needs a directory of frames",
        ),
    ];
    for (args, expect) in cases {
        let mut all = vec!["render".to_string()];
        all.extend(args);
        all.extend(["--out".into(), s(&dir.join("o.png")).into()]);
        let refs: Vec<&str> = all.iter().map(String::as_str).collect();
        let o = weft(&refs);
        assert!(!o.status.success(), "{all:?}");
        let err = stderr(&o);
        assert!(err.contains(expect), "{all:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let o = weft(&["render", s(&empty), "--out", s(&dir.join("o.png"))]);
    assert!(
        stderr(&o).contains("no .obj or .ply files"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_directory_becomes_a_contact_sheet_or_an_animation() {
    let dir = scratch("render_dir");
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    for f in 0..4 {
        let mut m = cylinder(10, 30, 0.3, 0.05);
        for p in &mut m.positions {
            p[0] += 0.05 * f64::from(f);
        }
        write_obj(&frames.join(format!("frame_{f}.obj")), &m).unwrap();
    }
    std::fs::write(frames.join("notes.txt"), "not a frame").unwrap();
    let out = dir.join("sheet.png");
    let o = weft(&[
        "render",
        s(&frames),
        "--camera",
        "front",
        "--size",
        "256",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("4 frames"), "{}", stdout(&o));
    assert_eq!(png_size(&out), (256, 256));
    let anim = dir.join("anim.png");
    let o = weft(&[
        "render",
        s(&frames),
        "--animate",
        "--size",
        "96",
        "--out",
        s(&anim),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&anim).unwrap();
    assert_eq!(bytes.windows(4).filter(|w| w == b"fcTL").count(), 4);
    let o = weft(&[
        "render",
        s(&frames),
        "--camera",
        "turntable",
        "--out",
        s(&out),
    ]);
    assert!(stderr(&o).contains("turntable"), "{}", stderr(&o));
}

#[test]
fn turntable_of_one_mesh() {
    let dir = scratch("render_turntable");
    let (g, _) = meshes(&dir);
    let out = dir.join("tt.png");
    let o = weft(&[
        "render",
        s(&g),
        "--camera",
        "turntable",
        "--views",
        "4",
        "--size",
        "512",
        "--shading",
        "flat",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(png_size(&out), (512, 128));
}
