//! Plots as pictures: training curves (several named series over steps, optionally on a
//! log y axis), per-frame error plots, and error histograms.
//!
//! They are drawn with this crate's own anti-aliased lines and bitmap fonts rather than
//! with plotters: plotters' text needs either system font libraries or a bundled
//! TrueType file plus a rasteriser, and the three kinds of plot weft needs are a few
//! hundred lines on top of what the renderer already has. Output is byte-for-byte
//! deterministic like every other picture here.
//!
//! Data that cannot be drawn (non-finite points, values ≤ 0 on a log axis, histogram
//! values outside a fixed range) is left out, breaks the line, and is counted in a note
//! at the bottom of the plot, never silently dropped.

use crate::error::RenderError;
use crate::font::{Align, Font, TextStyle};
use crate::image::{check_size, Image, Rgb};
use crate::legend::INK;
use crate::ticks;

/// Colours of successive series (matplotlib's "tab10", readable on white and distinct
/// from each other).
pub const PALETTE: [Rgb; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

const GRID: Rgb = [228, 228, 232];
const GRID_MINOR: Rgb = [242, 242, 245];
const WHITE: Rgb = [255, 255, 255];
const NOTE: Rgb = [176, 0, 176];

/// A named sequence of `(x, y)` points, drawn as a line in the given order.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Name in the legend (empty: not listed).
    pub name: String,
    /// Points in drawing order.
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// A series from points.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
        }
    }

    /// A series of `values` over x = 0, 1, 2, …: per-frame errors.
    pub fn from_values(name: impl Into<String>, values: &[f64]) -> Self {
        Series::new(
            name,
            values
                .iter()
                .enumerate()
                .map(|(i, &v)| (i as f64, v))
                .collect(),
        )
    }
}

/// A line plot: training curves (loss terms over steps, log y), validation errors per
/// epoch, per-frame errors of several methods.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct LinePlot {
    /// Title above the plot.
    pub title: String,
    /// Label under the x axis.
    pub x_label: String,
    /// Label beside the y axis.
    pub y_label: String,
    /// The lines, coloured by [`PALETTE`] in order.
    pub series: Vec<Series>,
    /// Logarithmic y axis (values ≤ 0 are left out and counted).
    pub log_y: bool,
}

/// One group of values in a [`Histogram`].
#[derive(Clone, Debug, PartialEq)]
pub struct HistogramSeries {
    /// Name in the legend (with mean and count added).
    pub name: String,
    /// The values (non-finite ones are left out and counted).
    pub values: Vec<f64>,
}

/// A histogram of one or more groups of values over shared bins, e.g. per-vertex errors
/// of several methods (seed 001, Fig. 3.9). Each group's mean is marked with a vertical
/// line.
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    /// Title above the plot.
    pub title: String,
    /// Label under the x axis (the quantity and unit).
    pub x_label: String,
    /// Label beside the y axis.
    pub y_label: String,
    /// The groups, coloured by [`PALETTE`] in order, overlaid.
    pub series: Vec<HistogramSeries>,
    /// Number of bins (1 to 10 000).
    pub bins: u32,
    /// Fixed bin range; `None` spans the finite values.
    pub range: Option<(f64, f64)>,
    /// Show fractions of each group instead of counts, so groups of different sizes
    /// compare.
    pub normalize: bool,
}

impl Default for Histogram {
    fn default() -> Self {
        Histogram {
            title: String::new(),
            x_label: String::new(),
            y_label: "count".into(),
            series: Vec::new(),
            bins: 40,
            range: None,
            normalize: false,
        }
    }
}

impl LinePlot {
    /// A per-frame plot: one series per method over frame numbers.
    pub fn per_frame(
        title: impl Into<String>,
        y_label: impl Into<String>,
        series: Vec<Series>,
    ) -> Self {
        LinePlot {
            title: title.into(),
            x_label: "frame".into(),
            y_label: y_label.into(),
            series,
            log_y: false,
        }
    }

