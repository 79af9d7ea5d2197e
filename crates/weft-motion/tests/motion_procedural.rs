//! The procedural library: determinism, joint limits, smoothness, gait consistency; and
//! resampling and pose histories on its motions.

use nalgebra::{UnitQuaternion, Vector3};
use weft_motion::{
    generate, limit_violation, motion_stats, pose_histories, posed_joints, resample, Motion,
    MotionKind, ProceduralParams, DEFAULT_REST_JOINTS, HISTORY_FEATURES,
};

fn params(
    kind: MotionKind,
    frames: usize,
    fps: f64,
    seed: u64,
    amplitude: f64,
) -> ProceduralParams {
    ProceduralParams {
        kind,
        frames,
        fps,
        seed,
        speed: None,
        amplitude,
    }
}

fn q(r: [f32; 3]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_scaled_axis(Vector3::new(
        f64::from(r[0]),
        f64::from(r[1]),
        f64::from(r[2]),
    ))
}

#[test]
fn same_seed_same_motion_other_seed_other_motion() {
    for kind in MotionKind::ALL {
        let a = generate(&params(kind, 60, 30.0, 7, 1.0)).unwrap();
        let b = generate(&params(kind, 60, 30.0, 7, 1.0)).unwrap();
        assert_eq!(a, b, "{kind}");
        let c = generate(&params(kind, 60, 30.0, 8, 1.0)).unwrap();
        assert!(c.distance(&a).unwrap().rotation > 1e-3, "{kind}");
    }
}

#[test]
fn every_kind_stays_within_joint_limits_at_any_amplitude() {
    for kind in MotionKind::ALL {
        for amplitude in [0.0, 0.5, 1.0, 2.0, 3.0] {
            for seed in 0..4 {
                let m = generate(&params(kind, 150, 30.0, seed, amplitude)).unwrap();
                for (t, pose) in m.poses().iter().enumerate() {
                    assert_eq!(
                        limit_violation(pose),
                        None,
                        "{kind} amplitude {amplitude} seed {seed} frame {t}"
                    );
                }
            }
        }
    }
}

/// The largest change of angular (or linear) velocity between consecutive frames.
fn max_velocity_jump(m: &Motion) -> (f64, f64) {
    let dt = 1.0 / m.fps();
    let mut rot = 0.0f64;
    let mut lin = 0.0f64;
    let p = m.poses();
    let t = m.trans();
    for f in 1..m.frame_count() - 1 {
        for ((a, b), c) in p[f - 1].iter().zip(&p[f]).zip(&p[f + 1]) {
            let v0 = (q(*a).inverse() * q(*b)).scaled_axis() / dt;
            let v1 = (q(*b).inverse() * q(*c)).scaled_axis() / dt;
            rot = rot.max((v1 - v0).norm());
        }
        for ((a, b), c) in t[f - 1].iter().zip(&t[f]).zip(&t[f + 1]) {
            let v0 = f64::from(b - a) / dt;
            let v1 = f64::from(c - b) / dt;
            lin = lin.max((v1 - v0).abs());
        }
    }
    (rot, lin)
}

#[test]
fn motions_are_c1_velocity_changes_shrink_with_the_time_step() {
    // For a C¹ motion the velocity change between frames is O(dt): halving dt halves
    // it. A kink (a velocity jump) would keep it constant.
    for kind in MotionKind::ALL {
        for amplitude in [1.0, 3.0] {
            let coarse = generate(&params(kind, 4 * 250, 250.0, 5, amplitude)).unwrap();
            let fine = generate(&params(kind, 4 * 500, 500.0, 5, amplitude)).unwrap();
            let (rc, lc) = max_velocity_jump(&coarse);
            let (rf, lf) = max_velocity_jump(&fine);
            assert!(
                rf < 0.65 * rc + 1e-3,
                "{kind} amplitude {amplitude}: rotation {rc} -> {rf}"
            );
            // Translations are stored as f32: at 500 fps a 1e-7 m rounding is 0.05 m/s.
            assert!(
                lf < 0.65 * lc + 0.2,
                "{kind} amplitude {amplitude}: translation {lc} -> {lf}"
            );
        }
    }
}

