//! Stanford PLY: ascii, binary little-endian and binary big-endian, read and written here.
//!
//! Our own reader and writer because no PLY crate is both well kept and small: the ones
//! on crates.io are unmaintained or pull in much more than weft needs, and none reports
//! errors with a line or element. The format is small: a text header declaring elements
//! and their typed properties, then the body. Reading is defensive: every count comes
//! from the file, so nothing is allocated or looped over on a count before checking it
//! against the bytes that remain.

use std::fmt;
use std::io::{self, Write};
use std::path::Path;

use super::{fmt_f64, LoadReport, MeshFormat};
use crate::error::MeshError;
use crate::mesh::TriMesh;
use crate::validate::check;

/// How a PLY body is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PlyEncoding {
    /// Text: one element per line.
    Ascii,
    /// Binary, little-endian (what weft writes by default: compact and exact).
    BinaryLittleEndian,
    /// Binary, big-endian.
    BinaryBigEndian,
}

impl PlyEncoding {
    /// The name in the header's `format` line.
    fn keyword(self) -> &'static str {
        match self {
            PlyEncoding::Ascii => "ascii",
            PlyEncoding::BinaryLittleEndian => "binary_little_endian",
            PlyEncoding::BinaryBigEndian => "binary_big_endian",
        }
    }
}

impl fmt::Display for PlyEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PlyEncoding::Ascii => "ascii",
            PlyEncoding::BinaryLittleEndian => "binary little-endian",
            PlyEncoding::BinaryBigEndian => "binary big-endian",
        })
    }
}

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The type of a header name, with the sized aliases (`int8` … `float64`).
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

const SCALAR_NAMES: &str = "char, uchar, short, ushort, int, uint, float, double \
                            (or int8 … float64)";

/// What a property holds.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
    /// Header line of the `element` statement.
    line: usize,
}

impl Element {
    fn property(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name)
    }

    /// The fewest body bytes one instance takes in binary (a list takes at least its
    /// count).
    fn min_binary_size(&self) -> usize {
        self.properties
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) | Kind::List { count: s, .. } => s.size(),
            })
            .sum()
    }
}

struct Header {
    encoding: PlyEncoding,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body_start: usize,
    /// Number of header lines (the body's first line is `lines + 1`).
    lines: usize,
}

/// Parses the header; errors carry the 1-based header line.
fn parse_header(bytes: &[u8]) -> Result<Header, (usize, String)> {
    let mut pos = 0usize;
    let mut line = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        line += 1;
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            let message = if line == 1 {
                "not a PLY file; expected `ply` on the first line"
            } else {
                "the header ends without `end_header`"
            };
            return Err((line, message.to_owned()));
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        if line == 1 {
            if raw != b"ply" {
                return Err((
                    line,
                    "not a PLY file; expected `ply` on the first line".to_owned(),
                ));
            }
            continue;
        }
        let text = std::str::from_utf8(raw)
            .map_err(|_| (line, "header line is not text; expected ASCII".to_owned()))?;
        let words: Vec<&str> = text.split_whitespace().collect();
        match words.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                if encoding.is_some() {
                    return Err((line, "a second `format` line".to_owned()));
                }
                let e = match words.get(1).copied() {
                    Some("ascii") => PlyEncoding::Ascii,
                    Some("binary_little_endian") => PlyEncoding::BinaryLittleEndian,
                    Some("binary_big_endian") => PlyEncoding::BinaryBigEndian,
                    _ => {
                        return Err((
                            line,
                            format!(
                                "unknown format `{}`; expected ascii, binary_little_endian \
                                 or binary_big_endian",
                                words.get(1).unwrap_or(&"")
                            ),
                        ))
                    }
                };
                if words.get(2) != Some(&"1.0") || words.len() != 3 {
                    return Err((
                        line,
                        format!("`{text}`; expected `format {} 1.0`", e.keyword()),
                    ));
                }
                encoding = Some(e);
            }
            Some("element") => {
                let (Some(name), Some(count), 3) = (words.get(1), words.get(2), words.len()) else {
                    return Err((line, format!("`{text}`; expected `element NAME COUNT`")));
                };
                let count: usize = count.parse().map_err(|_| {
                    (
                        line,
                        format!("element count `{count}` is not a non-negative integer"),
                    )
                })?;
                if elements.iter().any(|e| e.name == *name) {
                    return Err((line, format!("a second element `{name}`")));
                }
                if *name == "vertex" && count > u32::MAX as usize {
                    return Err((
                        line,
                        format!("{count} vertices; weft indexes at most 2^32 - 1"),
                    ));
                }
                elements.push(Element {
                    name: (*name).to_owned(),
                    count,
                    properties: Vec::new(),
                    line,
                });
            }
            Some("property") => {
                let Some(element) = elements.last_mut() else {
                    return Err((line, "`property` before any `element`".to_owned()));
                };
                let scalar = |name: &str| {
                    Scalar::parse(name).ok_or_else(|| {
                        (
                            line,
                            format!("unknown type `{name}`; expected {SCALAR_NAMES}"),
                        )
                    })
                };
                let (kind, name) = match words[1..] {
                    ["list", count, item, name] => {
                        let count = scalar(count)?;
                        if !count.is_integer() {
                            return Err((
                                line,
                                format!("list count type `{}`; expected an integer type", words[2]),
                            ));
                        }
                        (
                            Kind::List {
                                count,
                                item: scalar(item)?,
                            },
                            name,
                        )
                    }
                    [ty, name] if ty != "list" => (Kind::Scalar(scalar(ty)?), name),
                    _ => {
                        return Err((
                            line,
                            format!(
                                "`{text}`; expected `property TYPE NAME` or \
                                 `property list COUNT_TYPE ITEM_TYPE NAME`"
                            ),
                        ))
                    }
                };
                if element.property(name).is_some() {
                    return Err((
                        line,
                        format!("a second property `{name}` in element `{}`", element.name),
                    ));
                }
                element.properties.push(Property {
                    name: name.to_owned(),
                    kind,
                });
            }
            Some("end_header") => break,
            Some(other) => {
                return Err((
                    line,
                    format!(
                        "unknown header keyword `{other}`; expected format, comment, \
                         obj_info, element, property or end_header"
                    ),
                ))
            }
        }
    }
    let encoding = encoding.ok_or((line, "the header has no `format` line".to_owned()))?;
    Ok(Header {
        encoding,
        elements,
        body_start: pos,
        lines: line,
    })
}

