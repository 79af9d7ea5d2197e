//! A seeded library of procedural motions — walk, run, jump, dance, kick, raise arms,
//! twist, bow — for tests, demos and datasets that need motion without capture files.
//!
//! Each motion is a periodic gait or gesture: joint angles are sums of sinusoids of one
//! phase φ(t) = 2π·f·t + φ₀, shaped by smooth envelopes (`(1 − cos φ)/2`, its square,
//! smoothstep, `max(0, sin φ)²`), so every joint angle is at least C¹ in time (most are
//! C^∞). Angles then pass through [`soft_limit`](super::limits) into the joint limits of
//! [`JOINT_LIMITS_DEG`](super::JOINT_LIMITS_DEG), which keeps them C¹ even where a
//! large amplitude reaches a limit. At amplitude 1 no motion comes near a limit.
//!
//! The root translation follows the legs: walking and running move forward along +Z at
//! exactly the given speed, and the pelvis height is chosen each frame so that the lower
//! ankle (a smooth minimum of the two) stays at its rest height, which produces the
//! gait's natural bob; running adds a flight lift. Motions in place keep the ankles
//! planted (both ankles' midpoint, or the support ankle when kicking), so bending the
//! knees lowers the body rather than sinking the feet; jumping adds the flight height.
//! Feet are planted on the built-in rest skeleton
//! ([`DEFAULT_REST_JOINTS`](super::DEFAULT_REST_JOINTS)); on a body of other
//! proportions they are off by millimetres.
//!
//! A seed draws small variations (SplitMix64): the starting phase, ±4 % frequency, ±8 %
//! amplitude, a few degrees of arm carriage, lean and knee bend. The same parameters and
//! seed give the same motion, bit for bit.

use std::f64::consts::{PI, TAU};
use std::fmt;

use nalgebra::{UnitQuaternion, Vector3};
use weft_body::joints::SMPL_JOINT_COUNT;
use weft_body::Pose;
use weft_mesh::rng::SplitMix64;

use super::error::MotionError;
use super::fk::posed_joints;
use super::limits::{soft_limit, soft_limit_pose};
use super::rest::DEFAULT_REST_JOINTS;
use super::rot::about_axis;
use super::types::{Motion, MAX_FPS, MAX_FRAMES};

/// The motions of the procedural library.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MotionKind {
    /// Walking forward along +Z; speed in m/s (default 1.2, up to 2.5).
    Walk,
    /// Running forward along +Z; speed in m/s (default 3.0, up to 8).
    Run,
    /// Jumping in place, one jump every 1.2 s at speed 1.
    Jump,
    /// Bouncing, swaying dance at 120 beats per minute at speed 1.
    Dance,
    /// A front kick with the right leg every 2 s at speed 1.
    Kick,
    /// Raising both arms overhead and lowering them, every 3 s at speed 1.
    RaiseArms,
    /// Twisting the torso left and right, every 2.5 s at speed 1.
    Twist,
    /// Bowing forward from the hips and back up, every 4 s at speed 1.
    Bow,
}

impl MotionKind {
    /// Every kind.
    pub const ALL: [MotionKind; 8] = [
        MotionKind::Walk,
        MotionKind::Run,
        MotionKind::Jump,
        MotionKind::Dance,
        MotionKind::Kick,
        MotionKind::RaiseArms,
        MotionKind::Twist,
        MotionKind::Bow,
    ];

    /// The kind's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            MotionKind::Walk => "walk",
            MotionKind::Run => "run",
            MotionKind::Jump => "jump",
            MotionKind::Dance => "dance",
            MotionKind::Kick => "kick",
            MotionKind::RaiseArms => "raise-arms",
            MotionKind::Twist => "twist",
            MotionKind::Bow => "bow",
        }
    }

    /// The kind called `name` (any case; `_` and `-` alike).
    pub fn parse(name: &str) -> Option<Self> {
        let n = name.to_ascii_lowercase().replace('_', "-");
        Self::ALL.into_iter().find(|k| k.name() == n)
    }

    /// Whether speed is a forward speed in m/s (walk, run) rather than a tempo factor.
    pub fn is_locomotion(self) -> bool {
        matches!(self, MotionKind::Walk | MotionKind::Run)
    }

    /// The speed used when none is given: m/s for locomotion, 1 (natural tempo) else.
    pub fn default_speed(self) -> f64 {
        match self {
            MotionKind::Walk => 1.2,
            MotionKind::Run => 3.0,
            _ => 1.0,
        }
    }

    /// The accepted speed range, inclusive.
    pub fn speed_range(self) -> (f64, f64) {
        match self {
            MotionKind::Walk => (0.0, 2.5),
            MotionKind::Run => (0.0, 8.0),
            _ => (0.1, 5.0),
        }
    }
}