    /// Draws the plot at `width × height` pixels.
    pub fn render(&self, width: u32, height: u32) -> Result<Image, RenderError> {
        check_size(width, height)?;
        let mut skipped = 0usize;
        let mut xs = Range::default();
        let mut ys = Range::default();
        for s in &self.series {
            for &(x, y) in &s.points {
                if self.usable(x, y) {
                    xs.add(x);
                    ys.add(if self.log_y { y.log10() } else { y });
                } else {
                    skipped += 1;
                }
            }
        }
        let (x_lo, x_hi) = xs.span_or(0.0, 1.0);
        let (y_lo, y_hi) = if self.log_y {
            let (a, b) = ys.span_or(0.0, 1.0);
            let pad = 0.04 * (b - a);
            (10f64.powf(a - pad), 10f64.powf(b + pad))
        } else {
            let (a, b) = ys.span_or(0.0, 1.0);
            let pad = 0.05 * (b - a);
            let lo = if a >= 0.0 && a - pad < 0.0 {
                0.0
            } else {
                a - pad
            };
            (lo, b + pad)
        };
        let mut img = Image::new(width, height, WHITE);
        let axes = Axes::draw(
            &mut img,
            Labels {
                title: &self.title,
                x: &self.x_label,
                y: &self.y_label,
            },
            (x_lo, x_hi),
            (y_lo, y_hi),
            self.log_y,
        );
        let lw = axes.line_width();
        for (k, s) in self.series.iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()];
            let mut prev: Option<(f64, f64)> = None;
            for &(x, y) in &s.points {
                if !self.usable(x, y) {
                    prev = None;
                    continue;
                }
                let p = (axes.px(x), axes.py(y));
                img.line(prev.unwrap_or(p), p, lw, color);
                prev = Some(p);
            }
        }
        let entries: Vec<(String, Rgb)> = self
            .series
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.name.is_empty())
            .map(|(k, s)| (s.name.clone(), PALETTE[k % PALETTE.len()]))
            .collect();
        axes.legend(&mut img, &entries);
        if xs.count == 0 {
            axes.note(&mut img, "no data");
        } else if skipped > 0 {
            let why = if self.log_y {
                "non-finite or <= 0 on the log axis"
            } else {
                "non-finite"
            };
            axes.note(&mut img, &format!("{skipped} points not drawn ({why})"));
        }
        Ok(img)
    }

    fn usable(&self, x: f64, y: f64) -> bool {
        x.is_finite() && y.is_finite() && (!self.log_y || y > 0.0)
    }
}

impl Histogram {
    /// Draws the histogram at `width × height` pixels.
    pub fn render(&self, width: u32, height: u32) -> Result<Image, RenderError> {
        check_size(width, height)?;
        if !(1..=10_000).contains(&self.bins) {
            return Err(RenderError::Invalid(format!(
                "a histogram of {} bins; expected 1 to 10000",
                self.bins
            )));
        }
        let (lo, hi) = match self.range {
            Some((a, b)) if a.is_finite() && b.is_finite() && a < b => (a, b),
            Some((a, b)) => return Err(RenderError::Range { min: a, max: b }),
            None => {
                let mut r = Range::default();
                for v in self.series.iter().flat_map(|s| &s.values) {
                    if v.is_finite() {
                        r.add(*v);
                    }
                }
                r.span_or(0.0, 1.0)
            }
        };
        let bins = self.bins as usize;
        let width_bin = (hi - lo) / bins as f64;
        let mut nonfinite = 0usize;
        let mut outside = 0usize;
        let mut counts = vec![vec![0f64; bins]; self.series.len()];
        let mut means = Vec::new();
        for (s, c) in self.series.iter().zip(&mut counts) {
            let (mut sum, mut n) = (0.0, 0usize);
            for &v in &s.values {
                if !v.is_finite() {
                    nonfinite += 1;
                    continue;
                }
                sum += v;
                n += 1;
                if v < lo || v > hi {
                    outside += 1;
                    continue;
                }
                let b = (((v - lo) / width_bin) as usize).min(bins - 1);
                c[b] += 1.0;
            }
            if self.normalize && n > 0 {
                c.iter_mut().for_each(|x| *x /= n as f64);
            }
            means.push((n > 0).then(|| (sum / n as f64, n)));
        }
        let top = counts
            .iter()
            .flatten()
            .fold(0.0f64, |a, &b| a.max(b))
            .max(if self.normalize { 0.01 } else { 1.0 });
        let mut img = Image::new(width, height, WHITE);
        let axes = Axes::draw(
            &mut img,
            Labels {
                title: &self.title,
                x: &self.x_label,
                y: &self.y_label,
            },
            (lo, hi),
            (0.0, top * 1.08),
            false,
        );
        let alpha = if self.series.len() > 1 { 0.38 } else { 0.7 };
        let lw = axes.line_width();
        for (k, c) in counts.iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()];
            let y0 = axes.py(0.0);
            let mut prev_top = y0;
            for (b, &n) in c.iter().enumerate() {
                let xa = axes.px(lo + b as f64 * width_bin);
                let xb = axes.px(lo + (b + 1) as f64 * width_bin);
                let yt = axes.py(n);
                let (ia, ib) = (xa.round() as i64, xb.round() as i64);
                let it = yt.round() as i64;
                for y in it..y0.round() as i64 {
                    for x in ia..ib {
                        img.blend(x, y, color, alpha);
                    }
                }
                // Step outline: up or down to this bin's top, then across it.
                img.line((xa, prev_top), (xa, yt), lw * 0.6, color);
                img.line((xa, yt), (xb, yt), lw * 0.6, color);
                prev_top = yt;
            }
            let xe = axes.px(hi);
            img.line((xe, prev_top), (xe, y0), lw * 0.6, color);
        }
        for (k, m) in means.iter().enumerate() {
            if let Some((mean, _)) = m {
                if (lo..=hi).contains(mean) {
                    let x = axes.px(*mean);
                    let color = PALETTE[k % PALETTE.len()];
                    dashed_vertical(&mut img, x, axes.y0, axes.y1, lw * 0.7, color);
                }
            }
        }
        let entries: Vec<(String, Rgb)> = self
            .series
            .iter()
            .zip(&means)
            .enumerate()
            .filter(|(_, (s, _))| !s.name.is_empty())
            .map(|(k, (s, m))| {
                let text = match m {
                    Some((mean, n)) => format!("{} (mean {}, n={n})", s.name, ticks::value(*mean)),
                    None => format!("{} (no values)", s.name),
                };
                (text, PALETTE[k % PALETTE.len()])
            })
            .collect();
        axes.legend(&mut img, &entries);
        let mut notes = Vec::new();
        if nonfinite > 0 {
            notes.push(format!("{nonfinite} non-finite values left out"));
        }
        if outside > 0 {
            notes.push(format!("{outside} values outside the range"));
        }
        if !notes.is_empty() {
            axes.note(&mut img, &notes.join(", "));
        }
        Ok(img)
    }
}

