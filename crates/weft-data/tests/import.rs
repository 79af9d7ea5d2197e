//! `weft data import`: a user's caches become a dataset the loader reads like a
//! generated one, with units and axes converted, and bad input refused naming the file.

use std::path::{Path, PathBuf};

use weft_data::{import, Dataset, Split};
use weft_garment::{FitBody, GarmentKind, Style};
use weft_mesh::export::{write_mdd, write_pc2, Frames, Pc2Timing};
use weft_motion::{
    body_rest_joints, generate, write_motion, MotionFileOptions, MotionKind, ProceduralParams,
};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("weft-import-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A skirt on the default body (with UVs), a 12-frame walk as .npz, and a cache of the
/// skirt riding along with the walk's root translation: `f(k, p)` is frame k's vertex.
struct Fixture {
    dir: PathBuf,
    rest: Vec<[f64; 3]>,
    uvs: Vec<[[f64; 2]; 3]>,
    frames: Frames,
    trans: Vec<[f32; 3]>,
}

fn fixture(name: &str) -> Fixture {
    let dir = scratch(name);
    let body = weft_body::default_body().unwrap();
    let fit = FitBody::new(&body, &[]).unwrap();
    let skirt = fit
        .generate(
            GarmentKind::Skirt,
            &Style::from_seed(GarmentKind::Skirt, 1),
            400,
        )
        .unwrap();
    weft_garment::obj::write_obj(&dir.join("skirt.obj"), &skirt).unwrap();
    let mut p = ProceduralParams::new(MotionKind::Walk);
    p.frames = 12;
    let walk = generate(&p).unwrap();
    // Written as `weft motion generate` writes it: against the body's own rest joints.
    let rest = body_rest_joints(&body, &[]).unwrap();
    let options = MotionFileOptions::for_body(rest, None);
    write_motion(&dir.join("walk.npz"), &walk, &options).unwrap();
    let mut frames = Frames::with_vertex_count(skirt.mesh.vertex_count()).unwrap();
    for t in walk.trans() {
        let moved: Vec<[f64; 3]> = skirt
            .mesh
            .positions
            .iter()
            .map(|q| [0, 1, 2].map(|k| q[k] + f64::from(t[k] - walk.trans()[0][k])))
            .collect();
        frames.push_frame_f64(&moved).unwrap();
    }
    Fixture {
        rest: skirt.mesh.positions.clone(),
        uvs: skirt.corner_uvs.clone(),
        frames,
        trans: walk.trans().to_vec(),
        dir,
    }
}

fn spec(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("import.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn caches_become_a_dataset_the_loader_reads() {
    let f = fixture("ok");
    write_pc2(&f.dir.join("walk.pc2"), &f.frames, Pc2Timing::default()).unwrap();
    write_mdd(&f.dir.join("walk.mdd"), &f.frames, 30.0).unwrap();
    f.frames.write_npy(&f.dir.join("walk.npy")).unwrap();
    let s = spec(
        &f.dir,
        r#"
fps = 30
[[garments]]
id = "skirt"
template = "skirt.obj"
kind = "skirt"

[[sequences]]
garment = "skirt"
cache = "walk.pc2"
motion = "walk.npz"
split = "train"

[[sequences]]
garment = "skirt"
cache = "walk.mdd"
motion = "walk.npz"
split = "train"
start = 2
"#,
    );
    // Frame 0 with `start = 2` is motion frame 2: a 12-frame walk holds 10 from there,
    // the cache has 12.
    let out = f.dir.join("data");
    let e = import(&s, &out).unwrap_err().to_string();
    assert!(
        e.contains("walk.npz: 10 frames at 30 fps from frame 2 on") && e.contains("has 12"),
        "{e}"
    );
    assert!(!out.exists(), "a failed import left {}", out.display());
    let leftovers: Vec<_> = std::fs::read_dir(&f.dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");

    let text = std::fs::read_to_string(&s)
        .unwrap()
        .replace("start = 2", "split = \"test\"")
        .replace(
            "walk.mdd\"\nmotion = \"walk.npz\"\nsplit = \"train\"",
            "walk.mdd\"\nmotion = \"walk.npz\"",
        );
    std::fs::write(&s, text).unwrap();
    let e = import(&s, &out).unwrap_err().to_string();
    assert!(e.contains("garment \"skirt\" is in train and test"), "{e}");

    let s = spec(
        &f.dir,
        r#"
fps = 30
[[garments]]
id = "skirt"
template = "skirt.obj"
[[garments]]
id = "skirt_b"
template = "skirt.obj"

[[sequences]]
garment = "skirt"
cache = "walk.pc2"
motion = "walk.npz"
split = "train"

[[sequences]]
garment = "skirt"
cache = "walk.npy"
motion = "walk.npz"
split = "train"

[[sequences]]
garment = "skirt_b"
cache = "walk.mdd"
motion = "walk.npz"
split = "test"
"#,
    );
    let report = import(&s, &out).unwrap();
    assert_eq!(report.sequences, [2, 0, 1]);
    assert_eq!(report.frames, 36);
    assert!(report.flattened.is_empty());

    let ds = Dataset::open(&out).unwrap();
    let train: Vec<_> = ds.records_in(Split::Train).into_iter().cloned().collect();
    assert_eq!(train.len(), 2);
    assert_ne!(train[0].id, train[1].id);
    let test: Vec<_> = ds.records_in(Split::Test).into_iter().cloned().collect();
    let seq = ds.load_verified(&test[0]).unwrap();
    assert_eq!(seq.positions.len(), 12);
    assert_eq!(seq.positions[5], f.frames.frame(5).unwrap());
    for (a, b) in seq.trans.iter().zip(&f.trans) {
        assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-6), "{a:?} vs {b:?}");
    }
    let uvs: Vec<[[f32; 2]; 3]> = f
        .uvs
        .iter()
        .map(|t| t.map(|uv| uv.map(|x| x as f32)))
        .collect();
    assert_eq!(seq.corner_uvs, uvs);
    assert_eq!(seq.garment.positions[7], f.rest[7].map(|c| c as f32 as f64));
    assert!(ds.garment("skirt_b").is_ok());
}

#[test]
fn units_axes_and_flat_uvs_are_converted() {
    let f = fixture("units");
    // The same skirt in centimetres, Z up (x, y, z) -> (x, -z, y), without UVs.
    let to_z_cm = |p: [f64; 3]| [p[0] * 100.0, -p[2] * 100.0, p[1] * 100.0];
    let mesh = weft_mesh::TriMesh::new(
        f.rest.iter().map(|&p| to_z_cm(p)).collect(),
        weft_mesh::io::read_mesh(&f.dir.join("skirt.obj"))
            .unwrap()
            .faces,
    );
    weft_mesh::io::write_obj(&f.dir.join("skirt_cm.obj"), &mesh).unwrap();
    let mut cm = Frames::with_vertex_count(f.frames.vertex_count()).unwrap();
    for frame in f.frames.iter() {
        let p: Vec<[f64; 3]> = frame.iter().map(|q| to_z_cm(q.map(f64::from))).collect();
        cm.push_frame_f64(&p).unwrap();
    }
    write_pc2(&f.dir.join("walk_cm.pc2"), &cm, Pc2Timing::default()).unwrap();
    let body = r#"
[[garments]]
id = "skirt"
template = "skirt_cm.obj"
[[sequences]]
garment = "skirt"
cache = "walk_cm.pc2"
motion = "walk.npz"
split = "train"
"#;
    // Without the conversion the skirt is metres away from the body: refused.
    let s = spec(&f.dir, &format!("fps = 30\n{body}"));
    let e = import(&s, &f.dir.join("bad")).unwrap_err().to_string();
    assert!(
        e.contains("walk_cm.pc2: frame 0 is") && e.contains("check `scale`, `up`"),
        "{e}"
    );

    let s = spec(
        &f.dir,
        &format!("fps = 30\nscale = 0.01\nup = \"z\"\n{body}"),
    );
    let out = f.dir.join("data");
    let report = import(&s, &out).unwrap();
    assert_eq!(report.flattened, vec!["skirt".to_owned()]);
    let ds = Dataset::open(&out).unwrap();
    let r = ds.records_in(Split::Train)[0].clone();
    let seq = ds.load(&r).unwrap();
    for (a, b) in seq.positions[3].iter().zip(f.frames.frame(3).unwrap()) {
        assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-5), "{a:?} vs {b:?}");
    }
    // Flattened triangles keep their 3D edge lengths.
    let p = |i: u32| seq.garment.positions[i as usize];
    for (f3, uv) in seq.garment.faces.iter().zip(&seq.corner_uvs).take(50) {
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            let d3 = weft_mesh::vec3::norm(weft_mesh::vec3::sub(p(f3[a]), p(f3[b])));
            let d2 = f64::from((uv[a][0] - uv[b][0]).hypot(uv[a][1] - uv[b][1]));
            assert!((d3 - d2).abs() < 1e-5, "{d3} vs {d2}");
        }
    }
}