/// What the reader does with an element.
enum Role {
    /// Positions from the scalar properties at these indices.
    Vertex([usize; 3]),
    /// Polygons from the list property at this index.
    Face(usize),
    Skip,
}

fn role(element: &Element) -> Result<Role, (usize, String)> {
    let line = element.line;
    match element.name.as_str() {
        "vertex" => {
            let mut xyz = [0; 3];
            for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
                let i = element.property(axis).ok_or_else(|| {
                    (
                        line,
                        format!("element vertex has no property `{axis}`; expected x, y and z"),
                    )
                })?;
                if matches!(element.properties[i].kind, Kind::List { .. }) {
                    return Err((
                        line,
                        format!("vertex property `{axis}` is a list; expected a scalar"),
                    ));
                }
                xyz[k] = i;
            }
            Ok(Role::Vertex(xyz))
        }
        "face" => {
            let i = element
                .property("vertex_indices")
                .or_else(|| element.property("vertex_index"))
                .ok_or_else(|| {
                    (
                        line,
                        "element face has no `vertex_indices` (or `vertex_index`) list".to_owned(),
                    )
                })?;
            match element.properties[i].kind {
                Kind::List { item, .. } if item.is_integer() => Ok(Role::Face(i)),
                _ => Err((
                    line,
                    format!(
                        "face property `{}` is not a list of integers; expected e.g. \
                         `property list uchar int vertex_indices`",
                        element.properties[i].name
                    ),
                )),
            }
        }
        _ => Ok(Role::Skip),
    }
}

/// Where a body error happened.
enum Location {
    Line(usize),
    Byte(usize),
}

/// One encoding's way of reading body values.
trait Body {
    /// Starts one element instance (ascii: moves to its line).
    fn begin(&mut self) -> Result<(), String>;
    /// Ends one element instance (ascii: no values may be left on the line).
    fn end(&mut self) -> Result<(), String>;
    fn int(&mut self, ty: Scalar) -> Result<i64, String>;
    fn float(&mut self, ty: Scalar) -> Result<f64, String>;
    /// Skips `count` instances of `element` without looking at them, when that is cheap.
    /// Returns `false` when the caller has to walk them.
    fn skip_fixed(&mut self, element: &Element) -> Result<bool, String>;
    /// Bytes not yet read: the bound for anything a count would allocate.
    fn remaining(&self) -> usize;
    fn location(&self) -> Location;
    /// The most instances of `element` the rest of the body can hold.
    fn max_instances(&self, element: &Element) -> usize;
    /// The most items of type `item` a list starting here can hold.
    fn max_list_len(&self, item: Scalar) -> usize;
    /// Whether [`Body::max_instances`] is a hard limit worth failing on up front.
    fn counts_are_exact(&self) -> bool;
}

struct Ascii<'a> {
    lines: std::str::Split<'a, char>,
    /// Current line number.
    line: usize,
    tokens: std::str::SplitAsciiWhitespace<'a>,
    /// Bytes in the current line.
    line_len: usize,
    /// Bytes after the current line.
    remaining: usize,
}

impl<'a> Body for Ascii<'a> {
    fn begin(&mut self) -> Result<(), String> {
        loop {
            let Some(text) = self.lines.next() else {
                return Err("the file ends; expected another line".to_owned());
            };
            self.line += 1;
            self.remaining = self.remaining.saturating_sub(text.len() + 1);
            let tokens = text.split_ascii_whitespace();
            if tokens.clone().next().is_some() {
                self.tokens = tokens;
                self.line_len = text.len();
                return Ok(());
            }
        }
    }

    fn end(&mut self) -> Result<(), String> {
        match self.tokens.clone().count() {
            0 => Ok(()),
            1 => Err(
                "1 value left over at the end of the line; expected one element per line"
                    .to_owned(),
            ),
            n => Err(format!(
                "{n} values left over at the end of the line; expected one element per line"
            )),
        }
    }

    fn int(&mut self, ty: Scalar) -> Result<i64, String> {
        let word = self.word()?;
        if ty.is_integer() {
            word.parse()
                .map_err(|_| format!("`{word}` is not an integer"))
        } else {
            let x: f64 = word
                .parse()
                .map_err(|_| format!("`{word}` is not a number"))?;
            Ok(x as i64)
        }
    }

