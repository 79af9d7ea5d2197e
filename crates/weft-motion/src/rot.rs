//! Rotation conversions the motion code shares: axis-angle ↔ unit quaternion, the
//! shortest-arc rotation between two directions, and single-axis rotations.
//!
//! Motions store `f32` axis-angles (the AMASS layout); every composition, slerp and
//! Euler conversion runs on `f64` quaternions so that chains of 24 joints and round
//! trips through text formats lose no more than storage precision.

use nalgebra::{Unit, UnitQuaternion, Vector3};

/// The rotation of an axis-angle vector (direction = axis, length = angle in radians).
pub(crate) fn quat(aa: [f32; 3]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_scaled_axis(Vector3::new(
        f64::from(aa[0]),
        f64::from(aa[1]),
        f64::from(aa[2]),
    ))
}

/// The axis-angle vector of a rotation, with angle in `[0, π]`.
pub(crate) fn axis_angle(q: &UnitQuaternion<f64>) -> [f32; 3] {
    let v = q.scaled_axis();
    [v.x as f32, v.y as f32, v.z as f32]
}

/// The rotation by `angle` radians about coordinate axis `axis` (0 = X, 1 = Y, 2 = Z).
pub(crate) fn about_axis(axis: usize, angle: f64) -> UnitQuaternion<f64> {
    let a = match axis {
        0 => Vector3::x_axis(),
        1 => Vector3::y_axis(),
        _ => Vector3::z_axis(),
    };
    UnitQuaternion::from_axis_angle(&a, angle)
}

/// The smallest rotation taking direction `from` to direction `to`; the identity when
/// either is (nearly) zero. Opposite directions turn by π about an axis perpendicular
/// to `from`, since every such axis is equally short.
pub(crate) fn shortest_arc(from: Vector3<f64>, to: Vector3<f64>) -> UnitQuaternion<f64> {
    const EPS: f64 = 1e-12;
    if from.norm() < EPS || to.norm() < EPS {
        return UnitQuaternion::identity();
    }
    if let Some(q) = UnitQuaternion::rotation_between(&from, &to) {
        return q;
    }
    // Antiparallel: any axis perpendicular to `from`.
    let helper = if from.x.abs() < 0.9 * from.norm() {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let axis = Unit::new_normalize(from.cross(&helper));
    UnitQuaternion::from_axis_angle(&axis, std::f64::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_angle_round_trips() {
        for aa in [
            [0.0, 0.0, 0.0],
            [0.3, -1.2, 0.5],
            [0.0, 3.0, 0.0],
            [-2.0, 0.1, 1.0],
        ] {
            let back = axis_angle(&quat(aa));
            for k in 0..3 {
                assert!((back[k] - aa[k]).abs() < 1e-6, "{aa:?} -> {back:?}");
            }
        }
    }

    #[test]
    fn shortest_arc_maps_directions_including_opposite_ones() {
        let cases = [
            (Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, -2.0, 0.0)),
            (Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.0, -1.0, 0.0)),
            (Vector3::new(1.0, 0.0, 0.0), Vector3::new(-3.0, 0.0, 0.0)),
            (Vector3::new(0.2, 0.5, 0.1), Vector3::new(0.2, 0.5, 0.1)),
        ];
        for (a, b) in cases {
            let q = shortest_arc(a, b);
            assert!(
                (q * a.normalize() - b.normalize()).norm() < 1e-12,
                "{a} {b}"
            );
        }
        assert_eq!(
            shortest_arc(Vector3::zeros(), Vector3::x()),
            UnitQuaternion::identity()
        );
    }
}
