//! Perspective cameras: a fixed set of views (front, side, three-quarter, turntable) that
//! frame the scene automatically, so pictures of different garments, frames or methods
//! are comparable without anyone placing a camera by hand.
//!
//! weft's frame is right-handed, Y up, metres; a body faces +Z, so the front view looks
//! down −Z from the +Z side and the side view looks from +X (the body's left).

use weft_mesh::Aabb;

use crate::math::{add, cross, dot, is_finite, normalize, scale, sub, V3};

/// Vertical field of view of every preset: narrow enough that garments are not
/// distorted, wide enough to read as a perspective picture.
pub const DEFAULT_FOV_Y_DEG: f64 = 30.0;

/// Elevation of the three-quarter and turntable views, in degrees: a little from above,
/// so the top opening of a skirt or the shoulders read as 3D.
const RAISED_DEG: f64 = 12.0;

/// Fraction of the half-field of view the framed scene may fill, leaving a margin.
const FILL: f64 = 0.9;

/// Where the camera looks from, as a preset or an orbit angle around the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum View {
    /// From +Z towards −Z, level.
    Front,
    /// From +X towards −X, level.
    Side,
    /// From 35° round from the front towards +X, 12° above.
    ThreeQuarter,
    /// From `azimuth_deg` round the Y axis (0 = front, 90 = side) and `elevation_deg`
    /// above the horizontal.
    Orbit {
        /// Degrees around +Y from +Z towards +X.
        azimuth_deg: f64,
        /// Degrees above the horizontal plane, in (−90, 90).
        elevation_deg: f64,
    },
}

impl View {
    /// `views` orbit views evenly around the Y axis, starting at the front, 12° above.
    pub fn turntable(views: u32) -> Vec<View> {
        (0..views.max(1))
            .map(|k| View::Orbit {
                azimuth_deg: 360.0 * f64::from(k) / f64::from(views.max(1)),
                elevation_deg: RAISED_DEG,
            })
            .collect()
    }

    /// `(azimuth, elevation)` in degrees.
    fn angles(self) -> (f64, f64) {
        match self {
            View::Front => (0.0, 0.0),
            View::Side => (90.0, 0.0),
            View::ThreeQuarter => (35.0, RAISED_DEG),
            View::Orbit {
                azimuth_deg,
                elevation_deg,
            } => (azimuth_deg, elevation_deg.clamp(-89.0, 89.0)),
        }
    }

    /// Unit vector from the scene towards the camera.
    fn direction(self) -> V3 {
        let (az, el) = self.angles();
        let (az, el) = (az.to_radians(), el.to_radians());
        [az.sin() * el.cos(), el.sin(), az.cos() * el.cos()]
    }
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Position of the eye.
    pub eye: V3,
    /// Point the camera looks at (centre of the picture).
    pub target: V3,
    /// World direction that is up in the picture (need not be orthogonal to the view).
    pub up: V3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f64,
}

