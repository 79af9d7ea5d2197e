//! Any bytes: parsing a BVH and retargeting it to SMPL (what `weft` does with a `.bvh`
//! motion) never panics and holds at most `linear_bound` bytes while it reads; a BVH
//! that parses can be posed and written, and what it writes parses to the same skeleton
//! and frame count.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use weft_fuzz::{bounded, linear_bound};
use weft_motion::{retarget_bvh, Bvh, MotionFileOptions};

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.bvh");
    let options = MotionFileOptions::default().retarget();
    let (parsed, _) = bounded(data.len(), linear_bound(data.len()), || {
        let bvh = Bvh::parse(data, path)?;
        let motion = retarget_bvh(&bvh, path, &options);
        Ok::<_, weft_motion::MotionError>((bvh, motion))
    });
    let Ok((bvh, motion)) = parsed else {
        return;
    };
    if let Ok((motion, _)) = motion {
        assert!(motion.frame_count() >= 1);
    }
    let _ = bvh.rest_positions();
    let _ = bvh.global_transforms(bvh.frame_count() - 1);
    let mut text = Vec::new();
    bvh.write_to(&mut text).expect("writing to memory");
    let back = match Bvh::parse(&text, path) {
        Ok(b) => b,
        Err(e) => panic!("a written BVH does not parse: {e}\n{}", String::from_utf8_lossy(&text)),
    };
    assert_eq!(back.joints().len(), bvh.joints().len());
    assert_eq!(back.frame_count(), bvh.frame_count());
    assert_eq!(back.channel_count(), bvh.channel_count());
});
