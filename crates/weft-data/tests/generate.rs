//! Generation end to end: determinism, resuming after a kill, shard digests (a changed
//! shard is found by `--verify` and redone by a resumed run; manifests without digests
//! still read), `--shard i/n` jobs and their merge, diverged sequences, split
//! disjointness on the manifest, and the loader.
//!
//! The simulator here is a cheap deterministic stand-in (the garment sinks and follows
//! the root) so these run in well under a second each; the real simulator is exercised
//! by the ignored test at the end and by `weft data generate --preset tiny`.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use weft_data::manifest::Job;
use weft_data::{
    generate, merge_directory, DataConfig, DataError, Dataset, DatasetInfo, GarmentSpec,
    GenerateOptions, MotionSpec, Progress, SequenceSimulator, Silent, SimInput, SimOutcome, Split,
    Status,
};

/// Moves the rest garment by the root translation and sinks it 1 mm per frame; counts
/// calls; diverges at frame 2 for sequences whose body's β₀ is `diverge_beta0`.
struct FakeSim {
    calls: AtomicUsize,
    simulated: Mutex<Vec<String>>,
    diverge_beta0: Option<f64>,
}

impl FakeSim {
    fn new() -> Self {
        FakeSim {
            calls: AtomicUsize::new(0),
            simulated: Mutex::new(Vec::new()),
            diverge_beta0: None,
        }
    }
}

impl SequenceSimulator for FakeSim {
    fn simulate(
        &self,
        input: &SimInput<'_>,
        on_frame: &mut dyn FnMut(),
    ) -> Result<SimOutcome, String> {
        self.calls.fetch_add(1, Ordering::SeqCst);
        self.simulated
            .lock()
            .unwrap()
            .push(format!("{}", input.garment.vertex_count()));
        let mut frames = Vec::new();
        let mut stats = Vec::new();
        for t in 0..input.motion.frame_count() {
            if self.diverge_beta0 == Some(input.betas[0]) && t == 2 {
                return Ok(SimOutcome::Diverged {
                    frame: t,
                    message: "speed 1e9 m/s".into(),
                    frames,
                    stats: serde_json::Value::Array(stats),
                });
            }
            let tr = input.motion.trans()[t];
            frames.push(
                input
                    .garment
                    .positions
                    .iter()
                    .map(|p| {
                        [
                            (p[0] + f64::from(tr[0])) as f32,
                            (p[1] + f64::from(tr[1]) - 0.001 * t as f64) as f32,
                            (p[2] + f64::from(tr[2])) as f32,
                        ]
                    })
                    .collect(),
            );
            stats.push(serde_json::json!({ "frame": t }));
            on_frame();
        }
        Ok(SimOutcome::Finished {
            frames,
            stats: serde_json::Value::Array(stats),
        })
    }
}

/// Two garments of about 300 vertices in train, one in validation and test, three
/// frames each: 4 + 1 + 1 sequences.
fn small_config() -> DataConfig {
    let g = |kind: &str, seed| GarmentSpec {
        kind: kind.into(),
        vertices: 300,
        seed: Some(seed),
        material: None,
        length: None,
    };
    let m = |kind: &str, seed| MotionSpec {
        kind: Some(kind.into()),
        seed: Some(seed),
        frames: Some(3),
        ..MotionSpec::default()
    };
    let mut c = DataConfig::tiny();
    c.train.garments = vec![g("skirt", 1), g("tshirt", 2)];
    c.train.betas = vec![vec![0.0], vec![1.0, -0.5]];
    c.train.motions = vec![m("walk", 1), m("dance", 2)];
    c.train.motions_per_pair = 1;
    c.validation.garments = vec![g("skirt", 3)];
    c.validation.motions = vec![m("kick", 3)];
    c.test.garments = vec![g("tshirt", 4)];
    c.test.motions = vec![m("twist", 4)];
    c
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("weft-data-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for sub in ["shards", "garments"] {
        let mut names: Vec<_> = std::fs::read_dir(dir.join(sub))
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        for n in names {
            let bytes = std::fs::read(dir.join(sub).join(&n)).unwrap();
            out.push((format!("{sub}/{n}"), bytes));
        }
    }
    out
}