    fn float(&mut self, ty: Scalar) -> Result<f64, String> {
        let word = self.word()?;
        if ty.is_integer() {
            word.parse::<i64>()
                .map(|i| i as f64)
                .map_err(|_| format!("`{word}` is not an integer"))
        } else {
            word.parse()
                .map_err(|_| format!("`{word}` is not a number"))
        }
    }

    fn skip_fixed(&mut self, _: &Element) -> Result<bool, String> {
        Ok(false)
    }

    fn remaining(&self) -> usize {
        self.remaining
    }

    fn location(&self) -> Location {
        Location::Line(self.line)
    }

    fn max_instances(&self, element: &Element) -> usize {
        // Each value takes at least one character and a separator (a space or the
        // newline; the file's last line may lack it).
        (self.remaining + 1) / (2 * element.properties.len()).max(1)
    }

    fn max_list_len(&self, _: Scalar) -> usize {
        self.line_len / 2 + 1
    }

    fn counts_are_exact(&self) -> bool {
        false
    }
}

impl<'a> Ascii<'a> {
    fn word(&mut self) -> Result<&'a str, String> {
        self.tokens
            .next()
            .ok_or_else(|| "the line ends; expected another value".to_owned())
    }
}

struct Binary<'a> {
    bytes: &'a [u8],
    /// Offset into `bytes`.
    pos: usize,
    /// Offset of `bytes[0]` in the file, for messages.
    base: usize,
    big_endian: bool,
}

impl<'a> Binary<'a> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let chunk = self
            .bytes
            .get(self.pos..self.pos + N)
            .and_then(|s| <[u8; N]>::try_from(s).ok())
            .ok_or_else(|| {
                format!(
                    "the file ends after {} more bytes; expected {N}",
                    self.bytes.len() - self.pos
                )
            })?;
        self.pos += N;
        Ok(chunk)
    }

    fn value(&mut self, ty: Scalar) -> Result<Value, String> {
        macro_rules! read {
            ($t:ty, $n:literal) => {{
                let b = self.take::<$n>()?;
                if self.big_endian {
                    <$t>::from_be_bytes(b)
                } else {
                    <$t>::from_le_bytes(b)
                }
            }};
        }
        Ok(match ty {
            Scalar::I8 => Value::Int(i64::from(read!(i8, 1))),
            Scalar::U8 => Value::Int(i64::from(read!(u8, 1))),
            Scalar::I16 => Value::Int(i64::from(read!(i16, 2))),
            Scalar::U16 => Value::Int(i64::from(read!(u16, 2))),
            Scalar::I32 => Value::Int(i64::from(read!(i32, 4))),
            Scalar::U32 => Value::Int(i64::from(read!(u32, 4))),
            Scalar::F32 => Value::Float(f64::from(read!(f32, 4))),
            Scalar::F64 => Value::Float(read!(f64, 8)),
        })
    }
}

enum Value {
    Int(i64),
    Float(f64),
}

impl<'a> Body for Binary<'a> {
    fn begin(&mut self) -> Result<(), String> {
        Ok(())
    }

    fn end(&mut self) -> Result<(), String> {
        Ok(())
    }

    fn int(&mut self, ty: Scalar) -> Result<i64, String> {
        Ok(match self.value(ty)? {
            Value::Int(i) => i,
            Value::Float(x) => x as i64,
        })
    }

    fn float(&mut self, ty: Scalar) -> Result<f64, String> {
        Ok(match self.value(ty)? {
            Value::Int(i) => i as f64,
            Value::Float(x) => x,
        })
    }

    fn skip_fixed(&mut self, element: &Element) -> Result<bool, String> {
        if element
            .properties
            .iter()
            .any(|p| matches!(p.kind, Kind::List { .. }))
        {
            return Ok(false);
        }
        let total = element
            .count
            .checked_mul(element.min_binary_size())
            .filter(|&t| t <= self.remaining())
            .ok_or_else(|| {
                format!(
                    "{} instances of {} bytes do not fit in the {} bytes left",
                    element.count,
                    element.min_binary_size(),
                    self.remaining()
                )
            })?;
        self.pos += total;
        Ok(true)
    }

    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    fn location(&self) -> Location {
        Location::Byte(self.base + self.pos)
    }

    fn max_instances(&self, element: &Element) -> usize {
        match element.min_binary_size() {
            0 => usize::MAX,
            size => self.remaining() / size,
        }
    }

    fn max_list_len(&self, item: Scalar) -> usize {
        self.remaining() / item.size()
    }

    fn counts_are_exact(&self) -> bool {
        true
    }
}

