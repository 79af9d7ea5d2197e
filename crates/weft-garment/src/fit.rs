//! Body measurements that garments are fitted to.
//!
//! Garments are built around the body's rest pose (T-pose, metres, Y up, facing +Z,
//! left on +X, pelvis joint at the origin: the frame of weft's default body and SMPL).
//! Every generator reads only [`Measurements`]: heights of landmarks, the torso cross
//! section as an ellipse per height, and radii of the limbs. They come either from
//! [`Measurements::default`] (documented averages of an adult, used when no body model
//! is available) or from a body model at shape β ([`Measurements::from_body`]), which
//! takes joint positions from J(β) and cross-section extents from the shaped vertices.

use weft_body::BodyModel;

use crate::GarmentError;

/// One torso cross section: an ellipse at height `y`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorsoSection {
    /// Height (m).
    pub y: f64,
    /// Half width along X (m).
    pub half_x: f64,
    /// Half depth along Z (m).
    pub half_z: f64,
    /// Centre along Z (m): the torso is not centred on the spine.
    pub center_z: f64,
}

/// What garment generators need to know about a body in rest pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurements {
    /// Torso cross sections from below the crotch to the armpits, ascending in `y`.
    pub torso: Vec<TorsoSection>,
    /// Natural waist height (m).
    pub waist_y: f64,
    /// Crotch height (m).
    pub crotch_y: f64,
    /// Armpit height (m).
    pub armpit_y: f64,
    /// Neck base height at the side of the neck (m).
    pub neck_y: f64,
    /// Neck radius (m).
    pub neck_r: f64,
    /// Height of the top of the shoulder above the shoulder joint (m).
    pub shoulder_top_y: f64,
    /// Lateral position of the shoulder joints (m, positive).
    pub shoulder_x: f64,
    /// Lateral position of the elbows (m).
    pub elbow_x: f64,
    /// Lateral position of the wrists (m).
    pub wrist_x: f64,
    /// Height of the arm axis in T-pose (m).
    pub arm_y: f64,
    /// Upper-arm, elbow and wrist radii (m).
    pub arm_r: [f64; 3],
    /// Lateral position of the hip joints / leg axes (m, positive).
    pub leg_x: f64,
    /// Lateral position of the knees and ankles (m, positive): legs may splay.
    pub knee_x: f64,
    /// Lateral position of the ankles (m, positive).
    pub ankle_x: f64,
    /// Knee height (m).
    pub knee_y: f64,
    /// Ankle height (m).
    pub ankle_y: f64,
    /// Thigh (at the crotch), knee and ankle radii (m).
    pub leg_r: [f64; 3],
}

impl Default for Measurements {
    /// An average adult of about 1.72 m, pelvis joint at the origin (pelvis joint about
    /// 0.93 m above the floor). Used when no body model is available.
    fn default() -> Self {
        let s = |y, half_x, half_z, center_z| TorsoSection {
            y,
            half_x,
            half_z,
            center_z,
        };
        Measurements {
            torso: vec![
                s(-0.16, 0.17, 0.11, 0.0),
                s(-0.05, 0.18, 0.12, 0.0),
                s(0.04, 0.165, 0.11, 0.01),
                s(0.13, 0.14, 0.10, 0.02),
                s(0.25, 0.155, 0.11, 0.03),
                s(0.36, 0.17, 0.11, 0.02),
            ],
            waist_y: 0.13,
            crotch_y: -0.13,
            armpit_y: 0.35,
            neck_y: 0.55,
            neck_r: 0.065,
            shoulder_top_y: 0.06,
            shoulder_x: 0.19,
            elbow_x: 0.45,
            wrist_x: 0.70,
            arm_y: 0.46,
            arm_r: [0.05, 0.04, 0.03],
            leg_x: 0.095,
            knee_x: 0.095,
            ankle_x: 0.095,
            knee_y: -0.46,
            ankle_y: -0.85,
            leg_r: [0.08, 0.052, 0.04],
        }
    }
}

