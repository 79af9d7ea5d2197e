//! weft's default body, embedded in the binary: the MakeHuman/MPFB2 body (CC0) converted
//! to SMPL's layout by `weft body import-mpfb` (see assets/body/PROVENANCE.md and
//! docs/body.md). Embedding it means `weft body …` works on a fresh clone, offline,
//! with no path to configure; at under 2 MB it costs little.

use crate::error::BodyError;
use crate::model::BodyModel;

/// The `.npz` bytes of the default body (assets/body/weft_body.npz).
pub const DEFAULT_BODY_NPZ: &[u8] = include_bytes!("../../../assets/body/weft_body.npz");

/// The name the default body goes by in messages.
pub const DEFAULT_BODY_NAME: &str = "default body (assets/body/weft_body.npz)";

/// weft's default body: 13 380 vertices, SMPL's 24 joints, 10 shape components (β in
/// standard deviations of the sampled MakeHuman shapes), no pose blend shapes; metres,
/// Y up, facing +Z, T-pose, pelvis joint at the origin.
pub fn default_body() -> Result<BodyModel, BodyError> {
    BodyModel::from_npz_bytes(DEFAULT_BODY_NPZ.to_vec(), DEFAULT_BODY_NAME)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joints::SMPL_PARENTS;

    #[test]
    fn the_default_body_loads_and_is_human_sized() {
        let m = default_body().unwrap();
        assert_eq!(m.joint_count(), 24);
        assert_eq!(m.skeleton().parents(), &SMPL_PARENTS);
        assert_eq!(m.num_betas(), 10);
        assert!((7_000..=14_000).contains(&m.vertex_count()));
        let s = m.shaped(&[]).unwrap();
        let b = m.mesh(s.vertices.clone()).bounding_box().unwrap();
        let height = b.max[1] - b.min[1];
        assert!((1.55..1.85).contains(&height), "height {height}");
        // Pelvis at the origin, 0.8–1.0 m above the feet; head above the neck above the
        // pelvis; left joints on +X.
        assert!(
            s.joints[0].iter().all(|x| x.abs() < 0.01),
            "{:?}",
            s.joints[0]
        );
        assert!((0.8..1.0).contains(&(s.joints[0][1] - b.min[1])));
        assert!(s.joints[15][1] > s.joints[12][1] && s.joints[12][1] > s.joints[0][1]);
        for (l, r) in [(1, 2), (16, 17), (18, 19), (20, 21)] {
            assert!(s.joints[l][0] > 0.05 && s.joints[r][0] < -0.05);
        }
        // T-pose: shoulder, elbow and wrist at about the same height.
        assert!((s.joints[16][1] - s.joints[20][1]).abs() < 0.03);
        // β1 is the largest mode and makes the body taller.
        let tall = m
            .mesh(m.shape_vertices(&[2.0]).unwrap())
            .bounding_box()
            .unwrap();
        let short = m
            .mesh(m.shape_vertices(&[-2.0]).unwrap())
            .bounding_box()
            .unwrap();
        assert!(tall.max[1] - tall.min[1] > short.max[1] - short.min[1] + 0.2);
    }
}
