//! Shading: how bright a surface point is, given its normal and the camera.
//!
//! One headlight (a light at the eye, shining along the view) plus ambient light: every
//! visible surface is lit, nothing hides in a cast shadow, and the picture reads the same
//! from every preset view, which is what comparing deformations needs. The ambient share
//! is high so the colours of a colour map stay close to the legend's. Garments are open
//! surfaces, so both sides are lit; the inside (back faces) is drawn a little darker to
//! tell it from the outside.

use crate::image::Rgb;
use crate::math::{cross, normalize, sub, V3};

/// How normals vary over a triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Shading {
    /// One normal per face: facets show, which is right for inspecting a mesh.
    Flat,
    /// Area-weighted vertex normals interpolated per pixel (Phong interpolation): smooth
    /// cloth, the default.
    #[default]
    Smooth,
}

/// Light reaching every point regardless of its normal.
const AMBIENT: f64 = 0.38;
/// Diffuse (Lambert) share of the headlight.
const DIFFUSE: f64 = 0.62;
/// Strength of the white highlight (Blinn–Phong; half-vector = view for a headlight).
const SPECULAR: f64 = 0.10;
/// Highlight sharpness.
const SHININESS: i32 = 24;
/// Brightness of the inside of a surface relative to its outside.
const BACK_FACE: f64 = 0.78;

/// The lit colour of a point with base colour `base`, where `cos` is the cosine between
/// its camera-facing unit normal and the direction to the eye (clamped to `[0, 1]`).
pub(crate) fn lit(base: Rgb, cos: f64, back_face: bool) -> Rgb {
    let c = if cos.is_finite() {
        cos.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut k = AMBIENT + DIFFUSE * c;
    if back_face {
        k *= BACK_FACE;
    }
    let spec = 255.0 * SPECULAR * c.powi(SHININESS);
    base.map(|b| (f64::from(b) * k + spec).round().clamp(0.0, 255.0) as u8)
}

/// Unnormalised normal of a triangle (twice its area), counter-clockwise rule.
pub(crate) fn face_normal(a: V3, b: V3, c: V3) -> V3 {
    cross(sub(b, a), sub(c, a))
}

/// Area-weighted unit vertex normals (zero for vertices in no face). Faces must index
/// `positions`; the caller has checked that.
pub(crate) fn vertex_normals(positions: &[V3], faces: &[[u32; 3]]) -> Vec<V3> {
    let mut acc = vec![[0.0; 3]; positions.len()];
    for f in faces {
        let [a, b, c] = f.map(|i| positions[i as usize]);
        let n = face_normal(a, b, c);
        if !n.iter().all(|x| x.is_finite()) {
            continue;
        }
        for &i in f {
            let s = &mut acc[i as usize];
            for k in 0..3 {
                s[k] += n[k];
            }
        }
    }
    acc.into_iter().map(normalize).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn facing_the_light_is_brighter_and_inside_darker() {
        let base = [100, 150, 200];
        let full = lit(base, 1.0, false);
        let grazing = lit(base, 0.0, false);
        let inside = lit(base, 1.0, true);
        assert!(full[2] > grazing[2] && full[2] > inside[2]);
        assert_eq!(grazing, [38, 57, 76]);
        assert_eq!(lit(base, f64::NAN, false), grazing);
        assert_eq!(lit([255; 3], 1.0, false), [255; 3]);
    }

    #[test]
    fn normals_of_a_flat_square() {
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [5.0; 3],
        ];
        let n = vertex_normals(&p, &[[0, 1, 2], [0, 2, 3]]);
        for v in &n[..4] {
            assert_eq!(*v, [0.0, 0.0, 1.0]);
        }
        assert_eq!(n[4], [0.0; 3]);
    }
}