impl Measurements {
    /// The torso ellipse at height `y`, linearly interpolated (clamped at the ends).
    pub fn torso_at(&self, y: f64) -> TorsoSection {
        let t = &self.torso;
        let Some(first) = t.first() else {
            return TorsoSection {
                y,
                half_x: 0.15,
                half_z: 0.1,
                center_z: 0.0,
            };
        };
        if y <= first.y {
            return TorsoSection { y, ..*first };
        }
        for w in t.windows(2) {
            if y <= w[1].y {
                let a = (y - w[0].y) / (w[1].y - w[0].y).max(1e-9);
                let l = |p: f64, q: f64| p + (q - p) * a;
                return TorsoSection {
                    y,
                    half_x: l(w[0].half_x, w[1].half_x),
                    half_z: l(w[0].half_z, w[1].half_z),
                    center_z: l(w[0].center_z, w[1].center_z),
                };
            }
        }
        TorsoSection {
            y,
            ..t[t.len() - 1]
        }
    }

    /// Leg radius at height `y` (thigh at the crotch, tapering to knee and ankle).
    pub fn leg_r_at(&self, y: f64) -> f64 {
        // The calf is as wide as the knee down to 60% of the shin.
        let calf = self.knee_y - 0.6 * (self.knee_y - self.ankle_y);
        piecewise(
            y,
            &[
                (self.crotch_y, self.leg_r[0]),
                (self.knee_y, self.leg_r[1]),
                (calf, self.leg_r[1]),
                (self.ankle_y, self.leg_r[2]),
            ],
        )
    }

    /// Lateral position of the leg axis at height `y`: hip, knee and ankle joints.
    pub fn leg_x_at(&self, y: f64) -> f64 {
        piecewise(
            y,
            &[
                (self.crotch_y, self.leg_x),
                (self.knee_y, self.knee_x),
                (self.ankle_y, self.ankle_x),
            ],
        )
    }

    /// Arm radius at lateral distance `x` (positive) from the body's mid-plane.
    pub fn arm_r_at(&self, x: f64) -> f64 {
        piecewise(
            -x,
            &[
                (-self.shoulder_x, self.arm_r[0]),
                (-self.elbow_x, self.arm_r[1]),
                (-self.wrist_x, self.arm_r[2]),
            ],
        )
    }