/// Reads all elements; returns the mesh and the number of polygons split into fans.
fn read_body<B: Body>(
    header: &Header,
    body: &mut B,
    path: &Path,
) -> Result<(TriMesh, usize), MeshError> {
    let vertex_count = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    let mut polygons = 0usize;
    let mut corners: Vec<u32> = Vec::new();

    // Check every element's layout before reading any body, so header mistakes are
    // reported as such whatever the body holds.
    let roles = header
        .elements
        .iter()
        .map(role)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|(line, message)| MeshError::Parse {
            path: path.to_path_buf(),
            line,
            message,
        })?;
    for (element, role) in header.elements.iter().zip(roles) {
        let fail_at = |body: &B, i: Option<usize>, message: String| {
            let at = match i {
                Some(i) => format!("{} {i} of {}: {message}", element.name, element.count),
                None => format!("element {}: {message}", element.name),
            };
            match body.location() {
                Location::Line(line) => MeshError::Parse {
                    path: path.to_path_buf(),
                    line,
                    message: at,
                },
                Location::Byte(offset) => MeshError::Parse {
                    path: path.to_path_buf(),
                    line: 0,
                    message: format!("byte {offset}: {at}"),
                },
            }
        };
        let fail = |body: &B, i: usize, message: String| fail_at(body, Some(i), message);
        if element.properties.is_empty() {
            continue; // takes no bytes in any encoding
        }
        // Never allocate on the declared count alone: bound it by the bytes left. A binary
        // body that cannot hold the count fails here; an ascii body is walked so that
        // the error names the line where it ends.
        let bound = element.count.min(body.max_instances(element));
        if body.counts_are_exact() && bound < element.count {
            return Err(fail_at(
                body,
                None,
                format!(
                    "the header declares {} of them, at least {} bytes each, but only {} \
                     bytes follow",
                    element.count,
                    element.min_binary_size(),
                    body.remaining()
                ),
            ));
        }
        if matches!(role, Role::Skip)
            && body
                .skip_fixed(element)
                .map_err(|m| fail_at(body, None, m))?
        {
            continue;
        }
        match role {
            Role::Vertex(_) => positions.reserve(bound),
            Role::Face(_) => faces.reserve(bound),
            Role::Skip => {}
        }
        for i in 0..element.count {
            body.begin().map_err(|m| fail(body, i, m))?;
            let mut p = [0.0; 3];
            for (k, property) in element.properties.iter().enumerate() {
                let context = |m: String| format!("property `{}`: {m}", property.name);
                match property.kind {
                    Kind::Scalar(ty) => {
                        let x = body.float(ty).map_err(|m| fail(body, i, context(m)))?;
                        if let Role::Vertex(xyz) = role {
                            if let Some(axis) = xyz.iter().position(|&a| a == k) {
                                if !x.is_finite() {
                                    return Err(fail(
                                        body,
                                        i,
                                        context(format!(
                                            "{x} is not finite; expected a finite coordinate"
                                        )),
                                    ));
                                }
                                p[axis] = x;
                            }
                        }
                    }
                    Kind::List { count, item } => {
                        let n = body.int(count).map_err(|m| fail(body, i, context(m)))?;
                        let n = usize::try_from(n)
                            .ok()
                            .filter(|&n| n <= body.max_list_len(item))
                            .ok_or_else(|| {
                                fail(
                                    body,
                                    i,
                                    context(format!(
                                        "list length {n} is negative or longer than the file"
                                    )),
                                )
                            })?;
                        let is_face = matches!(role, Role::Face(f) if f == k);
                        corners.clear();
                        for _ in 0..n {
                            if is_face {
                                let v = body.int(item).map_err(|m| fail(body, i, context(m)))?;
                                let v = u32::try_from(v)
                                    .ok()
                                    .filter(|&v| (v as usize) < vertex_count)
                                    .ok_or_else(|| {
                                        fail(
                                            body,
                                            i,
                                            format!(
                                                "vertex index {v} is out of range; expected \
                                                 0 ≤ index < {vertex_count}"
                                            ),
                                        )
                                    })?;
                                corners.push(v);
                            } else {
                                body.float(item).map_err(|m| fail(body, i, context(m)))?;
                            }
                        }
                        if is_face {
                            if n < 3 {
                                return Err(fail(
                                    body,
                                    i,
                                    format!("a face with {n} corners; expected at least 3"),
                                ));
                            }
                            if n > 3 {
                                polygons += 1;
                            }
                            for pair in corners[1..].windows(2) {
                                faces.push([corners[0], pair[0], pair[1]]);
                            }
                        }
                    }
                }
            }
            body.end().map_err(|m| fail(body, i, m))?;
            if matches!(role, Role::Vertex(_)) {
                positions.push(p);
            }
        }
    }
    Ok((TriMesh::new(positions, faces), polygons))
}

/// Parses a PLY file held in memory; `path` only names the file in errors.
///
/// Reads `element vertex` (`x`, `y`, `z` of any scalar type; other properties skipped)
/// and `element face` (the list `vertex_indices` or `vertex_index`, any integer types;
/// polygons split into triangle fans and counted); other elements are skipped. Header
/// and ascii errors name the line; binary errors the element, its index and the byte.
pub fn load_ply_bytes(bytes: &[u8], path: &Path) -> Result<LoadReport, MeshError> {
    let header = parse_header(bytes).map_err(|(line, message)| MeshError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    })?;
    let body = &bytes[header.body_start..];
    let (mesh, triangulated_polygons) = match header.encoding {
        PlyEncoding::Ascii => {
            let text = std::str::from_utf8(body).map_err(|e| MeshError::Parse {
                path: path.to_path_buf(),
                line: header.lines + super::line_of(body, e.valid_up_to()),
                message: "not text in an ascii PLY body; expected ASCII numbers".to_owned(),
            })?;
            let mut reader = Ascii {
                lines: text.split('\n'),
                line: header.lines,
                tokens: "".split_ascii_whitespace(),
                line_len: 0,
                remaining: text.len(),
            };
            read_body(&header, &mut reader, path)?
        }
        binary => {
            let mut reader = Binary {
                bytes: body,
                pos: 0,
                base: header.body_start,
                big_endian: binary == PlyEncoding::BinaryBigEndian,
            };
            read_body(&header, &mut reader, path)?
        }
    };
    check(&mesh, path)?;
    Ok(LoadReport {
        mesh,
        format: MeshFormat::Ply(header.encoding),
        triangulated_polygons,
        corner_uvs: None,
    })
}