/// Running min and max of finite numbers.
#[derive(Clone, Copy, Debug)]
struct Range {
    lo: f64,
    hi: f64,
    count: usize,
}

impl Default for Range {
    fn default() -> Self {
        Range {
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
            count: 0,
        }
    }
}

impl Range {
    fn add(&mut self, v: f64) {
        self.lo = self.lo.min(v);
        self.hi = self.hi.max(v);
        self.count += 1;
    }

    /// `(lo, hi)` with `lo < hi`: the default when empty, widened when constant.
    fn span_or(&self, lo: f64, hi: f64) -> (f64, f64) {
        if self.count == 0 {
            (lo, hi)
        } else if self.hi > self.lo {
            (self.lo, self.hi)
        } else {
            let pad = (0.5 * self.lo.abs()).max(0.5);
            (self.lo - pad, self.hi + pad)
        }
    }
}

/// The texts around a plot.
struct Labels<'a> {
    title: &'a str,
    x: &'a str,
    y: &'a str,
}

/// A plot's data rectangle and its mapping from data to pixels.
struct Axes {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    xr: (f64, f64),
    yr: (f64, f64),
    log_y: bool,
    style: TextStyle,
    height: u32,
}

impl Axes {
    /// Lays out and draws title, grid, ticks, tick labels and axis labels; returns the
    /// mapping for the data.
    fn draw(
        img: &mut Image,
        labels: Labels<'_>,
        xr: (f64, f64),
        yr: (f64, f64),
        log_y: bool,
    ) -> Axes {
        let (w, h) = (img.width(), img.height());
        let style = TextStyle::for_height(h.min(w * 3 / 4), INK);
        let title_style = if style.font == Font::Small && h >= 300 {
            TextStyle::new(Font::Large, 1, INK)
        } else {
            style
        };
        let cw = f64::from(style.char_width());
        let lh = f64::from(style.line_height());
        let (x_ticks, x_step) =
            ticks::linear(xr.0, xr.1, (f64::from(w) / (cw * 14.0)).max(2.0) as usize);
        let (y_ticks, y_labels): (Vec<f64>, Vec<String>) = if log_y {
            let t = ticks::decades(yr.0, yr.1);
            let l = t.iter().map(|&v| ticks::decade(v)).collect();
            (t, l)
        } else {
            let (t, step) =
                ticks::linear(yr.0, yr.1, (f64::from(h) / (lh * 4.0)).max(2.0) as usize);
            let l = t.iter().map(|&v| ticks::label(v, step)).collect();
            (t, l)
        };
        let y_label_w = y_labels
            .iter()
            .map(|s| f64::from(style.width(s)))
            .fold(0.0, f64::max);
        let tick = (cw * 0.6).round();
        let gap = (cw * 0.6).round();
        let top = if labels.title.is_empty() {
            lh
        } else {
            f64::from(title_style.line_height()) * 2.0
        };
        let left = gap + if labels.y.is_empty() { 0.0 } else { lh + gap } + y_label_w + gap + tick;
        let bottom = tick + gap + lh + if labels.x.is_empty() { 0.0 } else { gap + lh } + gap + lh;
        let right = cw * 3.0;
        let axes = Axes {
            x0: left.round(),
            x1: (f64::from(w) - right).round().max(left + 2.0),
            y0: (f64::from(h) - bottom).round().max(top + 2.0),
            y1: top.round(),
            xr,
            yr,
            log_y,
            style,
            height: h,
        };
        // Grid first, so data and axes draw over it.
        if log_y && y_ticks.len() <= 7 {
            for &d in &y_ticks {
                for m in 2..10 {
                    let v = d * f64::from(m);
                    if v < yr.1 {
                        axes.hgrid(img, v, GRID_MINOR);
                    }
                }
                let below = d / 10.0;
                for m in 2..10 {
                    let v = below * f64::from(m);
                    if v > yr.0 && v < d {
                        axes.hgrid(img, v, GRID_MINOR);
                    }
                }
            }
        }
        for &v in &y_ticks {
            axes.hgrid(img, v, GRID);
        }
        for &v in &x_ticks {
            let x = axes.px(v).round() as i64;
            img.fill_rect(x, axes.y1 as i64, 1, (axes.y0 - axes.y1) as i64, GRID);
        }
        // Frame.
        let (fx, fy) = (axes.x0 as i64, axes.y1 as i64);
        let (fw, fh) = (
            (axes.x1 - axes.x0) as i64 + 1,
            (axes.y0 - axes.y1) as i64 + 1,
        );
        img.stroke_rect(fx, fy, fw, fh, INK);
        for (&v, s) in y_ticks.iter().zip(&y_labels) {
            let y = axes.py(v).round() as i64;
            img.fill_rect((axes.x0 - tick) as i64, y, tick as i64, 1, INK);
            style.draw(
                img,
                (axes.x0 - tick - gap) as i64,
                y - (lh / 2.0) as i64,
                Align::Right,
                s,
            );
        }
        for &v in &x_ticks {
            let x = axes.px(v).round() as i64;
            img.fill_rect(x, axes.y0 as i64 + 1, 1, tick as i64, INK);
            let s = ticks::label(v, x_step);
            style.draw(img, x, (axes.y0 + tick + gap) as i64, Align::Center, &s);
        }
        let cx = ((axes.x0 + axes.x1) / 2.0) as i64;
        if !labels.x.is_empty() {
            let y = axes.y0 + tick + gap + lh + gap;
            style.draw(img, cx, y as i64, Align::Center, labels.x);
        }
        if !labels.y.is_empty() {
            let cy = ((axes.y0 + axes.y1) / 2.0) as i64;
            style.draw_vertical(img, gap as i64, cy, labels.y);
        }
        if !labels.title.is_empty() {
            let y = (top - f64::from(title_style.line_height())) / 2.0;
            title_style.draw(img, cx, y as i64, Align::Center, labels.title);
        }
        axes
    }