    /// Measurements of `model` at shape `betas`, in its rest pose.
    ///
    /// Landmark heights come from the joints J(β) (SMPL order); each torso section's
    /// ellipse is the bounding ellipse of the body vertices in a 2 cm slab around its
    /// height (arms excluded by lateral position), so a garment with positive ease lies
    /// outside the body; limb radii are the largest radial distances of the vertices
    /// near each joint.
    pub fn from_body(model: &BodyModel, betas: &[f64]) -> Result<Self, GarmentError> {
        let joints = model.joints(betas)?;
        let verts = model.shape_vertices(betas)?;
        if joints.len() < 22 {
            return Err(GarmentError::Measurements(format!(
                "the body has {} joints; fitting needs SMPL's 24",
                joints.len()
            )));
        }
        let j = |i: usize| joints[i];
        let pelvis = j(0);
        let (hip, knee, ankle) = (j(1), j(4), j(7));
        let (neck, shoulder, elbow, wrist) = (j(12), j(16), j(18), j(20));
        let rel = |p: [f64; 3]| [p[0] - pelvis[0], p[1] - pelvis[1], p[2] - pelvis[2]];
        let (hip, knee, ankle) = (rel(hip), rel(knee), rel(ankle));
        let (neck, shoulder, elbow, wrist) = (rel(neck), rel(shoulder), rel(elbow), rel(wrist));
        let verts: Vec<[f64; 3]> = verts.iter().map(|&p| rel(p)).collect();
        let shoulder_x = shoulder[0].abs();
        let crotch_y = hip[1] - 0.6 * (hip[1] - knee[1]).abs() * 0.25;
        let armpit_y = shoulder[1] - 0.11 * (shoulder[1] - hip[1]).abs() / 0.55;
        let mut torso = Vec::new();
        let steps = 24;
        for s in 0..=steps {
            let y = crotch_y - 0.03 + (armpit_y - crotch_y + 0.03) * s as f64 / steps as f64;
            let slab: Vec<&[f64; 3]> = verts
                .iter()
                .filter(|p| {
                    // Arms only reach down to the armpit in T-pose; hips are wider than
                    // the shoulders' 85%, so the lateral cut applies near the armpit only.
                    (p[1] - y).abs() < 0.01
                        && (y < armpit_y - 0.06 || p[0].abs() < 0.85 * shoulder_x.max(0.1))
                })
                .collect();
            if slab.len() < 4 {
                continue;
            }
            let zmin = slab.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
            let zmax = slab.iter().map(|p| p[2]).fold(f64::NEG_INFINITY, f64::max);
            let cz = 0.5 * (zmin + zmax);
            let hx = slab.iter().map(|p| p[0].abs()).fold(0.0, f64::max);
            let hz = 0.5 * (zmax - zmin);
            // Smallest scale of the (hx, hz) ellipse that contains every slab vertex.
            let k = slab
                .iter()
                .map(|p| ((p[0] / hx).powi(2) + ((p[2] - cz) / hz).powi(2)).sqrt())
                .fold(1.0, f64::max);
            torso.push(TorsoSection {
                y,
                half_x: hx * k,
                half_z: hz * k,
                center_z: cz,
            });
        }
        let radial = |c: [f64; 3], axis: usize, side: f64, reach: f64| {
            verts
                .iter()
                .filter(|p| (p[axis] - c[axis]).abs() < reach && p[0] * side > 0.0)
                .map(|p| {
                    let d: f64 = (0..3)
                        .filter(|&a| a != axis)
                        .map(|a| (p[a] - c[a]).powi(2))
                        .sum();
                    d.sqrt()
                })
                .fold(0.0, f64::max)
        };
        let top_y = verts
            .iter()
            .filter(|p| (p[0].abs() - shoulder_x).abs() < 0.02 && p[2].abs() < 0.08)
            .map(|p| p[1])
            .fold(f64::NEG_INFINITY, f64::max);
        let m = Measurements {
            torso,
            waist_y: 0.5 * (hip[1] + shoulder[1]) - 0.05,
            crotch_y,
            armpit_y,
            neck_y: neck[1],
            neck_r: 0.065,
            shoulder_top_y: (top_y - shoulder[1]).max(0.03),
            shoulder_x,
            elbow_x: elbow[0].abs(),
            wrist_x: wrist[0].abs(),
            arm_y: shoulder[1],
            arm_r: [
                radial(
                    [elbow[0] * 0.5 + shoulder[0] * 0.5, shoulder[1], shoulder[2]],
                    0,
                    1.0,
                    0.02,
                )
                .min(0.09),
                radial(elbow, 0, 1.0, 0.02).min(0.08),
                radial(wrist, 0, 1.0, 0.02).min(0.06),
            ],
            leg_x: hip[0].abs(),
            knee_x: knee[0].abs(),
            ankle_x: ankle[0].abs(),
            knee_y: knee[1],
            ankle_y: ankle[1],
            leg_r: [
                radial([hip[0], crotch_y - 0.03, hip[2]], 1, 1.0, 0.01).min(hip[0].abs() + 0.02),
                radial(knee, 1, 1.0, 0.01).min(0.09),
                radial([ankle[0], ankle[1] + 0.05, ankle[2]], 1, 1.0, 0.01).min(0.07),
            ],
        };
        m.check()?;
        Ok(m)
    }

    /// Rejects measurements that would give degenerate garments.
    pub fn check(&self) -> Result<(), GarmentError> {
        let positive = self
            .torso
            .iter()
            .all(|s| s.half_x > 0.0 && s.half_z > 0.0 && s.y.is_finite())
            && self
                .arm_r
                .iter()
                .chain(&self.leg_r)
                .all(|r| *r > 0.0 && r.is_finite())
            && self.torso.len() >= 2;
        let ordered = self.ankle_y < self.knee_y
            && self.knee_y < self.crotch_y
            && self.crotch_y < self.waist_y
            && self.waist_y < self.armpit_y
            && self.armpit_y < self.arm_y
            && self.shoulder_x < self.elbow_x
            && self.elbow_x < self.wrist_x;
        if positive && ordered {
            Ok(())
        } else {
            Err(GarmentError::Measurements(format!("{self:?}")))
        }
    }
}

/// Linear interpolation through `(x, value)` knots sorted by descending `x`, clamped.
fn piecewise(x: f64, knots: &[(f64, f64)]) -> f64 {
    let (Some(first), Some(last)) = (knots.first(), knots.last()) else {
        return 0.0;
    };
    if x >= first.0 {
        return first.1;
    }
    for w in knots.windows(2) {
        if x >= w[1].0 {
            let t = (w[0].0 - x) / (w[0].0 - w[1].0).max(1e-9);
            return w[0].1 + (w[1].1 - w[0].1) * t;
        }
    }
    last.1
}