fn run(config: &DataConfig, dir: &Path, sim: &FakeSim, job: Option<Job>) {
    generate(config, dir, &GenerateOptions { job }, sim, &Silent).unwrap();
}

#[test]
fn same_config_and_seed_give_identical_files() {
    let c = small_config();
    let (a, b) = (scratch("det-a"), scratch("det-b"));
    run(&c, &a, &FakeSim::new(), None);
    run(&c, &b, &FakeSim::new(), None);
    assert_eq!(files(&a), files(&b));
    assert_eq!(
        std::fs::read(a.join("manifest.json")).unwrap(),
        std::fs::read(b.join("manifest.json")).unwrap()
    );
    assert_eq!(
        files(&a)
            .iter()
            .filter(|(n, _)| n.starts_with("shards/"))
            .count(),
        6
    );
    // Another seed: other garment styles and shapes only where the config leaves them
    // free; the explicit ones here stay, so compare a config without explicit seeds.
    let mut free = c.clone();
    for g in &mut free.train.garments {
        g.seed = None;
    }
    let (x, y) = (scratch("det-x"), scratch("det-y"));
    run(&free, &x, &FakeSim::new(), None);
    free.seed = 7;
    run(&free, &y, &FakeSim::new(), None);
    assert_ne!(files(&x), files(&y));
}

#[test]
fn a_killed_run_resumes_and_redoes_only_the_broken_shard() {
    let c = small_config();
    let dir = scratch("resume");
    run(&c, &dir, &FakeSim::new(), None);
    let before = files(&dir);
    let manifest_before = std::fs::read(dir.join("manifest.json")).unwrap();
    let ds = Dataset::open(&dir).unwrap();
    let victim = ds.records()[1].clone();
    // A kill mid-write: the shard is gone and a truncated temporary file is left.
    let shard = dir.join(&victim.shard);
    let bytes = std::fs::read(&shard).unwrap();
    std::fs::remove_file(&shard).unwrap();
    let temp = dir.join(format!("shards/.{}.safetensors.999.0.tmp", victim.id));
    std::fs::write(&temp, &bytes[..bytes.len() / 2]).unwrap();
    // And another shard truncated in place (a copy made outside weft, a bad disk).
    let other = ds.records()[3].clone();
    let other_path = dir.join(&other.shard);
    let other_bytes = std::fs::read(&other_path).unwrap();
    std::fs::write(&other_path, &other_bytes[..100]).unwrap();

    // A manifest write cut short too.
    let manifest_temp = dir.join(".manifest.json.999.1.tmp");
    std::fs::write(&manifest_temp, &manifest_before[..10]).unwrap();

    let sim = FakeSim::new();
    let report = generate(&c, &dir, &GenerateOptions::default(), &sim, &Silent).unwrap();
    assert!(!manifest_temp.exists());
    assert_eq!(sim.calls.load(Ordering::SeqCst), 2);
    assert_eq!(report.kept, 4);
    assert_eq!(report.done, 2);
    assert!(!temp.exists(), "the stale temporary file is removed");
    assert_eq!(files(&dir), before);
    assert_eq!(
        std::fs::read(dir.join("manifest.json")).unwrap(),
        manifest_before
    );

    // Nothing left to do: a third run simulates nothing.
    let sim = FakeSim::new();
    run(&c, &dir, &sim, None);
    assert_eq!(sim.calls.load(Ordering::SeqCst), 0);
}

