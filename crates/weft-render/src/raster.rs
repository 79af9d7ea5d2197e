//! The z-buffered triangle rasteriser: which pixels a projected triangle covers and
//! which surface is nearest there.
//!
//! Coverage is tested at pixel centres with edge functions and a top-left rule, so two
//! triangles sharing an edge never both draw, nor both miss, a pixel on it; the depth
//! test keeps the nearer surface (`1 / depth`, larger is nearer, ties keep the first
//! drawn). Attributes are interpolated perspective-correctly. Everything is sequential
//! `f64` arithmetic in a fixed order, so the same input gives the same pixels.

use crate::image::{Image, Rgb};

/// A colour buffer with a depth buffer of the same size.
pub(crate) struct Target {
    width: usize,
    height: usize,
    color: Vec<Rgb>,
    /// `1 / depth` of the nearest surface drawn so far; 0 where nothing is.
    inv_depth: Vec<f32>,
}

impl Target {
    pub(crate) fn new(width: u32, height: u32, background: Rgb) -> Self {
        let (w, h) = (width.max(1) as usize, height.max(1) as usize);
        Target {
            width: w,
            height: h,
            color: vec![background; w * h],
            inv_depth: vec![0.0; w * h],
        }
    }

    /// Draws the triangle with pixel-space corners `v[i] = (x, y, depth)` (depth > 0).
    /// `shade` receives the perspective-correct barycentric weights of corners 0, 1, 2
    /// at a covered pixel that passed the depth test and returns its colour.
    /// Triangles of either winding are drawn: garments are open, their inside shows.
    pub(crate) fn triangle<F>(&mut self, v: [[f64; 3]; 3], mut shade: F)
    where
        F: FnMut([f64; 3]) -> Rgb,
    {
        // Wind counter-clockwise in the edge-function sense; remember the permutation so
        // `shade` sees weights in the caller's corner order.
        let area0 = edge(v[0], v[1], v[2]);
        let (order, area) = if area0 < 0.0 {
            ([0usize, 2, 1], -area0)
        } else {
            ([0usize, 1, 2], area0)
        };
        if area.is_nan() || area <= 1e-12 || !area.is_finite() {
            return;
        }
        let p = order.map(|i| v[i]);
        let inv_z = p.map(|q| 1.0 / q[2]);
        let min_x = p.iter().map(|q| q[0]).fold(f64::INFINITY, f64::min);
        let max_x = p.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max);
        let min_y = p.iter().map(|q| q[1]).fold(f64::INFINITY, f64::min);
        let max_y = p.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max);
        // Pixel (x, y) has its centre at (x + 0.5, y + 0.5).
        let x0 = (min_x - 0.5).ceil().max(0.0);
        let x1 = (max_x - 0.5).floor().min(self.width as f64 - 1.0);
        let y0 = (min_y - 0.5).ceil().max(0.0);
        let y1 = (max_y - 0.5).floor().min(self.height as f64 - 1.0);
        if !(x0 <= x1 && y0 <= y1) {
            return;
        }
        let (x0, x1, y0, y1) = (x0 as usize, x1 as usize, y0 as usize, y1 as usize);
        // Edge i is opposite corner i.
        let edges = [(p[1], p[2]), (p[2], p[0]), (p[0], p[1])];
        let top_left = edges.map(|(a, b)| is_top_left(a, b));
        for y in y0..=y1 {
            let py = y as f64 + 0.5;
            let row = y * self.width;
            for x in x0..=x1 {
                let px = x as f64 + 0.5;
                let q = [px, py, 0.0];
                let mut w = [0.0; 3];
                let mut inside = true;
                for i in 0..3 {
                    w[i] = edge(edges[i].0, edges[i].1, q);
                    if w[i] < 0.0 || (w[i] == 0.0 && !top_left[i]) {
                        inside = false;
                        break;
                    }
                }
                if !inside {
                    continue;
                }
                let b = w.map(|wi| wi / area);
                let inv = b[0] * inv_z[0] + b[1] * inv_z[1] + b[2] * inv_z[2];
                let idx = row + x;
                let inv32 = inv as f32;
                if inv32 <= self.inv_depth[idx] {
                    continue;
                }
                let persp = [0, 1, 2].map(|i| b[i] * inv_z[i] / inv);
                let mut weights = [0.0; 3];
                for (k, &i) in order.iter().enumerate() {
                    weights[i] = persp[k];
                }
                self.inv_depth[idx] = inv32;
                self.color[idx] = shade(weights);
            }
        }
    }

    /// The colour buffer as an image, each `factor × factor` block averaged into one
    /// pixel (box filter): how a supersampled rendering becomes an anti-aliased one.
    /// Sides should be multiples of `factor`; a remainder is cut off.
    pub(crate) fn resolve(self, factor: u32) -> Image {
        let f = factor.max(1) as usize;
        let (w, h) = ((self.width / f).max(1), (self.height / f).max(1));
        if f == 1 {
            // The buffer always holds width × height pixels.
            return Image::from_pixels(w as u32, h as u32, &self.color)
                .unwrap_or_else(|| Image::new(w as u32, h as u32, [0; 3]));
        }
        let n = (f * f) as u32;
        let mut out = Vec::with_capacity(w * h);
        let mut acc = vec![[0u32; 3]; w];
        for oy in 0..h {
            acc.iter_mut().for_each(|a| *a = [0; 3]);
            for sy in 0..f {
                let start = (oy * f + sy) * self.width;
                let row = &self.color[start..start + w * f];
                for (a, block) in acc.iter_mut().zip(row.chunks_exact(f)) {
                    for px in block {
                        a[0] += u32::from(px[0]);
                        a[1] += u32::from(px[1]);
                        a[2] += u32::from(px[2]);
                    }
                }
            }
            out.extend(acc.iter().map(|a| a.map(|v| ((v + n / 2) / n) as u8)));
        }
        Image::from_pixels(w as u32, h as u32, &out)
            .unwrap_or_else(|| Image::new(w as u32, h as u32, [0; 3]))
    }
}