#[test]
fn bad_imports_name_the_file_and_write_nothing() {
    let f = fixture("bad");
    write_pc2(&f.dir.join("walk.pc2"), &f.frames, Pc2Timing::default()).unwrap();
    let short = Frames::from_frames(&[vec![[0.0; 3]; 5]]).unwrap();
    write_pc2(&f.dir.join("short.pc2"), &short, Pc2Timing::default()).unwrap();
    let out = f.dir.join("data");
    for (text, needle) in [
        ("fps = 30\nframez = 2\n", "unknown field `framez`"),
        (
            "fps = 30\n[[garments]]\nid = \"a b\"\ntemplate = \"skirt.obj\"\n[[sequences]]\ngarment = \"a b\"\ncache = \"walk.pc2\"\nmotion = \"walk.npz\"\nsplit = \"train\"\n",
            "garment id \"a b\": expected letters",
        ),
        (
            "fps = 30\n[[garments]]\nid = \"s\"\ntemplate = \"skirt.obj\"\n[[sequences]]\ngarment = \"s\"\ncache = \"short.pc2\"\nmotion = \"walk.npz\"\nsplit = \"train\"\n",
            "short.pc2: 5 vertices per frame but the rest mesh",
        ),
        (
            "fps = 30\n[[garments]]\nid = \"s\"\ntemplate = \"skirt.obj\"\n[[sequences]]\ngarment = \"t\"\ncache = \"walk.pc2\"\nmotion = \"walk.npz\"\nsplit = \"train\"\n",
            "garment \"t\" is not among the [[garments]]",
        ),
        (
            "fps = 0\n[[garments]]\nid = \"s\"\ntemplate = \"skirt.obj\"\n[[sequences]]\ngarment = \"s\"\ncache = \"walk.pc2\"\nmotion = \"walk.npz\"\nsplit = \"train\"\n",
            "fps = 0; expected a frame rate",
        ),
        (
            "fps = 30\n[[garments]]\nid = \"s\"\ntemplate = \"skirt.obj\"\n[[sequences]]\ngarment = \"s\"\ncache = \"missing.pc2\"\nmotion = \"walk.npz\"\nsplit = \"train\"\n",
            "missing.pc2",
        ),
    ] {
        let s = spec(&f.dir, text);
        let e = import(&s, &out).unwrap_err().to_string();
        assert!(e.contains(needle), "{text}\n=> {e}");
        assert!(!out.exists());
    }
    // An existing dataset is never overwritten.
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "mine").unwrap();
    let s = spec(
        &f.dir,
        "fps = 30\n[[garments]]\nid = \"s\"\ntemplate = \"skirt.obj\"\n[[sequences]]\ngarment = \"s\"\ncache = \"walk.pc2\"\nmotion = \"walk.npz\"\nsplit = \"train\"\n",
    );
    let e = import(&s, &out).unwrap_err().to_string();
    assert!(e.contains("not an empty directory"), "{e}");
    assert_eq!(
        std::fs::read_to_string(out.join("keep.txt")).unwrap(),
        "mine"
    );
}
