//! Skirt profiles: the sections of a flared cone from the waist (or the dress's waist)
//! to the hem, never closer to the body than the ease.

use crate::fit::Measurements;
use crate::kind::Style;
use crate::tube::{segments, Section};

/// Skirt length: where the hem sits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkirtLength {
    /// Mid-thigh.
    Mini,
    /// Just below the knee.
    Knee,
    /// Above the ankle.
    Maxi,
}

impl SkirtLength {
    /// Hem height for these measurements.
    pub fn hem_y(self, m: &Measurements) -> f64 {
        match self {
            SkirtLength::Mini => m.crotch_y - 0.4 * (m.crotch_y - m.knee_y),
            SkirtLength::Knee => m.knee_y - 0.05,
            SkirtLength::Maxi => m.ankle_y + 0.12,
        }
    }
}

/// Half axes of the body's envelope at height `y`: the torso above the crotch, both
/// legs together below it.
pub fn body_envelope(m: &Measurements, y: f64) -> ([f64; 2], f64) {
    if y >= m.crotch_y {
        let s = m.torso_at(y);
        ([s.half_x, s.half_z], s.center_z)
    } else {
        let r = m.leg_r_at(y);
        let s = m.torso_at(m.crotch_y);
        (
            [
                (m.leg_x_at(y) + r).max(s.half_x * 0.8),
                r.max(s.half_z * 0.8),
            ],
            0.0,
        )
    }
}

/// Sections from `hem_y` up to `top_y` (ascending) with the style's ease. Below the hips
/// the skirt widens by the style's `flare` (0 straight, 1 a wide A-line: 0.6 m of extra radius per metre of length);
/// waviness grows towards the hem.
pub fn skirt_sections(
    m: &Measurements,
    top_y: f64,
    hem_y: f64,
    style: &Style,
    h: f64,
) -> Vec<Section> {
    let (flare, ease, wave, lobes) = (style.flare, style.ease, style.wave, style.lobes);
    let count = segments(top_y - hem_y, h).max(2);
    let hip_y = m.crotch_y + 0.35 * (m.waist_y - m.crotch_y);
    // Cloth hangs: going down from the waist the radius never shrinks, so each section
    // takes the largest body envelope at or above it (a running maximum), then the
    // flare below the hips. This follows the waist, drapes over the hips without a step
    // and clears the buttocks and thighs.
    let envelope_above = |y: f64| {
        let mut r = [0.0f64; 2];
        let mut t = top_y;
        while t >= y {
            let (e, _) = body_envelope(m, t);
            r = [r[0].max(e[0]), r[1].max(e[1])];
            t -= 0.005;
        }
        let (e, _) = body_envelope(m, y);
        [r[0].max(e[0]), r[1].max(e[1])]
    };
    (0..=count)
        .map(|s| {
            let y = hem_y + (top_y - hem_y) * s as f64 / count as f64;
            let (_, cz) = body_envelope(m, y);
            let below = (hip_y - y).max(0.0);
            let extra = 0.6 * flare * below;
            let env = envelope_above(y);
            let radii = [env[0] + extra + ease, env[1] + extra + ease];
            let toward_hem = (below / (hip_y - hem_y).max(1e-3)).clamp(0.0, 1.0);
            Section {
                y,
                radii,
                center_z: if y < hip_y {
                    cz * (1.0 - toward_hem)
                } else {
                    cz
                },
                wave: wave * toward_hem,
                lobes,
            }
        })
        .collect()
}
