//! Any bytes: reading an AMASS-style motion from an in-memory `.npz` never panics and
//! holds at most `inflating_bound` bytes while it reads; a motion that reads has as many
//! translations as poses and writes back to an archive that reads to the same frames.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use weft_fuzz::{bounded, inflating_bound};
use weft_mesh::io::npz::Npz;
use weft_motion::{amass_from_npz, amass_npz, AmassOptions};

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.npz");
    // Both ways a file is read: frame rate required (the default) and supplied.
    let options = AmassOptions {
        fps_if_missing: data.first().map(|&b| f64::from(b) + 1.0),
        ..AmassOptions::default()
    };
    let (read, _) = bounded(data.len(), inflating_bound(data.len()), || {
        let mut npz = Npz::from_bytes(data.to_vec(), path).ok()?;
        let strict = amass_from_npz(&mut npz, &AmassOptions::default());
        let lenient = amass_from_npz(&mut npz, &options);
        Some((strict, lenient))
    });
    let Some((strict, lenient)) = read else {
        return;
    };
    if let Ok((motion, _)) = &strict {
        assert!(lenient.is_ok(), "a supplied frame rate refuses what reads without one");
        let _ = motion;
    }
    let Ok((motion, _)) = lenient else {
        return;
    };
    assert_eq!(motion.poses().len(), motion.trans().len());
    // Near f32::MAX, the pelvis offsets of writing and reading again may overflow.
    if motion.trans().iter().flatten().any(|x| x.abs() > 1e30) {
        return;
    }
    let written = amass_npz(&motion, &AmassOptions::default())
        .and_then(|w| w.to_bytes().map_err(|e| weft_motion::MotionError::Invalid(e.to_string())))
        .expect("a motion that reads writes");
    let mut npz = Npz::from_bytes(written, path).expect("a written archive opens");
    let (back, _) = amass_from_npz(&mut npz, &AmassOptions::default()).expect("a written motion reads");
    assert_eq!(back.frame_count(), motion.frame_count());
});
