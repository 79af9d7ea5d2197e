//! Motion inputs found by fuzzing (docs/fuzzing.md): each must give an error naming the
//! file and line, never a panic, and what reads must write back to what reads the same.

use std::path::Path;

use weft_motion::Bvh;

/// The fuzzer's input: an SMPL BVH with the line `JOINT left_collar{\t\t\t\t{`. The name
/// `left_collar{` was read, and written back as `JOINT left_collar{` + `{`, which reads
/// as a joint `left_collar` followed by a stray `{`. A name ending in `{` is refused.
#[test]
fn a_joint_name_ending_in_a_brace_is_refused() {
    let path = Path::new("fuzz_joint_name_brace.bvh");
    let bytes = include_bytes!("data/fuzz_joint_name_brace.bvh");
    let e = Bvh::parse(bytes, path).unwrap_err().to_string();
    assert!(e.starts_with("fuzz_joint_name_brace.bvh:78: "), "{e}");
    assert!(e.contains("joint name 'left_collar{' ends with '{'"), "{e}");

    let minimal = b"HIERARCHY\nROOT Hips{ {\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0\n";
    let e = Bvh::parse(minimal, path).unwrap_err().to_string();
    assert!(e.contains(":2: joint name 'Hips{'"), "{e}");

    // One brace on the name's line still opens the block; braces inside a name are kept
    // and written back as they were read.
    for text in ["ROOT Hips{", "ROOT Hips {", "ROOT Hi}ps{", "ROOT {Hips\n{"] {
        let file = format!(
            "HIERARCHY\n{text}\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0\n"
        );
        let bvh = Bvh::parse(file.as_bytes(), path).unwrap_or_else(|e| panic!("{text}: {e}"));
        let mut written = Vec::new();
        bvh.write_to(&mut written).unwrap();
        assert_eq!(Bvh::parse(&written, path).unwrap(), bvh, "{text}");
    }
}
