//! Euclidean point–joint distances: the body's joint–vertex distance matrix `D` and the
//! garment nodes' "distance to every body joint".
//!
//! * Seed 000 §3.2, "Body shape information": `D ∈ ℝ^{N_b × S}`, the distance from every
//!   vertex of the body mesh `T_b` to every joint, is the input of the body-shape
//!   encoder `E^bs`. It describes the shape β, so compute it on the *shaped rest body*
//!   (`v_template + shapedirs·β` with joints `J(β)`), not on a posed frame.
//! * Seed 000 §3.2, "Garment graph information": each garment node's feature vector
//!   holds its position, normal and "distance to all body joints" — the same function
//!   on the garment vertices.
//! * Seed 001 §3.2.1 uses *volumetric geodesic* distances for the same role; see
//!   [`super::volumetric`] for the approximation weft provides.

use rayon::prelude::*;

use super::error::FeatureError;
use super::matrix::FeatureMatrix;
use weft_mesh::vec3::{dist, is_finite};

/// Fails with the index of the first non-finite point.
pub(crate) fn check_points(points: &[[f64; 3]], what: &'static str) -> Result<(), FeatureError> {
    match points.iter().position(|&p| !is_finite(p)) {
        Some(index) => Err(FeatureError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// The `points.len() × joints.len()` matrix of Euclidean distances `‖p_i − J_s‖`
/// (metres), row-major, in parallel over the points.
///
/// For the body this is seed 000's `D` (pass the shaped rest vertices and `J(β)`); for
/// a garment it is the per-node joint-distance feature. Fails on an empty joint list or
/// a non-finite coordinate.
pub fn joint_distances(
    points: &[[f64; 3]],
    joints: &[[f64; 3]],
) -> Result<FeatureMatrix, FeatureError> {
    if joints.is_empty() {
        return Err(FeatureError::Shape { len: 0, cols: 0 });
    }
    check_points(points, "point")?;
    check_points(joints, "joint")?;
    let s = joints.len();
    let mut m = FeatureMatrix::zeros(points.len(), s);
    m.as_mut_slice()
        .par_chunks_mut(s)
        .zip(points.par_iter())
        .for_each(|(row, &p)| {
            for (d, &j) in row.iter_mut().zip(joints) {
                *d = dist(p, j);
            }
        });
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_of_a_right_triangle() {
        let d = joint_distances(
            &[[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]],
            &[[0.0; 3], [3.0, 0.0, 0.0]],
        )
        .unwrap();
        assert_eq!((d.rows(), d.cols()), (2, 2));
        assert_eq!(d.as_slice(), &[0.0, 3.0, 5.0, 4.0]);
        assert!(joint_distances(&[[0.0; 3]], &[]).is_err());
        assert_eq!(
            joint_distances(&[[0.0, f64::NAN, 0.0]], &[[0.0; 3]]),
            Err(FeatureError::NonFinite {
                what: "point",
                index: 0
            })
        );
    }
}