/// Adds `delta` to the first value of a shard's `positions` tensor in place: the header,
/// dtypes and shapes stay valid, only the data changes.
fn nudge_first_position(path: &Path, delta: f32) {
    let mut bytes = std::fs::read(path).unwrap();
    let header_len = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + header_len]).unwrap();
    let start = header["positions"]["data_offsets"][0].as_u64().unwrap() as usize;
    let at = 8 + header_len + start;
    let old = f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    bytes[at..at + 4].copy_from_slice(&(old + delta).to_le_bytes());
    std::fs::write(path, &bytes).unwrap();
}

/// A [`Progress`] that keeps the messages.
#[derive(Default)]
struct Messages(Mutex<Vec<String>>);

impl Progress for Messages {
    fn start(&self, _: u64, _: usize, _: usize) {}
    fn frame(&self) {}
    fn message(&self, text: &str) {
        self.0.lock().unwrap().push(text.to_string());
    }
    fn finish(&self) {}
}

#[test]
fn the_manifest_records_each_shards_sha256() {
    let c = small_config();
    let dir = scratch("digest");
    run(&c, &dir, &FakeSim::new(), None);
    let ds = Dataset::open(&dir).unwrap();
    for r in ds.records() {
        let bytes = std::fs::read(dir.join(&r.shard)).unwrap();
        let digest = weft_data::shard::sha256_hex(&bytes);
        assert_eq!(r.sha256.as_deref(), Some(digest.as_str()), "{}", r.id);
    }
    let text = std::fs::read_to_string(dir.join("manifest.json")).unwrap();
    assert_eq!(text.matches("\"sha256\": \"").count(), 6, "{text}");
}

#[test]
fn verify_names_a_shard_changed_after_it_was_written() {
    let c = small_config();
    let dir = scratch("verify-changed");
    run(&c, &dir, &FakeSim::new(), None);
    let mut info = DatasetInfo::of(&dir).unwrap();
    info.verify(&dir).unwrap();
    let v = info.verified.as_ref().unwrap();
    assert_eq!((v.loaded, v.broken.len(), v.unrecorded.len()), (6, 0, 0));

    // One vertex moved by 0.5 m: the shard still has a valid header and shapes.
    let victim = Dataset::open(&dir).unwrap().records()[2].clone();
    nudge_first_position(&dir.join(&victim.shard), 0.5);
    let ds = Dataset::open(&dir).unwrap();
    assert!(
        ds.load(&victim).is_ok(),
        "the plain loader checks shapes only"
    );
    let err = ds.load_verified(&victim).unwrap_err();
    assert!(matches!(err, DataError::Digest { .. }), "{err}");

    let mut info = DatasetInfo::of(&dir).unwrap();
    info.verify(&dir).unwrap();
    let v = info.verified.as_ref().unwrap();
    assert_eq!(v.loaded, 5);
    assert_eq!(v.broken.len(), 1);
    let (id, why) = &v.broken[0];
    assert_eq!(id, &victim.id);
    assert!(
        why.contains(&victim.shard) && why.contains("changed since it was written"),
        "{why}"
    );
    let text = info.to_string();
    assert!(
        text.contains(&format!("broken shard: {}", victim.id))
            && text.contains("to repair: run `weft data generate`"),
        "{text}"
    );
}

#[test]
fn a_resumed_run_redoes_a_changed_shard_byte_identically() {
    let c = small_config();
    let dir = scratch("resume-changed");
    run(&c, &dir, &FakeSim::new(), None);
    let before = files(&dir);
    let manifest_before = std::fs::read(dir.join("manifest.json")).unwrap();
    let victim = Dataset::open(&dir).unwrap().records()[4].clone();
    nudge_first_position(&dir.join(&victim.shard), 0.5);
    assert_ne!(files(&dir), before);

    let sim = FakeSim::new();
    let messages = Messages::default();
    let report = generate(&c, &dir, &GenerateOptions::default(), &sim, &messages).unwrap();
    assert_eq!(
        sim.calls.load(Ordering::SeqCst),
        1,
        "only the changed shard"
    );
    assert_eq!((report.kept, report.done), (5, 1));
    assert_eq!(report.redone.len(), 1);
    assert_eq!(report.redone[0].0, victim.id);
    assert!(
        report.redone[0].1.contains("changed since it was written"),
        "{:?}",
        report.redone
    );
    let said = messages.0.lock().unwrap().join("\n");
    assert!(
        said.contains(&victim.id) && said.contains("simulating it again"),
        "{said}"
    );
    assert_eq!(files(&dir), before);
    assert_eq!(
        std::fs::read(dir.join("manifest.json")).unwrap(),
        manifest_before
    );
    let mut info = DatasetInfo::of(&dir).unwrap();
    info.verify(&dir).unwrap();
    assert!(info.verified.unwrap().broken.is_empty());
}

