//! Tops: shoulder straps or shoulder panels over the top ring of a torso tube, and
//! sleeves extruded from the armholes they leave.
//!
//! A strap is a grid bridging a run of front vertices of the top ring to the mirrored
//! run at the back, arching over the shoulder. Two straps split the open top of the
//! tube into a neck hole and two armholes, so a tank top has four boundary loops; a
//! sleeve continues an armhole, so a t-shirt also has four (neck, hem, two cuffs).

use crate::build::{add, extrude, lerp3, scale, Builder, ExtrudeRing, Ring};
use crate::fit::Measurements;
use crate::tube::segments;

/// How wide the shoulder bridges are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shoulders {
    /// Narrow straps (tank tops, strap dresses).
    Straps,
    /// Panels from the neck to the armhole (t-shirts, long sleeves, jumpsuits).
    Panels,
}

/// Builds both shoulder bridges over `top` (a closed ring of `n` vertices, `n` a
/// multiple of 4, vertex 0 on the left side, `n/4` at the front) and returns the two
/// armhole loops (left, right).
pub fn shoulders(
    b: &mut Builder,
    m: &Measurements,
    top: &Ring,
    kind: Shoulders,
    ease: f64,
    h: f64,
) -> [Vec<u32>; 2] {
    let n = top.idx.len();
    let q = n / 4;
    let pos = |b: &Builder, i: usize| b.positions[top.idx[i % n] as usize];
    let half_x = pos(b, 0)[0].abs().max(1e-3);
    let (x_in, x_out) = match kind {
        Shoulders::Straps => {
            let c = 0.5 * (m.neck_r + m.shoulder_x);
            (c - 0.025, c + 0.025)
        }
        Shoulders::Panels => (m.neck_r + 0.02, half_x * 0.85),
    };
    // Index of the front vertex whose x is closest to a lateral position.
    let index_of = |x: f64| {
        ((x / half_x).clamp(-1.0, 1.0).acos() / std::f64::consts::TAU * n as f64).round() as usize
    };
    let i_out = index_of(x_out).clamp(1, q.saturating_sub(2).max(1));
    let i_in = index_of(x_in).clamp(i_out + 1, q.saturating_sub(1).max(i_out + 1));
    let left: Vec<usize> = (i_out..=i_in).collect();
    let right: Vec<usize> = (n / 2 - i_in..=n / 2 - i_out).collect();
    let top_y = |x: f64| {
        // Shoulder line from the side of the neck down to the shoulder tip.
        let t = ((x.abs() - m.neck_r) / (m.shoulder_x - m.neck_r).max(1e-3)).clamp(0.0, 1.0);
        let neck_side = m.neck_y - 0.02;
        let tip = m.arm_y + m.shoulder_top_y;
        neck_side + (tip - neck_side) * t + ease
    };
    let strap = |b: &mut Builder, cols: &[usize]| -> Vec<Vec<u32>> {
        // Arc length over the shoulder sets the row count.
        let p0 = pos(b, cols[0]);
        let span = 2.0 * (top_y(p0[0]) - p0[1]).max(0.0) + (2.0 * p0[2].abs());
        let k_rows = segments(span, h).max(2);
        let mut rows: Vec<Vec<u32>> = vec![cols.iter().map(|&i| top.idx[i]).collect()];
        for k in 1..k_rows {
            let t = k as f64 / k_rows as f64;
            let pts: Vec<[f64; 3]> = cols
                .iter()
                .map(|&i| {
                    let p = pos(b, i);
                    let q = pos(b, n - i);
                    let mid = lerp3(p, q, 0.5);
                    // A superellipse arc (exponent 3) from the front over `top_y` to
                    // the back: boxier than a parabola, so it clears the chest and
                    // shoulder-blade corners of the shoulder's cross section.
                    let theta = std::f64::consts::PI * t;
                    let boxy = |c: f64| c.signum() * c.abs().powf(2.0 / 3.0);
                    let half_depth = 0.5 * (p[2] - q[2]);
                    let height = (top_y(p[0]) - mid[1]).max(0.0);
                    [
                        p[0] + (q[0] - p[0]) * t,
                        mid[1] + height * boxy(theta.sin()),
                        mid[2] + half_depth * boxy(theta.cos()),
                    ]
                })
                .collect();
            rows.push(pts.iter().map(|&p| b.vertex(p)).collect());
        }
        rows.push(cols.iter().map(|&i| top.idx[n - i]).collect());
        let mut v = 0.0;
        let mut prev = b.row(rows[0].clone(), v, false);
        for r in &rows[1..] {
            v += span / k_rows as f64;
            let ring = b.row(r.clone(), v, false);
            b.strip(&prev, &ring);
            prev = ring;
        }
        rows
    };
    let l_rows = strap(b, &left);
    let r_rows = strap(b, &right);
    // Left armhole: front base of the outer column, round the side to the back base,
    // then up the strap's outer column back to the front.
    let mut left_loop: Vec<u32> = (0..=2 * i_out)
        .map(|k| top.idx[(i_out + n - k) % n])
        .collect();
    left_loop.extend(l_rows[1..l_rows.len() - 1].iter().rev().map(|r| r[0]));
    let mut right_loop: Vec<u32> = (0..=2 * i_out)
        .map(|k| top.idx[n / 2 - i_out + k])
        .collect();
    right_loop.extend(
        r_rows[1..r_rows.len() - 1]
            .iter()
            .rev()
            .filter_map(|r| r.last().copied()),
    );
    [left_loop, right_loop]
}

/// Extrudes a sleeve from an armhole out along the arm (`side` +1 left, -1 right) to
/// lateral distance `end_x`, with `ease` added to the arm radius.
pub fn sleeve(
    b: &mut Builder,
    m: &Measurements,
    armhole: &[u32],
    side: f64,
    end_x: f64,
    ease: f64,
    h: f64,
) -> Ring {
    let pts: Vec<[f64; 3]> = armhole.iter().map(|&i| b.positions[i as usize]).collect();
    let start_x = pts.iter().map(|p| p[0] * side).fold(0.0, f64::max);
    let n = pts.len().max(1) as f64;
    let c = scale(pts.iter().fold([0.0; 3], |s, &p| add(s, p)), 1.0 / n);
    let loop_r = pts
        .iter()
        .map(|p| ((p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt())
        .sum::<f64>()
        / n;
    let length = (end_x - start_x).max(2.0 * h);
    let count = segments(length, h).max(2);
    // Narrow to the arm within the sleeve even when it is short.
    let transition = (0.6 * length).min(0.12);
    let rings: Vec<ExtrudeRing> = (1..=count)
        .map(|s| {
            let d = length * s as f64 / count as f64;
            let x = start_x + d;
            let t = (d / transition).min(1.0);
            let smooth = t * t * (3.0 - 2.0 * t);
            let axis = [side * x, m.arm_y, 0.0];
            let from = [side * x, c[1], c[2]];
            ExtrudeRing {
                center: lerp3(from, axis, smooth),
                radius: loop_r + (m.arm_r_at(x) + ease - loop_r) * smooth,
                blend: smooth.max(0.35),
            }
        })
        .collect();
    extrude(b, armhole, [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], &rings)
}
