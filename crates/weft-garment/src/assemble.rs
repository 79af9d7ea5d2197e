//! Puts the parts together for each kind at one edge length `h`.

use crate::build::Builder;
use crate::fit::Measurements;
use crate::kind::{DressTop, GarmentKind, Style};
use crate::pants::legs;
use crate::skirt::{skirt_sections, SkirtLength};
use crate::top::{shoulders, sleeve, Shoulders};
use crate::tube::{around, perimeter, segments, vertical_tube, Section};

/// Torso sections from `bottom` to `top` (ascending) with `ease`.
fn torso_sections(m: &Measurements, bottom: f64, top: f64, ease: f64, h: f64) -> Vec<Section> {
    let count = segments(top - bottom, h).max(1);
    (0..=count)
        .map(|s| {
            let y = bottom + (top - bottom) * s as f64 / count as f64;
            let t = m.torso_at(y);
            Section {
                y,
                radii: [t.half_x + ease, t.half_z + ease],
                center_z: t.center_z,
                wave: 0.0,
                lobes: 0.0,
            }
        })
        .collect()
}

/// Vertices around for a tube through `sections`: from their mean perimeter.
fn ring_count(sections: &[Section], h: f64) -> usize {
    let p = sections
        .iter()
        .map(|s| perimeter(s.radii[0], s.radii[1]))
        .sum::<f64>()
        / sections.len().max(1) as f64;
    around(p, h)
}

/// Builds `kind` at edge length `h`.
pub fn assemble(kind: GarmentKind, style: &Style, m: &Measurements, h: f64) -> Builder {
    let mut b = Builder::default();
    let e = style.ease;
    let top_y = m.armpit_y - 0.03;
    let hip_hem = m.crotch_y + 0.06;
    let waistband = m.waist_y - 0.04;
    match kind {
        GarmentKind::Skirt => {
            let s = skirt_sections(m, waistband, style.length.hem_y(m), style, h);
            let n = ring_count(&s, h);
            vertical_tube(&mut b, &s, n);
        }
        GarmentKind::Dress => {
            let length = if style.length == SkirtLength::Mini {
                SkirtLength::Knee
            } else {
                style.length
            };
            let mut s = skirt_sections(m, m.waist_y, length.hem_y(m), style, h);
            s.pop();
            let bodice_top = if style.dress_top == DressTop::Strapless {
                top_y - 0.02
            } else {
                top_y
            };
            s.extend(torso_sections(m, m.waist_y, bodice_top, e, h));
            let n = ring_count(&s, h);
            let rings = vertical_tube(&mut b, &s, n);
            if let Some(top) = rings.last() {
                match style.dress_top {
                    DressTop::Strapless => {}
                    DressTop::Straps => {
                        shoulders(&mut b, m, top, Shoulders::Straps, e, h);
                    }
                    DressTop::Sleeves => {
                        let holes = shoulders(&mut b, m, top, Shoulders::Panels, e, h);
                        let end = m.shoulder_x + 0.25 * (m.elbow_x - m.shoulder_x);
                        sleeve(&mut b, m, &holes[0], 1.0, end, e, h);
                        sleeve(&mut b, m, &holes[1], -1.0, end, e, h);
                    }
                }
            }
        }
        GarmentKind::Tank | GarmentKind::TShirt | GarmentKind::LongSleeve => {
            let s = torso_sections(m, hip_hem, top_y, e, h);
            let n = ring_count(&s, h);
            let rings = vertical_tube(&mut b, &s, n);
            if let Some(top) = rings.last() {
                let style_of = if kind == GarmentKind::Tank {
                    Shoulders::Straps
                } else {
                    Shoulders::Panels
                };
                let holes = shoulders(&mut b, m, top, style_of, e, h);
                let end = match kind {
                    GarmentKind::TShirt => Some(m.shoulder_x + 0.55 * (m.elbow_x - m.shoulder_x)),
                    GarmentKind::LongSleeve => Some(m.wrist_x - 0.03),
                    _ => None,
                };
                if let Some(end) = end {
                    sleeve(&mut b, m, &holes[0], 1.0, end, e, h);
                    sleeve(&mut b, m, &holes[1], -1.0, end, e, h);
                }
            }
        }
        GarmentKind::Shorts | GarmentKind::Pants | GarmentKind::Jumpsuit => {
            let crotch_ring = m.crotch_y + 0.03;
            let top = if kind == GarmentKind::Jumpsuit {
                top_y
            } else {
                waistband
            };
            let s = torso_sections(m, crotch_ring, top, e, h);
            let n = ring_count(&s, h);
            let rings = vertical_tube(&mut b, &s, n);
            let end_y = if kind == GarmentKind::Shorts {
                m.crotch_y - 0.35 * (m.crotch_y - m.knee_y)
            } else {
                m.ankle_y + 0.08
            };
            if let Some(bottom) = rings.first() {
                legs(&mut b, m, bottom, end_y, e, h);
            }
            if kind == GarmentKind::Jumpsuit {
                if let Some(top) = rings.last() {
                    let holes = shoulders(&mut b, m, top, Shoulders::Panels, e, h);
                    let end = m.shoulder_x + 0.45 * (m.elbow_x - m.shoulder_x);
                    sleeve(&mut b, m, &holes[0], 1.0, end, e, h);
                    sleeve(&mut b, m, &holes[1], -1.0, end, e, h);
                }
            }
        }
    }
    b
}
