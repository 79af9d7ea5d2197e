//! MakeHuman morph targets (`*.target.gz`): gzipped text, one moved vertex per line,
//! `index dx dy dz` (0-based index into the base mesh, offsets in decimetres), `#`
//! comments. A target is applied with a weight: `p_i += w · d_i`.

use std::io::Read;
use std::path::Path;

use super::error::MpfbError;

/// A sparse morph target: (vertex, offset) pairs, offsets in the base mesh's units.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Target {
    /// Moved vertices and their offsets.
    pub offsets: Vec<(u32, [f32; 3])>,
}

impl Target {
    /// Reads a `.target.gz` (or an uncompressed `.target`) whose indices must be below
    /// `vertex_count`.
    pub fn read(path: &Path, vertex_count: usize) -> Result<Self, MpfbError> {
        let bytes = weft_mesh::io::read_input(path).map_err(|e| MpfbError::io(path, e))?;
        let text = if bytes.starts_with(&[0x1f, 0x8b]) {
            let mut s = String::new();
            flate2::read::GzDecoder::new(&bytes[..])
                .read_to_string(&mut s)
                .map_err(|e| MpfbError::parse(path, 0, format!("not a readable gzip file: {e}")))?;
            s
        } else {
            String::from_utf8(bytes).map_err(|_| {
                MpfbError::parse(path, 0, "not text; expected `index dx dy dz` lines")
            })?
        };
        Self::parse(&text, path, vertex_count)
    }

    /// Parses the text of a target.
    pub fn parse(text: &str, path: &Path, vertex_count: usize) -> Result<Self, MpfbError> {
        let mut offsets = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let bad = |m: String| MpfbError::parse(path, n + 1, m);
            let mut it = line.split_whitespace();
            let i: u32 = it
                .next()
                .and_then(|t| t.parse().ok())
                .ok_or_else(|| bad(format!("`{line}`: expected `index dx dy dz`")))?;
            if i as usize >= vertex_count {
                return Err(bad(format!(
                    "vertex {i} is out of range (the base mesh has {vertex_count})"
                )));
            }
            let mut d = [0.0f32; 3];
            for c in &mut d {
                *c = it
                    .next()
                    .and_then(|t| t.parse().ok())
                    .filter(|x: &f32| x.is_finite())
                    .ok_or_else(|| {
                        bad(format!(
                            "`{line}`: expected three finite offsets after the index"
                        ))
                    })?;
            }
            offsets.push((i, d));
        }
        Ok(Target { offsets })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_makehuman_numbers() {
        let t = Target::parse(
            "# x\n0 -.097 6.886 .410\n\n12 0 0 1e-2\n",
            Path::new("t.target"),
            13,
        )
        .unwrap();
        assert_eq!(
            t.offsets,
            vec![(0, [-0.097, 6.886, 0.41]), (12, [0.0, 0.0, 0.01])]
        );
        let e = Target::parse("13 0 0 0\n", Path::new("t.target"), 13).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.target:1: vertex 13 is out of range (the base mesh has 13)"
        );
        assert!(Target::parse("1 0 0\n", Path::new("t"), 13).is_err());
    }
}
