//! The RGB image every drawing function paints into, and its PNG / APNG encoding.
//!
//! Pixels are 8-bit sRGB, row-major, top row first, no alpha: pictures go into reports and
//! papers on a white page, so transparency would only make them depend on the viewer.
//! Encoding is deterministic (fixed filter and compression, no time stamps), so the same
//! picture always gives the same bytes. Files are written through
//! [`weft_mesh::io::write_atomic`]: an error never leaves a partial PNG behind.

use std::io::Write;
use std::path::Path;

use crate::error::RenderError;

/// An 8-bit sRGB colour.
pub type Rgb = [u8; 3];

/// The largest image side any function here accepts: 16 384 pixels (768 MiB of RGB at
/// most), far above any figure, low enough that a typo cannot exhaust memory silently.
pub const MAX_SIDE: u32 = 16_384;

/// An RGB image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    width: u32,
    height: u32,
    /// `width * height * 3` bytes, row-major, top row first.
    data: Vec<u8>,
}

/// Checks that `width × height` is a drawable size.
pub(crate) fn check_size(width: u32, height: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(RenderError::Size {
            width,
            height,
            max: MAX_SIDE,
        });
    }
    Ok(())
}

impl Image {
    /// A `width × height` image filled with `fill`. Sides are clamped to `1..=MAX_SIDE`;
    /// functions taking sizes from users check them first with a typed error.
    pub fn new(width: u32, height: u32, fill: Rgb) -> Self {
        let width = width.clamp(1, MAX_SIDE);
        let height = height.clamp(1, MAX_SIDE);
        let data = fill.repeat(width as usize * height as usize);
        Image {
            width,
            height,
            data,
        }
    }

    /// An image from row-major pixels, top row first; `None` unless there are exactly
    /// `width × height` of them.
    pub(crate) fn from_pixels(width: u32, height: u32, pixels: &[Rgb]) -> Option<Self> {
        if pixels.len() != width as usize * height as usize || width == 0 || height == 0 {
            return None;
        }
        Some(Image {
            width,
            height,
            data: pixels.concat(),
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The raw RGB bytes, row-major, top row first.
    pub fn as_bytes(&self) -> &[u8] {
        &self.data
    }

    fn index(&self, x: i64, y: i64) -> Option<usize> {
        if x < 0 || y < 0 || x >= i64::from(self.width) || y >= i64::from(self.height) {
            return None;
        }
        Some((y as usize * self.width as usize + x as usize) * 3)
    }

    /// The colour at `(x, y)`, `None` outside the image.
    pub fn get(&self, x: i64, y: i64) -> Option<Rgb> {
        let i = self.index(x, y)?;
        Some([self.data[i], self.data[i + 1], self.data[i + 2]])
    }

    /// Sets `(x, y)`; outside the image it does nothing, so shapes may be clipped freely.
    pub fn set(&mut self, x: i64, y: i64, c: Rgb) {
        if let Some(i) = self.index(x, y) {
            self.data[i..i + 3].copy_from_slice(&c);
        }
    }

    /// Mixes `c` into `(x, y)` with opacity `alpha` in `[0, 1]` (in sRGB space, which is
    /// what anti-aliased strokes on white paper look right with at these sizes).
    pub fn blend(&mut self, x: i64, y: i64, c: Rgb, alpha: f64) {
        let a = alpha.clamp(0.0, 1.0);
        if a <= 0.0 {
            return;
        }
        if let Some(i) = self.index(x, y) {
            for (d, &src) in self.data[i..i + 3].iter_mut().zip(&c) {
                let old = f64::from(*d);
                *d = (old + (f64::from(src) - old) * a).round() as u8;
            }
        }
    }

    /// Fills the rectangle `[x, x + w) × [y, y + h)`, clipped to the image.
    pub fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        let x0 = x.max(0);
        let y0 = y.max(0);
        let x1 = (x + w).min(i64::from(self.width));
        let y1 = (y + h).min(i64::from(self.height));
        for yy in y0..y1 {
            for xx in x0..x1 {
                self.set(xx, yy, c);
            }
        }
    }

    /// Outlines the rectangle `[x, x + w) × [y, y + h)` with 1-pixel lines.
    pub fn stroke_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        self.fill_rect(x, y, w, 1, c);
        self.fill_rect(x, y + h - 1, w, 1, c);
        self.fill_rect(x, y, 1, h, c);
        self.fill_rect(x + w - 1, y, 1, h, c);
    }

    /// Copies `src` with its top-left corner at `(x, y)`, clipped to this image.
    pub fn blit(&mut self, src: &Image, x: i64, y: i64) {
        // Source columns that land inside this image.
        let sx0 = (-x).max(0);
        let sx1 = i64::from(src.width).min(i64::from(self.width) - x);
        if sx0 >= sx1 {
            return;
        }
        let n = (sx1 - sx0) as usize * 3;
        for sy in 0..i64::from(src.height) {
            let ty = y + sy;
            if ty < 0 || ty >= i64::from(self.height) {
                continue;
            }
            let s = ((sy * i64::from(src.width) + sx0) * 3) as usize;
            let t = ((ty * i64::from(self.width) + x + sx0) * 3) as usize;
            self.data[t..t + n].copy_from_slice(&src.data[s..s + n]);
        }
    }

    /// An anti-aliased line segment of width `width` with round caps: each pixel is
    /// covered by how far its centre lies inside the stroke, so lines are smooth at any
    /// angle and the result does not depend on drawing order within one segment.
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), width: f64, c: Rgb) {
        if !(a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite()) {
            return;
        }
        let half = (width * 0.5).max(0.35);
        let pad = half + 1.0;
        let x0 = (a.0.min(b.0) - pad)
            .floor()
            .max(-1.0)
            .min(f64::from(self.width)) as i64;
        let x1 = (a.0.max(b.0) + pad)
            .ceil()
            .max(-1.0)
            .min(f64::from(self.width)) as i64;
        let y0 = (a.1.min(b.1) - pad)
            .floor()
            .max(-1.0)
            .min(f64::from(self.height)) as i64;
        let y1 = (a.1.max(b.1) + pad)
            .ceil()
            .max(-1.0)
            .min(f64::from(self.height)) as i64;
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len2 = dx * dx + dy * dy;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let t = if len2 > 0.0 {
                    (((px - a.0) * dx + (py - a.1) * dy) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let (qx, qy) = (a.0 + t * dx - px, a.1 + t * dy - py);
                let d = (qx * qx + qy * qy).sqrt();
                let cover = (half + 0.5 - d).clamp(0.0, 1.0);
                if cover > 0.0 {
                    self.blend(x, y, c, cover);
                }
            }
        }
    }

    /// The image as PNG bytes (8-bit RGB, adaptive filtering, balanced compression).
    pub fn encode_png(&self) -> Result<Vec<u8>, RenderError> {
        let mut out = Vec::new();
        self.write_png_to(&mut out)?;
        Ok(out)
    }

    /// Writes the image as PNG to `w`.
    pub fn write_png_to(&self, w: &mut dyn Write) -> Result<(), RenderError> {
        let mut writer = encoder(w, self.width, self.height)
            .write_header()
            .map_err(encode_err)?;
        writer.write_image_data(&self.data).map_err(encode_err)?;
        writer.finish().map_err(encode_err)
    }

    /// Writes the image as a PNG file, atomically: on error `path` is left as it was.
    pub fn write_png(&self, path: &Path) -> Result<(), RenderError> {
        write_file(path, |w| self.write_png_to(w))
    }
}