/// Writes `mesh` as PLY: `double` coordinates, optional `uchar` colours (one per vertex,
/// else `InvalidInput`), faces as `list uchar uint vertex_indices`.
pub fn write_ply_to(
    w: &mut dyn Write,
    mesh: &TriMesh,
    encoding: PlyEncoding,
    colors: Option<&[[u8; 3]]>,
) -> io::Result<()> {
    let mut out = PlyWriter::new(w, encoding);
    out.header(
        mesh.positions.len(),
        colors,
        "face",
        mesh.faces.len(),
        &["property list uchar uint vertex_indices"],
    )?;
    out.vertices(&mesh.positions, colors)?;
    for f in &mesh.faces {
        out.list_u32(f)?;
    }
    out.finish()
}

/// Writes a graph as PLY: vertices (optionally coloured) and an `edge` element with
/// `uint vertex1, vertex2`.
pub fn write_ply_graph_to(
    w: &mut dyn Write,
    positions: &[[f64; 3]],
    edges: &[[u32; 2]],
    colors: Option<&[[u8; 3]]>,
    encoding: PlyEncoding,
) -> io::Result<()> {
    let mut out = PlyWriter::new(w, encoding);
    out.header(
        positions.len(),
        colors,
        "edge",
        edges.len(),
        &["property uint vertex1", "property uint vertex2"],
    )?;
    out.vertices(positions, colors)?;
    for e in edges {
        out.u32s(e)?;
    }
    out.finish()
}

/// Buffers rows and writes them in chunks, in either encoding.
struct PlyWriter<'w> {
    w: &'w mut dyn Write,
    encoding: PlyEncoding,
    buf: Vec<u8>,
    text: String,
}

impl<'w> PlyWriter<'w> {
    const CHUNK: usize = 1 << 16;

    fn new(w: &'w mut dyn Write, encoding: PlyEncoding) -> Self {
        PlyWriter {
            w,
            encoding,
            buf: Vec::with_capacity(Self::CHUNK + 64),
            text: String::new(),
        }
    }