#[test]
fn walking_moves_forward_at_the_given_speed_with_alternating_legs() {
    for speed in [0.6, 1.2, 2.0] {
        let mut p = params(MotionKind::Walk, 301, 60.0, 2, 1.0);
        p.speed = Some(speed);
        let m = generate(&p).unwrap();
        let t = m.trans();
        let v = f64::from(t[300][2] - t[0][2]) / m.duration();
        assert!((v - speed).abs() < 1e-4, "speed {speed}: {v}");
        // Left and right hip flexion in antiphase: strongly negatively correlated.
        let l: Vec<f64> = m.poses().iter().map(|p| f64::from(p[1][0])).collect();
        let r: Vec<f64> = m.poses().iter().map(|p| f64::from(p[2][0])).collect();
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
        let (ml, mr) = (mean(&l), mean(&r));
        let cov: f64 = l.iter().zip(&r).map(|(a, b)| (a - ml) * (b - mr)).sum();
        let var = |x: &[f64], m: f64| x.iter().map(|a| (a - m).powi(2)).sum::<f64>();
        assert!(cov / (var(&l, ml) * var(&r, mr)).sqrt() < -0.95);
        // The lower foot stays near the floor (its rest height) all the time.
        for (pose, tr) in m.poses().iter().zip(t) {
            let j = posed_joints(pose, *tr, &DEFAULT_REST_JOINTS);
            let low = j[7][1].min(j[8][1]);
            assert!((low - DEFAULT_REST_JOINTS[7][1]).abs() < 0.02, "{low}");
        }
    }
}

#[test]
fn walk_joint_ranges_look_like_walking() {
    let mut p = params(MotionKind::Walk, 241, 60.0, 0, 1.0);
    p.speed = Some(1.3);
    let m = generate(&p).unwrap();
    let s = motion_stats(&m);
    let range = |j: usize, k: usize| (s.joints[j].min_deg[k], s.joints[j].max_deg[k]);
    for j in [1, 4, 7, 16, 18] {
        let r = &s.joints[j];
        println!(
            "{:>14}: x [{:6.1}, {:6.1}]  y [{:6.1}, {:6.1}]  z [{:6.1}, {:6.1}]",
            r.name,
            r.min_deg[0],
            r.max_deg[0],
            r.min_deg[1],
            r.max_deg[1],
            r.min_deg[2],
            r.max_deg[2]
        );
    }
    // Hip: about 30° of flexion to 15° of extension (flexion is −X).
    let (lo, hi) = range(1, 0);
    assert!(
        (-35.0..-20.0).contains(&lo) && (8.0..20.0).contains(&hi),
        "hip {lo} {hi}"
    );
    // Knee: nearly straight in stance, about 60° in swing.
    let (lo, hi) = range(4, 0);
    assert!(
        (3.0..12.0).contains(&lo) && (55.0..72.0).contains(&hi),
        "knee {lo} {hi}"
    );
    // Ankle: some dorsi- and plantar flexion.
    let (lo, hi) = range(7, 0);
    assert!(lo < -3.0 && hi > 15.0, "ankle {lo} {hi}");
    println!(
        "root path {:.3} m in {:.2} s",
        s.root_path_length, s.duration
    );
}

#[test]
fn resampling_at_the_same_rate_is_the_identity_and_changes_count_otherwise() {
    let m = generate(&params(MotionKind::Dance, 91, 30.0, 4, 1.0)).unwrap();
    assert_eq!(resample(&m, 30.0).unwrap(), m);
    let r = resample(&m, 60.0).unwrap();
    assert_eq!(r.frame_count(), 181);
    // Every other frame of the 60 fps motion is a 30 fps frame, unchanged.
    for f in 0..91 {
        assert_eq!(r.poses()[2 * f], m.poses()[f]);
    }
    // In-between frames are close to the generator's own 60 fps frames.
    let direct = generate(&params(MotionKind::Dance, 181, 60.0, 4, 1.0)).unwrap();
    let d = r.distance(&direct).unwrap();
    assert!(d.rotation < 0.02 && d.translation < 0.002, "{d:?}");
}

#[test]
fn pose_histories_have_the_seed_000_shape() {
    let m = generate(&params(MotionKind::Run, 20, 30.0, 0, 1.0)).unwrap();
    let h = pose_histories(&m, 5).unwrap();
    assert_eq!(HISTORY_FEATURES, 75);
    assert_eq!(h.len(), 20 * 5 * 75);
    // Frame 10, row 0: its own pose and its root displacement.
    let row = &h[10 * 5 * 75..10 * 5 * 75 + 75];
    assert_eq!(&row[..3], &m.poses()[10][0]);
    let dz = m.trans()[10][2] - m.trans()[9][2];
    assert_eq!(row[74], dz);
    assert!(dz > 0.0, "running forward");
}
