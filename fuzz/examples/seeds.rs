//! Writes the seed corpora of the fuzz targets into `seeds/<target>/` (run from `fuzz/`):
//! small valid inputs written by weft's own writers, plus a few edge cases each reader
//! must handle (other dtypes, Fortran order, stored and deflated members, CRLF, …).
//!
//! ```sh
//! cargo run --release --example seeds                   # every target but the burn ones
//! cargo run --release --example seeds --features burn   # and run configs, checkpoints
//! ```
//!
//! Seeds up to 32 KiB go to `seeds/` (in git; most are a few hundred bytes, the tiny
//! model checkpoint is 24 KiB, mostly 256-byte tensor alignment); larger ones (the
//! optimiser record after a step, 56 KiB) to the git-ignored `corpus/`.

use std::io::{Cursor, Write as _};
use std::path::Path;

use weft_mesh::export::npy::write_npy_to;
use weft_mesh::io::npz::NpzWriter;
use weft_mesh::io::{write_obj_to, write_ply_to, PlyEncoding};
use weft_mesh::primitives::grid;
use weft_motion::{amass_npz, generate, motion_to_bvh, AmassOptions, MotionKind, ProceduralParams};

/// Writes a seed to `seeds/<target>/` (in git), or when it is over 32 KiB to
/// `corpus/<target>/` (git-ignored, where the fuzzer's own finds go).
fn put(target: &str, name: &str, bytes: &[u8]) {
    let home = if bytes.len() <= 32 << 10 { "seeds" } else { "corpus" };
    let dir = Path::new(home).join(target);
    std::fs::create_dir_all(&dir).expect("seed directory");
    std::fs::write(dir.join(name), bytes).expect("writing a seed");
}

/// A `.npy` member with any header (other dtypes, Fortran order) for hand-made archives.
fn npy_bytes(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}\n",
        if fortran { "True" } else { "False" }
    );
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.extend_from_slice(data);
    out
}

fn zip_of(members: &[(&str, Vec<u8>)], deflate: bool) -> Vec<u8> {
    let method = if deflate {
        zip::CompressionMethod::Deflated
    } else {
        zip::CompressionMethod::Stored
    };
    let options = zip::write::SimpleFileOptions::default().compression_method(method);
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    for (name, bytes) in members {
        zip.start_file(*name, options).unwrap();
        zip.write_all(bytes).unwrap();
    }
    zip.finish().unwrap().into_inner()
}

fn meshes() {
    let mesh = grid(3, 3, 0.5);
    let mut obj = Vec::new();
    write_obj_to(&mut obj, &mesh).unwrap();
    put("read_obj", "grid.obj", &obj);
    put(
        "read_obj",
        "quad_ngon_groups.obj",
        b"# a quad and a pentagon\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\n\
vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\ng a\ns 1\nusemtl m\nf 1/1/1 2/2/1 3/3/1 4/1/1\nf -5//1 -4//1 -3//1 -1//1 -2//1\nl 1 2\n",
    );
    put("read_obj", "crlf.obj", b"v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n");
    for (name, encoding) in [
        ("grid_ascii.ply", PlyEncoding::Ascii),
        ("grid_le.ply", PlyEncoding::BinaryLittleEndian),
        ("grid_be.ply", PlyEncoding::BinaryBigEndian),
    ] {
        let mut ply = Vec::new();
        write_ply_to(&mut ply, &mesh, encoding, None).unwrap();
        put("read_ply", name, &ply);
    }
    let colors = vec![[200u8, 10, 10]; mesh.positions.len()];
    let mut ply = Vec::new();
    write_ply_to(&mut ply, &mesh, PlyEncoding::BinaryLittleEndian, Some(&colors)).unwrap();
    put("read_ply", "grid_colored.ply", &ply);
    put(
        "read_ply",
        "quad_edges_ascii.ply",
        b"ply\nformat ascii 1.0\ncomment a quad\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\n\
element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n4 0 1 2 3\n0 1\n",
    );
}