impl Camera {
    /// A camera looking at `bbox` from `view`, at the distance where the whole box fits a
    /// picture of width/height `aspect` with a margin, centred on the box's picture.
    pub fn frame(view: View, bbox: &Aabb, aspect: f64) -> Camera {
        let corners: Vec<V3> = (0..8)
            .map(|i| {
                [
                    if i & 1 == 0 { bbox.min[0] } else { bbox.max[0] },
                    if i & 2 == 0 { bbox.min[1] } else { bbox.max[1] },
                    if i & 4 == 0 { bbox.min[2] } else { bbox.max[2] },
                ]
            })
            .collect();
        Self::frame_points(view, &corners, aspect).unwrap_or(Camera {
            eye: [0.0, 0.0, 1.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: DEFAULT_FOV_Y_DEG,
        })
    }

    /// A camera looking from `view` at the finite `points` (the vertices to be drawn), at
    /// the distance where all of them fit a picture of width/height `aspect` with a
    /// margin, centred on their picture. `None` without a finite point.
    ///
    /// Fitting the points themselves rather than their bounding box keeps the subject
    /// large from every side: the corners of a T-posed body's box seen from the side are
    /// far nearer the camera than any vertex. Three passes alternate the distance and a
    /// sideways shift that centres the projected points; a last pass sets the distance.
    pub fn frame_points(view: View, points: &[[f64; 3]], aspect: f64) -> Option<Camera> {
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in points.iter().filter(|p| is_finite(**p)) {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if lo[0] > hi[0] {
            return None;
        }
        let center = scale(add(lo, hi), 0.5);
        let size = sub(hi, lo);
        let d = view.direction();
        let up = [0.0, 1.0, 0.0];
        let (right, up_v) = basis(scale(d, -1.0), up);
        let ty = (DEFAULT_FOV_Y_DEG.to_radians() * 0.5).tan() * FILL;
        let tx = ty * aspect;
        // Camera-frame coordinates (right, up, towards the camera) around the centre.
        let local: Vec<V3> = points
            .iter()
            .filter(|p| is_finite(**p))
            .map(|&p| {
                let c = sub(p, center);
                [dot(c, right), dot(c, up_v), dot(c, d)]
            })
            .collect();
        let (mut ox, mut oy) = (0.0, 0.0);
        let fit = |ox: f64, oy: f64| {
            let dist = local
                .iter()
                .map(|c| (c[2] + (c[0] - ox).abs() / tx).max(c[2] + (c[1] - oy).abs() / ty))
                .fold(0.0, f64::max);
            // A flat subject seen edge-on still needs some distance.
            dist.max(1e-3 * dot(size, size).sqrt()).max(1e-9)
        };
        for _ in 0..3 {
            let dist = fit(ox, oy);
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for c in &local {
                let depth = dist - c[2];
                let s = [(c[0] - ox) / depth, (c[1] - oy) / depth];
                for k in 0..2 {
                    lo[k] = lo[k].min(s[k]);
                    hi[k] = hi[k].max(s[k]);
                }
            }
            ox += 0.5 * (lo[0] + hi[0]) * dist;
            oy += 0.5 * (lo[1] + hi[1]) * dist;
        }
        let dist = fit(ox, oy);
        let target = add(center, add(scale(right, ox), scale(up_v, oy)));
        Some(Camera {
            eye: add(target, scale(d, dist)),
            target,
            up,
            fov_y_deg: DEFAULT_FOV_Y_DEG,
        })
    }

    /// The projection of this camera onto a `width × height` pixel grid.
    pub(crate) fn projector(&self, width: f64, height: f64) -> Projector {
        let forward = normalize(sub(self.target, self.eye));
        let (right, up) = basis(forward, self.up);
        let fov = self.fov_y_deg.clamp(1.0, 170.0).to_radians();
        Projector {
            eye: self.eye,
            right,
            up,
            forward,
            focal: 0.5 * height / (0.5 * fov).tan(),
            cx: 0.5 * width,
            cy: 0.5 * height,
            near: 1e-6 * dot(sub(self.target, self.eye), sub(self.target, self.eye)).sqrt(),
        }
    }
}

/// Right and up unit vectors for a camera looking along `forward` with `up` roughly up;
/// falls back to +Z as up when looking straight along `up`.
fn basis(forward: V3, up: V3) -> (V3, V3) {
    let mut right = normalize(cross(forward, up));
    if right == [0.0; 3] {
        right = normalize(cross(forward, [0.0, 0.0, 1.0]));
    }
    (right, cross(right, forward))
}

/// World → pixel mapping of a camera for one picture size.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projector {
    pub(crate) eye: V3,
    right: V3,
    up: V3,
    /// Unit viewing direction; the headlight shines along it.
    pub(crate) forward: V3,
    focal: f64,
    cx: f64,
    cy: f64,
    near: f64,
}

impl Projector {
    /// `(x, y, depth)`: pixel coordinates (y down) and distance along the view axis, or
    /// `None` for points not in front of the camera (or not finite).
    pub(crate) fn project(&self, p: V3) -> Option<[f64; 3]> {
        let v = sub(p, self.eye);
        let depth = dot(v, self.forward);
        if depth.is_nan() || depth <= self.near || !depth.is_finite() {
            return None;
        }
        let x = self.cx + self.focal * dot(v, self.right) / depth;
        let y = self.cy - self.focal * dot(v, self.up) / depth;
        Some([x, y, depth])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb {
            min: [-0.5, 0.0, -0.2],
            max: [0.5, 1.7, 0.2],
        }
    }