impl fmt::Display for MotionKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The largest accepted amplitude factor.
pub const MAX_AMPLITUDE: f64 = 3.0;

/// What to generate.
#[derive(Clone, Debug, PartialEq)]
pub struct ProceduralParams {
    /// Which motion.
    pub kind: MotionKind,
    /// Number of frames, 1 to [`MAX_FRAMES`].
    pub frames: usize,
    /// Frames per second, above 0 and at most 1000.
    pub fps: f64,
    /// Seed of the small variations.
    pub seed: u64,
    /// Forward speed in m/s for walk and run, tempo factor for the others; `None` for
    /// [`MotionKind::default_speed`].
    pub speed: Option<f64>,
    /// Scales every joint excursion (and the jump height); 1 is natural, 0 stands still,
    /// at most [`MAX_AMPLITUDE`].
    pub amplitude: f64,
}

impl ProceduralParams {
    /// 120 frames at 30 fps, seed 0, default speed, amplitude 1.
    pub fn new(kind: MotionKind) -> Self {
        ProceduralParams {
            kind,
            frames: 120,
            fps: 30.0,
            seed: 0,
            speed: None,
            amplitude: 1.0,
        }
    }

    /// Fails with [`MotionError::Parameter`] naming the first parameter out of range.
    pub fn check(&self) -> Result<(), MotionError> {
        let bad = |m: String| Err(MotionError::Parameter(m));
        if self.frames == 0 || self.frames > MAX_FRAMES {
            return bad(format!(
                "{} frames; expected 1 to {MAX_FRAMES}",
                self.frames
            ));
        }
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= MAX_FPS) {
            return bad(format!(
                "frame rate {}; expected frames per second above 0 and at most {MAX_FPS}",
                self.fps
            ));
        }
        let (lo, hi) = self.kind.speed_range();
        if let Some(s) = self.speed {
            if !(s.is_finite() && (lo..=hi).contains(&s)) {
                let unit = if self.kind.is_locomotion() {
                    " m/s"
                } else {
                    " (a tempo factor)"
                };
                return bad(format!(
                    "speed {s} for {}; expected {lo} to {hi}{unit}",
                    self.kind
                ));
            }
        }
        if !(self.amplitude.is_finite() && (0.0..=MAX_AMPLITUDE).contains(&self.amplitude)) {
            return bad(format!(
                "amplitude {}; expected 0 to {MAX_AMPLITUDE}",
                self.amplitude
            ));
        }
        Ok(())
    }
}

/// Generates a procedural motion (see the module documentation). Parameters are
/// checked before anything is allocated.
pub fn generate(params: &ProceduralParams) -> Result<Motion, MotionError> {
    params.check()?;
    let speed = params.speed.unwrap_or(params.kind.default_speed());
    let var = Variation::draw(params.seed, params.kind);
    let rest = &DEFAULT_REST_JOINTS;
    let mut poses: Vec<Pose> = Vec::with_capacity(params.frames);
    let mut trans = Vec::with_capacity(params.frames);
    for k in 0..params.frames {
        let t = k as f64 / params.fps;
        let frame = frame_at(params.kind, t, speed, params.amplitude, &var);
        let mut aa = frame.axis_angles();
        soft_limit_pose(&mut aa);
        let pose: Pose = aa.map(|r| r.map(|x| x as f32));
        let posed = posed_joints(&pose, [0.0; 3], rest);
        let ankle = |j: usize| Vector3::from(posed[j]);
        let rest_ankle = |j: usize| Vector3::from(rest[j]);
        let correction = match frame.anchor {
            Anchor::Both => (rest_ankle(7) + rest_ankle(8)) * 0.5 - (ankle(7) + ankle(8)) * 0.5,
            Anchor::Left => rest_ankle(7) - ankle(7),
            Anchor::LowestY => Vector3::new(
                0.0,
                rest[7][1] - smooth_min(posed[7][1], posed[8][1], 60.0),
                0.0,
            ),
        };
        let p = correction + frame.shift;
        poses.push(pose);
        trans.push([p.x as f32, p.y as f32, p.z as f32]);
    }
    Motion::new(params.fps, poses, trans, None)
}