#[test]
fn a_manifest_without_digests_still_reads_and_resume_records_them() {
    let c = small_config();
    let dir = scratch("old-manifest");
    run(&c, &dir, &FakeSim::new(), None);
    let manifest_path = dir.join("manifest.json");
    let current = std::fs::read(&manifest_path).unwrap();
    // The manifest as weft wrote it before shard digests.
    let mut old: serde_json::Value = serde_json::from_slice(&current).unwrap();
    for s in old["sequences"].as_array_mut().unwrap() {
        s.as_object_mut().unwrap().remove("sha256").unwrap();
    }
    let mut text = serde_json::to_string_pretty(&old).unwrap();
    text.push('\n');
    assert!(!text.contains("sha256"));
    std::fs::write(&manifest_path, &text).unwrap();

    let ds = Dataset::open(&dir).unwrap();
    assert!(ds.records().iter().all(|r| r.sha256.is_none()));
    let r = ds.records_in(Split::Train)[0].clone();
    assert_eq!(ds.load_verified(&r).unwrap(), ds.load(&r).unwrap());
    let mut info = DatasetInfo::of(&dir).unwrap();
    info.verify(&dir).unwrap();
    let v = info.verified.as_ref().unwrap();
    assert_eq!((v.loaded, v.broken.len(), v.unrecorded.len()), (6, 0, 6));
    let shown = info.to_string();
    assert!(
        shown.contains("no SHA-256 recorded for 6 shards") && shown.contains("weft data generate"),
        "{shown}"
    );

    // A resumed run keeps every shard, simulates nothing and records the digests: the
    // manifest is the one a fresh run writes.
    let sim = FakeSim::new();
    let report = generate(&c, &dir, &GenerateOptions::default(), &sim, &Silent).unwrap();
    assert_eq!(sim.calls.load(Ordering::SeqCst), 0);
    assert_eq!((report.kept, report.digests_recorded), (6, 6));
    assert!(report.redone.is_empty());
    assert_eq!(std::fs::read(&manifest_path).unwrap(), current);
}

#[test]
fn a_directory_of_another_config_is_refused() {
    let c = small_config();
    let dir = scratch("conflict");
    run(&c, &dir, &FakeSim::new(), None);
    let mut other = c.clone();
    other.seed = 3;
    let err = generate(
        &other,
        &dir,
        &GenerateOptions::default(),
        &FakeSim::new(),
        &Silent,
    )
    .unwrap_err();
    assert!(matches!(err, DataError::Conflict { .. }), "{err}");
}