/// Encodes `frames` as one animated PNG (APNG) that loops forever at `fps` frames per
/// second. Browsers and most viewers play it; others show the first frame, which is why
/// an APNG is a safe default for sequences in reports. All frames must have one size.
pub fn encode_apng(frames: &[Image], fps: u16) -> Result<Vec<u8>, RenderError> {
    let mut out = Vec::new();
    write_apng_to(&mut out, frames, fps)?;
    Ok(out)
}

/// Writes `frames` as an APNG file, atomically; see [`encode_apng`].
pub fn write_apng(path: &Path, frames: &[Image], fps: u16) -> Result<(), RenderError> {
    // Check before creating anything, so bad arguments leave no temporary file behind.
    check_apng(frames, fps)?;
    write_file(path, |w| write_apng_to(w, frames, fps))
}

fn check_apng(frames: &[Image], fps: u16) -> Result<(), RenderError> {
    let first = frames
        .first()
        .ok_or_else(|| RenderError::Invalid("an animation needs at least one frame".into()))?;
    if fps == 0 {
        return Err(RenderError::Invalid(
            "frames per second must be at least 1".into(),
        ));
    }
    if let Some((i, f)) = frames
        .iter()
        .enumerate()
        .find(|(_, f)| (f.width, f.height) != (first.width, first.height))
    {
        return Err(RenderError::Invalid(format!(
            "animation frame {i} is {}×{}, frame 0 is {}×{}; expected one size for all frames",
            f.width, f.height, first.width, first.height
        )));
    }
    Ok(())
}

