//! Text in pictures: two built-in bitmap fonts, drawn at integer scales.
//!
//! Legends, axis labels and frame numbers need text, and a TrueType stack would bring
//! either system libraries (fontconfig, freetype) or a bundled font file and a rasteriser
//! crate. Bitmap glyphs keep the crate free of both and make text byte-for-byte identical
//! on every machine. The glyphs are the X11 misc-fixed 6×13 and 10×20 fonts (public
//! domain, see `tools/gen_font.py`), covering printable ASCII and Latin-1, so `°`, `µ`
//! and `×` work; typographic dashes and the minus sign are drawn as `-`, anything else as
//! `?`.

use crate::font_data::{LARGE, LARGE_SIZE, SMALL, SMALL_SIZE};
use crate::image::{Image, Rgb};

/// A built-in bitmap font.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Font {
    /// 6×13 pixels per glyph: tick labels on small pictures.
    Small,
    /// 10×20 pixels per glyph: labels on pictures of about 800 pixels and more.
    Large,
}

/// How text is drawn: font, integer magnification and colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextStyle {
    /// The font.
    pub font: Font,
    /// Integer magnification (1 = native size); 0 is treated as 1.
    pub scale: u32,
    /// Ink colour.
    pub color: Rgb,
}

/// Horizontal placement of text relative to the given x.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// x is the left edge.
    Left,
    /// x is the centre.
    Center,
    /// x is the right edge.
    Right,
}

impl TextStyle {
    /// `font` at `scale` in `color`.
    pub fn new(font: Font, scale: u32, color: Rgb) -> Self {
        TextStyle { font, scale, color }
    }

    /// A readable style for a picture `height` pixels tall: the small font below 600
    /// pixels, the large one up to 1400, then the large one magnified.
    pub fn for_height(height: u32, color: Rgb) -> Self {
        let (font, scale) = match height {
            0..=599 => (Font::Small, 1),
            600..=1399 => (Font::Large, 1),
            h => (Font::Large, (h / 1400 + 1).min(8)),
        };
        TextStyle { font, scale, color }
    }

    fn s(&self) -> u32 {
        self.scale.max(1)
    }

    /// Advance per character in pixels.
    pub fn char_width(&self) -> u32 {
        self.font.cell().0 * self.s()
    }

    /// Line height in pixels.
    pub fn line_height(&self) -> u32 {
        self.font.cell().1 * self.s()
    }

    /// Width of `text` in pixels (one advance per character: the fonts are monospaced).
    pub fn width(&self, text: &str) -> u32 {
        let n = u32::try_from(text.chars().count()).unwrap_or(u32::MAX);
        n.saturating_mul(self.char_width())
    }

    /// Draws `text` with its top edge at `y`, placed horizontally at `x` by `align`.
    pub fn draw(&self, img: &mut Image, x: i64, y: i64, align: Align, text: &str) {
        let w = i64::from(self.width(text));
        let mut cx = match align {
            Align::Left => x,
            Align::Center => x - w / 2,
            Align::Right => x - w,
        };
        let s = i64::from(self.s());
        let (cw, _) = self.font.cell();
        for c in text.chars() {
            let rows = self.font.glyph(c);
            for (gy, bits) in rows.iter().enumerate() {
                for gx in 0..cw {
                    if bits & (0x8000 >> gx) != 0 {
                        img.fill_rect(cx + i64::from(gx) * s, y + gy as i64 * s, s, s, self.color);
                    }
                }
            }
            cx += i64::from(cw) * s;
        }
    }

    /// Draws `text` turned 90° counter-clockwise (reading bottom to top), as y-axis
    /// labels are. `(x, y)` is the left edge and the vertical centre of the rotated text.
    pub fn draw_vertical(&self, img: &mut Image, x: i64, y_center: i64, text: &str) {
        let w = i64::from(self.width(text));
        let s = i64::from(self.s());
        let (cw, _) = self.font.cell();
        // Text runs upwards from the bottom end.
        let bottom = y_center + w / 2;
        for (i, c) in text.chars().enumerate() {
            let rows = self.font.glyph(c);
            for (gy, bits) in rows.iter().enumerate() {
                for gx in 0..cw {
                    if bits & (0x8000 >> gx) != 0 {
                        // Glyph pixel (gx, gy) maps to (gy, -gx) after the turn.
                        let px = x + gy as i64 * s;
                        let py = bottom - (i as i64 * i64::from(cw) + i64::from(gx) + 1) * s;
                        img.fill_rect(px, py, s, s, self.color);
                    }
                }
            }
        }
    }
}

