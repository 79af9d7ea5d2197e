//! Self-contained HTML reports: headings, paragraphs, tables and pictures in one file
//! that opens offline in any browser, for `weft eval` and `weft demo` to hand to people.
//!
//! Pictures are embedded as base64 `data:` URIs, the style sheet is inline, and there is
//! no script. A Content-Security-Policy meta tag forbids loading anything else, so a
//! report that opens correctly here opens the same way on a laptop with no network, and
//! a mistake that referenced an outside resource would show up as a console error in the
//! headless-browser test rather than as a silent dependency.

use std::fmt::Write as _;
use std::path::Path;

use crate::error::RenderError;
use crate::image::{write_file, Image};

/// A report under construction; blocks appear in the order they were added.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Report {
    title: String,
    blocks: Vec<Block>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Block {
    Heading {
        level: u8,
        text: String,
    },
    Paragraph(String),
    Table {
        header: Vec<String>,
        rows: Vec<Vec<String>>,
    },
    Figure {
        png: Vec<u8>,
        size: (u32, u32),
        caption: String,
    },
    Code(String),
}

/// The 8-byte signature every PNG starts with.
const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

impl Report {
    /// An empty report; `title` is the page title and the first heading.
    pub fn new(title: impl Into<String>) -> Self {
        Report {
            title: title.into(),
            blocks: Vec::new(),
        }
    }

    /// A section heading (`<h2>`).
    pub fn heading(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Heading {
            level: 2,
            text: text.into(),
        });
        self
    }

    /// A subsection heading (`<h3>`).
    pub fn subheading(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Heading {
            level: 3,
            text: text.into(),
        });
        self
    }

    /// A paragraph of plain text (escaped; blank lines do not split it).
    pub fn paragraph(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.into()));
        self
    }

    /// Preformatted text in a monospace font: a command line, a config, a log excerpt.
    pub fn code(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Code(text.into()));
        self
    }

    /// A table with a header row; rows shorter than the header are padded with empty
    /// cells. Cells that look like numbers are right-aligned so columns of figures line
    /// up.
    pub fn table<H, R, C>(&mut self, header: H, rows: R) -> &mut Self
    where
        H: IntoIterator,
        H::Item: Into<String>,
        R: IntoIterator<Item = C>,
        C: IntoIterator,
        C::Item: Into<String>,
    {
        let header: Vec<String> = header.into_iter().map(Into::into).collect();
        let rows = rows
            .into_iter()
            .map(|r| r.into_iter().map(Into::into).collect())
            .collect();
        self.blocks.push(Block::Table { header, rows });
        self
    }

    /// A picture with a caption, encoded as PNG into the page.
    pub fn image(
        &mut self,
        image: &Image,
        caption: impl Into<String>,
    ) -> Result<&mut Self, RenderError> {
        let png = image.encode_png()?;
        self.blocks.push(Block::Figure {
            png,
            size: (image.width(), image.height()),
            caption: caption.into(),
        });
        Ok(self)
    }

    /// A picture given as PNG bytes (e.g. an APNG animation, or a file read from disk).
    /// Fails unless the bytes start with a PNG signature and header.
    pub fn png(
        &mut self,
        png: Vec<u8>,
        caption: impl Into<String>,
    ) -> Result<&mut Self, RenderError> {
        let size = png_size(&png).ok_or_else(|| {
            RenderError::Invalid(format!(
                "{} bytes given as a PNG picture, but they do not start with a PNG signature and header",
                png.len()
            ))
        })?;
        self.blocks.push(Block::Figure {
            png,
            size,
            caption: caption.into(),
        });
        Ok(self)
    }

    /// The whole page as HTML.
    pub fn to_html(&self) -> String {
        let mut out = String::new();
        out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        out.push_str(
            "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; \
             img-src data:; style-src 'unsafe-inline'\">\n",
        );
        out.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        let _ = writeln!(out, "<title>{}</title>", escape(&self.title));
        out.push_str(STYLE);
        out.push_str("</head>\n<body>\n<main>\n");
        let _ = writeln!(out, "<h1>{}</h1>", escape(&self.title));
        for b in &self.blocks {
            match b {
                Block::Heading { level, text } => {
                    let _ = writeln!(out, "<h{level}>{}</h{level}>", escape(text));
                }
                Block::Paragraph(t) => {
                    let _ = writeln!(out, "<p>{}</p>", escape(t));
                }
                Block::Code(t) => {
                    let _ = writeln!(out, "<pre>{}</pre>", escape(t));
                }
                Block::Table { header, rows } => table_html(&mut out, header, rows),
                Block::Figure { png, size, caption } => {
                    let _ = write!(
                        out,
                        "<figure>\n<img src=\"data:image/png;base64,{}\" width=\"{}\" height=\"{}\" alt=\"{}\">\n",
                        base64(png),
                        size.0,
                        size.1,
                        escape(caption)
                    );
                    if !caption.is_empty() {
                        let _ = writeln!(out, "<figcaption>{}</figcaption>", escape(caption));
                    }
                    out.push_str("</figure>\n");
                }
            }
        }
        out.push_str("</main>\n</body>\n</html>\n");
        out
    }

    /// Writes the page to `path`, atomically.
    pub fn write(&self, path: &Path) -> Result<(), RenderError> {
        let html = self.to_html();
        write_file(path, |w| {
            w.write_all(html.as_bytes())
                .map_err(|source| RenderError::Io {
                    path: path.to_path_buf(),
                    source,
                })
        })
    }
}

