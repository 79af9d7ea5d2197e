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
            [(m.leg_x + r).max(s.half_x * 0.8), r.max(s.half_z * 0.8)],
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
    // Largest envelope between the waist and the hips sets where the flare starts from.
    let mut rest = [0.0f64; 2];
    let mut y = hip_y;
    while y <= top_y {
        let (r, _) = body_envelope(m, y);
        rest = [rest[0].max(r[0]), rest[1].max(r[1])];
        y += 0.01;
    }
    (0..=count)
        .map(|s| {
            let y = hem_y + (top_y - hem_y) * s as f64 / count as f64;
            let (env, cz) = body_envelope(m, y);
            let below = (hip_y - y).max(0.0);
            let extra = 0.6 * flare * below;
            let radii = if y < hip_y {
                [
                    (rest[0] + extra).max(env[0]) + ease,
                    (rest[1] + extra).max(env[1]) + ease,
                ]
            } else {
                [env[0] + ease, env[1] + ease]
            };
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