#[test]
fn a_second_writer_is_refused_and_jobs_share_the_directory() {
    use weft_mesh::io::lock::{Access, DirLock, LOCK_FILE};
    let c = small_config();
    let dir = scratch("locked");
    let generate_as =
        |job: Option<Job>| generate(&c, &dir, &GenerateOptions { job }, &FakeSim::new(), &Silent);
    // A whole run in progress: nothing else may write.
    let held = DirLock::acquire(&dir, LOCK_FILE, Access::Exclusive, "weft data generate").unwrap();
    for job in [None, Some(Job { index: 0, count: 2 })] {
        let err = generate_as(job).unwrap_err();
        assert!(matches!(err, DataError::Lock(_)), "{err}");
        assert!(err.to_string().contains("weft data generate, pid"), "{err}");
    }
    assert!(!dir.join("manifest.json").exists());
    drop(held);
    // Job 0 in progress: job 1 runs beside it; a whole run and a second job 0 are refused.
    let shared = DirLock::acquire(&dir, LOCK_FILE, Access::Shared, "job 0").unwrap();
    let own = DirLock::acquire(
        &dir,
        ".manifest.part-0-of-2.json.lock",
        Access::Exclusive,
        "weft data generate --shard 0/2",
    )
    .unwrap();
    generate_as(Some(Job { index: 1, count: 2 })).unwrap();
    assert!(matches!(generate_as(None), Err(DataError::Lock(_))));
    let err = generate_as(Some(Job { index: 0, count: 2 })).unwrap_err();
    assert!(err.to_string().contains("--shard 0/2"), "{err}");
    drop((shared, own));
    // A whole run removes the temporary files a killed run left.
    let stale = dir.join("shards/.train-x.safetensors.999999.3.tmp");
    std::fs::write(&stale, [0u8; 32]).unwrap();
    generate_as(None).unwrap();
    assert!(!stale.exists());
}

#[test]
fn shard_jobs_merge_into_the_single_job_manifest() {
    let c = small_config();
    let single = scratch("jobs-single");
    run(&c, &single, &FakeSim::new(), None);
    let jobs = scratch("jobs");
    for i in [1, 0, 2] {
        let sim = FakeSim::new();
        run(&c, &jobs, &sim, Some(Job { index: i, count: 3 }));
        assert_eq!(sim.calls.load(Ordering::SeqCst), 2, "job {i}");
    }
    let err = Dataset::open(&jobs).unwrap_err().to_string();
    assert!(err.contains("weft data merge"), "{err}");
    merge_directory(&jobs).unwrap();
    assert_eq!(
        std::fs::read(jobs.join("manifest.json")).unwrap(),
        std::fs::read(single.join("manifest.json")).unwrap()
    );
    assert_eq!(files(&jobs), files(&single));
}

#[test]
fn a_missing_job_is_named_by_merge() {
    let c = small_config();
    let dir = scratch("jobs-missing");
    run(&c, &dir, &FakeSim::new(), Some(Job { index: 0, count: 2 }));
    let err = merge_directory(&dir).unwrap_err().to_string();
    assert!(err.contains("job 1/2"), "{err}");
}

#[test]
fn a_diverged_sequence_is_recorded_and_the_others_finish() {
    let c = small_config();
    let dir = scratch("diverged");
    let sim = FakeSim {
        diverge_beta0: Some(1.0),
        ..FakeSim::new()
    };
    let report = generate(&c, &dir, &GenerateOptions::default(), &sim, &Silent).unwrap();
    // Train body b001 (β₀ = 1) carries 2 of the 4 train sequences.
    assert_eq!(report.diverged.len(), 2);
    assert!(report
        .diverged
        .iter()
        .all(|(id, frame)| id.contains("b001") && *frame == 2));
    assert_eq!(report.done, 4);
    let ds = Dataset::open(&dir).unwrap();
    let bad: Vec<_> = ds
        .records()
        .iter()
        .filter(|r| r.status == Status::Diverged)
        .collect();
    assert_eq!(bad.len(), 2);
    for r in &bad {
        assert_eq!((r.frames, r.diverged_at), (2, Some(2)));
        let s = ds.load(r).unwrap();
        assert_eq!(s.positions.len(), 2);
    }
    let info = DatasetInfo::of(&dir).unwrap();
    assert_eq!(info.problems.len(), 2);
    let text = info.to_string();
    assert!(
        text.contains("diverged:") && text.contains("at frame 2"),
        "{text}"
    );
    // Diverged sequences are final: a resumed run keeps them.
    let again = FakeSim::new();
    run(&c, &dir, &again, None);
    assert_eq!(again.calls.load(Ordering::SeqCst), 0);
}

