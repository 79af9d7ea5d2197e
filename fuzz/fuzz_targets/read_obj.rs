//! Any bytes: reading an OBJ never panics, holds at most `linear_bound` bytes while it
//! reads, and whatever reads writes back to the same mesh.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use weft_fuzz::{bounded, linear_bound};
use weft_mesh::io::{load_obj_bytes, write_obj_to};
use weft_mesh::validate::{summarize, validate};

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.obj");
    let (read, _) = bounded(data.len(), linear_bound(data.len()), || {
        load_obj_bytes(data, path)
    });
    let Ok(report) = read else {
        return;
    };
    let findings = validate(&report.mesh);
    let _ = summarize(&findings);
    let mut bytes = Vec::new();
    write_obj_to(&mut bytes, &report.mesh).expect("writing to memory");
    let back = load_obj_bytes(&bytes, path).expect("a written mesh reads back");
    assert_eq!(back.mesh, report.mesh);
});