/// How the root translation keeps the feet on the floor.
#[derive(Clone, Copy, Debug)]
enum Anchor {
    /// Both ankles' midpoint stays at its rest place.
    Both,
    /// The left ankle stays at its rest place (the right leg kicks).
    Left,
    /// Only the height: the lower ankle (smooth minimum) stays at rest height.
    LowestY,
}

/// One frame before limits and anchoring: local rotations, the anchoring rule and a
/// translation added on top (forward progress, sway, flight).
struct Frame {
    rot: [UnitQuaternion<f64>; SMPL_JOINT_COUNT],
    anchor: Anchor,
    shift: Vector3<f64>,
}

impl Frame {
    /// The local rotations as axis-angle vectors (radians), before limits.
    fn axis_angles(&self) -> [[f64; 3]; SMPL_JOINT_COUNT] {
        self.rot.map(|q| {
            let v = q.scaled_axis();
            [v.x, v.y, v.z]
        })
    }
}

/// The seeded variations of one motion.
#[derive(Clone, Debug)]
struct Variation {
    phase: f64,
    freq: f64,
    amp: f64,
    /// Extra degrees the arms hang down (negative: further out).
    arm: f64,
    /// Extra degrees of forward lean.
    lean: f64,
    /// Extra degrees of knee bend.
    knee: f64,
}

impl Variation {
    fn draw(seed: u64, kind: MotionKind) -> Self {
        // Each kind draws from its own stream, so seed 0 of walk and run differ.
        let salt = (kind as u64 + 1).wrapping_mul(0x5851_f42d_4c95_7f2d);
        let mut r = SplitMix64::new(seed ^ salt);
        Variation {
            phase: r.uniform(0.0, TAU),
            freq: r.uniform(0.96, 1.04),
            amp: r.uniform(0.92, 1.08),
            arm: r.uniform(-4.0, 4.0),
            lean: r.uniform(-2.0, 2.0),
            knee: r.uniform(0.0, 4.0),
        }
    }
}

/// A rotation about one axis, its angle smoothly saturated below ±160°: at large
/// amplitudes a formula may ask for more than 180°, whose axis-angle would flip to the
/// other side and make the pose jump; saturating first keeps every pose C¹ in time
/// (the joint limits then bound it further).
fn about(axis: usize, deg: f64) -> UnitQuaternion<f64> {
    about_axis(axis, soft_limit(deg, -160.0, 160.0).to_radians())
}
fn rx(deg: f64) -> UnitQuaternion<f64> {
    about(0, deg)
}
fn ry(deg: f64) -> UnitQuaternion<f64> {
    about(1, deg)
}
fn rz(deg: f64) -> UnitQuaternion<f64> {
    about(2, deg)
}

/// A smooth minimum (log-sum-exp with sharpness `k` per metre), C^∞, within
/// `ln 2 / k` of the true minimum.
fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    let m = a.min(b);
    m - ((-k * (a - m)).exp() + (-k * (b - m)).exp()).ln() / k
}

/// A C¹ bump: `max(0, x)²`.
fn pos2(x: f64) -> f64 {
    let p = x.max(0.0);
    p * p
}

/// Writes joint rotations in anatomical terms, both sides with the same sign meaning.
/// Angles are in degrees; see [`super::limits`] for the axis conventions.
struct Builder {
    rot: [UnitQuaternion<f64>; SMPL_JOINT_COUNT],
}

impl Builder {
    fn new() -> Self {
        Builder {
            rot: [UnitQuaternion::identity(); SMPL_JOINT_COUNT],
        }
    }

    /// Pelvis: turn left (yaw), tilt forward, raise the left side (list).
    fn pelvis(&mut self, yaw: f64, tilt: f64, list: f64) {
        self.rot[0] = ry(yaw) * rx(tilt) * rz(list);
    }

    /// Each of the three spine joints: bend forward, turn left, bend left... sideways.
    fn spine(&mut self, flex: f64, yaw: f64, side: f64) {
        for j in [3, 6, 9] {
            self.rot[j] = ry(yaw) * rx(flex) * rz(side);
        }
    }

