//! Checkpoint inputs found by fuzzing (docs/fuzzing.md, target `read_checkpoint`).
//!
//! This test binary counts live heap bytes (its own global allocator) to check that a
//! small checkpoint file costs little memory whatever its header claims.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

use weft_models::multilevel::{MultilevelConfig, Predictor};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let now = LIVE.fetch_add(layout.size(), Relaxed) + layout.size();
        PEAK.fetch_max(now, Relaxed);
        System.alloc(layout)
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Relaxed);
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A burnpack header (magic `NRUB`, version 1) claiming 100 MiB − 1 of metadata, then
/// nothing. `Module::try_load_file` allocated the claimed 100 MiB before finding the file
/// ends; `Predictor::from_checkpoint` reads the file's bytes and refuses the claim first.
#[test]
fn a_huge_metadata_claim_fails_without_allocating_it() {
    let dir = std::env::temp_dir().join(format!("weft-models-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("step-000001.bpk");
    let mut bytes = b"NRUB\x01\x00".to_vec();
    bytes.extend_from_slice(&((100u32 << 20) - 1).to_le_bytes());
    bytes.extend_from_slice(&[0xa1; 10]);
    std::fs::write(&path, &bytes).unwrap();

    let config = MultilevelConfig::new()
        .with_joints(2)
        .with_feature_width(2)
        .with_gg_widths(vec![2])
        .with_gg_heads(1)
        .with_gs_hidden(vec![2])
        .with_bs_hidden(vec![2])
        .with_nystrom_landmarks(2)
        .with_body_samples(2)
        .with_history(1)
        .with_t1_layers(1)
        .with_t2_layers(1)
        .with_mp_submodules(1)
        .with_mp_levels(1)
        .with_mp_channels(2)
        .with_mp_heads(1)
        .with_out_heads(1);
    let device = weft_nn::backend::cpu();
    let base = LIVE.load(Relaxed);
    PEAK.store(base, Relaxed);
    let result = Predictor::from_checkpoint(config, &path, &device);
    let peak = PEAK.load(Relaxed) - base;
    let _ = std::fs::remove_dir_all(&dir);
    let e = match result {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a 20-byte checkpoint loads"),
    };
    assert!(e.contains("step-000001.bpk"), "{e}");
    assert!(
        peak < 16 << 20,
        "{peak} bytes at the peak for a 20-byte file"
    );
}
