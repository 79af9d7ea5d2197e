//! Trouser legs: a crotch seam splits the bottom ring of the torso tube into two leg
//! loops, and each loop is extruded down its leg.
//!
//! The seam is a row of new vertices from the front centre to the back centre, shared by
//! both legs (each seam edge gets one face from each leg), so the garment stays one
//! manifold piece with the waist and two leg openings as its only boundaries below.

use crate::build::{add, extrude, lerp3, scale, Builder, ExtrudeRing, Ring};
use crate::fit::Measurements;
use crate::tube::segments;

/// Builds both legs under `bottom` (closed, `n` a multiple of 4, vertex 0 on the left,
/// `n/4` at the front) down to height `end_y`, with `ease` over the leg radius.
pub fn legs(
    b: &mut Builder,
    m: &Measurements,
    bottom: &Ring,
    end_y: f64,
    ease: f64,
    h: f64,
) -> [Ring; 2] {
    let n = bottom.idx.len();
    let q = n / 4;
    let front = b.positions[bottom.idx[q] as usize];
    let back = b.positions[bottom.idx[3 * q] as usize];
    let seam_count = segments((front[2] - back[2]).abs(), h).max(2) - 1;
    // The seam passes below the crotch (the ring sits 3 cm above it).
    let depth = 0.045;
    let seam: Vec<u32> = (1..=seam_count)
        .map(|j| {
            let t = j as f64 / (seam_count + 1) as f64;
            let mut p = lerp3(front, back, t);
            p[0] = 0.0;
            p[1] -= depth * (std::f64::consts::PI * t).sin();
            b.vertex(p)
        })
        .collect();
    let mut left: Vec<u32> = (0..=2 * q).map(|k| bottom.idx[(3 * q + k) % n]).collect();
    left.extend(seam.iter().copied());
    let mut right: Vec<u32> = (q..=3 * q).map(|k| bottom.idx[k]).collect();
    right.extend(seam.iter().rev().copied());
    let top_y = front[1] - depth;
    let length = (top_y - end_y).max(2.0 * h);
    let count = segments(length, h).max(2);
    let leg = |b: &mut Builder, loop_idx: &[u32], side: f64| {
        let pts: Vec<[f64; 3]> = loop_idx.iter().map(|&i| b.positions[i as usize]).collect();
        let k = pts.len().max(1) as f64;
        let c = scale(pts.iter().fold([0.0; 3], |s, &p| add(s, p)), 1.0 / k);
        let loop_r = pts
            .iter()
            .map(|p| ((p[0] - c[0]).powi(2) + (p[2] - c[2]).powi(2)).sqrt())
            .sum::<f64>()
            / k;
        let transition = 0.08;
        let rings: Vec<ExtrudeRing> = (1..=count)
            .map(|s| {
                let d = length * s as f64 / count as f64;
                let y = top_y - d;
                let t = (d / transition).min(1.0);
                let smooth = t * t * (3.0 - 2.0 * t);
                let axis_x = side * m.leg_x_at(y);
                let center = lerp3([c[0], y, c[2]], [axis_x, y, 0.0], smooth);
                // Keep both legs on their own side of the mid-plane.
                let radius = (loop_r + (m.leg_r_at(y) + ease - loop_r) * smooth)
                    .min(center[0].abs() - 0.004);
                ExtrudeRing {
                    center,
                    radius: radius.max(0.01),
                    blend: smooth.max(0.35),
                }
            })
            .collect();
        extrude(b, loop_idx, [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], &rings)
    };
    let l = leg(b, &left, 1.0);
    let r = leg(b, &right, -1.0);
    [l, r]
}
