//! Rotations for skinning: Rodrigues' formula (axis-angle → matrix), its inverse, the
//! shortest rotation between two directions, and unit dual quaternions (Kavan et al.
//! 2007) for dual quaternion skinning.
//!
//! Everything is `f64`: a pose chains up to a dozen rotations from the root to a
//! fingertip, and the skinning of thousands of vertices reuses them, so the few extra
//! digits cost nothing measurable and keep rigid parts rigid to 1e-12.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// The rotation matrix of an axis-angle vector `ω` (axis `ω/|ω|`, angle `|ω|` radians,
/// right-handed), by Rodrigues' formula `R = I + a [ω]× + b [ω]×²` with
/// `a = sin θ / θ`, `b = (1 − cos θ) / θ²`.
///
/// Near zero, `a` and `b` are evaluated by their Taylor series, so small rotations (the
/// bulk of a natural pose) lose no precision to cancellation and `ω = 0` gives exactly
/// the identity; the result is smooth in `ω` everywhere.
pub fn rodrigues(omega: [f64; 3]) -> Matrix3<f64> {
    let w = Vector3::from(omega);
    let t2 = w.norm_squared();
    let (a, b) = if t2 < 1e-6 {
        // Error below θ⁶/5040 < 1e-21 for θ < 1e-3.
        (
            1.0 - t2 / 6.0 + t2 * t2 / 120.0,
            0.5 - t2 / 24.0 + t2 * t2 / 720.0,
        )
    } else {
        let t = t2.sqrt();
        (t.sin() / t, (1.0 - t.cos()) / t2)
    };
    let k = skew(w);
    Matrix3::identity() + k * a + k * k * b
}