fn arrays() {
    let mut b = Vec::new();
    let frames: Vec<f32> = (0..2 * 4 * 3).map(|i| i as f32 * 0.25 - 1.0).collect();
    write_npy_to(&mut b, &[2, 4, 3], &frames).unwrap();
    put("read_npy", "frames_f4.npy", &b);
    b.clear();
    write_npy_to(&mut b, &[3, 2], &[1.5f64, -2.0, 0.0, 1e300, -1e-300, 3.0]).unwrap();
    put("read_npy", "f8.npy", &b);
    b.clear();
    write_npy_to(&mut b, &[2, 3], &[0i32, 1, 2, 2, 3, 0]).unwrap();
    put("read_npy", "faces_i4.npy", &b);
    b.clear();
    write_npy_to(&mut b, &[4], &[1i64, -1, i64::MAX, i64::MIN]).unwrap();
    put("read_npy", "i8.npy", &b);
    b.clear();
    write_npy_to(&mut b, &[3], &[7u32, 8, 9]).unwrap();
    put("read_npy", "u4.npy", &b);
    b.clear();
    write_npy_to(&mut b, &[], &[42u8]).unwrap();
    put("read_npy", "scalar_u1.npy", &b);
    b.clear();
    write_npy_to::<f32>(&mut b, &[0, 3], &[]).unwrap();
    put("read_npy", "empty.npy", &b);
    // Version 2.0 (a u32 header length).
    let mut v2 = b"\x93NUMPY\x02\x00".to_vec();
    let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (2,), }\n";
    v2.extend_from_slice(&(dict.len() as u32).to_le_bytes());
    v2.extend_from_slice(dict.as_bytes());
    v2.extend_from_slice(&[0, 0, 128, 63, 0, 0, 0, 64]);
    put("read_npy", "v2.npy", &v2);

    for compressed in [false, true] {
        let mut w = NpzWriter::new(compressed);
        w.add("v", &[4, 3], &frames[..12]).unwrap();
        w.add("f", &[2, 3], &[0u32, 1, 2, 2, 3, 0]).unwrap();
        w.add("d", &[2], &[0.5f64, -1.0]).unwrap();
        w.add("i", &[3], &[1i64, 2, 3]).unwrap();
        w.add("n", &[2, 2], &[1i32, -2, 3, -4]).unwrap();
        w.add("b", &[3], &[true, false, true]).unwrap();
        w.add("u", &[], &[9u8]).unwrap();
        let name = if compressed { "writer_deflated.npz" } else { "writer_stored.npz" };
        put("read_npz", name, &w.to_bytes().unwrap());
    }
    let members = [
        ("fortran.npy", npy_bytes("<f8", true, "(2, 3)", &[0u8; 48])),
        ("small_ints.npy", npy_bytes("|i1", false, "(4,)", &[1, 255, 0, 128])),
        ("halves.npy", npy_bytes("<u2", false, "(2,)", &[1, 0, 255, 255])),
        ("i2.npy", npy_bytes("<i2", false, "(1,)", &[255, 255])),
        ("big_u8.npy", npy_bytes("<u8", false, "(1,)", &[255; 8])),
        ("v3.npy", {
            let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (1,), }\n";
            let mut m = b"\x93NUMPY\x03\x00".to_vec();
            m.extend_from_slice(&(dict.len() as u32).to_le_bytes());
            m.extend_from_slice(dict.as_bytes());
            m.extend_from_slice(&[0, 0, 128, 63]);
            m
        }),
        ("strings.npy", npy_bytes("<U5", false, "(1,)", &[0u8; 20])),
        ("dir/", Vec::new()),
    ];
    put("read_npz", "dtypes_stored.npz", &zip_of(&members, false));
    put("read_npz", "dtypes_deflated.npz", &zip_of(&members, true));
}

