//! MPFB rigs: `rigs/standard/rig.NAME.json` (bones, with heads and tails placed on the
//! mesh) and `weights.NAME.json` (skinning weights per bone).
//!
//! A bone's head is placed by one of three strategies: `VERTEX` (one vertex),
//! `CUBE` (the centre of a `joint-*` helper cube: the mean of its distinct vertices) or
//! `MEAN` (the mean of listed vertices), so every head is an average of base-mesh
//! vertices and follows the morph targets. `default_position` holds the head in
//! Blender's frame (metres, Z up) for the unmorphed base mesh; the import checks its own
//! placement against it.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::Value;

use super::error::MpfbError;
use super::obj::BaseMesh;

/// One bone of the rig.
#[derive(Clone, Debug, PartialEq)]
pub struct Bone {
    /// The bone's name (`upperarm01.L`).
    pub name: String,
    /// The parent bone's name; `None` for the root.
    pub parent: Option<String>,
    /// The base-mesh vertices whose mean is the head.
    pub head: Vec<u32>,
    /// The head on the unmorphed base mesh in Blender's frame (metres, Z up), if given.
    pub default_head: Option<[f64; 3]>,
}

/// A rig: its bones by name, and each bone's skinning weights.
#[derive(Clone, Debug)]
pub struct Rig {
    /// Bones by name.
    pub bones: BTreeMap<String, Bone>,
    /// Per bone, (base-mesh vertex, weight) pairs.
    pub weights: BTreeMap<String, Vec<(u32, f64)>>,
}

impl Rig {
    /// Reads `rig_path` and `weights_path`, resolving `CUBE` heads against `mesh`.
    pub fn read(rig_path: &Path, weights_path: &Path, mesh: &BaseMesh) -> Result<Self, MpfbError> {
        let rig = read_json(rig_path)?;
        let bones_v = rig.get("bones").unwrap_or(&rig);
        let obj = bones_v
            .as_object()
            .ok_or_else(|| MpfbError::parse(rig_path, 0, "expected a JSON object of bones"))?;
        let n = mesh.positions.len();
        let mut bones = BTreeMap::new();
        for (name, b) in obj {
            let bad = |m: String| MpfbError::parse(rig_path, 0, format!("bone `{name}`: {m}"));
            let parent = match b.get("parent").and_then(Value::as_str) {
                None | Some("") => None,
                Some(p) => Some(p.to_string()),
            };
            let head_v = b.get("head").ok_or_else(|| bad("no `head`".into()))?;
            let head = placement(head_v, mesh).map_err(bad)?;
            if let Some(&i) = head.iter().find(|&&i| i as usize >= n) {
                return Err(bad(format!(
                    "head vertex {i} is out of range (the base mesh has {n})"
                )));
            }
            let default_head = head_v
                .get("default_position")
                .and_then(Value::as_array)
                .and_then(|a| {
                    let v: Vec<f64> = a.iter().filter_map(Value::as_f64).collect();
                    (v.len() == 3).then(|| [v[0], v[1], v[2]])
                });
            bones.insert(
                name.clone(),
                Bone {
                    name: name.clone(),
                    parent,
                    head,
                    default_head,
                },
            );
        }
        for b in bones.values() {
            if let Some(p) = &b.parent {
                if !bones.contains_key(p) {
                    return Err(MpfbError::parse(
                        rig_path,
                        0,
                        format!(
                            "bone `{}` has parent `{p}`, which is not in the rig",
                            b.name
                        ),
                    ));
                }
            }
        }
        if bones.values().filter(|b| b.parent.is_none()).count() != 1 {
            return Err(MpfbError::parse(
                rig_path,
                0,
                "expected exactly one root bone (no parent)",
            ));
        }

        let wj = read_json(weights_path)?;
        let wobj = wj
            .get("weights")
            .and_then(Value::as_object)
            .ok_or_else(|| {
                MpfbError::parse(weights_path, 0, "expected an object with `weights`")
            })?;
        let mut weights = BTreeMap::new();
        for (bone, list) in wobj {
            let bad = |m: String| MpfbError::parse(weights_path, 0, format!("bone `{bone}`: {m}"));
            if !bones.contains_key(bone) {
                return Err(bad("not in the rig".into()));
            }
            let arr = list
                .as_array()
                .ok_or_else(|| bad("expected a list of [vertex, weight]".into()))?;
            let mut pairs = Vec::with_capacity(arr.len());
            for e in arr {
                let (v, w) = e
                    .as_array()
                    .filter(|p| p.len() == 2)
                    .and_then(|p| Some((p[0].as_u64()?, p[1].as_f64()?)))
                    .ok_or_else(|| bad(format!("entry {e} is not [vertex, weight]")))?;
                if v as usize >= n || !w.is_finite() || w < 0.0 {
                    return Err(bad(format!(
                        "entry [{v}, {w}]: expected a vertex below {n} and a finite weight ≥ 0"
                    )));
                }
                pairs.push((v as u32, w));
            }
            weights.insert(bone.clone(), pairs);
        }
        Ok(Rig { bones, weights })
    }