/// The cross-product matrix `[v]×`, with `[v]× u = v × u`.
pub fn skew(v: Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The axis-angle vector of a rotation matrix, angle in `[0, π]` (the inverse of
/// [`rodrigues`] there). Goes through a quaternion, which is stable at 0 and π alike.
pub fn axis_angle(r: &Matrix3<f64>) -> [f64; 3] {
    let q = UnitQuaternion::from_matrix(r);
    let v = q.scaled_axis();
    [v.x, v.y, v.z]
}

/// The smallest rotation taking direction `from` to direction `to` (the identity if
/// either is zero; a half turn about an axis perpendicular to `from` if they are
/// opposite).
pub fn rotation_between(from: [f64; 3], to: [f64; 3]) -> Matrix3<f64> {
    let (a, b) = (Vector3::from(from), Vector3::from(to));
    if a.norm() < 1e-300 || b.norm() < 1e-300 {
        return Matrix3::identity();
    }
    match UnitQuaternion::rotation_between(&a, &b) {
        Some(q) => q.to_rotation_matrix().into_inner(),
        None => {
            let helper = if a.x.abs() < 0.9 * a.norm() {
                Vector3::x()
            } else {
                Vector3::y()
            };
            let axis = a.cross(&helper).normalize() * std::f64::consts::PI;
            rodrigues([axis.x, axis.y, axis.z])
        }
    }
}

/// A dual quaternion `real + ε dual`, components `(w, x, y, z)`. A unit dual quaternion
/// (unit `real`, `real · dual = 0`) is a rigid transform: rotation `real`, translation
/// `t = 2 dual real*`.
///
/// Dual quaternion skinning blends these linearly and normalises the sum: unlike
/// blending matrices (LBS), the result is always rigid, so joints do not collapse
/// ("candy wrapper") under twist.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualQuat {
    /// The rotation part.
    pub real: Quaternion<f64>,
    /// The translation part, `t q / 2` for translation `t` as a pure quaternion.
    pub dual: Quaternion<f64>,
}

impl DualQuat {
    /// The identity transform.
    pub fn identity() -> Self {
        DualQuat {
            real: Quaternion::identity(),
            dual: Quaternion::new(0.0, 0.0, 0.0, 0.0),
        }
    }

    /// The rigid transform `x ↦ R x + t`; `r` must be a rotation matrix.
    pub fn from_rigid(r: &Matrix3<f64>, t: &Vector3<f64>) -> Self {
        let q = UnitQuaternion::from_matrix(r).into_inner();
        let tq = Quaternion::new(0.0, t.x, t.y, t.z);
        DualQuat {
            real: q,
            dual: tq * q * 0.5,
        }
    }

    /// `self * s` component-wise (for blending).
    pub fn scale(&self, s: f64) -> Self {
        DualQuat {
            real: self.real * s,
            dual: self.dual * s,
        }
    }

    /// Component-wise sum (for blending).
    pub fn add(&self, o: &Self) -> Self {
        DualQuat {
            real: self.real + o.real,
            dual: self.dual + o.dual,
        }
    }

    /// The rigid transform `(R, t)` of this dual quaternion after normalisation: the
    /// real part is scaled to unit length and the dual part's component along it is
    /// removed (Kavan et al., eq. for the blended `DLB`). `None` when the real part
    /// vanishes (weights that cancel out, which [`dqs`](crate::skinning) prevents by its
    /// antipodality fix).
    pub fn to_rigid(&self) -> Option<(Matrix3<f64>, Vector3<f64>)> {
        let n = self.real.norm();
        // Also refuses NaN.
        if n.is_nan() || n <= 1e-12 {
            return None;
        }
        let r = self.real / n;
        let d = self.dual / n;
        // Project out the part of `d` along `r` so (r, d) is a unit dual quaternion.
        let d = d - r * r.dot(&d);
        let rot = UnitQuaternion::new_unchecked(r)
            .to_rotation_matrix()
            .into_inner();
        let t = d * r.conjugate() * 2.0;
        Some((rot, Vector3::new(t.i, t.j, t.k)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `exp(K)` by its power series, to 40 terms (converges fast for |θ| ≤ 4).
    fn expm(k: Matrix3<f64>) -> Matrix3<f64> {
        let mut sum = Matrix3::identity();
        let mut term = Matrix3::identity();
        for n in 1..40 {
            term = term * k / f64::from(n);
            sum += term;
        }
        sum
    }

    fn close(a: &Matrix3<f64>, b: &Matrix3<f64>, tol: f64) -> bool {
        (a - b).abs().max() <= tol
    }

    #[test]
    fn closed_forms() {
        let h = std::f64::consts::FRAC_PI_2;
        // A quarter turn about Z takes X to Y.
        let r = rodrigues([0.0, 0.0, h]);
        assert!((r * Vector3::x() - Vector3::y()).norm() < 1e-15);
        // About X takes Y to Z; about Y takes Z to X.
        assert!((rodrigues([h, 0.0, 0.0]) * Vector3::y() - Vector3::z()).norm() < 1e-15);
        assert!((rodrigues([0.0, h, 0.0]) * Vector3::z() - Vector3::x()).norm() < 1e-15);
        assert_eq!(rodrigues([0.0; 3]), Matrix3::identity());
        // A half turn.
        let r = rodrigues([std::f64::consts::PI, 0.0, 0.0]);
        assert!(close(
            &r,
            &Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0)),
            1e-15
        ));
    }

    #[test]
    fn small_angles_keep_full_precision() {
        for t in [1e-20, 1e-12, 1e-8, 1e-4, 9.9e-4, 1.1e-3] {
            let w = Vector3::new(0.3, -0.5, 0.8).normalize() * t;
            let r = rodrigues([w.x, w.y, w.z]);
            let e = expm(skew(w));
            assert!(close(&r, &e, 5e-16), "θ = {t}: {}", (r - e).abs().max());
            // Orthonormal to rounding.
            assert!(close(&(r.transpose() * r), &Matrix3::identity(), 4e-16));
        }
    }

    #[test]
    fn derivative_matches_finite_differences_of_the_series() {
        // d/dω R(ω) at ω0, by central differences of rodrigues vs of expm.
        let w0 = [0.4, -0.2, 0.9];
        let h = 1e-6;
        for k in 0..3 {
            let (mut p, mut m) = (w0, w0);
            p[k] += h;
            m[k] -= h;
            let d_rod = (rodrigues(p) - rodrigues(m)) / (2.0 * h);
            let d_exp = (expm(skew(Vector3::from(p))) - expm(skew(Vector3::from(m)))) / (2.0 * h);
            assert!(close(&d_rod, &d_exp, 1e-8), "axis {k}");
        }
        // At zero the derivative along e_k is [e_k]×.
        for k in 0..3 {
            let mut p = [0.0; 3];
            p[k] = h;
            let mut m = [0.0; 3];
            m[k] = -h;
            let d = (rodrigues(p) - rodrigues(m)) / (2.0 * h);
            let mut e = Vector3::zeros();
            e[k] = 1.0;
            assert!(close(&d, &skew(e), 1e-10));
        }
    }

    #[test]
    fn opposite_directions_turn_half_way() {
        let r = rotation_between([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]);
        assert!((r * Vector3::x() + Vector3::x()).norm() < 1e-12);
        assert!(close(&(r.transpose() * r), &Matrix3::identity(), 1e-12));
        assert_eq!(
            rotation_between([0.0; 3], [1.0, 0.0, 0.0]),
            Matrix3::identity()
        );
    }

    fn omega() -> impl Strategy<Value = [f64; 3]> {
        prop::array::uniform3(-2.0f64..2.0)
    }

    proptest! {
        #[test]
        fn rodrigues_is_the_matrix_exponential(w in omega()) {
            let r = rodrigues(w);
            prop_assert!(close(&r, &expm(skew(Vector3::from(w))), 1e-13));
            prop_assert!(close(&(r.transpose() * r), &Matrix3::identity(), 1e-14));
            prop_assert!((r.determinant() - 1.0).abs() < 1e-14);
            // The axis is fixed.
            let v = Vector3::from(w);
            prop_assert!((r * v - v).norm() < 1e-14);
        }

        #[test]
        fn axis_angle_inverts_rodrigues(w in omega()) {
            let back = axis_angle(&rodrigues(w));
            prop_assert!(close(&rodrigues(back), &rodrigues(w), 1e-13));
            let n = Vector3::from(w).norm();
            if n < 3.0 {
                prop_assert!((Vector3::from(back) - Vector3::from(w)).norm() < 1e-10);
            }
        }

        #[test]
        fn rotation_between_takes_from_to_to(a in prop::array::uniform3(-1.0f64..1.0), b in prop::array::uniform3(-1.0f64..1.0)) {
            let (va, vb) = (Vector3::from(a), Vector3::from(b));
            prop_assume!(va.norm() > 1e-3 && vb.norm() > 1e-3);
            let r = rotation_between(a, b);
            prop_assert!((r * va.normalize() - vb.normalize()).norm() < 1e-9);
        }

        #[test]
        fn dual_quaternions_round_trip_rigid_transforms(w in omega(), t in prop::array::uniform3(-3.0f64..3.0)) {
            let r = rodrigues(w);
            let t = Vector3::from(t);
            let dq = DualQuat::from_rigid(&r, &t);
            // Any positive scale normalises away; so does the sign.
            for s in [1.0, 2.5, -0.7] {
                let (r2, t2) = dq.scale(s).to_rigid().unwrap();
                prop_assert!(close(&r2, &r, 1e-12));
                prop_assert!((t2 - t).norm() < 1e-12);
            }
        }
    }
}