    fn header(
        &mut self,
        vertices: usize,
        colors: Option<&[[u8; 3]]>,
        element: &str,
        count: usize,
        properties: &[&str],
    ) -> io::Result<()> {
        if colors.is_some_and(|c| c.len() != vertices) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "expected one colour per vertex",
            ));
        }
        let mut h = format!(
            "ply\nformat {} 1.0\ncomment written by weft\nelement vertex {vertices}\n\
             property double x\nproperty double y\nproperty double z\n",
            self.encoding.keyword()
        );
        if colors.is_some() {
            h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
        }
        h += &format!("element {element} {count}\n");
        for p in properties {
            h += p;
            h.push('\n');
        }
        h += "end_header\n";
        self.w.write_all(h.as_bytes())
    }

    fn vertices(&mut self, positions: &[[f64; 3]], colors: Option<&[[u8; 3]]>) -> io::Result<()> {
        for (i, p) in positions.iter().enumerate() {
            let color = colors.and_then(|c| c.get(i));
            match self.encoding {
                PlyEncoding::Ascii => {
                    self.text.clear();
                    for (k, &c) in p.iter().enumerate() {
                        if k > 0 {
                            self.text.push(' ');
                        }
                        fmt_f64(&mut self.text, c);
                    }
                    if let Some(rgb) = color {
                        self.text += &format!(" {} {} {}", rgb[0], rgb[1], rgb[2]);
                    }
                    self.text.push('\n');
                    self.buf.extend_from_slice(self.text.as_bytes());
                }
                PlyEncoding::BinaryLittleEndian => {
                    for c in p {
                        self.buf.extend_from_slice(&c.to_le_bytes());
                    }
                    self.buf
                        .extend_from_slice(color.map_or(&[][..], |c| &c[..]));
                }
                PlyEncoding::BinaryBigEndian => {
                    for c in p {
                        self.buf.extend_from_slice(&c.to_be_bytes());
                    }
                    self.buf
                        .extend_from_slice(color.map_or(&[][..], |c| &c[..]));
                }
            }
            self.flush_if_full()?;
        }
        Ok(())
    }

    /// A list row: `uchar` length, then `uint` items.
    fn list_u32(&mut self, items: &[u32]) -> io::Result<()> {
        match self.encoding {
            PlyEncoding::Ascii => self
                .buf
                .extend_from_slice(format!("{} ", items.len()).as_bytes()),
            _ => self.buf.push(items.len() as u8),
        }
        self.u32s(items)
    }

    /// A row of `uint` values.
    fn u32s(&mut self, items: &[u32]) -> io::Result<()> {
        match self.encoding {
            PlyEncoding::Ascii => {
                use std::fmt::Write as _;
                self.text.clear();
                for (k, v) in items.iter().enumerate() {
                    let sep = if k == 0 { "" } else { " " };
                    // Writing into a String cannot fail.
                    let _ = write!(self.text, "{sep}{v}");
                }
                self.text.push('\n');
                self.buf.extend_from_slice(self.text.as_bytes());
            }
            PlyEncoding::BinaryLittleEndian => {
                for v in items {
                    self.buf.extend_from_slice(&v.to_le_bytes());
                }
            }
            PlyEncoding::BinaryBigEndian => {
                for v in items {
                    self.buf.extend_from_slice(&v.to_be_bytes());
                }
            }
        }
        self.flush_if_full()
    }

    fn flush_if_full(&mut self) -> io::Result<()> {
        if self.buf.len() >= Self::CHUNK {
            self.w.write_all(&self.buf)?;
            self.buf.clear();
        }
        Ok(())
    }

    fn finish(mut self) -> io::Result<()> {
        self.w.write_all(&self.buf)?;
        self.buf.clear();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::obj::tests::small_mesh;
    use proptest::prelude::*;

    const ENCODINGS: [PlyEncoding; 3] = [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ];

    fn load(bytes: &[u8]) -> Result<LoadReport, MeshError> {
        load_ply_bytes(bytes, Path::new("t.ply"))
    }

    fn err(bytes: &[u8]) -> String {
        load(bytes).unwrap_err().to_string()
    }

    /// A header for `body`, with the given element lines.
    fn ply(format: &str, elements: &str, body: &[u8]) -> Vec<u8> {
        let mut v = format!("ply\nformat {format} 1.0\n{elements}end_header\n").into_bytes();
        v.extend_from_slice(body);
        v
    }

    const XYZ_FLOAT: &str = "property float x\nproperty float y\nproperty float z\n";

    #[test]
    fn reads_an_ascii_file_with_extras_quads_and_other_elements() {
        let header = format!(
            "comment hi\nobj_info x\nelement vertex 4\nproperty uchar red\n{XYZ_FLOAT}\
             property list uchar float weights\nelement face 2\nproperty uchar flags\n\
             property list uchar int vertex_index\nelement material 1\nproperty double shine\n"
        );
        let body = b"1 0 0 0 2 0.5 0.5\r\n2 1 0 0 0\n\n3 1 1 0 1 1\n4 0 1 0 0\n7 4 0 1 2 3\n0 3 0 3 1\n9.5\n";
        let r = load(&ply("ascii", &header, body)).unwrap();
        assert_eq!(
            r.mesh.positions,
            vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]]
        );
        assert_eq!(r.mesh.faces, vec![[0, 1, 2], [0, 2, 3], [0, 3, 1]]);
        assert_eq!(r.triangulated_polygons, 1);
        assert_eq!(r.format, MeshFormat::Ply(PlyEncoding::Ascii));
    }

    /// Builds a binary file whose vertex x,y,z and face lists use the given types.
    fn binary_with_types(big: bool, xyz: Scalar, count: Scalar, item: Scalar) -> Vec<u8> {
        let name = |s: Scalar| match s {
            Scalar::I8 => "int8",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "uint16",
            Scalar::I32 => "int",
            Scalar::U32 => "uint32",
            Scalar::F32 => "float32",
            Scalar::F64 => "double",
        };
        let enc = |v: f64, s: Scalar| -> Vec<u8> {
            macro_rules! e {
                ($x:expr) => {
                    if big {
                        $x.to_be_bytes().to_vec()
                    } else {
                        $x.to_le_bytes().to_vec()
                    }
                };
            }
            match s {
                Scalar::I8 => e!(v as i8),
                Scalar::U8 => e!(v as u8),
                Scalar::I16 => e!(v as i16),
                Scalar::U16 => e!(v as u16),
                Scalar::I32 => e!(v as i32),
                Scalar::U32 => e!(v as u32),
                Scalar::F32 => e!(v as f32),
                Scalar::F64 => e!(v),
            }
        };
        let header = format!(
            "element vertex 4\nproperty {0} x\nproperty {0} y\nproperty short skip\nproperty {0} z\n\
             element edge 1\nproperty int vertex1\nproperty int vertex2\n\
             element face 1\nproperty list {1} {2} vertex_indices\n",
            name(xyz),
            name(count),
            name(item)
        );
        let mut body = Vec::new();
        for p in [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 2.]] {
            body.extend(enc(p[0], xyz));
            body.extend(enc(p[1], xyz));
            body.extend(enc(-7.0, Scalar::I16));
            body.extend(enc(p[2], xyz));
        }
        body.extend(enc(0.0, Scalar::I32));
        body.extend(enc(1.0, Scalar::I32));
        body.extend(enc(4.0, count));
        for i in 0..4 {
            body.extend(enc(i as f64, item));
        }
        let format = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        ply(format, &header, &body)
    }

    #[test]
    fn reads_binary_files_of_every_scalar_type_and_byte_order() {
        let all = [
            Scalar::I8,
            Scalar::U8,
            Scalar::I16,
            Scalar::U16,
            Scalar::I32,
            Scalar::U32,
            Scalar::F32,
            Scalar::F64,
        ];
        let ints = &all[..6];
        for big in [false, true] {
            for (k, &xyz) in all.iter().enumerate() {
                let count = ints[k % ints.len()];
                let item = ints[(k + 3) % ints.len()];
                let r = load(&binary_with_types(big, xyz, count, item))
                    .unwrap_or_else(|e| panic!("{xyz:?} {count:?} {item:?}: {e}"));
                assert_eq!(r.mesh.positions[3], [0., 1., 2.]);
                assert_eq!(r.mesh.faces, vec![[0, 1, 2], [0, 2, 3]]);
                assert_eq!(r.triangulated_polygons, 1);
            }
        }
    }

    #[test]
    fn header_errors_name_the_line() {
        assert_eq!(
            err(b"plx\nformat ascii 1.0\n"),
            "t.ply:1: not a PLY file; expected `ply` on the first line"
        );
        assert_eq!(
            err(b"ply"),
            "t.ply:1: not a PLY file; expected `ply` on the first line"
        );
        assert_eq!(
            err(b"ply\nformat ascii 1.0\n"),
            "t.ply:3: the header ends without `end_header`"
        );
        assert_eq!(
            err(b"ply\nformat ascii 2.0\nend_header\n"),
            "t.ply:2: `format ascii 2.0`; expected `format ascii 1.0`"
        );
        assert!(err(b"ply\nformat utf8 1.0\nend_header\n")
            .starts_with("t.ply:2: unknown format `utf8`"));
        assert_eq!(
            err(b"ply\nelement vertex 0\nend_header\n"),
            "t.ply:3: the header has no `format` line"
        );
        assert!(
            err(&ply("ascii", "element vertex 3\nproperty flaot x\n", b""))
                .starts_with("t.ply:4: unknown type `flaot`; expected char, uchar")
        );
        assert!(err(&ply("ascii", "property float x\n", b""))
            .starts_with("t.ply:3: `property` before any `element`"));
        assert!(err(&ply("ascii", "element vertex -1\n", b""))
            .starts_with("t.ply:3: element count `-1`"));
        assert!(err(&ply("ascii", "element vertex 99999999999\n", b""))
            .starts_with("t.ply:3: 99999999999 vertices; weft indexes"));
        assert!(err(&ply(
            "ascii",
            "element vertex 1\nproperty list float int x\n",
            b""
        ))
        .starts_with("t.ply:4: list count type `float`"));
        assert!(err(&ply("ascii", "bogus\n", b""))
            .starts_with("t.ply:3: unknown header keyword `bogus`"));
        assert!(err(&ply(
            "ascii",
            "element vertex 1\nproperty float x\nproperty float y\n",
            b"0 0\n"
        ))
        .starts_with("t.ply:3: element vertex has no property `z`"));
        assert!(err(&ply("ascii", &format!("element vertex 1\n{XYZ_FLOAT}element face 1\nproperty list uchar float vertex_indices\n"), b"")).starts_with("t.ply:7: face property `vertex_indices` is not a list of integers"));
        assert!(err(&ply(
            "ascii",
            &format!("element vertex 1\n{XYZ_FLOAT}property float x\n"),
            b""
        ))
        .starts_with("t.ply:7: a second property `x`"));
        assert!(err(b"ply\r\nformat ascii 1.0\r\n\xff\r\nend_header\r\n")
            .starts_with("t.ply:3: header line is not text"));
    }

    #[test]
    fn ascii_body_errors_name_the_line() {
        let h = format!(
            "element vertex 3\n{XYZ_FLOAT}element face 1\nproperty list uchar int vertex_indices\n"
        );
        assert_eq!(
            err(&ply("ascii", &h, b"0 0 0\n1 0 0\n0 1\n3 0 1 2\n")),
            "t.ply:12: vertex 2 of 3: property `z`: the line ends; expected another value"
        );
        assert_eq!(err(&ply("ascii", &h, b"0 0 0\n1 0 0\n0 1 0 5\n3 0 1 2\n")), "t.ply:12: vertex 2 of 3: 1 value left over at the end of the line; expected one element per line");
        assert_eq!(
            err(&ply("ascii", &h, b"0 0 0\n1 x 0\n")),
            "t.ply:11: vertex 1 of 3: property `y`: `x` is not a number"
        );
        assert_eq!(err(&ply("ascii", &h, b"0 0 0\n1 nan 0\n")), "t.ply:11: vertex 1 of 3: property `y`: NaN is not finite; expected a finite coordinate");
        assert_eq!(
            err(&ply("ascii", &h, b"0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")),
            "t.ply:13: face 0 of 1: vertex index 3 is out of range; expected 0 ≤ index < 3"
        );
        assert_eq!(
            err(&ply("ascii", &h, b"0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n")),
            "t.ply:13: face 0 of 1: vertex index -1 is out of range; expected 0 ≤ index < 3"
        );
        assert_eq!(
            err(&ply("ascii", &h, b"0 0 0\n1 0 0\n0 1 0\n2 0 1\n")),
            "t.ply:13: face 0 of 1: a face with 2 corners; expected at least 3"
        );
        assert_eq!(
            err(&ply("ascii", &h, b"0 0 0\n1 0 0\n0 1 0\n")),
            "t.ply:13: face 0 of 1: the file ends; expected another line"
        );
        assert!(
            err(&ply("ascii", &h, b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n")).starts_with(
                "t.ply:13: face 0 of 1: property `vertex_indices`: `2.5` is not an integer"
            )
        );
        assert!(err(&ply("ascii", &h, b"0 0 0\n\xff\n"))
            .starts_with("t.ply:11: not text in an ascii PLY body"));
    }

    #[test]
    fn binary_body_errors_name_element_and_byte() {
        let h = format!(
            "element vertex 2\n{XYZ_FLOAT}element face 1\n\
             property list uchar int vertex_indices\nproperty float quality\n"
        );
        let body = [
            &[0u8; 24][..],
            &[3, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 7, 7],
        ]
        .concat();
        let file = ply("binary_little_endian", &h, &body);
        let start = file.len() - body.len();
        assert_eq!(
            load(&file).unwrap_err().to_string(),
            format!(
                "t.ply: byte {}: face 0 of 1: property `quality`: the file ends after 2 more \
                 bytes; expected 4",
                start + 37
            )
        );
        let huge = ply(
            "binary_big_endian",
            "element vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n",
            &[0u8; 64],
        );
        assert!(load(&huge).unwrap_err().to_string().contains(
            "element vertex: the header declares 4000000000 of them, at least 12 bytes each, but only 64 bytes follow"
        ));
        let long_list = ply("binary_little_endian", &format!("element vertex 3\n{XYZ_FLOAT}element face 1\nproperty list uint int vertex_indices\n"), &[[0u8; 36].as_slice(), &[255, 255, 255, 0]].concat());
        assert!(load(&long_list).unwrap_err().to_string().contains("face 0 of 1: property `vertex_indices`: list length 16777215 is negative or longer than the file"));
        let mut nan = ply(
            "binary_little_endian",
            &format!("element vertex 1\n{XYZ_FLOAT}"),
            &[0u8; 12],
        );
        let n = nan.len();
        nan[n - 4..].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(load(&nan)
            .unwrap_err()
            .to_string()
            .contains("vertex 0 of 1: property `z`: NaN is not finite"));
        let skipped = ply(
            "binary_little_endian",
            &format!("element vertex 3\n{XYZ_FLOAT}element junk 1000\nproperty double a\n"),
            &[0u8; 36],
        );
        assert!(load(&skipped)
            .unwrap_err()
            .to_string()
            .contains("element junk: the header declares 1000 of them, at least 8 bytes each, but only 0 bytes follow"));
    }

    #[test]
    fn empty_elements_and_propertyless_elements_cost_nothing() {
        // An element with no properties but an enormous count takes no bytes and no time.
        let h = format!("element nothing 18446744073709551615\nelement vertex 3\n{XYZ_FLOAT}element face 1\nproperty list uchar uint vertex_indices\n");
        let mut body = Vec::new();
        for x in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
            body.extend(x.to_le_bytes());
        }
        body.extend([3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
        let m = load(&ply("binary_little_endian", &h, &body)).unwrap().mesh;
        assert_eq!(m.faces, vec![[0, 1, 2]]);
        // No face element: an empty mesh, reported as such.
        let e = load(&ply(
            "ascii",
            &format!("element vertex 1\n{XYZ_FLOAT}"),
            b"0 0 0\n",
        ))
        .unwrap_err();
        assert!(matches!(
            e,
            MeshError::Empty {
                vertices: 1,
                faces: 0,
                ..
            }
        ));
    }

    #[test]
    fn graph_files_carry_edges() {
        let mut out = Vec::new();
        write_ply_graph_to(
            &mut out,
            &[[0.; 3], [1., 2., 3.]],
            &[[0, 1]],
            Some(&[[1, 2, 3], [4, 5, 6]]),
            PlyEncoding::Ascii,
        )
        .unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("element edge 1\nproperty uint vertex1\nproperty uint vertex2\nend_header\n0 0 0 1 2 3\n1 2 3 4 5 6\n0 1\n"), "{text}");
    }

    proptest! {
        #[test]
        fn write_then_read_is_identity(mesh in small_mesh(), enc in 0usize..3, colored in any::<bool>()) {
            let colors: Vec<[u8; 3]> = (0..mesh.positions.len()).map(|i| [i as u8, 7, 200]).collect();
            let mut bytes = Vec::new();
            write_ply_to(&mut bytes, &mesh, ENCODINGS[enc], colored.then_some(&colors[..])).unwrap();
            let back = load_ply_bytes(&bytes, Path::new("p.ply")).unwrap();
            prop_assert_eq!(back.mesh, mesh);
            prop_assert_eq!(back.format, MeshFormat::Ply(ENCODINGS[enc]));
        }

        /// Any prefix of a valid binary file fails cleanly (no panic, no huge allocation).
        #[test]
        fn truncations_fail_cleanly(mesh in small_mesh(), enc in 0usize..3, cut in any::<prop::sample::Index>()) {
            let mut bytes = Vec::new();
            write_ply_to(&mut bytes, &mesh, ENCODINGS[enc], None).unwrap();
            let cut = cut.index(bytes.len());
            // An ascii file cut right after its last complete line may still parse.
            let _ = load_ply_bytes(&bytes[..cut], Path::new("p.ply"));
        }
    }
}