/// Twice the signed area of `(a, b, c)` in pixel coordinates (y down): positive when
/// `c` lies to the left of `a → b` as seen on screen with y flipped.
fn edge(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether pixel centres exactly on edge `a → b` belong to this triangle. The rule
/// assigns each such pixel to exactly one of the two triangles sharing the edge, which
/// traverse it in opposite directions.
fn is_top_left(a: [f64; 3], b: [f64; 3]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    dy < 0.0 || (dy == 0.0 && dx > 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(t: &Target, c: Rgb) -> usize {
        t.color.iter().filter(|&&x| x == c).count()
    }

    #[test]
    fn a_square_of_two_triangles_covers_each_pixel_once() {
        // Corners on pixel centres, so many centres lie exactly on the shared diagonal.
        let mut t = Target::new(16, 16, [0; 3]);
        let a = [2.5, 2.5, 1.0];
        let b = [12.5, 2.5, 1.0];
        let c = [12.5, 12.5, 1.0];
        let d = [2.5, 12.5, 1.0];
        let mut hits = vec![0u32; 256];
        for tri in [[a, b, c], [a, c, d]] {
            t.triangle(tri, |_| [255, 0, 0]);
            let mut alone = Target::new(16, 16, [0; 3]);
            alone.triangle(tri, |_| [1, 1, 1]);
            for (h, c) in hits.iter_mut().zip(&alone.color) {
                *h += u32::from(*c == [1, 1, 1]);
            }
        }
        assert!(hits.iter().all(|&h| h <= 1));
        assert_eq!(hits.iter().filter(|&&h| h == 1).count(), 100);
        assert_eq!(count(&t, [255, 0, 0]), 100);
    }

    proptest::proptest! {
        /// A jittered grid of triangles tiling a square covers every pixel centre inside
        /// the square exactly once, whatever the jitter that keeps it a tiling.
        #[test]
        fn a_triangulated_square_covers_each_pixel_exactly_once(
            jitter in proptest::collection::vec((-0.3f64..0.3, -0.3f64..0.3), 25),
        ) {
            let n = 4usize;
            let (lo, hi) = (2.3, 29.7);
            let cell = (hi - lo) / n as f64;
            let vertex = |i: usize, j: usize| {
                let (mut x, mut y) = (lo + i as f64 * cell, lo + j as f64 * cell);
                if i > 0 && i < n && j > 0 && j < n {
                    let (dx, dy) = jitter[j * (n + 1) + i];
                    x += dx * cell;
                    y += dy * cell;
                }
                [x, y, 1.0]
            };
            // The property is about tilings: jitter that folds a triangle over its
            // neighbour (possible once two vertices move more than a quarter cell towards
            // each other) makes the triangles overlap, so such draws are skipped.
            let signed_area = |[a, b, c]: [[f64; 3]; 3]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            let mut triangles = Vec::new();
            for j in 0..n {
                for i in 0..n {
                    let (a, b, c, d) = (vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1));
                    triangles.extend([[a, b, c], [a, c, d]]);
                }
            }
            proptest::prop_assume!(triangles.iter().all(|&t| signed_area(t) > 0.0));
            let mut hits = vec![0u32; 32 * 32];
            for tri in triangles {
                let mut t = Target::new(32, 32, [0; 3]);
                t.triangle(tri, |_| [1, 1, 1]);
                for (h, c) in hits.iter_mut().zip(&t.color) {
                    *h += u32::from(*c == [1, 1, 1]);
                }
            }
            for y in 0..32 {
                for x in 0..32 {
                    let inside = (2..=29).contains(&x) && (2..=29).contains(&y);
                    proptest::prop_assert_eq!(hits[y * 32 + x], u32::from(inside), "pixel {} {}", x, y);
                }
            }
        }
    }

    #[test]
    fn resolve_averages_blocks() {
        let mut t = Target::new(4, 2, [0; 3]);
        t.color[0] = [255; 3];
        t.color[4] = [255; 3];
        let img = t.resolve(2);
        assert_eq!((img.width(), img.height()), (2, 1));
        assert_eq!(img.get(0, 0), Some([128, 128, 128]));
        assert_eq!(img.get(1, 0), Some([0, 0, 0]));
        let t = Target::new(3, 2, [7; 3]);
        assert_eq!(t.resolve(1), Image::new(3, 2, [7; 3]));
    }

    #[test]
    fn nearer_surface_wins_in_either_order() {
        let near = [[0.0, 0.0, 1.0], [10.0, 0.0, 1.0], [0.0, 10.0, 1.0]];
        let far = [[0.0, 0.0, 2.0], [10.0, 0.0, 2.0], [0.0, 10.0, 2.0]];
        for order in [[near, far], [far, near]] {
            let mut t = Target::new(10, 10, [0; 3]);
            for (k, tri) in order.iter().enumerate() {
                let c = if tri[0][2] == 1.0 {
                    [9, 9, 9]
                } else {
                    [k as u8 + 1; 3]
                };
                t.triangle(*tri, |_| c);
            }
            assert_eq!(t.color[0], [9, 9, 9]);
        }
    }

    #[test]
    fn weights_follow_caller_order_and_sum_to_one() {
        let mut t = Target::new(20, 20, [0; 3]);
        // Clockwise on screen: the rasteriser flips it internally.
        let tri = [[1.0, 1.0, 1.0], [1.0, 19.0, 3.0], [19.0, 1.0, 2.0]];
        let mut seen = Vec::new();
        t.triangle(tri, |w| {
            seen.push(w);
            [1, 1, 1]
        });
        assert!(!seen.is_empty());
        for w in &seen {
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(w.iter().all(|&x| (-1e-12..=1.0 + 1e-12).contains(&x)));
        }
        // The pixel nearest corner 1 weighs corner 1 most.
        let mut t = Target::new(20, 20, [0; 3]);
        t.triangle(tri, |w| if w[1] > 0.75 { [7, 7, 7] } else { [1, 1, 1] });
        assert_eq!(t.color[17 * 20 + 1], [7, 7, 7]);
    }

    #[test]
    fn degenerate_and_offscreen_triangles_draw_nothing() {
        let mut t = Target::new(8, 8, [0; 3]);
        t.triangle([[1.0, 1.0, 1.0], [5.0, 5.0, 1.0], [3.0, 3.0, 1.0]], |_| {
            [1; 3]
        });
        t.triangle(
            [[-9.0, -9.0, 1.0], [-5.0, -9.0, 1.0], [-9.0, -5.0, 1.0]],
            |_| [1; 3],
        );
        t.triangle(
            [[f64::NAN, 1.0, 1.0], [5.0, 5.0, 1.0], [3.0, 1.0, 1.0]],
            |_| [1; 3],
        );
        assert_eq!(count(&t, [1; 3]), 0);
    }
}