    fn hgrid(&self, img: &mut Image, v: f64, c: Rgb) {
        let y = self.py(v).round() as i64;
        img.fill_rect(self.x0 as i64, y, (self.x1 - self.x0) as i64, 1, c);
    }

    /// Stroke width of data lines: grows with the text size.
    fn line_width(&self) -> f64 {
        (f64::from(self.style.line_height()) / 7.0).clamp(1.5, 6.0)
    }

    fn px(&self, x: f64) -> f64 {
        self.x0 + (x - self.xr.0) / (self.xr.1 - self.xr.0) * (self.x1 - self.x0)
    }

    fn py(&self, y: f64) -> f64 {
        let t = if self.log_y {
            (y.log10() - self.yr.0.log10()) / (self.yr.1.log10() - self.yr.0.log10())
        } else {
            (y - self.yr.0) / (self.yr.1 - self.yr.0)
        };
        self.y0 - t * (self.y0 - self.y1)
    }

    /// A boxed legend in the top-right corner of the data rectangle.
    fn legend(&self, img: &mut Image, entries: &[(String, Rgb)]) {
        if entries.is_empty() {
            return;
        }
        let cw = i64::from(self.style.char_width());
        let lh = i64::from(self.style.line_height());
        let swatch = 3 * cw;
        let text_w = entries
            .iter()
            .map(|(s, _)| i64::from(self.style.width(s)))
            .max()
            .unwrap_or(0);
        let bw = cw + swatch + cw + text_w + cw;
        let bh = lh * entries.len() as i64 + lh / 2;
        let bx = self.x1 as i64 - cw - bw;
        let by = self.y1 as i64 + cw;
        img.fill_rect(bx, by, bw, bh, WHITE);
        img.stroke_rect(bx, by, bw, bh, [200, 200, 205]);
        for (i, (s, c)) in entries.iter().enumerate() {
            let y = by + lh / 4 + i as i64 * lh;
            let ly = (y + lh / 2) as f64;
            img.line(
                ((bx + cw) as f64, ly),
                ((bx + cw + swatch) as f64, ly),
                self.line_width(),
                *c,
            );
            self.style
                .draw(img, bx + cw + swatch + cw, y, Align::Left, s);
        }
    }