    /// The head of `bone` on `positions` (the mean of its placement vertices).
    pub fn head(&self, bone: &str, positions: &[[f64; 3]]) -> Option<[f64; 3]> {
        let b = self.bones.get(bone)?;
        Some(mean(&b.head, positions))
    }

    /// The nearest ancestor of `bone` (itself included) for which `pick` answers.
    pub fn resolve<T: Copy>(&self, bone: &str, pick: impl Fn(&str) -> Option<T>) -> Option<T> {
        let mut cur = Some(bone.to_string());
        while let Some(name) = cur {
            if let Some(t) = pick(&name) {
                return Some(t);
            }
            cur = self.bones.get(&name).and_then(|b| b.parent.clone());
        }
        None
    }
}

/// The mean of `positions[idx]`.
pub fn mean(idx: &[u32], positions: &[[f64; 3]]) -> [f64; 3] {
    let mut s = [0.0; 3];
    for &i in idx {
        for k in 0..3 {
            s[k] += positions[i as usize][k];
        }
    }
    s.map(|x| x / idx.len().max(1) as f64)
}

fn read_json(path: &Path) -> Result<Value, MpfbError> {
    let text = weft_mesh::io::read_input_to_string(path).map_err(|e| MpfbError::io(path, e))?;
    serde_json::from_str(&text).map_err(|e| MpfbError::parse(path, e.line(), e.to_string()))
}

/// The vertices a `head`/`tail` placement averages.
fn placement(v: &Value, mesh: &BaseMesh) -> Result<Vec<u32>, String> {
    let strategy = v.get("strategy").and_then(Value::as_str).unwrap_or("");
    match strategy {
        "VERTEX" => v
            .get("vertex_index")
            .and_then(Value::as_u64)
            .map(|i| vec![i as u32])
            .ok_or_else(|| "VERTEX placement without `vertex_index`".into()),
        "CUBE" => {
            let cube = v
                .get("cube_name")
                .and_then(Value::as_str)
                .ok_or("CUBE placement without `cube_name`")?;
            let verts = mesh.group_vertices(cube);
            if verts.is_empty() {
                return Err(format!("cube `{cube}` is not a group of the base mesh"));
            }
            Ok(verts)
        }
        "MEAN" => {
            let list = v
                .get("vertex_indices")
                .and_then(Value::as_array)
                .ok_or("MEAN placement without `vertex_indices`")?;
            let idx: Option<Vec<u32>> = list.iter().map(|x| x.as_u64().map(|i| i as u32)).collect();
            match idx {
                Some(i) if !i.is_empty() => Ok(i),
                _ => Err("MEAN placement with an empty or non-integer `vertex_indices`".into()),
            }
        }
        other => Err(format!(
            "placement strategy `{other}`; expected VERTEX, CUBE or MEAN"
        )),
    }
}