#[test]
fn splits_share_no_garment_body_or_motion_in_the_manifest() {
    let c = small_config();
    let dir = scratch("splits");
    run(&c, &dir, &FakeSim::new(), None);
    let ds = Dataset::open(&dir).unwrap();
    let m = ds.manifest();
    for (i, a) in Split::ALL.iter().enumerate() {
        for b in &Split::ALL[i + 1..] {
            let of = |s: Split| -> (HashSet<String>, HashSet<Vec<u32>>, HashSet<String>) {
                let recs = ds.records().iter().filter(|r| r.split == s);
                let mut g = HashSet::new();
                let mut body = HashSet::new();
                let mut mo = HashSet::new();
                for r in recs {
                    let gr = m.garments.iter().find(|x| x.id == r.garment_id).unwrap();
                    g.insert(format!("{}/{}/{}", gr.kind, gr.target_vertices, gr.seed));
                    body.insert(r.betas.iter().map(|x| x.to_bits()).collect());
                    let mr = m.motions.iter().find(|x| x.id == r.motion_id).unwrap();
                    mo.insert(format!("{:?}", mr.origin));
                }
                (g, body, mo)
            };
            let (ga, ba, ma) = of(*a);
            let (gb, bb, mb) = of(*b);
            assert!(ga.is_disjoint(&gb), "{a}/{b} share a garment");
            assert!(ba.is_disjoint(&bb), "{a}/{b} share a body shape");
            assert!(ma.is_disjoint(&mb), "{a}/{b} share a motion");
        }
    }
}