    #[test]
    fn framed_box_fits_and_is_centred() {
        for view in [View::Front, View::Side, View::ThreeQuarter]
            .into_iter()
            .chain(View::turntable(7))
        {
            for aspect in [1.0, 0.5, 2.0] {
                let (w, h) = (400.0 * aspect, 400.0);
                let cam = Camera::frame(view, &unit_box(), aspect);
                let p = cam.projector(w, h);
                let b = unit_box();
                let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
                for i in 0..8 {
                    let c = [
                        if i & 1 == 0 { b.min[0] } else { b.max[0] },
                        if i & 2 == 0 { b.min[1] } else { b.max[1] },
                        if i & 4 == 0 { b.min[2] } else { b.max[2] },
                    ];
                    let s = p.project(c).expect("in front");
                    for k in 0..2 {
                        lo[k] = lo[k].min(s[k]);
                        hi[k] = hi[k].max(s[k]);
                    }
                }
                assert!(lo[0] >= 0.0 && lo[1] >= 0.0, "{view:?} {aspect} {lo:?}");
                assert!(hi[0] <= w && hi[1] <= h, "{view:?} {aspect} {hi:?}");
                // Centred to within a pixel, and filling the tight direction.
                assert!(((lo[0] + hi[0]) / 2.0 - w / 2.0).abs() < 1.0, "{view:?}");
                assert!(((lo[1] + hi[1]) / 2.0 - h / 2.0).abs() < 1.0, "{view:?}");
                let fill = ((hi[0] - lo[0]) / w).max((hi[1] - lo[1]) / h);
                assert!(fill > 0.8 && fill <= 0.91, "{view:?} {aspect} {fill}");
            }
        }
    }

    #[test]
    fn front_looks_down_minus_z_and_up_is_up() {
        let cam = Camera::frame(View::Front, &unit_box(), 1.0);
        assert!(cam.eye[2] > 1.0);
        let p = cam.projector(100.0, 100.0);
        let top = p.project([0.0, 1.7, 0.0]).unwrap();
        let bottom = p.project([0.0, 0.0, 0.0]).unwrap();
        assert!(top[1] < bottom[1]);
        // +X is to the right when looking from the front.
        let right = p.project([0.5, 0.8, 0.0]).unwrap();
        assert!(right[0] > 50.0);
        assert!(p.project(add(cam.eye, [0.0, 0.0, 1.0])).is_none());
        assert!(p.project([f64::NAN, 0.0, 0.0]).is_none());
    }

    #[test]
    fn degenerate_boxes_frame_without_nan() {
        for b in [
            Aabb {
                min: [0.0; 3],
                max: [0.0; 3],
            },
            Aabb {
                min: [0.0; 3],
                max: [1.0, 0.0, 1.0],
            },
        ] {
            for view in [View::Front, View::Side, View::ThreeQuarter] {
                let cam = Camera::frame(view, &b, 1.0);
                assert!(cam.eye.iter().all(|c| c.is_finite()), "{view:?}");
            }
        }
        let top = Camera::frame(
            View::Orbit {
                azimuth_deg: 0.0,
                elevation_deg: 90.0,
            },
            &unit_box(),
            1.0,
        );
        assert!(top.projector(10.0, 10.0).project([0.0, 0.8, 0.0]).is_some());
    }
}