    fn neck_head(&mut self, flex: f64, yaw: f64, side: f64) {
        self.rot[12] = ry(0.5 * yaw) * rx(0.5 * flex) * rz(0.5 * side);
        self.rot[15] = ry(0.5 * yaw) * rx(0.5 * flex) * rz(0.5 * side);
    }

    /// One leg (`left`): hip flexion (thigh forward), abduction (away from the
    /// midline), knee flexion, ankle plantar flexion, toe extension.
    fn leg(&mut self, left: bool, hip: f64, abduct: f64, knee: f64, ankle: f64, toes: f64) {
        let side = if left { 1.0 } else { -1.0 };
        let (h, k, a, f) = if left { (1, 4, 7, 10) } else { (2, 5, 8, 11) };
        self.rot[h] = rx(-hip) * rz(side * abduct);
        self.rot[k] = rx(knee);
        self.rot[a] = rx(ankle);
        self.rot[f] = rx(-toes);
    }

    /// One arm (`left`): lowered `down` degrees from the T-pose, swung `forward`
    /// degrees, elbow bent `elbow` degrees; `shrug` raises the collar bone.
    fn arm(&mut self, left: bool, down: f64, forward: f64, elbow: f64, shrug: f64) {
        let side = if left { 1.0 } else { -1.0 };
        let (c, s, e) = if left { (13, 16, 18) } else { (14, 17, 19) };
        self.rot[c] = rz(side * shrug);
        self.rot[s] = rx(-forward) * rz(-side * down);
        self.rot[e] = ry(-side * elbow);
    }
}

