//! Scalar colour maps: how a per-vertex number (error in mm, attribution, displacement)
//! becomes a colour, and the value range that maps onto the colour bar.
//!
//! Two maps cover what the papers show: [`Colormap::Viridis`] for magnitudes (errors are
//! never negative; viridis is perceptually uniform and readable with colour-vision
//! deficiency, and prints in grey scale monotonically) and [`Colormap::Diverging`] for
//! signed values (attribution, signed distance) with white at zero, blue below and red
//! above. Values that are not finite are no colour of either map: they are drawn in
//! [`ERROR_COLOR`] so that a NaN coming out of a network is seen, not hidden.

use crate::error::RenderError;
use crate::image::Rgb;

/// Colour of non-finite values and of faces touching a non-finite position: magenta,
/// which neither colour map, the body nor the default garment colour contain.
pub const ERROR_COLOR: Rgb = [255, 0, 255];

/// A scalar colour map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Colormap {
    /// Matplotlib's viridis: dark purple (low) through teal to yellow (high).
    Viridis,
    /// ColorBrewer RdBu, reversed: dark blue (low), white (middle), dark red (high).
    Diverging,
}

/// Matplotlib viridis sampled at t = 0, 0.1, …, 1 (matplotlib, CC0).
const VIRIDIS: [Rgb; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

/// ColorBrewer RdBu with 11 classes, blue end first (Cynthia Brewer, Apache-2.0).
const RDBU: [Rgb; 11] = [
    [0x05, 0x30, 0x61],
    [0x21, 0x66, 0xac],
    [0x43, 0x93, 0xc3],
    [0x92, 0xc5, 0xde],
    [0xd1, 0xe5, 0xf0],
    [0xf7, 0xf7, 0xf7],
    [0xfd, 0xdb, 0xc7],
    [0xf4, 0xa5, 0x82],
    [0xd6, 0x60, 0x4d],
    [0xb2, 0x18, 0x2b],
    [0x67, 0x00, 0x1f],
];

impl Colormap {
    /// The colour at `t` in `[0, 1]` (clamped), linearly interpolated between the
    /// anchors; a non-finite `t` gives [`ERROR_COLOR`].
    pub fn sample(self, t: f64) -> Rgb {
        if !t.is_finite() {
            return ERROR_COLOR;
        }
        let anchors = match self {
            Colormap::Viridis => &VIRIDIS,
            Colormap::Diverging => &RDBU,
        };
        let x = t.clamp(0.0, 1.0) * (anchors.len() - 1) as f64;
        let i = (x.floor() as usize).min(anchors.len() - 2);
        let f = x - i as f64;
        let (a, b) = (anchors[i], anchors[i + 1]);
        [0, 1, 2].map(|k| (f64::from(a[k]) + (f64::from(b[k]) - f64::from(a[k])) * f).round() as u8)
    }

    /// A 256-entry lookup table, so per-pixel colouring is one index.
    pub(crate) fn lut(self) -> [Rgb; 256] {
        let mut lut = [[0u8; 3]; 256];
        for (i, c) in lut.iter_mut().enumerate() {
            *c = self.sample(i as f64 / 255.0);
        }
        lut
    }

    /// The map's name as the CLI spells it.
    pub fn name(self) -> &'static str {
        match self {
            Colormap::Viridis => "viridis",
            Colormap::Diverging => "diverging",
        }
    }
}

/// Which values map onto the ends of the colour map.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum ScalarRange {
    /// From the data: `[min, max]` of the finite values for viridis; `[-m, m]` with
    /// `m = max |v|` for the diverging map, so zero stays white.
    #[default]
    Auto,
    /// Fixed ends (for comparable pictures across methods or frames); values outside
    /// are clamped to the end colours.
    Fixed {
        /// Value at the low end.
        min: f64,
        /// Value at the high end.
        max: f64,
    },
}

impl ScalarRange {
    /// A fixed range, checked: both finite and `min < max`.
    pub fn fixed(min: f64, max: f64) -> Result<Self, RenderError> {
        if !(min.is_finite() && max.is_finite() && min < max) {
            return Err(RenderError::Range { min, max });
        }
        Ok(ScalarRange::Fixed { min, max })
    }