#[test]
fn the_loader_reads_what_was_generated() {
    let c = small_config();
    let dir = scratch("loader");
    run(&c, &dir, &FakeSim::new(), None);
    let ds = Dataset::open(&dir).unwrap();
    assert_eq!(ds.records_in(Split::Train).len(), 4);
    assert_eq!(ds.records_in(Split::Validation).len(), 1);
    assert_eq!(ds.records_in(Split::Test).len(), 1);
    let r = ds.records_in(Split::Train)[0].clone();
    let s = ds.load(&r).unwrap();
    assert_eq!(s.positions.len(), 3);
    assert_eq!(s.poses.len(), 3);
    assert_eq!(s.trans.len(), 3);
    assert_eq!(s.garment.vertex_count(), r.vertices);
    assert_eq!(s.positions[0].len(), r.vertices);
    assert_eq!(s.corner_uvs.len(), s.garment.face_count());
    assert_eq!(r.betas.len(), 10);
    // Frame 0 of the stand-in is the rest garment moved by the root translation.
    let t0 = s.trans[0];
    let p = s.positions[0][5];
    let q = s.garment.positions[5];
    assert!((f64::from(p[1]) - (q[1] + f64::from(t0[1]))).abs() < 1e-5);
    // The zero-shape template of the garment.
    let g = ds.garment(&r.garment_id).unwrap();
    assert!(g.vertex_count() > 200);
    let err = ds.garment("g999-cape").unwrap_err().to_string();
    assert!(err.contains("g999-cape"), "{err}");

    // A damaged shard: the error names the file and the tensor.
    let path = dir.join(&r.shard);
    let mut bytes = std::fs::read(&path).unwrap();
    // Rename tensor "poses" to "posez" in the header (same length, still valid JSON).
    let header_len = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header = String::from_utf8(bytes[8..8 + header_len].to_vec()).unwrap();
    let patched = header.replace("\"poses\"", "\"posez\"");
    bytes[8..8 + header_len].copy_from_slice(patched.as_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let err = ds.load(&r).unwrap_err().to_string();
    assert!(
        err.contains(&r.shard) && err.contains("\"poses\"") && err.contains("missing"),
        "{err}"
    );
}

/// The real simulator on one small sequence (slow in the test profile: run with
/// `cargo test -p weft-data --release -- --ignored`).
#[test]
#[ignore]
fn the_real_simulator_generates_a_small_dataset() {
    let mut c = small_config();
    c.warmup_frames = 3;
    let dir = scratch("physics");
    let report = generate(
        &c,
        &dir,
        &GenerateOptions::default(),
        &weft_data::Physics,
        &Silent,
    )
    .unwrap();
    assert_eq!(report.done + report.diverged.len(), 6, "{report:?}");
    let ds = Dataset::open(&dir).unwrap();
    for r in ds.records() {
        let s = ds.load(r).unwrap();
        assert!(s
            .positions
            .iter()
            .flatten()
            .flatten()
            .all(|x| x.is_finite()));
    }
}

#[test]
fn file_motions_are_resampled_and_windowed() {
    use weft_motion::{generate as procedural, write_motion, MotionFileOptions};
    use weft_motion::{MotionKind, ProceduralParams};
    let dir = scratch("file-motion");
    // A 60 fps walk of 20 frames written as AMASS .npz; the dataset runs at 30 fps.
    let mut params = ProceduralParams::new(MotionKind::Walk);
    params.frames = 20;
    params.fps = 60.0;
    let walk = procedural(&params).unwrap();
    let file = dir.join("capture.npz");
    write_motion(&file, &walk, &MotionFileOptions::default()).unwrap();
    let mut c = small_config();
    c.test.motions = vec![MotionSpec {
        file: Some(file.clone()),
        start: 2,
        frames: Some(4),
        ..MotionSpec::default()
    }];
    let out = dir.join("out");
    run(&c, &out, &FakeSim::new(), None);
    let ds = Dataset::open(&out).unwrap();
    let r = ds.records_in(Split::Test)[0].clone();
    assert_eq!(r.motion_id, "m003-capture");
    assert_eq!((r.frame_range, r.frames), ([2, 6], 4));
    assert_eq!(ds.load(&r).unwrap().poses.len(), 4);
    // A window past the end of the file is refused before anything is written, naming
    // the motion and the frames.
    c.test.motions[0].frames = Some(40);
    let out = dir.join("out2");
    let err = generate(
        &c,
        &out,
        &GenerateOptions::default(),
        &FakeSim::new(),
        &Silent,
    )
    .unwrap_err();
    let message = format!("{err:#}");
    assert!(
        message.contains("m003-capture") && message.contains("frames 2..42"),
        "{message}"
    );
    assert!(!out.exists());
}

/// Records what the simulator was given with `garment_body`: per body (β₄), the rest
/// shape and the start positions; frames are the start moved by the root.
struct StartSim {
    seen: Mutex<Vec<Given>>,
}

/// β₄, the rest shape and the start positions a simulator was given.
type Given = (f64, Vec<[f64; 3]>, Option<Vec<[f64; 3]>>);

impl SequenceSimulator for StartSim {
    fn simulate(
        &self,
        input: &SimInput<'_>,
        on_frame: &mut dyn FnMut(),
    ) -> Result<SimOutcome, String> {
        self.seen.lock().unwrap().push((
            input.betas[3],
            input.garment.positions.clone(),
            input.start_positions.map(<[[f64; 3]]>::to_vec),
        ));
        let start = input.start_positions.unwrap_or(&input.garment.positions);
        let mut frames = Vec::new();
        for t in 0..input.motion.frame_count() {
            let tr = input.motion.trans()[t];
            frames.push(
                start
                    .iter()
                    .map(|p| std::array::from_fn(|k| (p[k] + f64::from(tr[k])) as f32))
                    .collect(),
            );
            on_frame();
        }
        Ok(SimOutcome::Finished {
            frames,
            stats: serde_json::Value::Array(vec![]),
        })
    }
}

/// Issue 14, fit data: with `garment_body` every garment is one pattern (the template
/// written, made on that body), simulated on each body as its rest shape from the
/// pattern fitted onto that body (`fit_onto`, once per garment–body pair, not per
/// sequence); the shard's rest positions are that fitted garment, which differs from
/// body to body, and the same config gives the same bytes.
#[test]
fn garment_body_starts_one_pattern_fitted_onto_each_body() {
    let g = |kind: &str, length: &str, seed| GarmentSpec {
        kind: kind.into(),
        vertices: 300,
        seed: Some(seed),
        material: None,
        length: Some(length.into()),
    };
    let m = |kind: &str, seed| MotionSpec {
        kind: Some(kind.into()),
        seed: Some(seed),
        frames: Some(2),
        ..MotionSpec::default()
    };
    let weight = |w: f64| vec![0.0, 0.0, 0.0, w];
    let mut c = DataConfig::garfit_tiny();
    c.train.garments = vec![g("skirt", "knee", 1)];
    c.train.betas = vec![weight(1.5), weight(-1.5)];
    c.train.motions = vec![m("walk", 1), m("jump", 2)];
    c.train.motions_per_pair = 0;
    c.validation.garments = vec![g("skirt", "mini", 2)];
    c.validation.betas = vec![weight(0.5)];
    c.validation.motions = vec![m("kick", 3)];
    c.test.garments = vec![g("dress", "maxi", 3)];
    c.test.betas = vec![weight(0.0)];
    c.test.motions = vec![m("dance", 4)];

    let dir = scratch("garment-body");
    let sim = StartSim {
        seen: Mutex::new(Vec::new()),
    };
    let messages = Messages::default();
    let report = generate(&c, &dir, &GenerateOptions::default(), &sim, &messages).unwrap();
    assert_eq!((report.done, report.failed.len()), (6, 0), "{report:?}");
    let messages = messages.0.into_inner().unwrap();
    assert!(
        messages
            .iter()
            .any(|t| t.contains("(4 garment-body pairs)")),
        "{messages:?}"
    );

    let seen = sim.seen.into_inner().unwrap();
    assert_eq!(seen.len(), 6);
    assert!(seen.iter().all(|(_, _, start)| start.is_some()));
    let ds = Dataset::open(&dir).unwrap();
    let pattern = ds.garment("g000-skirt").unwrap();
    let mut fitted = Vec::new();
    for r in ds.records_in(Split::Train) {
        let s = ds.load(r).unwrap();
        let w = f64::from(r.betas[3]);
        let (_, rest, start) = seen.iter().find(|(b, _, _)| *b == w).unwrap();
        // The rest shape given to the simulator is the template written (f32 in OBJ).
        assert_eq!(rest.len(), pattern.vertex_count());
        assert!(rest
            .iter()
            .zip(&pattern.positions)
            .all(|(a, b)| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-5)));
        // The shard's rest positions are the fitted start, not the pattern.
        let start = start.as_ref().unwrap();
        assert!(s
            .garment
            .positions
            .iter()
            .zip(start)
            .all(|(a, b)| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-5)));
        fitted.push((w, s.garment.positions.clone()));
    }
    let moved = |a: &[[f64; 3]], b: &[[f64; 3]]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| weft_mesh::vec3::dist(*p, *q))
            .sum::<f64>()
            / a.len() as f64
    };
    let fat = &fitted.iter().find(|(w, _)| *w > 0.0).unwrap().1;
    let thin = &fitted.iter().find(|(w, _)| *w < 0.0).unwrap().1;
    assert!(moved(fat, &pattern.positions) > 0.005);
    assert!(moved(thin, &pattern.positions) > 0.005);
    assert!(moved(fat, thin) > 0.01);

    let again = scratch("garment-body-again");
    generate(
        &c,
        &again,
        &GenerateOptions::default(),
        &StartSim {
            seen: Mutex::new(Vec::new()),
        },
        &Silent,
    )
    .unwrap();
    assert!(files(&dir) == files(&again), "not byte-identical");
    assert_eq!(
        std::fs::read(dir.join("manifest.json")).unwrap(),
        std::fs::read(again.join("manifest.json")).unwrap()
    );
}
