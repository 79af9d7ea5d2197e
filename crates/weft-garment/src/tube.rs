//! Vertical tubes around the torso and the skirt: rings of ellipses stacked along Y.

use crate::build::{ellipse, Builder, Ring};

/// One ring of a vertical tube.
#[derive(Clone, Copy, Debug)]
pub struct Section {
    /// Height (m).
    pub y: f64,
    /// Half axes along X and Z (m), ease included.
    pub radii: [f64; 2],
    /// Centre along Z (m).
    pub center_z: f64,
    /// Hem waviness amplitude (relative radius), 0 for a plain ring.
    pub wave: f64,
    /// Number of lobes of the waviness.
    pub lobes: f64,
}

/// Builds a tube through `sections` (ascending `y`) with `n` vertices per ring and
/// returns its rings, lowest first. Angles start on the body's left (+X) and run towards
/// the front (+Z), so with rows stripped lowest-first the normals point outwards.
pub fn vertical_tube(b: &mut Builder, sections: &[Section], n: usize) -> Vec<Ring> {
    let mut rings: Vec<Ring> = Vec::with_capacity(sections.len());
    let top = sections.last().map(|s| s.y).unwrap_or(0.0);
    for s in sections {
        let (wave, lobes) = (s.wave, s.lobes);
        // (1 + sin)/2 ≥ 0: waves only push the cloth out, never into the body.
        let f = move |t: f64| wave * 0.5 * (1.0 + (lobes * t).sin());
        let pts = ellipse(
            [0.0, s.y, s.center_z],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            s.radii,
            n,
            &f,
        );
        let ring = b.new_row(&pts, top - s.y, true);
        if let Some(prev) = rings.last() {
            b.strip(prev, &ring);
        }
        rings.push(ring);
    }
    rings
}

/// Ring count along a span of `length` at edge length `h` (at least one segment).
pub fn segments(length: f64, h: f64) -> usize {
    ((length / h).round() as usize).max(1)
}

/// Vertices around a tube of perimeter `perimeter` at edge length `h`, a multiple of 4
/// (so the left, front, right and back lie on vertices), at least 12.
pub fn around(perimeter: f64, h: f64) -> usize {
    (((perimeter / h) / 4.0).round() as usize * 4).max(12)
}

/// Perimeter of an ellipse (Ramanujan's approximation).
pub fn perimeter(a: f64, b: f64) -> f64 {
    let h = ((a - b) / (a + b)).powi(2);
    std::f64::consts::PI * (a + b) * (1.0 + 3.0 * h / (10.0 + (4.0 - 3.0 * h).sqrt()))
}
