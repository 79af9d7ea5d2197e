//! Any bytes: reading a PLY never panics, holds at most `linear_bound` bytes while it
//! reads (so never allocates on an unchecked count), and whatever reads writes back to
//! the same mesh in every encoding.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use weft_fuzz::{bounded, linear_bound};
use weft_mesh::io::{load_ply_bytes, write_ply_to, PlyEncoding};
use weft_mesh::validate::{summarize, validate};

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.ply");
    let (read, _) = bounded(data.len(), linear_bound(data.len()), || {
        load_ply_bytes(data, path)
    });
    let Ok(report) = read else {
        return;
    };
    let findings = validate(&report.mesh);
    let _ = summarize(&findings);
    for encoding in [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ] {
        let mut bytes = Vec::new();
        write_ply_to(&mut bytes, &report.mesh, encoding, None).expect("writing to memory");
        let back = load_ply_bytes(&bytes, path).expect("a written mesh reads back");
        assert_eq!(back.mesh, report.mesh, "{encoding}");
    }
});