/// Quiet, print-friendly typography; images scale down to the page width.
const STYLE: &str = "<style>
body { margin: 0; background: #fafafa; color: #222; font: 15px/1.5 system-ui, -apple-system, 'Segoe UI', sans-serif; }
main { max-width: 1100px; margin: 0 auto; padding: 24px 32px 64px; background: #fff; }
h1 { font-size: 26px; margin: 8px 0 16px; }
h2 { font-size: 20px; margin: 32px 0 8px; border-bottom: 1px solid #e4e4e8; padding-bottom: 4px; }
h3 { font-size: 16px; margin: 24px 0 6px; }
table { border-collapse: collapse; margin: 12px 0; font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #dcdce2; padding: 4px 10px; text-align: left; }
th { background: #f2f2f6; }
td.num { text-align: right; }
figure { margin: 16px 0; }
img { max-width: 100%; height: auto; border: 1px solid #e4e4e8; }
figcaption { color: #555; font-size: 13px; margin-top: 4px; }
pre { background: #f4f4f7; padding: 8px 12px; overflow-x: auto; }
</style>
";

fn table_html(out: &mut String, header: &[String], rows: &[Vec<String>]) {
    out.push_str("<table>\n");
    if !header.is_empty() {
        out.push_str("<thead><tr>");
        for h in header {
            let _ = write!(out, "<th>{}</th>", escape(h));
        }
        out.push_str("</tr></thead>\n");
    }
    out.push_str("<tbody>\n");
    let width = rows
        .iter()
        .map(Vec::len)
        .max()
        .unwrap_or(0)
        .max(header.len());
    for r in rows {
        out.push_str("<tr>");
        for i in 0..width {
            let cell = r.get(i).map_or("", String::as_str);
            if looks_numeric(cell) {
                let _ = write!(out, "<td class=\"num\">{}</td>", escape(cell));
            } else {
                let _ = write!(out, "<td>{}</td>", escape(cell));
            }
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody>\n</table>\n");
}

/// Whether a cell is a number, possibly with a sign, exponent, `%` or `±` part.
fn looks_numeric(s: &str) -> bool {
    let t = s.trim();
    !t.is_empty()
        && t.chars().any(|c| c.is_ascii_digit())
        && t.chars()
            .all(|c| c.is_ascii_digit() || "+-.eE%± ".contains(c))
}

/// Escapes text for HTML element content and attribute values.
pub(crate) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// Standard base64 (RFC 4648) with padding: a few lines instead of a dependency.
pub(crate) fn base64(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(data.len().div_ceil(3) * 4);
    for chunk in data.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        out.push(char::from(A[(n >> 18) as usize & 63]));
        out.push(char::from(A[(n >> 12) as usize & 63]));
        out.push(if chunk.len() > 1 {
            char::from(A[(n >> 6) as usize & 63])
        } else {
            '='
        });
        out.push(if chunk.len() > 2 {
            char::from(A[n as usize & 63])
        } else {
            '='
        });
    }
    out
}

/// Width and height from a PNG's IHDR chunk, if `png` starts like a PNG.
fn png_size(png: &[u8]) -> Option<(u32, u32)> {
    if png.len() < 24 || png[..8] != PNG_SIGNATURE || &png[12..16] != b"IHDR" {
        return None;
    }
    let w = u32::from_be_bytes([png[16], png[17], png[18], png[19]]);
    let h = u32::from_be_bytes([png[20], png[21], png[22], png[23]]);
    Some((w, h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
        assert_eq!(base64(&[0xff, 0xfe, 0xfd]), "//79");
    }

    #[test]
    fn html_is_escaped_and_self_contained() {
        let mut r = Report::new("A <b> & \"c\"");
        r.heading("Errors")
            .paragraph("x < y & z")
            .table(
                ["method", "E_verts (mm)"],
                [vec!["ours", "12.5"], vec!["<script>"]],
            )
            .code("weft render a.obj");
        r.image(&Image::new(3, 2, [255, 0, 0]), "a red <picture>")
            .unwrap();
        let html = r.to_html();
        assert!(html.contains("<title>A &lt;b&gt; &amp; &quot;c&quot;</title>"));
        assert!(html.contains("<p>x &lt; y &amp; z</p>"));
        assert!(html.contains("<td class=\"num\">12.5</td>"));
        assert!(html.contains("<td>&lt;script&gt;</td><td></td>"));
        assert!(html.contains("src=\"data:image/png;base64,iVBORw0KGgo"));
        assert!(html.contains("width=\"3\" height=\"2\""));
        assert!(!html.contains("<script"));
        assert!(!html.contains("http://") && !html.contains("https://"));
        assert_eq!(html, r.to_html());
    }

    #[test]
    fn png_bytes_are_checked() {
        let mut r = Report::new("t");
        assert!(r.png(b"GIF89a".to_vec(), "x").is_err());
        let png = Image::new(5, 4, [0; 3]).encode_png().unwrap();
        r.png(png, "").unwrap();
        assert!(r.to_html().contains("width=\"5\" height=\"4\""));
    }

    #[test]
    fn numeric_cells() {
        for s in ["1", "-2.5", "3e-4", "12 %", "1.2 ± 0.3"] {
            assert!(looks_numeric(s), "{s}");
        }
        for s in ["", "ours", "e", "1a", "-"] {
            assert!(!looks_numeric(s), "{s}");
        }
    }
}
