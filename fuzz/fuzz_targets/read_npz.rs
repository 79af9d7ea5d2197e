//! Any bytes: opening a `.npz` and reading every member as `describe`, `floats` and
//! `ints` never panics, and holds at most `inflating_bound` bytes (the reader's own
//! deflate limit × the input) while it reads; what reads has as many elements as its
//! shape says.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use weft_fuzz::{bounded, inflating_bound};
use weft_mesh::io::npz::Npz;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.npz");
    bounded(data.len(), inflating_bound(data.len()), || {
        let Ok(mut npz) = Npz::from_bytes(data.to_vec(), path) else {
            return;
        };
        for key in npz.keys() {
            assert!(npz.contains(&key));
            let described = npz.describe(&key);
            if let Ok(a) = npz.floats(&key, &[]) {
                assert_eq!(a.data.len(), a.shape.iter().product::<usize>());
            }
            match npz.floats(&key, &[None, None]) {
                Ok(a) => {
                    assert_eq!(a.data.len(), a.shape.iter().product::<usize>());
                    let (_, shape) = described.as_ref().expect("a member that reads describes");
                    assert_eq!(&a.shape, shape);
                }
                Err(e) => {
                    let _ = e.to_string();
                }
            }
            match npz.ints(&key, &[None]) {
                Ok(a) => assert_eq!(a.data.len(), a.shape.iter().product::<usize>()),
                Err(e) => {
                    let _ = e.to_string();
                }
            }
        }
        let _ = npz.floats("no such key", &[]).map_err(|e| e.to_string());
    });
});