fn write_apng_to(w: &mut dyn Write, frames: &[Image], fps: u16) -> Result<(), RenderError> {
    check_apng(frames, fps)?;
    let (width, height) = (frames[0].width, frames[0].height);
    let count = u32::try_from(frames.len())
        .map_err(|_| RenderError::Invalid("too many animation frames".into()))?;
    let mut enc = encoder(w, width, height);
    enc.set_animated(count, 0).map_err(encode_err)?;
    enc.set_frame_delay(1, fps).map_err(encode_err)?;
    let mut writer = enc.write_header().map_err(encode_err)?;
    for f in frames {
        writer.write_image_data(&f.data).map_err(encode_err)?;
    }
    writer.finish().map_err(encode_err)
}

/// An encoder with weft's fixed settings: 8-bit RGB, sRGB, balanced compression.
fn encoder(w: &mut dyn Write, width: u32, height: u32) -> png::Encoder<'static, &mut dyn Write> {
    let mut enc = png::Encoder::new(w, width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Balanced);
    enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    enc
}

fn encode_err(e: png::EncodingError) -> RenderError {
    match e {
        png::EncodingError::IoError(e) => RenderError::Encode(e.to_string()),
        other => RenderError::Encode(other.to_string()),
    }
}

/// Writes `path` atomically with `fill`, mapping every failure to an error naming `path`.
pub(crate) fn write_file<F>(path: &Path, fill: F) -> Result<(), RenderError>
where
    F: FnOnce(&mut dyn Write) -> Result<(), RenderError>,
{
    let mut inner = None;
    let result = weft_mesh::io::write_atomic(path, |w| {
        fill(w).map_err(|e| {
            let msg = e.to_string();
            inner = Some(e);
            std::io::Error::other(msg)
        })
    });
    match (result, inner) {
        (Ok(()), _) => Ok(()),
        (Err(_), Some(RenderError::Encode(m))) => Err(RenderError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other(m),
        }),
        (Err(_), Some(e)) => Err(e),
        (Err(source), None) => Err(RenderError::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trips_and_is_deterministic() {
        let mut img = Image::new(7, 5, [255, 255, 255]);
        img.set(3, 2, [10, 20, 30]);
        img.set(-1, 99, [1, 2, 3]);
        let a = img.encode_png().unwrap();
        assert_eq!(a, img.encode_png().unwrap());
        let dec = png::Decoder::new(std::io::Cursor::new(&a));
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (7, 5));
        assert_eq!(&buf[..info.buffer_size()], img.as_bytes());
    }

    #[test]
    fn blit_clips_on_every_side() {
        let mut src = Image::new(3, 2, [9, 9, 9]);
        src.set(0, 0, [1, 2, 3]);
        for (x, y) in [(-2, -1), (4, 3), (-5, 0), (0, 9), (1, 1)] {
            let mut dst = Image::new(5, 4, [0; 3]);
            dst.blit(&src, x, y);
            for ty in 0..4i64 {
                for tx in 0..5i64 {
                    let expect = src.get(tx - x, ty - y).unwrap_or([0; 3]);
                    assert_eq!(dst.get(tx, ty), Some(expect), "{x} {y} at {tx} {ty}");
                }
            }
        }
    }

    #[test]
    fn apng_has_one_frame_control_per_frame() {
        let frames: Vec<Image> = (0..3).map(|i| Image::new(4, 4, [i * 80, 0, 0])).collect();
        let bytes = encode_apng(&frames, 10).unwrap();
        let fctl = bytes.windows(4).filter(|w| w == b"fcTL").count();
        assert_eq!(fctl, 3);
        assert!(bytes.windows(4).any(|w| w == b"acTL"));
        let e = encode_apng(&[Image::new(4, 4, [0; 3]), Image::new(5, 4, [0; 3])], 10);
        assert!(e.unwrap_err().to_string().contains("frame 1 is 5×4"));
        assert!(encode_apng(&[], 10).is_err());
    }

    #[test]
    fn unwritable_path_is_an_error_naming_it_and_leaves_nothing() {
        let dir = std::env::temp_dir().join(format!("weft-render-img-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let ok = dir.join("ok.png");
        Image::new(2, 2, [0; 3]).write_png(&ok).unwrap();
        // A parent that is a file (missing parents are created, see write_atomic).
        let path = ok.join("out.png");
        let e = Image::new(2, 2, [0; 3]).write_png(&path).unwrap_err();
        assert!(e.to_string().contains("ok.png/out.png"), "{e}");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("ok.png")]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn lines_cover_their_middle_and_skip_non_finite_ends() {
        let mut img = Image::new(20, 20, [255; 3]);
        img.line((2.0, 10.0), (18.0, 10.0), 2.0, [0, 0, 0]);
        assert_eq!(img.get(10, 10), Some([0, 0, 0]));
        assert_eq!(img.get(10, 2), Some([255; 3]));
        img.line((f64::NAN, 0.0), (5.0, 5.0), 2.0, [0, 0, 0]);
    }
}
