//! The colour-bar legend beside a colour-mapped picture: what the quantity is, which
//! colour is which value, at round tick values.

use crate::colormap::Colormap;
use crate::font::{Align, TextStyle};
use crate::image::{Image, Rgb};
use crate::ticks;

/// Dark grey for text and outlines: softer than black on white, still high contrast.
pub(crate) const INK: Rgb = [40, 40, 48];

/// What a legend shows.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Legend<'a> {
    pub(crate) colormap: Colormap,
    pub(crate) range: (f64, f64),
    pub(crate) label: &'a str,
}

/// Sizes derived from the picture height and text style.
struct Layout {
    margin: i64,
    bar_w: i64,
    tick: i64,
    gap: i64,
}

impl<'a> Legend<'a> {
    fn layout(style: &TextStyle, height: u32) -> Layout {
        let cw = i64::from(style.char_width());
        Layout {
            margin: cw,
            bar_w: (i64::from(height) / 40).max(10),
            tick: (cw / 2).max(3),
            gap: (cw / 2).max(3),
        }
    }

    fn ticks(&self) -> Vec<(f64, String)> {
        let (lo, hi) = self.range;
        let (vals, step) = ticks::linear(lo, hi, 6);
        vals.into_iter()
            .map(|v| (v, ticks::label(v, step)))
            .collect()
    }

    /// Width in pixels the legend needs in a picture `height` pixels tall, capped at a
    /// third of `max_width` (a long label then runs left over the picture's margin).
    pub(crate) fn width(&self, style: &TextStyle, height: u32, max_width: u32) -> u32 {
        let l = Self::layout(style, height);
        let labels = self
            .ticks()
            .iter()
            .map(|(_, s)| i64::from(style.width(s)))
            .max()
            .unwrap_or(0);
        let bar = 2 * l.margin + l.bar_w + l.tick + l.gap + labels;
        let title = 2 * l.margin + i64::from(style.width(self.label));
        let w = bar.max(title).min(i64::from(max_width / 3)).max(0);
        u32::try_from(w).unwrap_or(0)
    }

    /// Draws the legend into the panel `[x, x + w) × [0, height)` of `img`.
    pub(crate) fn draw(&self, img: &mut Image, x: i64, w: i64, style: &TextStyle) {
        let height = img.height();
        let l = Self::layout(style, height);
        let lh = i64::from(style.line_height());
        let bar_h = (i64::from(height) * 11 / 20).max(20);
        let title_h = if self.label.is_empty() { 0 } else { lh + l.gap };
        let top = (i64::from(height) - bar_h - title_h) / 2;
        let bar_x = x + l.margin;
        let bar_y = top + title_h;
        if !self.label.is_empty() {
            let tw = i64::from(style.width(self.label));
            let tx = bar_x.min(x + w - l.margin - tw);
            style.draw(img, tx, top, Align::Left, self.label);
        }
        let lut = self.colormap.lut();
        for r in 0..bar_h {
            let t = 1.0 - r as f64 / (bar_h - 1) as f64;
            let c = lut[(t * 255.0).round() as usize];
            img.fill_rect(bar_x, bar_y + r, l.bar_w, 1, c);
        }
        img.stroke_rect(bar_x - 1, bar_y - 1, l.bar_w + 2, bar_h + 2, INK);
        let (lo, hi) = self.range;
        for (v, s) in self.ticks() {
            let t = (v - lo) / (hi - lo);
            let ty = bar_y + bar_h - 1 - (t * (bar_h - 1) as f64).round() as i64;
            let tx = bar_x + l.bar_w + 1;
            img.fill_rect(tx, ty, l.tick, 1, INK);
            style.draw(img, tx + l.tick + l.gap, ty - lh / 2, Align::Left, &s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::font::Font;

    #[test]
    fn legend_fits_its_width_and_shows_both_ends_of_the_map() {
        let style = TextStyle::new(Font::Small, 1, INK);
        let legend = Legend {
            colormap: Colormap::Viridis,
            range: (0.0, 12.5),
            label: "error (mm)",
        };
        let w = legend.width(&style, 300, 600);
        assert!(w > 40 && w <= 200, "{w}");
        let mut img = Image::new(w, 300, [255; 3]);
        legend.draw(&mut img, 0, i64::from(w), &style);
        let has = |c: Rgb| img.as_bytes().chunks(3).any(|p| p == c);
        assert!(has(Colormap::Viridis.sample(0.0)));
        assert!(has(Colormap::Viridis.sample(1.0)));
        assert!(has(INK));
    }
}
