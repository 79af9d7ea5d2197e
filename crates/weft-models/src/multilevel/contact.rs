//! Body contact: where the posed body surface is, seen from each garment vertex, per frame
//! (config `body_contact`; issue 15). Not in seed 000, whose network sees the body only
//! through joint distances, poses and sampled velocities: it cannot tell where the thigh
//! is relative to a hem vertex, and a prediction right to a centimetre on average ends
//! up inside the leg wherever it errs inwards (docs/multilevel.md, "Legs through the
//! skirt").
//!
//! For every frame the garment is skinned with its prior weights (the transferred
//! weights, no blend shapes: a function of the inputs alone, so it costs nothing at
//! training time beyond the window's cache), and for each vertex `p` the closest point
//! on the posed body gives [`CONTACT_FEATURES`] numbers:
//!
//! - the signed distance `h(p)` over `contact_radius`, clamped to `[−1, 1]` (further than
//!   the radius the body does not matter to the vertex);
//! - the body's interpolated normal at the closest point, taken back to the rest frame by
//!   the transpose of the vertex's blended rotation: the direction, in the frame the blend
//!   shapes live in, that moves the vertex out of the body.

use weft_body::query::BodySurface;

use crate::error::ModelError;

/// Numbers per garment vertex and frame: scaled signed distance and rest-frame normal.
pub const CONTACT_FEATURES: usize = 4;

/// Appends the contact features `[N, 4]` of one frame to `out`.
///
/// `rest` is `[N, 3]`, `weights` `[N, S]` (rows summing to one), `transforms` the frame's
/// `[S, 12]` joint transforms `[R | t]` row-major, `surface` the body posed in that frame.
pub fn contact_features(
    rest: &[f32],
    weights: &[f32],
    transforms: &[f32],
    surface: &BodySurface,
    radius: f64,
    out: &mut Vec<f32>,
) -> Result<(), ModelError> {
    let s = transforms.len() / 12;
    let n = rest.len() / 3;
    if weights.len() != n * s {
        return Err(ModelError::mismatch(
            "contact skinning weights (vertices × joints)",
            n * s,
            weights.len(),
        ));
    }
    let mut blended = vec![[0.0f64; 12]; n];
    let mut posed = Vec::with_capacity(n);
    for (i, a) in blended.iter_mut().enumerate() {
        for (j, &w) in weights[i * s..(i + 1) * s].iter().enumerate() {
            if w != 0.0 {
                for (k, x) in a.iter_mut().enumerate() {
                    *x += f64::from(w) * f64::from(transforms[j * 12 + k]);
                }
            }
        }
        let r = [0, 1, 2].map(|k| f64::from(rest[3 * i + k]));
        posed.push([0, 1, 2].map(|row| {
            a[4 * row] * r[0] + a[4 * row + 1] * r[1] + a[4 * row + 2] * r[2] + a[4 * row + 3]
        }));
    }
    let closest = surface
        .closest_points(&posed)
        .map_err(|e| ModelError::Body(format!("body contact: {e}")))?;
    out.reserve(n * CONTACT_FEATURES);
    for (c, a) in closest.iter().zip(&blended) {
        out.push((c.signed_distance / radius).clamp(-1.0, 1.0) as f32);
        let n_world = c.interpolated_normal;
        // Rᵀ n: the blended rotation's transpose (its inverse while the blend is rigid).
        let back: [f64; 3] =
            [0, 1, 2].map(|col| (0..3).map(|row| a[4 * row + col] * n_world[row]).sum());
        let len = back.iter().map(|x| x * x).sum::<f64>().sqrt();
        let unit = if len > 1e-12 {
            back.map(|x| x / len)
        } else {
            [0.0; 3]
        };
        out.extend(unit.map(|x| x as f32));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube centred at the origin, outward faces.
    fn cube() -> BodySurface {
        let p: Vec<[f64; 3]> = (0..8)
            .map(|k| [k & 1, (k >> 1) & 1, (k >> 2) & 1].map(|b| b as f64 - 0.5))
            .collect();
        let f = [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        BodySurface::new(&p, &f).unwrap()
    }

    #[test]
    fn distance_and_normal_come_back_to_the_rest_frame() {
        let surface = cube();
        assert!(surface.is_closed());
        // One joint: a quarter turn about z (x → y) and no translation.
        let t = [0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        // Rest point (0.55, 0, 0) lands at (0, 0.55, 0): 5 cm outside the +y face.
        // A rest point (0, −0.45, 0) lands at (0.45, 0, 0): 5 cm inside, nearest the +x face.
        let rest = [0.55, 0.0, 0.0, 0.0, -0.45, 0.0];
        let mut out = Vec::new();
        contact_features(&rest, &[1.0, 1.0], &t, &surface, 0.1, &mut out).unwrap();
        assert_eq!(out.len(), 2 * CONTACT_FEATURES);
        assert!((out[0] - 0.5).abs() < 1e-5, "{out:?}");
        // World normal +y is rest +x.
        for (a, b) in out[1..4].iter().zip([1.0, 0.0, 0.0]) {
            assert!((a - b).abs() < 1e-5, "{out:?}");
        }
        assert!((out[4] + 0.5).abs() < 1e-5, "{out:?}");
        // World normal +x is rest −y.
        for (a, b) in out[5..8].iter().zip([0.0, -1.0, 0.0]) {
            assert!((a - b).abs() < 1e-5, "{out:?}");
        }
        // Far away: the distance saturates at the radius.
        let mut far = Vec::new();
        contact_features(&[3.0, 0.0, 0.0], &[1.0], &t, &surface, 0.1, &mut far).unwrap();
        assert_eq!(far[0], 1.0);
        // Weights of another width are refused by name.
        let e = contact_features(&rest, &[1.0], &t, &surface, 0.1, &mut Vec::new());
        assert!(e.unwrap_err().to_string().contains("contact"));
    }
}
