//! MakeHuman's base mesh (`3dobjs/base.obj`): vertices, and quads by group.
//!
//! The file holds the body (group `body`) and helper geometry that MakeHuman uses for
//! fitting clothes and for its rig: `helper-tights`, `helper-skirt`, `helper-hair`,
//! eyes, teeth, tongue, eyelashes, genitals, and one small cube per joint (`joint-*`).
//! The import keeps the body's faces; the helpers matter only because morph targets
//! move them too and the rig places bones at the centres of the `joint-*` cubes.
//! Coordinates are MakeHuman's: decimetres, Y up, the body facing +Z, its left on +X.

use std::collections::BTreeMap;
use std::path::Path;

use super::error::MpfbError;

/// The base mesh as read: every vertex, and each group's polygons (vertex indices,
/// 0-based, into `positions`).
#[derive(Clone, Debug)]
pub struct BaseMesh {
    /// All vertex positions (decimetres, Y up).
    pub positions: Vec<[f64; 3]>,
    /// Polygons of each group, in file order.
    pub groups: BTreeMap<String, Vec<Vec<u32>>>,
}

impl BaseMesh {
    /// Parses `base.obj` (only `v`, `g` and `f` matter; texture coordinates, smoothing
    /// groups and materials are skipped).
    pub fn parse(text: &str, path: &Path) -> Result<Self, MpfbError> {
        let mut positions = Vec::new();
        let mut groups: BTreeMap<String, Vec<Vec<u32>>> = BTreeMap::new();
        let mut group = String::from("default");
        let mut faces_raw: Vec<(String, usize, Vec<i64>)> = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line_no = n + 1;
            let mut it = line.split_whitespace();
            match it.next() {
                Some("v") => {
                    let mut p = [0.0; 3];
                    for c in &mut p {
                        let tok = it.next().ok_or_else(|| {
                            MpfbError::parse(path, line_no, "a vertex needs three coordinates")
                        })?;
                        let x: f64 = tok.parse().map_err(|_| {
                            MpfbError::parse(path, line_no, format!("`{tok}` is not a number"))
                        })?;
                        *c = x;
                        if !x.is_finite() {
                            return Err(MpfbError::parse(path, line_no, "non-finite coordinate"));
                        }
                    }
                    positions.push(p);
                }
                Some("g") => group = it.next().unwrap_or("default").to_string(),
                Some("f") => {
                    let mut idx = Vec::new();
                    for tok in it {
                        let v = tok.split('/').next().unwrap_or("");
                        let i: i64 = v.parse().map_err(|_| {
                            MpfbError::parse(
                                path,
                                line_no,
                                format!("`{tok}` is not a vertex reference"),
                            )
                        })?;
                        idx.push(i);
                    }
                    if idx.len() < 3 {
                        return Err(MpfbError::parse(
                            path,
                            line_no,
                            "a face needs at least three vertices",
                        ));
                    }
                    faces_raw.push((group.clone(), line_no, idx));
                }
                _ => {}
            }
        }
        let count = positions.len() as i64;
        for (g, line_no, idx) in faces_raw {
            let mut poly = Vec::with_capacity(idx.len());
            for i in idx {
                // OBJ indices are 1-based; negative ones count back from the end.
                let k = if i > 0 { i - 1 } else { count + i };
                if !(0..count).contains(&k) {
                    return Err(MpfbError::parse(
                        path,
                        line_no,
                        format!("vertex {i} is out of range (the file has {count} vertices)"),
                    ));
                }
                poly.push(k as u32);
            }
            groups.entry(g).or_default().push(poly);
        }
        Ok(BaseMesh { positions, groups })
    }

    /// The distinct vertices of a group's polygons, sorted (a `joint-*` cube's eight
    /// corners, say). Empty for an unknown group.
    pub fn group_vertices(&self, name: &str) -> Vec<u32> {
        let mut v: Vec<u32> = self
            .groups
            .get(name)
            .map(|polys| polys.iter().flatten().copied().collect())
            .unwrap_or_default();
        v.sort_unstable();
        v.dedup();
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_and_indices() {
        let text = "# c\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\ng body\ns off\nf 1/1 2/2 3/3 4/4\ng joint-x\nf -1 -2 -3\n";
        let m = BaseMesh::parse(text, Path::new("base.obj")).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.groups["body"], vec![vec![0, 1, 2, 3]]);
        assert_eq!(m.group_vertices("joint-x"), vec![1, 2, 3]);
        let e = BaseMesh::parse("v 0 0 0\nf 1 2 3\n", Path::new("b.obj")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "b.obj:2: vertex 2 is out of range (the file has 1 vertices)"
        );
        let e = BaseMesh::parse("v 0 x 0\n", Path::new("b.obj")).unwrap_err();
        assert_eq!(e.to_string(), "b.obj:1: `x` is not a number");
    }
}