impl Font {
    /// Glyph cell `(width, height)` in pixels at scale 1.
    pub fn cell(self) -> (u32, u32) {
        match self {
            Font::Small => (SMALL_SIZE.0, SMALL_SIZE.1),
            Font::Large => (LARGE_SIZE.0, LARGE_SIZE.1),
        }
    }

    /// Rows of the glyph for `c` (top first, bit 15 = leftmost column).
    fn glyph(self, c: char) -> &'static [u16] {
        let i = glyph_index(c);
        match self {
            Font::Small => &SMALL[i],
            Font::Large => &LARGE[i],
        }
    }
}

/// Index into the glyph tables: U+0020..=U+007E, then U+00A0..=U+00FF; a few common
/// typographic characters map to their ASCII look-alikes, anything else to `?`.
fn glyph_index(c: char) -> usize {
    let c = match c {
        '\u{2010}'..='\u{2015}' | '\u{2212}' => '-',
        '\u{2018}' | '\u{2019}' => '\'',
        '\u{201c}' | '\u{201d}' => '"',
        '\u{2026}' => '.',
        '\u{03bc}' => '\u{00b5}',
        c => c,
    };
    let u = c as u32;
    match u {
        0x20..=0x7e => (u - 0x20) as usize,
        0xa0..=0xff => (u - 0xa0) as usize + 95,
        _ => ('?' as u32 - 0x20) as usize,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ink(img: &Image) -> usize {
        img.as_bytes().chunks(3).filter(|p| p[0] == 0).count()
    }

    #[test]
    fn glyphs_cover_ascii_and_latin1() {
        assert_eq!(glyph_index(' '), 0);
        assert_eq!(glyph_index('~'), 94);
        assert_eq!(glyph_index('\u{a0}'), 95);
        assert_eq!(glyph_index('ÿ'), 190);
        assert_eq!(glyph_index('−'), glyph_index('-'));
        assert_eq!(glyph_index('€'), glyph_index('?'));
        // Space is blank, letters are not.
        assert!(SMALL[glyph_index(' ')].iter().all(|&r| r == 0));
        assert!(LARGE[glyph_index('A')].iter().any(|&r| r != 0));
        assert!(SMALL[glyph_index('°')].iter().any(|&r| r != 0));
    }

    #[test]
    fn text_is_drawn_where_asked_and_scales() {
        let style = TextStyle::new(Font::Small, 1, [0, 0, 0]);
        assert_eq!(style.width("abc"), 18);
        let mut a = Image::new(40, 20, [255; 3]);
        style.draw(&mut a, 20, 2, Align::Center, "Hi");
        let n1 = ink(&a);
        assert!(n1 > 10);
        // Nothing left of x = 20 - 6 or right of 20 + 6.
        for y in 0..20 {
            assert_eq!(a.get(13, y), Some([255; 3]));
            assert_eq!(a.get(27, y), Some([255; 3]));
        }
        let mut b = Image::new(80, 40, [255; 3]);
        TextStyle::new(Font::Small, 2, [0, 0, 0]).draw(&mut b, 0, 0, Align::Left, "Hi");
        assert_eq!(ink(&b), 4 * n1);
    }

    #[test]
    fn vertical_text_has_the_same_ink() {
        let style = TextStyle::new(Font::Large, 1, [0, 0, 0]);
        let mut h = Image::new(100, 30, [255; 3]);
        style.draw(&mut h, 0, 0, Align::Left, "y (mm)");
        let mut v = Image::new(30, 100, [255; 3]);
        style.draw_vertical(&mut v, 0, 50, "y (mm)");
        assert_eq!(ink(&h), ink(&v));
    }
}