    /// The `(low, high)` ends for `values` under `colormap`; always finite with
    /// `low < high`, also for constant or all-NaN data (then a unit-wide range around
    /// the value, or `[0, 1]`).
    pub fn resolve<I>(self, values: I, colormap: Colormap) -> (f64, f64)
    where
        I: IntoIterator<Item = f64>,
    {
        if let ScalarRange::Fixed { min, max } = self {
            if min.is_finite() && max.is_finite() && min < max {
                return (min, max);
            }
        }
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for v in values.into_iter().filter(|v| v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if lo > hi {
            return match colormap {
                Colormap::Viridis => (0.0, 1.0),
                Colormap::Diverging => (-1.0, 1.0),
            };
        }
        if colormap == Colormap::Diverging {
            let m = lo.abs().max(hi.abs());
            return if m > 0.0 { (-m, m) } else { (-1.0, 1.0) };
        }
        if hi > lo {
            (lo, hi)
        } else if lo == 0.0 {
            (0.0, 1.0)
        } else {
            let pad = 0.05 * lo.abs();
            (lo - pad, hi + pad)
        }
    }
}

/// Where `v` falls in `(lo, hi)`, in `[0, 1]`; NaN for non-finite `v`.
pub(crate) fn normalize(v: f64, (lo, hi): (f64, f64)) -> f64 {
    if !v.is_finite() {
        return f64::NAN;
    }
    ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_middle() {
        assert_eq!(Colormap::Viridis.sample(0.0), VIRIDIS[0]);
        assert_eq!(Colormap::Viridis.sample(1.0), VIRIDIS[10]);
        assert_eq!(Colormap::Viridis.sample(7.0), VIRIDIS[10]);
        assert_eq!(Colormap::Diverging.sample(0.5), [0xf7; 3]);
        assert_eq!(Colormap::Diverging.sample(f64::NAN), ERROR_COLOR);
        let lut = Colormap::Viridis.lut();
        assert_eq!((lut[0], lut[255]), (VIRIDIS[0], VIRIDIS[10]));
    }

    #[test]
    fn viridis_gets_brighter() {
        let luma = |c: Rgb| 0.3 * f64::from(c[0]) + 0.59 * f64::from(c[1]) + 0.11 * f64::from(c[2]);
        let lut = Colormap::Viridis.lut();
        for w in lut.windows(2) {
            assert!(luma(w[1]) >= luma(w[0]) - 0.6, "{:?}", w);
        }
    }

    #[test]
    fn ranges() {
        let v = [1.0, f64::NAN, 3.0, -0.5, f64::INFINITY];
        assert_eq!(ScalarRange::Auto.resolve(v, Colormap::Viridis), (-0.5, 3.0));
        assert_eq!(
            ScalarRange::Auto.resolve(v, Colormap::Diverging),
            (-3.0, 3.0)
        );
        assert_eq!(
            ScalarRange::Auto.resolve([2.0, 2.0], Colormap::Viridis),
            (1.9, 2.1)
        );
        assert_eq!(
            ScalarRange::Auto.resolve([0.0], Colormap::Viridis),
            (0.0, 1.0)
        );
        assert_eq!(
            ScalarRange::Auto.resolve([f64::NAN], Colormap::Viridis),
            (0.0, 1.0)
        );
        assert_eq!(
            ScalarRange::Auto.resolve([0.0], Colormap::Diverging),
            (-1.0, 1.0)
        );
        let f = ScalarRange::fixed(0.0, 10.0).unwrap();
        assert_eq!(f.resolve(v, Colormap::Viridis), (0.0, 10.0));
        assert!(ScalarRange::fixed(1.0, 1.0).is_err());
        assert!(ScalarRange::fixed(f64::NAN, 1.0).is_err());
        assert_eq!(normalize(5.0, (0.0, 10.0)), 0.5);
        assert_eq!(normalize(50.0, (0.0, 10.0)), 1.0);
        assert!(normalize(f64::NAN, (0.0, 10.0)).is_nan());
    }
}