fn frame_at(kind: MotionKind, t: f64, speed: f64, amplitude: f64, var: &Variation) -> Frame {
    let amp = amplitude * var.amp;
    let mut b = Builder::new();
    let mut shift = Vector3::zeros();
    let anchor;
    match kind {
        MotionKind::Walk | MotionKind::Run => {
            let run = kind == MotionKind::Run;
            let v = speed;
            // Cadence (steps per second) grows with speed; step length follows.
            let cadence = if run {
                2.7 * (v / 3.0).powf(0.3)
            } else {
                1.8 * (v / 1.3).sqrt()
            } * var.freq;
            let step = if cadence > 0.0 { v / cadence } else { 0.0 };
            // Hip swing that covers the step with a 0.9 m leg.
            let swing = (step / 1.8).atan().to_degrees() * if run { 0.8 } else { 1.0 };
            let natural = if run { 25.0 } else { 20.0 };
            let scale = amp * (swing / natural).min(1.3);
            let phi = PI * cadence * t + var.phase;
            for left in [true, false] {
                let p = if left { phi } else { phi + PI };
                let (s, c) = p.sin_cos();
                // Phase p: heel strike at π/2, toe-off near −π/2. The hip leads by
                // 0.5 rad, as in measured gait (it extends most before toe-off and
                // flexes most before heel strike), so the thigh is already forward
                // when the knee bends most in swing.
                let hip = (if run { 0.6 } else { 0.4 }) * natural * scale
                    + natural * scale * (p + 0.5).sin();
                let swing_bump = (1.0 + (p + 0.13).cos()) / 2.0;
                let knee = if run {
                    15.0 + var.knee + 95.0 * scale * swing_bump.powi(2)
                } else {
                    // Swing flexion (about 60°) and the small loading-response bend
                    // after heel strike.
                    5.0 + var.knee
                        + 50.0 * scale * swing_bump.powi(3)
                        + 10.0 * scale * ((1.0 + (p - 2.3).cos()) / 2.0).powi(4)
                };
                let ankle = if run {
                    (10.0 - 10.0 * s - 15.0 * c) * scale
                } else {
                    (7.5 - 7.5 * s - 12.5 * c) * scale
                };
                let toes = (if run { 20.0 } else { 15.0 }) * scale * ((1.0 - s) / 2.0).powi(2);
                b.leg(left, hip, 2.0, knee, ankle, toes);
                // Arms swing against the legs: the left arm forward with the right leg.
                let arm_swing = (if run { 35.0 } else { 18.0 }) * scale * -s;
                let elbow = if run {
                    85.0 - 15.0 * s * scale
                } else {
                    15.0 - 8.0 * s * scale
                };
                b.arm(left, 72.0 + var.arm, arm_swing, elbow, 0.0);
            }
            let (s, c) = phi.sin_cos();
            let lean = if run { 8.0 } else { 3.0 } + var.lean;
            b.pelvis(
                -(if run { 7.0 } else { 5.0 }) * s * scale,
                lean + 1.5 * (2.0 * phi).sin() * scale,
                -(if run { 4.0 } else { 3.0 }) * c * scale,
            );
            b.spine(
                if run { 4.0 } else { 1.0 },
                (if run { 3.5 } else { 2.7 }) * s * scale,
                0.0,
            );
            b.neck_head(-lean * 0.5, -s * scale, 0.0);
            anchor = Anchor::LowestY;
            let lift = if run {
                0.05 * scale * (1.0 - (2.0 * phi).cos()) / 2.0
            } else {
                0.0
            };
            shift = Vector3::new(-0.015 * c * scale, lift, v * t);
        }
        MotionKind::Jump => {
            let phi = TAU * speed * var.freq * t / 1.2 + var.phase;
            let w = phi.sin();
            let crouch = ((1.0 - w) / 2.0).powi(2);
            let flight = pos2(w);
            for left in [true, false] {
                b.leg(
                    left,
                    5.0 + (70.0 * crouch + 25.0 * flight) * amp,
                    3.0,
                    5.0 + var.knee + (80.0 * crouch + 20.0 * flight) * amp,
                    (-18.0 * crouch + 25.0 * flight) * amp,
                    0.0,
                );
                b.arm(
                    left,
                    65.0 + var.arm,
                    (-40.0 * crouch + 70.0 * flight) * amp,
                    20.0,
                    0.0,
                );
            }
            b.pelvis(0.0, var.lean, 0.0);
            b.spine(15.0 * crouch * amp / 3.0, 0.0, 0.0);
            anchor = Anchor::Both;
            shift.y = 0.3 * amp * flight;
        }
        MotionKind::Dance => {
            let phi = TAU * speed * var.freq * t + var.phase;
            let bounce = (1.0 - (2.0 * phi).cos()) / 2.0;
            let (s, _) = phi.sin_cos();
            for left in [true, false] {
                let side = if left { 1.0 } else { -1.0 };
                b.leg(
                    left,
                    4.0 + 12.0 * bounce * amp,
                    4.0 + 3.0 * side * s * amp,
                    8.0 + var.knee + 18.0 * bounce * amp,
                    -8.0 * bounce * amp,
                    0.0,
                );
                let arm_phase = if left { 0.5 } else { 0.5 + PI };
                b.arm(
                    left,
                    40.0 + var.arm - 30.0 * side * s * amp,
                    25.0 * (2.0 * phi + arm_phase).sin() * amp,
                    70.0 + 30.0 * side * (2.0 * phi).sin() * amp,
                    5.0 * bounce * amp,
                );
            }
            b.pelvis(10.0 * (phi + 0.7).sin() * amp, var.lean, 6.0 * s * amp);
            b.spine(1.0, -3.0 * (phi + 0.7).sin() * amp, -2.5 * s * amp);
            b.neck_head(
                8.0 * (2.0 * phi).sin() * amp,
                0.0,
                10.0 * (phi + 1.0).sin() * amp,
            );
            anchor = Anchor::Both;
        }
        MotionKind::Kick => {
            let phi = TAU * speed * var.freq * t / 2.0 + var.phase;
            let e = ((1.0 - phi.cos()) / 2.0).powi(2);
            b.leg(
                true,
                5.0 + 5.0 * e,
                2.0,
                8.0 + var.knee + 12.0 * e,
                -6.0 * e,
                0.0,
            );
            b.leg(
                false,
                85.0 * e * amp,
                2.0,
                280.0 * e * (1.0 - e) * amp + var.knee,
                30.0 * e * amp,
                0.0,
            );
            b.arm(
                true,
                55.0 + var.arm - 20.0 * e * amp,
                25.0 * e * amp,
                30.0,
                0.0,
            );
            b.arm(
                false,
                55.0 + var.arm - 20.0 * e * amp,
                -30.0 * e * amp,
                30.0,
                0.0,
            );
            b.pelvis(0.0, var.lean - 8.0 * e * amp, 0.0);
            b.spine(-4.0 * e * amp, 0.0, 0.0);
            anchor = Anchor::Left;
        }
        MotionKind::RaiseArms => {
            let phi = TAU * speed * var.freq * t / 3.0 + var.phase;
            let e = (1.0 - phi.cos()) / 2.0;
            for left in [true, false] {
                b.arm(
                    left,
                    72.0 + var.arm - 140.0 * e * amp,
                    0.0,
                    10.0,
                    25.0 * e * amp,
                );
                b.leg(left, 0.0, 3.0, 3.0 + var.knee, 0.0, 0.0);
            }
            b.pelvis(0.0, var.lean, 0.0);
            b.spine(-2.0 * e * amp, 0.0, 0.0);
            b.neck_head(-8.0 * e * amp, 0.0, 0.0);
            anchor = Anchor::Both;
        }
        MotionKind::Twist => {
            let phi = TAU * speed * var.freq * t / 2.5 + var.phase;
            let s = phi.sin();
            for left in [true, false] {
                let side = if left { 1.0 } else { -1.0 };
                b.arm(left, 55.0 + var.arm, -15.0 * side * s * amp, 40.0, 0.0);
                b.leg(left, 3.0, 4.0, 6.0 + var.knee, 0.0, 0.0);
            }
            b.pelvis(-6.0 * s * amp, var.lean, 0.0);
            b.spine(1.0, 14.0 * s * amp, 0.0);
            b.neck_head(0.0, 14.0 * s * amp, 0.0);
            anchor = Anchor::Both;
        }
        MotionKind::Bow => {
            let phi = TAU * speed * var.freq * t / 4.0 + var.phase;
            let e = (1.0 - phi.cos()) / 2.0;
            let e = e * e * (3.0 - 2.0 * e);
            let depth = 70.0 * amp;
            // The pelvis tips forward and the hips flex by as much, so the legs stay
            // vertical while the trunk bends.
            let tilt = 0.45 * depth * e + var.lean;
            for left in [true, false] {
                b.leg(left, tilt, 3.0, 5.0 + var.knee, 0.0, 0.0);
                b.arm(left, 75.0 + var.arm, 0.0, 10.0, 0.0);
            }
            b.pelvis(0.0, tilt, 0.0);
            b.spine(0.55 * depth * e / 3.0, 0.0, 0.0);
            b.neck_head(-0.1 * depth * e, 0.0, 0.0);
            anchor = Anchor::Both;
        }
    }
    Frame {
        rot: b.rot,
        anchor,
        shift,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_parse_by_name() {
        for k in MotionKind::ALL {
            assert_eq!(MotionKind::parse(k.name()), Some(k));
        }
        assert_eq!(MotionKind::parse("Raise_Arms"), Some(MotionKind::RaiseArms));
        assert_eq!(MotionKind::parse("moonwalk"), None);
    }

    #[test]
    fn parameters_are_checked_before_generating() {
        let mut p = ProceduralParams::new(MotionKind::Walk);
        p.frames = usize::MAX;
        assert!(generate(&p)
            .unwrap_err()
            .to_string()
            .contains("expected 1 to"));
        p.frames = 10;
        p.speed = Some(30.0);
        let e = generate(&p).unwrap_err().to_string();
        assert!(
            e.contains("speed 30 for walk; expected 0 to 2.5 m/s"),
            "{e}"
        );
        p.speed = None;
        p.amplitude = f64::NAN;
        assert!(generate(&p).is_err());
        p.amplitude = 1.0;
        p.fps = 0.0;
        assert!(generate(&p).is_err());
    }

    #[test]
    fn at_amplitude_one_the_limits_change_nothing() {
        // Natural motions stay clear of the soft limits' margins, so they are exactly
        // what the formulas say.
        for kind in MotionKind::ALL {
            for seed in 0..3 {
                let var = Variation::draw(seed, kind);
                for k in 0..300 {
                    let t = k as f64 / 60.0;
                    let raw = frame_at(kind, t, kind.default_speed(), 1.0, &var).axis_angles();
                    let mut limited = raw;
                    soft_limit_pose(&mut limited);
                    for j in 0..SMPL_JOINT_COUNT {
                        for a in 0..3 {
                            let d = (raw[j][a] - limited[j][a]).abs();
                            assert!(
                                d < 1e-12,
                                "{kind} seed {seed} t {t}: joint {j} axis {a} moved by {d}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn smooth_min_is_close_to_min() {
        assert!((smooth_min(0.0, 1.0, 60.0) - 0.0).abs() < 1e-12);
        assert!((smooth_min(0.3, 0.3, 60.0) - (0.3 - 2f64.ln() / 60.0)).abs() < 1e-12);
    }
}