    /// A note about data left out, at the bottom left of the picture.
    fn note(&self, img: &mut Image, text: &str) {
        let style = TextStyle {
            color: NOTE,
            ..self.style
        };
        let y = i64::from(self.height) - i64::from(style.line_height()) - 2;
        style.draw(img, i64::from(style.char_width()), y, Align::Left, text);
    }
}

/// A dashed vertical line from `y_bottom` to `y_top` at `x`.
fn dashed_vertical(img: &mut Image, x: f64, y_bottom: f64, y_top: f64, width: f64, c: Rgb) {
    let dash = 6.0 * width.max(1.0);
    let mut y = y_bottom;
    while y > y_top {
        let end = (y - dash).max(y_top);
        img.line((x, y), (x, end), width, c);
        y -= 2.0 * dash;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn has(img: &Image, c: Rgb) -> usize {
        img.as_bytes().chunks(3).filter(|p| *p == c).count()
    }

    #[test]
    fn line_plot_draws_each_series_in_its_colour() {
        let plot = LinePlot {
            title: "training".into(),
            x_label: "step".into(),
            y_label: "loss".into(),
            series: vec![
                Series::new(
                    "vertex",
                    (0..100)
                        .map(|i| (i as f64, 1.0 / (1.0 + i as f64)))
                        .collect(),
                ),
                Series::new(
                    "edge",
                    (0..100)
                        .map(|i| (i as f64, 0.5 / (1.0 + i as f64)))
                        .collect(),
                ),
            ],
            log_y: true,
        };
        let img = plot.render(640, 400).unwrap();
        assert!(has(&img, PALETTE[0]) > 50);
        assert!(has(&img, PALETTE[1]) > 50);
        assert_eq!(img, plot.render(640, 400).unwrap());
    }

    #[test]
    fn bad_points_are_counted_not_fatal() {
        let plot = LinePlot {
            series: vec![Series::from_values("e", &[1.0, f64::NAN, 3.0, -1.0, 2.0])],
            log_y: true,
            ..LinePlot::default()
        };
        let img = plot.render(300, 200).unwrap();
        assert!(has(&img, NOTE) > 0);
        let empty = LinePlot::default().render(200, 100).unwrap();
        assert!(has(&empty, NOTE) > 0);
        assert!(LinePlot::default().render(0, 100).is_err());
    }

    #[test]
    fn histogram_of_two_groups() {
        let h = Histogram {
            title: "vertex error".into(),
            x_label: "error (mm)".into(),
            series: vec![
                HistogramSeries {
                    name: "ours".into(),
                    values: (0..1000).map(|i| (i % 97) as f64 * 0.1).collect(),
                },
                HistogramSeries {
                    name: "baseline".into(),
                    values: (0..500)
                        .map(|i| (i % 89) as f64 * 0.15)
                        .chain([f64::NAN])
                        .collect(),
                },
            ],
            normalize: true,
            ..Histogram::default()
        };
        let img = h.render(640, 400).unwrap();
        assert!(has(&img, NOTE) > 0, "the NaN is reported");
        assert_eq!(img, h.render(640, 400).unwrap());
        let bad = Histogram {
            bins: 0,
            ..Histogram::default()
        };
        assert!(bad.render(100, 100).is_err());
        let bad = Histogram {
            range: Some((1.0, 0.0)),
            ..Histogram::default()
        };
        assert!(bad.render(100, 100).is_err());
    }
}