fn motions() {
    let mut params = ProceduralParams::new(MotionKind::Walk);
    params.frames = 3;
    let motion = generate(&params).unwrap();
    let w = amass_npz(&motion, &AmassOptions::default()).unwrap();
    put("read_amass", "smpl_stored.npz", &w.to_bytes().unwrap());
    // AMASS's own variants: SMPL-H poses (N, 156) in float32, deflated, with extra keys.
    let n = 2;
    let poses: Vec<f32> = (0..n * 156).map(|i| (i % 7) as f32 * 0.05).collect();
    let trans: Vec<f32> = (0..n * 3).map(|i| i as f32 * 0.1).collect();
    let mut w = NpzWriter::new(true);
    w.add("poses", &[n, 156], &poses).unwrap();
    w.add("trans", &[n, 3], &trans).unwrap();
    w.add("mocap_framerate", &[], &[120.0f64]).unwrap();
    w.add("betas", &[1, 4], &[0.1f32, 0.2, 0.3, 0.4]).unwrap();
    w.add("dmpls", &[n, 2], &[0.0f32; 4]).unwrap();
    put("read_amass", "smplh_deflated.npz", &w.to_bytes().unwrap());
    // SMPL-X split by part, integer frame rate under the other key.
    let mut w = NpzWriter::new(false);
    w.add("root_orient", &[n, 3], &[0.1f64; 6]).unwrap();
    w.add("pose_body", &[n, 63], &vec![0.01f64; n * 63]).unwrap();
    w.add("trans", &[n, 3], &[0.0f64; 6]).unwrap();
    w.add("mocap_frame_rate", &[1], &[60i64]).unwrap();
    w.add("gender", &[3], &[109u8, 97, 108]).unwrap();
    put("read_amass", "parts_stored.npz", &w.to_bytes().unwrap());

    let bvh = motion_to_bvh(&motion, &weft_motion::DEFAULT_REST_JOINTS).unwrap();
    let mut text = Vec::new();
    bvh.write_to(&mut text).unwrap();
    put("read_bvh", "smpl_3_frames.bvh", &text);
    let cmu = include_bytes!("../../crates/weft-motion/tests/data/cmu_tiny.bvh");
    put("read_bvh", "cmu_tiny.bvh", cmu);
    put(
        "read_bvh",
        "minimal.bvh",
        b"HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n  \
JOINT Spine\n  {\n    OFFSET 0 10 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n    End Site\n    {\n      OFFSET 0 5 0\n    }\n  }\n}\n\
MOTION\nFrames: 2\nFrame Time: 0.033333\n0 0 0 0 0 0 0 0 0\n1 2 3 4 5 6 7 8 9\n",
    );
}

fn configs() {
    let tiny = weft_data::DataConfig::tiny();
    put("read_data_config", "tiny.toml", tiny.to_toml().unwrap().as_bytes());
    let paper = weft_data::DataConfig::paper();
    put("read_data_config", "paper.toml", paper.to_toml().unwrap().as_bytes());
    put(
        "read_data_config",
        "partial.toml",
        b"fps = 30.0\nframes = 12\n[train]\nrandom_bodies = 1\n[[train.motions]]\nkind = \"walk\"\nseed = 3\n",
    );
}

#[cfg(feature = "burn")]
fn burn_seeds() {
    use burn::module::Module;
    use weft_models::multilevel::Multilevel;

    for preset in ["cpu", "paper"] {
        let run = weft_train::MultilevelRun::preset(preset).unwrap();
        let text = run.to_toml().unwrap();
        put("read_run_config", &format!("{preset}.toml"), text.as_bytes());
    }
    put(
        "read_run_config",
        "partial.toml",
        b"format_version = 1\nmodel_kind = \"multilevel\"\npreset = \"cpu\"\n[train]\nsteps = 9\n[model]\nmp_channels = 4\n",
    );

    let device = weft_nn::backend::cpu();
    let model = Multilevel::new(&weft_fuzz::tiny_multilevel(), &device).unwrap();
    let bytes = model.into_record().into_bytes().unwrap();
    put("read_checkpoint", "tiny_model.bpk", &bytes);
    let cfg = weft_train::TrainConfig::preset("cpu").unwrap();
    let mut optim = cfg.optimizer.init(cfg.grad_clip_norm);
    put("read_checkpoint", "fresh_optimizer.bpk", &optim.into_bytes().unwrap());

    // One step on the sum of squared parameters, so the optimiser has state per parameter.
    struct SquaredSum(Option<burn::tensor::Tensor<1>>);
    impl burn::module::ModuleVisitor for SquaredSum {
        fn visit_float<const D: usize>(&mut self, param: &burn::module::Param<burn::tensor::Tensor<D>>) {
            let v = param.val();
            let s = (v.clone() * v).sum();
            self.0 = Some(match self.0.take() {
                Some(acc) => acc + s,
                None => s,
            });
        }
    }
    let device = weft_nn::backend::cpu_autodiff();
    let model = Multilevel::new(&weft_fuzz::tiny_multilevel(), &device).unwrap();
    let mut sum = SquaredSum(None);
    model.visit(&mut sum);
    let loss = sum.0.expect("the model has parameters");
    let grads = burn::optim::GradientsParams::from_grads(loss.backward(), &model);
    let _model = optim.step(1e-3, model, grads);
    put("read_checkpoint", "stepped_optimizer.bpk", &optim.into_bytes().unwrap());
}

fn main() {
    meshes();
    arrays();
    motions();
    configs();
    #[cfg(feature = "burn")]
    burn_seeds();
}
