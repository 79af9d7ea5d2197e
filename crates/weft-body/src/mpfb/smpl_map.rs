//! How MPFB's "standard" rig (`rig.default.json`, 163 bones) maps onto SMPL's 24 joints.
//!
//! Two tables:
//! - **where each SMPL joint is**: the head of one MPFB bone, or the mean of several
//!   heads (SMPL's foot joint sits at the ball of the foot, the mean of the five toe
//!   bases; its hand joint at the knuckles, the mean of the four finger bases);
//! - **which bones' skinning weights it takes**: the listed anchor bones, and every other
//!   bone through its nearest listed ancestor. Merged bones' weights add up, so each
//!   vertex's weights still sum to 1.
//!
//! Choices (heights for the default 1.67 m base mesh): SMPL's spine1/2/3 go to MPFB's
//! spine04 (0.95 m), spine02 (1.09 m) and spine01 (1.24 m), with spine03 merged into
//! spine1 and the breasts into spine3; the neck takes neck01–03, the head every face
//! bone (jaw, eyes, tongue, expression bones); the collar takes clavicle and
//! shoulder01 (the scapula); the wrist takes the metacarpals; the hand all finger
//! bones, thumb included; the foot all toe bones.

/// Where each SMPL joint is: the MPFB bones whose heads it averages, in SMPL order
/// (see [`crate::joints::SMPL_JOINT_NAMES`]).
pub const JOINT_HEADS: [&[&str]; 24] = [
    &["spine05"],
    &["upperleg01.L"],
    &["upperleg01.R"],
    &["spine04"],
    &["lowerleg01.L"],
    &["lowerleg01.R"],
    &["spine02"],
    &["foot.L"],
    &["foot.R"],
    &["spine01"],
    &["toe1-1.L", "toe2-1.L", "toe3-1.L", "toe4-1.L", "toe5-1.L"],
    &["toe1-1.R", "toe2-1.R", "toe3-1.R", "toe4-1.R", "toe5-1.R"],
    &["neck01"],
    &["clavicle.L"],
    &["clavicle.R"],
    &["head"],
    &["upperarm01.L"],
    &["upperarm01.R"],
    &["lowerarm01.L"],
    &["lowerarm01.R"],
    &["wrist.L"],
    &["wrist.R"],
    &["finger2-1.L", "finger3-1.L", "finger4-1.L", "finger5-1.L"],
    &["finger2-1.R", "finger3-1.R", "finger4-1.R", "finger5-1.R"],
];

/// Anchor bones and the SMPL joint whose weights they join; other bones follow their
/// nearest anchored ancestor.
pub const WEIGHT_ANCHORS: &[(&str, usize)] = &[
    ("root", 0),
    ("spine05", 0),
    ("pelvis.L", 0),
    ("pelvis.R", 0),
    ("upperleg01.L", 1),
    ("upperleg01.R", 2),
    ("spine04", 3),
    ("lowerleg01.L", 4),
    ("lowerleg01.R", 5),
    ("spine02", 6),
    ("foot.L", 7),
    ("foot.R", 8),
    ("spine01", 9),
    ("breast.L", 9),
    ("breast.R", 9),
    ("toe1-1.L", 10),
    ("toe2-1.L", 10),
    ("toe3-1.L", 10),
    ("toe4-1.L", 10),
    ("toe5-1.L", 10),
    ("toe1-1.R", 11),
    ("toe2-1.R", 11),
    ("toe3-1.R", 11),
    ("toe4-1.R", 11),
    ("toe5-1.R", 11),
    ("neck01", 12),
    ("clavicle.L", 13),
    ("clavicle.R", 14),
    ("head", 15),
    ("upperarm01.L", 16),
    ("upperarm01.R", 17),
    ("lowerarm01.L", 18),
    ("lowerarm01.R", 19),
    ("wrist.L", 20),
    ("wrist.R", 21),
    ("finger1-1.L", 22),
    ("finger2-1.L", 22),
    ("finger3-1.L", 22),
    ("finger4-1.L", 22),
    ("finger5-1.L", 22),
    ("finger1-1.R", 23),
    ("finger2-1.R", 23),
    ("finger3-1.R", 23),
    ("finger4-1.R", 23),
    ("finger5-1.R", 23),
];

/// The SMPL joint an anchor bone feeds, if it is one.
pub fn anchor(bone: &str) -> Option<usize> {
    WEIGHT_ANCHORS
        .iter()
        .find(|(b, _)| *b == bone)
        .map(|&(_, j)| j)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joints::SMPL_MIRROR;

    #[test]
    fn tables_are_mirror_symmetric() {
        let mirror = |b: &str| {
            b.replace(".L", ".#")
                .replace(".R", ".L")
                .replace(".#", ".R")
        };
        for (j, heads) in JOINT_HEADS.iter().enumerate() {
            let m: Vec<String> = heads.iter().map(|b| mirror(b)).collect();
            assert_eq!(m, JOINT_HEADS[SMPL_MIRROR[j]], "joint {j}");
        }
        for (b, j) in WEIGHT_ANCHORS {
            assert_eq!(anchor(&mirror(b)), Some(SMPL_MIRROR[*j]), "{b}");
        }
        // Every joint gets weights from some anchor.
        for j in 0..24 {
            assert!(WEIGHT_ANCHORS.iter().any(|&(_, k)| k == j), "joint {j}");
        }
    }
}
