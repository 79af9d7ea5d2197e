//! Very large BVH skeletons (issue 17 item 8): reading, writing and retargeting a file
//! of 100 000 joints is linear in its size and needs no call stack as deep as the
//! hierarchy.
//!
//! The parser used to check each new joint name against every joint before it, so
//! 100 000 joints took 26 s and 200 000 over a minute; the writer recursed once per
//! level, so a 100 000-deep chain overflowed the stack, and indented each level one tab
//! deeper, so its text grew with the square of the depth. The time bound below is
//! generous (the fixed code takes well under a second here even unoptimised); the
//! quadratic parser took over 20 s on the same input.

use std::path::Path;
use std::time::{Duration, Instant};

use weft_motion::{
    generate, motion_to_bvh, retarget_bvh, Bvh, BvhJoint, MotionKind, ProceduralParams,
    RetargetOptions, DEFAULT_REST_JOINTS,
};

/// Joints added below the SMPL skeleton.
const EXTRA: usize = 100_000;

/// Generous: for a parse that is linear in the file's size.
const LIMIT: Duration = Duration::from_secs(10);

#[test]
fn a_bvh_with_a_100k_joint_chain_is_written_parsed_and_retargeted_in_linear_time() {
    // A two-frame walk on the SMPL skeleton, with a chain of 100 000 joints without
    // channels hanging below its head: the frame values stay those of the walk.
    let mut p = ProceduralParams::new(MotionKind::Walk);
    p.frames = 2;
    let walk = generate(&p).unwrap();
    let smpl = motion_to_bvh(&walk, &DEFAULT_REST_JOINTS).unwrap();
    let head = smpl.joint_index("head").unwrap();
    let mut joints: Vec<BvhJoint> = smpl.joints().to_vec();
    let values: Vec<f64> = (0..smpl.frame_count())
        .flat_map(|f| smpl.frame(f).to_vec())
        .collect();
    for k in 0..EXTRA {
        let parent = if k == 0 { head } else { joints.len() - 1 };
        joints.push(BvhJoint {
            name: format!("chain{k}"),
            parent: Some(parent),
            offset: [0.0, 1e-6, 0.0],
            channels: Vec::new(),
            end_sites: Vec::new(),
            line: 0,
        });
    }
    let big = Bvh::new(joints, smpl.frame_time(), values).unwrap();

    // Writing: iterative, and the text linear in the joints (indentation is capped).
    let mut text = Vec::new();
    big.write_to(&mut text).unwrap();
    assert!(
        text.len() < 400 * (EXTRA + 24),
        "{} bytes for {} joints",
        text.len(),
        EXTRA + 24
    );

    // Parsing.
    let started = Instant::now();
    let back = Bvh::parse(&text, Path::new("chain.bvh")).unwrap();
    let parse = started.elapsed();
    assert_eq!(back.joints().len(), EXTRA + 24);
    // The deepest joint hangs 100 000 levels below the head.
    let deepest = back.joint_index(&format!("chain{}", EXTRA - 1)).unwrap();
    let mut depth = 0;
    let mut j = deepest;
    while let Some(p) = back.joints()[j].parent {
        depth += 1;
        j = p;
    }
    assert!(depth > EXTRA, "{depth}");
    assert!(
        parse < LIMIT,
        "parsing {} joints took {parse:?}",
        EXTRA + 24
    );

    // Retargeting: the chain is unused, the walk comes through.
    let started = Instant::now();
    let (motion, report) =
        retarget_bvh(&back, Path::new("chain.bvh"), &RetargetOptions::default()).unwrap();
    let retarget = started.elapsed();
    assert!(retarget < LIMIT, "retargeting took {retarget:?}");
    assert_eq!(report.unused.len(), EXTRA);
    let d = motion.distance(&walk).unwrap();
    assert!(d.rotation < 1e-4 && d.translation < 1e-4, "{d:?}");

    // A duplicate name is still found, at the end of the file.
    let dup = String::from_utf8(text).unwrap().replacen(
        &format!("JOINT chain{}\n", EXTRA - 1),
        "JOINT chain7\n",
        1,
    );
    let e = Bvh::parse(dup.as_bytes(), Path::new("dup.bvh"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("a second joint named 'chain7'"), "{e}");
}
