//! glTF 2.0 binary (`.glb`): meshes animated by morph targets, for engines, web viewers
//! and Blender.
//!
//! What is written, and why:
//!
//! - One node and one mesh per [`AnimatedMesh`] (the garment, optionally the body), a single
//!   triangle primitive with `POSITION`, optional `NORMAL`, `TEXCOORD_0` when the mesh has
//!   UVs, and `u32` indices, and a double-sided material (garments are open surfaces seen
//!   from both sides).
//! - glTF keeps one UV per vertex, so a vertex on a UV seam is written once per distinct
//!   UV it has (positions, morph deltas and normals copied; normals are computed on the
//!   unsplit mesh, so the seam shades smoothly). V is flipped (`1 − v`): glTF's texture
//!   origin is the top-left corner, OBJ's the bottom-left.
//! - The base positions are those of frame 0. An animated mesh has **one morph target per
//!   frame** holding that frame's position deltas from the base (and normal deltas, when
//!   normals are written), and an animation channel on the node's `weights` with `STEP`
//!   interpolation: at `t_k = k / fps` the weight vector is one-hot for target `k`. So
//!   every engine that plays glTF morph animation shows frame `k` exactly, with no
//!   blending between frames and no skinning solve — the garment's deformation is
//!   arbitrary, which is the whole point of learning it.
//! - The mesh's `extras.targetNames` (`frame_00000`, …) names the targets; Blender's
//!   importer uses them as shape key names.
//! - Accessor `min`/`max` are exact for every `POSITION` accessor (the spec requires them,
//!   for morph targets too) and for the animation times.
//!
//! Units and axes need no conversion: glTF is right-handed, Y up, metres, seconds, like
//! weft. Size grows as `T × N × 24` bytes (positions and normals) plus `T² × 4` for the
//! one-hot weights, so this suits clips of up to a few thousand frames; a `.glb` is
//! limited to 4 GiB.
//!
//! Not written yet: the skinned variant (a skin driven by the body's joints plus per-frame
//! corrective targets), which needs the body crate's skeleton.

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::{self, Write};
use std::path::Path;
use std::rc::Rc;

use serde_json::{json, Value};

use super::error::ExportError;
use super::frames::bounds;
use super::scene::{check_scene, AnimatedMesh, IndexedUvs};
use super::{frame_times, Frames};
use crate::io::write_atomic;

mod skin;
pub use skin::{write_skinned_glb, Skeleton, SkinBinding};

/// `glTF` in ASCII, little-endian.
const GLB_MAGIC: u32 = 0x4654_6C67;
/// Chunk type `JSON`.
const CHUNK_JSON: u32 = 0x4E4F_534A;
/// Chunk type `BIN\0`.
const CHUNK_BIN: u32 = 0x004E_4942;
/// `bufferView.target` for vertex attributes.
const ARRAY_BUFFER: u32 = 34962;
/// `bufferView.target` for indices.
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
/// `accessor.componentType` for `f32`.
const FLOAT: u32 = 5126;
/// `accessor.componentType` for `u32`.
const UNSIGNED_INT: u32 = 5125;

/// How to write a `.glb`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlbOptions {
    /// Frames per second: frame `k` is shown from `k / fps` seconds on.
    pub fps: f32,
    /// Write area-weighted vertex normals (and per-frame normal deltas), so shading
    /// follows the deformation. Without them viewers fall back to flat shading.
    pub normals: bool,
}

impl Default for GlbOptions {
    fn default() -> Self {
        GlbOptions {
            fps: 30.0,
            normals: true,
        }
    }
}

/// Writes the meshes as one `.glb`, atomically. Fails without touching `path` on no
/// meshes, a mesh without frames, NaN coordinates, faces out of range, animated meshes
/// with different frame counts, a bad `fps`, or a file over 4 GiB.
pub fn write_glb(
    path: &Path,
    meshes: &[AnimatedMesh<'_>],
    options: GlbOptions,
) -> Result<(), ExportError> {
    let doc = Document::build(meshes, options, None)?;
    write_atomic(path, |w| doc.write_to(w)).map_err(|e| ExportError::write(path, e))
}

/// The `.glb` bytes in memory (for tests and small scenes); see [`write_glb`].
pub fn glb_bytes(meshes: &[AnimatedMesh<'_>], options: GlbOptions) -> Result<Vec<u8>, ExportError> {
    let doc = Document::build(meshes, options, None)?;
    let mut out = Vec::with_capacity(doc.total_len);
    doc.write_to(&mut out)
        .map_err(|e| ExportError::write("<memory>", e))?;
    Ok(out)
}

/// Writes one section of the binary chunk.
type WriteSection<'a> = Box<dyn Fn(&mut dyn Write) -> io::Result<()> + 'a>;

/// A section of the binary chunk: its length and how to write it.
struct Blob<'a> {
    len: usize,
    write: WriteSection<'a>,
}

/// The JSON and the binary sections, laid out but not yet written, so the whole file
/// streams to disk without holding the binary chunk in memory.
struct Document<'a> {
    json: Vec<u8>,
    blobs: Vec<Blob<'a>>,
    bin_len: usize,
    total_len: usize,
}

/// Accumulates buffer views and accessors with their byte offsets.
struct Layout<'a> {
    views: Vec<Value>,
    accessors: Vec<Value>,
    blobs: Vec<Blob<'a>>,
    offset: usize,
}

impl<'a> Layout<'a> {
    /// Adds a buffer view of `len` bytes (a multiple of 4, so every view stays aligned)
    /// written by `write`; returns its index.
    fn view(
        &mut self,
        len: usize,
        target: Option<u32>,
        stride: Option<usize>,
        write: impl Fn(&mut dyn Write) -> io::Result<()> + 'a,
    ) -> usize {
        let mut v = json!({"buffer": 0, "byteOffset": self.offset, "byteLength": len});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.views.push(v);
        self.blobs.push(Blob {
            len,
            write: Box::new(write),
        });
        self.offset += len;
        self.views.len() - 1
    }

    /// An accessor of `count` elements of `kind` (`SCALAR`, `VEC3`, …) and
    /// `component` type over the whole of `view`.
    fn plain_accessor(&mut self, view: usize, component: u32, count: usize, kind: &str) -> usize {
        self.accessor(json!({
            "bufferView": view,
            "componentType": component,
            "count": count,
            "type": kind,
        }))
    }

    fn accessor(&mut self, a: Value) -> usize {
        self.accessors.push(a);
        self.accessors.len() - 1
    }
}

impl<'a> Document<'a> {
    /// Lays out `meshes` (morph-animated, or with `skin` skinned to its skeleton, one
    /// binding per mesh).
    fn build(
        meshes: &[AnimatedMesh<'a>],
        options: GlbOptions,
        skin: Option<skin::SkinInput<'a>>,
    ) -> Result<Self, ExportError> {
        let mut frame_count = check_scene(meshes)?;
        if let Some(skin) = &skin {
            frame_count = skin.check(meshes, frame_count)?;
        }
        let times = frame_times(frame_count, options.fps)?;

        let mut l = Layout {
            views: Vec::new(),
            accessors: Vec::new(),
            blobs: Vec::new(),
            offset: 0,
        };
        let mut json_meshes = Vec::new();
        let mut nodes = Vec::new();
        let mut materials = Vec::new();
        let mut animated_nodes = Vec::new();
        for (i, m) in meshes.iter().enumerate() {
            let split = m.uvs.map(|uvs| SeamSplit::new(m.faces, uvs));
            // The base shape: frame 0, or the bind pose of a skinned mesh (whose frames
            // are then its per-frame correctives in the bind pose).
            let binding = skin.as_ref().map(|s| &s.bindings[i]);
            let base = match binding {
                Some(b) => b.rest,
                None => m.frames.frame(0).unwrap_or(&[]),
            };
            let (mut attributes, targets) =
                mesh_data(&mut l, m, base, split.as_ref(), options.normals)?;
            if let Some(b) = binding {
                skin::attributes(&mut l, b, split.as_ref(), &mut attributes);
            }
            let faces = match split {
                Some(split) => Cow::Owned(split.faces),
                None => Cow::Borrowed(m.faces),
            };
            let indices = index_accessor(&mut l, faces)?;
            materials.push(json!({
                "name": m.name,
                "doubleSided": true,
                "pbrMetallicRoughness": {
                    "baseColorFactor": m.color.map(f64::from),
                    "metallicFactor": 0.0,
                    "roughnessFactor": 0.8,
                },
            }));
            let mut primitive = json!({
                "attributes": attributes,
                "indices": indices,
                "material": i,
                "mode": 4,
            });
            let mut mesh = json!({"name": m.name});
            if !targets.is_empty() {
                let t = targets.len();
                primitive["targets"] = Value::Array(targets);
                let mut weights = vec![0.0; t];
                weights[0] = 1.0;
                mesh["weights"] = json!(weights);
                mesh["extras"] = json!({
                    "targetNames": (0..t).map(|k| format!("frame_{k:05}")).collect::<Vec<_>>(),
                });
                animated_nodes.push(i);
            }
            mesh["primitives"] = json!([primitive]);
            json_meshes.push(mesh);
            let mut node = json!({"name": m.name, "mesh": i});
            if skin.is_some() {
                node["skin"] = json!(0);
            }
            nodes.push(node);
        }
        let mut scene_nodes: Vec<usize> = (0..meshes.len()).collect();
        let mut skins = None;
        let mut joint_channels = Vec::new();
        if let Some(skin) = &skin {
            let first_joint = nodes.len();
            nodes.extend(skin.skeleton.nodes(first_joint));
            scene_nodes.push(first_joint);
            skins = Some(json!([skin.skeleton.skin(&mut l, first_joint)]));
            joint_channels = skin.skeleton.channels(&mut l, first_joint);
        }

        let mut root = json!({
            "asset": {
                "version": "2.0",
                "generator": concat!("weft ", env!("CARGO_PKG_VERSION")),
                "extras": {"units": "metres, seconds; Y up", "fps": options.fps},
            },
            "scene": 0,
            "scenes": [{"name": "weft", "nodes": scene_nodes}],
            "nodes": nodes,
            "meshes": json_meshes,
            "materials": materials,
        });
        if let Some(skins) = skins {
            root["skins"] = skins;
        }
        // Skeletal animation plays between frames too, so its correctives blend
        // (LINEAR); a morph-only animation shows each frame exactly (STEP).
        let interpolation = if skin.is_some() { "LINEAR" } else { "STEP" };
        if !animated_nodes.is_empty() || !joint_channels.is_empty() {
            root["animations"] = json!([animation(
                &mut l,
                &times,
                &animated_nodes,
                interpolation,
                joint_channels
            )?]);
        }
        root["accessors"] = Value::Array(std::mem::take(&mut l.accessors));
        root["bufferViews"] = Value::Array(std::mem::take(&mut l.views));
        root["buffers"] = json!([{"byteLength": l.offset}]);

        let mut json = serde_json::to_vec(&root)
            .map_err(|e| ExportError::write("<glTF JSON>", io::Error::other(e)))?;
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let bin_len = l.offset;
        let total = 12 + 8 + json.len() as u64 + 8 + bin_len as u64;
        if total > u64::from(u32::MAX) {
            return Err(ExportError::TooLarge {
                format: "a .glb file",
                what: "the file size in bytes",
                value: total,
                max: u64::from(u32::MAX),
            });
        }
        Ok(Document {
            json,
            blobs: l.blobs,
            bin_len,
            total_len: total as usize,
        })
    }

    fn write_to(&self, w: &mut dyn Write) -> io::Result<()> {
        let mut head = Vec::with_capacity(28);
        for x in [
            GLB_MAGIC,
            2,
            self.total_len as u32,
            self.json.len() as u32,
            CHUNK_JSON,
        ] {
            head.extend_from_slice(&x.to_le_bytes());
        }
        w.write_all(&head)?;
        w.write_all(&self.json)?;
        w.write_all(&(self.bin_len as u32).to_le_bytes())?;
        w.write_all(&CHUNK_BIN.to_le_bytes())?;
        for (k, blob) in self.blobs.iter().enumerate() {
            let mut counted = Counting { inner: w, n: 0 };
            (blob.write)(&mut counted)?;
            if counted.n != blob.len {
                return Err(io::Error::other(format!(
                    "internal error: buffer view {k} wrote {} bytes, laid out {}",
                    counted.n, blob.len
                )));
            }
        }
        Ok(())
    }
}

/// A mesh's vertices split at its UV seams: every (vertex, UV) pair used by a corner
/// becomes one glTF vertex.
struct SeamSplit {
    /// The source vertex of each glTF vertex.
    source: Rc<[u32]>,
    /// The UV of each glTF vertex, V flipped.
    texcoords: Vec<[f32; 2]>,
    /// The triangles over glTF vertices.
    faces: Vec<[u32; 3]>,
}

impl SeamSplit {
    fn new(faces: &[[u32; 3]], uvs: &super::scene::CornerUvs) -> Self {
        let indexed = IndexedUvs::new(uvs);
        let mut of_pair: HashMap<(u32, u32), u32> = HashMap::new();
        let mut source = Vec::new();
        let mut texcoords = Vec::new();
        let faces = faces
            .iter()
            .zip(&indexed.corners)
            .map(|(f, t)| {
                [0, 1, 2].map(|k| {
                    *of_pair.entry((f[k], t[k])).or_insert_with(|| {
                        let [u, v] = indexed.values[t[k] as usize];
                        source.push(f[k]);
                        texcoords.push([u, 1.0 - v]);
                        (source.len() - 1) as u32
                    })
                })
            })
            .collect();
        SeamSplit {
            source: source.into(),
            texcoords,
            faces,
        }
    }
}

/// The values of `per_source` for each written vertex: all of them, or gathered through
/// a seam split's sources.
fn gather<'b, T: Copy + 'b>(
    per_source: impl Fn(usize) -> T + 'b,
    count: usize,
    source: Option<&'b [u32]>,
) -> Box<dyn Iterator<Item = T> + 'b> {
    match source {
        Some(s) => Box::new(s.iter().map(move |&i| per_source(i as usize))),
        None => Box::new((0..count).map(per_source)),
    }
}

/// Base attributes and morph targets of one mesh.
fn mesh_data<'a>(
    l: &mut Layout<'a>,
    m: &AnimatedMesh<'a>,
    base: &'a [[f32; 3]],
    split: Option<&SeamSplit>,
    with_normals: bool,
) -> Result<(Value, Vec<Value>), ExportError> {
    let frames = m.frames;
    let faces = m.faces;
    let source = split.map(|s| s.source.clone());
    let n = source.as_ref().map_or(frames.vertex_count(), |s| s.len());
    let t = frames.frame_count();
    let vec3_len = n
        .checked_mul(12)
        .ok_or_else(|| too_large("the vertex count", n))?;
    let (lo, hi) = bounds(base).unwrap_or(([0.0; 3], [0.0; 3]));
    let src = source.clone();
    let view = l.view(vec3_len, Some(ARRAY_BUFFER), None, move |w| {
        write_vec3s(w, gather(|i| base[i], base.len(), src.as_deref()))
    });
    let position = l.accessor(vec3_accessor(view, 0, n, Some((lo, hi))));
    let mut attributes = json!({"POSITION": position});
    let base_normals = with_normals.then(|| vertex_normals(base, faces));
    if let Some(normals) = &base_normals {
        let normals = normals.clone();
        let src = source.clone();
        let view = l.view(vec3_len, Some(ARRAY_BUFFER), None, move |w| {
            write_vec3s(w, gather(|i| normals[i], normals.len(), src.as_deref()))
        });
        attributes["NORMAL"] = json!(l.accessor(vec3_accessor(view, 0, n, None)));
    }
    if let Some(split) = split {
        let texcoords = split.texcoords.clone();
        let view = l.view(n * 8, Some(ARRAY_BUFFER), None, move |w| {
            write_le(w, texcoords.as_flattened())
        });
        attributes["TEXCOORD_0"] = json!(l.plain_accessor(view, FLOAT, n, "VEC2"));
    }
    if t < 2 {
        return Ok((attributes, Vec::new()));
    }

    // Position deltas of every frame from the base, in one strided view.
    let all_len = vec3_len
        .checked_mul(t)
        .ok_or_else(|| too_large("frames × vertices", t.saturating_mul(n)))?;
    let src = source.clone();
    let pos_view = l.view(all_len, Some(ARRAY_BUFFER), Some(12), move |w| {
        for frame in frames.iter() {
            let d = |i: usize| delta(frame[i], base[i]);
            write_vec3s(w, gather(d, base.len(), src.as_deref()))?;
        }
        Ok(())
    });
    let nrm_view = base_normals.map(|base_normals| {
        let src = source.clone();
        l.view(all_len, Some(ARRAY_BUFFER), Some(12), move |w| {
            for frame in frames.iter() {
                let normals = vertex_normals(frame, faces);
                let d = |i: usize| delta(normals[i], base_normals[i]);
                write_vec3s(w, gather(d, normals.len(), src.as_deref()))?;
            }
            Ok(())
        })
    });
    let mut targets = Vec::with_capacity(t);
    for (k, frame) in frames.iter().enumerate() {
        // The bounds of the written deltas: a split copies values, it adds none.
        let d: Vec<[f32; 3]> = deltas(frame, base).collect();
        let b = bounds(&d);
        let mut target = json!({
            "POSITION": l.accessor(vec3_accessor(pos_view, k * vec3_len, n, b)),
        });
        if let Some(v) = nrm_view {
            target["NORMAL"] = json!(l.accessor(vec3_accessor(v, k * vec3_len, n, None)));
        }
        targets.push(target);
    }
    Ok((attributes, targets))
}

/// `frame − base` per vertex, rounded once from the `f64` difference.
fn deltas<'b>(frame: &'b [[f32; 3]], base: &'b [[f32; 3]]) -> impl Iterator<Item = [f32; 3]> + 'b {
    frame.iter().zip(base).map(|(&p, &b)| delta(p, b))
}

/// `p − b`, rounded once from the `f64` difference.
fn delta(p: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|k| (f64::from(p[k]) - f64::from(b[k])) as f32)
}

fn index_accessor<'a>(
    l: &mut Layout<'a>,
    faces: Cow<'a, [[u32; 3]]>,
) -> Result<usize, ExportError> {
    let count = faces.len() * 3;
    let len = faces
        .len()
        .checked_mul(12)
        .ok_or_else(|| too_large("the face count", faces.len()))?;
    let view = l.view(len, Some(ELEMENT_ARRAY_BUFFER), None, move |w| {
        let mut buf = Vec::with_capacity(1 << 16);
        for chunk in faces.chunks(4096) {
            buf.clear();
            for &i in chunk.as_flattened() {
                buf.extend_from_slice(&i.to_le_bytes());
            }
            w.write_all(&buf)?;
        }
        Ok(())
    });
    Ok(l.plain_accessor(view, UNSIGNED_INT, count, "SCALAR"))
}

/// The sampler times, the one-hot morph weights with one channel per morph-animated
/// node, and `joints`: (sampler output accessor, node, path) of a skeleton's channels.
fn animation(
    l: &mut Layout<'_>,
    times: &[f32],
    nodes: &[usize],
    interpolation: &str,
    joints: Vec<(usize, usize, &'static str)>,
) -> Result<Value, ExportError> {
    let t = times.len();
    let times = times.to_vec();
    let (first, last) = (times[0], times[t - 1]);
    let input_view = l.view(t * 4, None, None, move |w| write_le(w, &times));
    let input = l.accessor(json!({
        "bufferView": input_view,
        "componentType": FLOAT,
        "count": t,
        "type": "SCALAR",
        "min": [f64::from(first)],
        "max": [f64::from(last)],
    }));
    let output = if nodes.is_empty() {
        None
    } else {
        let weights_len = t
            .checked_mul(t)
            .and_then(|x| x.checked_mul(4))
            .ok_or_else(|| too_large("the frame count", t))?;
        let output_view = l.view(weights_len, None, None, move |w| {
            // Key k: weight 1 for target k, 0 for the others.
            let mut row = vec![0u8; t * 4];
            for k in 0..t {
                row[k * 4..k * 4 + 4].copy_from_slice(&1f32.to_le_bytes());
                w.write_all(&row)?;
                row[k * 4..k * 4 + 4].copy_from_slice(&0f32.to_le_bytes());
            }
            Ok(())
        });
        Some(l.plain_accessor(output_view, FLOAT, t * t, "SCALAR"))
    };
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    let all = output
        .into_iter()
        .flat_map(|o| nodes.iter().map(move |&node| (o, node, "weights")))
        .chain(joints);
    for (s, (output, node, path)) in all.enumerate() {
        samplers.push(json!({"input": input, "output": output, "interpolation": interpolation}));
        channels.push(json!({"sampler": s, "target": {"node": node, "path": path}}));
    }
    Ok(json!({"name": "weft", "samplers": samplers, "channels": channels}))
}

fn vec3_accessor(
    view: usize,
    offset: usize,
    count: usize,
    min_max: Option<([f32; 3], [f32; 3])>,
) -> Value {
    let mut a = json!({
        "bufferView": view,
        "componentType": FLOAT,
        "count": count,
        "type": "VEC3",
    });
    if offset > 0 {
        a["byteOffset"] = json!(offset);
    }
    if let Some((lo, hi)) = min_max {
        // Widened exactly, so the validator's comparison with the stored f32 is exact.
        a["min"] = json!(lo.map(f64::from));
        a["max"] = json!(hi.map(f64::from));
    }
    a
}

fn too_large(what: &'static str, value: usize) -> ExportError {
    ExportError::TooLarge {
        format: "a .glb file",
        what,
        value: value as u64,
        max: u64::from(u32::MAX),
    }
}

/// A number of the binary chunk, written little-endian.
pub(super) trait LittleEndian: Copy {
    /// Appends the number's bytes.
    fn put(self, buf: &mut Vec<u8>);
}

impl LittleEndian for f32 {
    fn put(self, buf: &mut Vec<u8>) {
        buf.extend_from_slice(&self.to_le_bytes());
    }
}

impl LittleEndian for u16 {
    fn put(self, buf: &mut Vec<u8>) {
        buf.extend_from_slice(&self.to_le_bytes());
    }
}

/// `values` little-endian, in one write.
pub(super) fn write_le<T: LittleEndian>(w: &mut dyn Write, values: &[T]) -> io::Result<()> {
    let mut buf = Vec::with_capacity(std::mem::size_of_val(values));
    for &v in values {
        v.put(&mut buf);
    }
    w.write_all(&buf)
}

/// Writes `f32` triples little-endian, in blocks.
fn write_vec3s(w: &mut dyn Write, v: impl Iterator<Item = [f32; 3]>) -> io::Result<()> {
    let mut buf = Vec::with_capacity(12 * 4096);
    for p in v {
        for c in p {
            buf.extend_from_slice(&c.to_le_bytes());
        }
        if buf.len() >= 12 * 4096 {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    w.write_all(&buf)
}

/// Area-weighted unit vertex normals of `positions` with `faces`, accumulated in `f64`.
/// A vertex without a usable normal (isolated, or only degenerate faces) gets +Y: glTF
/// requires unit normals, and +Y is the neutral choice for a Y-up scene.
fn vertex_normals(positions: &[[f32; 3]], faces: &[[u32; 3]]) -> Vec<[f32; 3]> {
    use crate::vec3::{add, cross, norm, sub};
    let p = |i: u32| positions[i as usize].map(f64::from);
    let mut acc = vec![[0.0f64; 3]; positions.len()];
    for f in faces {
        let (a, b, c) = (p(f[0]), p(f[1]), p(f[2]));
        let n = cross(sub(b, a), sub(c, a));
        for &i in f {
            acc[i as usize] = add(acc[i as usize], n);
        }
    }
    acc.into_iter()
        .map(|n| {
            let len = norm(n);
            if len > 0.0 && len.is_finite() {
                n.map(|c| (c / len) as f32)
            } else {
                [0.0, 1.0, 0.0]
            }
        })
        .collect()
}

/// A writer that counts bytes.
struct Counting<'w> {
    inner: &'w mut dyn Write,
    n: usize,
}

impl Write for Counting<'_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let k = self.inner.write(buf)?;
        self.n += k;
        Ok(k)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

// ---------------------------------------------------------------------------------------
// Reading back.

/// A mesh of a `.glb` read back, with its animation evaluated at every key time.
#[derive(Clone, Debug, PartialEq)]
pub struct GlbMeshFrames {
    /// The node's name.
    pub name: String,
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
    /// Positions at each key time (one frame for a static mesh).
    pub frames: Frames,
    /// `TEXCOORD_0` per vertex, as stored (V down), when the primitive has it.
    pub texcoords: Option<Vec<[f32; 2]>>,
}

/// A `.glb` scene read back by [`read_glb`].
#[derive(Clone, Debug, PartialEq)]
pub struct GlbScene {
    /// The meshes of the default scene's nodes, in node order.
    pub meshes: Vec<GlbMeshFrames>,
    /// The key times of the first animation (empty without animation).
    pub times: Vec<f32>,
}

/// Reads a `.glb` the way a viewer plays it: for every mesh node of the default scene,
/// base positions plus the weighted morph-target deltas at each key time of the
/// node's `weights` channel. Covers what [`write_glb`] writes (one triangle primitive per
/// mesh, float positions, `u32`/`u16` indices); other files fail with a clear error, never
/// a panic.
pub fn read_glb(path: &Path) -> Result<GlbScene, ExportError> {
    let bytes = crate::io::read_input(path).map_err(|e| ExportError::read(path, e))?;
    parse_glb(&bytes, path)
}

/// Parses a `.glb` held in memory; see [`read_glb`].
pub fn parse_glb(bytes: &[u8], path: &Path) -> Result<GlbScene, ExportError> {
    let bad = |m: String| ExportError::format(path, m);
    let u32_at = |o: usize| -> Result<u32, ExportError> {
        bytes
            .get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| bad(format!("truncated at byte {o}")))
    };
    if u32_at(0)? != GLB_MAGIC || u32_at(4)? != 2 {
        return Err(bad("not a glTF 2.0 binary (.glb) file".into()));
    }
    if u32_at(8)? as usize != bytes.len() {
        return Err(bad(format!(
            "the header says {} bytes but the file has {}",
            u32_at(8)?,
            bytes.len()
        )));
    }
    let json_len = u32_at(12)? as usize;
    if u32_at(16)? != CHUNK_JSON {
        return Err(bad("the first chunk is not JSON".into()));
    }
    let json_end = 20usize
        .checked_add(json_len)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| bad("the JSON chunk runs past the end".into()))?;
    let root: Value = serde_json::from_slice(&bytes[20..json_end])
        .map_err(|e| bad(format!("the JSON chunk does not parse: {e}")))?;
    let bin: &[u8] = if json_end + 8 <= bytes.len() {
        let len = u32_at(json_end)? as usize;
        if u32_at(json_end + 4)? != CHUNK_BIN {
            return Err(bad("the second chunk is not BIN".into()));
        }
        bytes
            .get(json_end + 8..json_end + 8 + len)
            .ok_or_else(|| bad("the BIN chunk runs past the end".into()))?
    } else {
        &[]
    };
    let r = Reader {
        root: &root,
        bin,
        path,
    };

    let scene = root.get("scene").and_then(Value::as_u64).unwrap_or(0) as usize;
    let node_ids = r.array(&root["scenes"][scene]["nodes"], "scene nodes")?;
    let animation = &root["animations"][0];
    let mut times = Vec::new();
    let mut meshes = Vec::new();
    for node_id in node_ids {
        let node_id = r.index(node_id, "node index")?;
        let node = &root["nodes"][node_id];
        let Some(mesh_id) = node.get("mesh") else {
            continue;
        };
        let mesh = &root["meshes"][r.index(mesh_id, "mesh index")?];
        let prim = &mesh["primitives"][0];
        let base = r.vec3(&prim["attributes"]["POSITION"])?;
        let n = base.len();
        let faces = r.indices(&prim["indices"], n)?;
        let targets: Vec<Vec<[f32; 3]>> = match prim.get("targets") {
            Some(ts) => r
                .array(ts, "morph targets")?
                .iter()
                .map(|t| r.vec3(&t["POSITION"]))
                .collect::<Result<_, _>>()?,
            None => Vec::new(),
        };
        if targets.iter().any(|t| t.len() != n) {
            return Err(bad(
                "a morph target's vertex count differs from the base".into()
            ));
        }
        let channel = animation["channels"].as_array().and_then(|cs| {
            cs.iter().find(|c| {
                c["target"]["node"].as_u64() == Some(node_id as u64)
                    && c["target"]["path"] == "weights"
            })
        });
        let mut frames = Frames::with_vertex_count(n)?;
        match channel {
            None => frames.push_frame(&base)?,
            Some(c) => {
                let sampler = &animation["samplers"][r.index(&c["sampler"], "sampler")?];
                let input = r.scalars(&sampler["input"])?;
                let weights = r.scalars(&sampler["output"])?;
                let m = targets.len();
                if m == 0 || weights.len() != input.len() * m {
                    return Err(bad(format!(
                        "{} weights for {} keys of {m} targets",
                        weights.len(),
                        input.len()
                    )));
                }
                for row in weights.chunks_exact(m) {
                    let mut p = base.clone();
                    for (w, target) in row.iter().zip(&targets) {
                        if *w != 0.0 {
                            for (q, d) in p.iter_mut().zip(target) {
                                for k in 0..3 {
                                    q[k] += w * d[k];
                                }
                            }
                        }
                    }
                    frames.push_frame(&p)?;
                }
                if times.is_empty() {
                    times = input;
                }
            }
        }
        let texcoords = match prim["attributes"].get("TEXCOORD_0") {
            Some(id) => {
                let uv = r.floats(id, 2)?;
                if uv.len() != 2 * n {
                    return Err(bad("TEXCOORD_0's count differs from POSITION's".into()));
                }
                Some(uv.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
            }
            None => None,
        };
        meshes.push(GlbMeshFrames {
            name: node["name"].as_str().unwrap_or("").to_owned(),
            faces,
            frames,
            texcoords,
        });
    }
    Ok(GlbScene { meshes, times })
}

/// Accessor reading with bounds checks.
struct Reader<'r> {
    root: &'r Value,
    bin: &'r [u8],
    path: &'r Path,
}

impl Reader<'_> {
    fn bad(&self, m: impl Into<String>) -> ExportError {
        ExportError::format(self.path, m)
    }

    fn array<'v>(&self, v: &'v Value, what: &str) -> Result<&'v Vec<Value>, ExportError> {
        v.as_array()
            .ok_or_else(|| self.bad(format!("{what}: expected an array")))
    }

    fn index(&self, v: &Value, what: &str) -> Result<usize, ExportError> {
        v.as_u64()
            .map(|x| x as usize)
            .ok_or_else(|| self.bad(format!("{what}: expected a non-negative integer")))
    }

    /// The bytes of each element of accessor `id`: (component type, count, element
    /// stride, start offset).
    fn layout(&self, id: &Value, comps: usize) -> Result<(u64, usize, usize, usize), ExportError> {
        let a = &self.root["accessors"][self.index(id, "accessor index")?];
        let ct = a["componentType"].as_u64().unwrap_or(0);
        let size = match ct {
            5126 | 5125 => 4,
            5123 => 2,
            _ => return Err(self.bad(format!("accessor component type {ct} is not supported"))),
        };
        let count = self.index(&a["count"], "accessor count")?;
        let view = &self.root["bufferViews"][self.index(&a["bufferView"], "buffer view")?];
        let view_start = self.index(&view["byteOffset"], "byteOffset").unwrap_or(0);
        let view_end = view_start.checked_add(self.index(&view["byteLength"], "byteLength")?);
        let start = view_start.checked_add(a["byteOffset"].as_u64().unwrap_or(0) as usize);
        let element = size * comps;
        let stride = view["byteStride"].as_u64().map_or(element, |s| s as usize);
        if stride < element {
            return Err(self.bad(format!(
                "byteStride {stride} is smaller than an element ({element} bytes)"
            )));
        }
        let end = start.and_then(|s| {
            if count == 0 {
                Some(s)
            } else {
                stride
                    .checked_mul(count - 1)?
                    .checked_add(s)?
                    .checked_add(element)
            }
        });
        let (Some(start), Some(end), Some(view_end)) = (start, end, view_end) else {
            return Err(self.bad("an accessor's byte range overflows"));
        };
        if end > view_end || view_end > self.bin.len() {
            return Err(self.bad("an accessor reaches past its buffer view or the BIN chunk"));
        }
        Ok((ct, count, stride, start))
    }

    fn floats(&self, id: &Value, comps: usize) -> Result<Vec<f32>, ExportError> {
        let (ct, count, stride, start) = self.layout(id, comps)?;
        if ct != u64::from(FLOAT) {
            return Err(self.bad("expected a float accessor"));
        }
        let mut out = Vec::with_capacity(count * comps);
        for i in 0..count {
            for c in 0..comps {
                let o = start + i * stride + c * 4;
                let b = &self.bin[o..o + 4];
                out.push(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            }
        }
        Ok(out)
    }

    fn vec3(&self, id: &Value) -> Result<Vec<[f32; 3]>, ExportError> {
        Ok(self
            .floats(id, 3)?
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect())
    }

    fn scalars(&self, id: &Value) -> Result<Vec<f32>, ExportError> {
        self.floats(id, 1)
    }

    fn indices(&self, id: &Value, vertices: usize) -> Result<Vec<[u32; 3]>, ExportError> {
        let (ct, count, stride, start) = self.layout(id, 1)?;
        if count % 3 != 0 {
            return Err(self.bad(format!("{count} indices; expected triangles")));
        }
        let mut out = Vec::with_capacity(count);
        for i in 0..count {
            let o = start + i * stride;
            let v = match ct {
                5125 => u32::from_le_bytes([
                    self.bin[o],
                    self.bin[o + 1],
                    self.bin[o + 2],
                    self.bin[o + 3],
                ]),
                5123 => u32::from(u16::from_le_bytes([self.bin[o], self.bin[o + 1]])),
                _ => return Err(self.bad("indices must be unsigned integers")),
            };
            if v as usize >= vertices {
                return Err(self.bad(format!("index {v} out of range for {vertices} vertices")));
            }
            out.push(v);
        }
        Ok(out.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::{BODY_COLOR, GARMENT_COLOR};
    use crate::primitives::{cylinder, grid};

    fn frames_of(mesh: &crate::TriMesh, t: usize) -> Frames {
        let mut f = Frames::with_vertex_count(mesh.vertex_count()).unwrap();
        for k in 0..t {
            let s = k as f64 * 0.1;
            let p: Vec<[f64; 3]> = mesh
                .positions
                .iter()
                .map(|p| [p[0] * (1.0 + s), p[1] + s * p[0] * p[0], p[2] - s])
                .collect();
            f.push_frame_f64(&p).unwrap();
        }
        f
    }

    fn close(a: &Frames, b: &Frames) -> bool {
        a.frame_count() == b.frame_count()
            && a.vertex_count() == b.vertex_count()
            && a.as_flat()
                .iter()
                .zip(b.as_flat())
                .all(|(x, y)| (x - y).abs() <= 1e-6 * x.abs().max(1.0))
    }

    #[test]
    fn round_trip_garment_and_static_body() {
        let g = cylinder(4, 6, 0.3, 0.1);
        let b = grid(3, 3, 0.5);
        let gf = frames_of(&g, 5);
        let bf = frames_of(&b, 1);
        let meshes = [
            AnimatedMesh {
                name: "garment",
                faces: &g.faces,
                frames: &gf,
                uvs: None,
                color: GARMENT_COLOR,
            },
            AnimatedMesh {
                name: "body",
                faces: &b.faces,
                frames: &bf,
                uvs: None,
                color: BODY_COLOR,
            },
        ];
        for normals in [true, false] {
            let bytes = glb_bytes(&meshes, GlbOptions { fps: 24.0, normals }).unwrap();
            assert_eq!(bytes.len() % 4, 0);
            let s = parse_glb(&bytes, Path::new("t.glb")).unwrap();
            assert_eq!(s.times.len(), 5);
            assert_eq!(s.times[1], (1.0f64 / 24.0) as f32);
            assert_eq!(s.meshes.len(), 2);
            assert_eq!(s.meshes[0].name, "garment");
            assert_eq!(s.meshes[0].faces, g.faces);
            assert!(close(&s.meshes[0].frames, &gf));
            assert_eq!(s.meshes[1].frames, bf);
        }
    }

    #[test]
    fn uv_seams_split_vertices_and_keep_every_corner() {
        // A grid with a seam down its middle column: the faces right of it use UVs
        // shifted by 10, so the seam vertices carry two UVs each.
        let g = grid(3, 3, 1.0);
        let frames = frames_of(&g, 3);
        let uvs: Vec<[[f32; 2]; 3]> = g
            .faces
            .iter()
            .map(|f| {
                let right = f.iter().any(|&i| g.positions[i as usize][0] > 1.5);
                f.map(|i| {
                    let p = g.positions[i as usize];
                    [p[0] as f32 + if right { 10.0 } else { 0.0 }, p[2] as f32]
                })
            })
            .collect();
        let bytes = glb_bytes(
            &[AnimatedMesh {
                name: "garment",
                faces: &g.faces,
                uvs: Some(&uvs),
                frames: &frames,
                color: GARMENT_COLOR,
            }],
            GlbOptions::default(),
        )
        .unwrap();
        let scene = parse_glb(&bytes, Path::new("t.glb")).unwrap();
        let m = &scene.meshes[0];
        let texcoords = m.texcoords.as_ref().unwrap();
        let distinct: std::collections::HashSet<(u32, [u32; 2])> = g
            .faces
            .iter()
            .zip(&uvs)
            .flat_map(|(f, t)| (0..3).map(move |k| (f[k], t[k].map(f32::to_bits))))
            .collect();
        assert!(m.frames.vertex_count() > g.vertex_count());
        assert_eq!(m.frames.vertex_count(), distinct.len());
        assert_eq!(m.faces.len(), g.faces.len());
        for (fi, (f, written)) in g.faces.iter().zip(&m.faces).enumerate() {
            for k in 0..3 {
                let (src, dst) = (f[k] as usize, written[k] as usize);
                assert_eq!(texcoords[dst], [uvs[fi][k][0], 1.0 - uvs[fi][k][1]]);
                for t in 0..3 {
                    let a = frames.frame(t).unwrap()[src];
                    let b = m.frames.frame(t).unwrap()[dst];
                    assert!((0..3).all(|c| (a[c] - b[c]).abs() < 1e-6), "{a:?} {b:?}");
                }
            }
        }
    }

    #[test]
    fn json_has_what_the_spec_requires() {
        let g = grid(3, 2, 1.0);
        let f = frames_of(&g, 3);
        let bytes = glb_bytes(
            &[AnimatedMesh {
                name: "g",
                faces: &g.faces,
                frames: &f,
                uvs: None,
                color: GARMENT_COLOR,
            }],
            GlbOptions::default(),
        )
        .unwrap();
        let len = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
        let root: Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
        let prim = &root["meshes"][0]["primitives"][0];
        assert_eq!(prim["targets"].as_array().unwrap().len(), 3);
        for t in prim["targets"].as_array().unwrap() {
            let a = &root["accessors"][t["POSITION"].as_u64().unwrap() as usize];
            assert!(a["min"].is_array() && a["max"].is_array());
        }
        assert_eq!(
            root["animations"][0]["samplers"][0]["interpolation"],
            "STEP"
        );
        assert_eq!(root["meshes"][0]["extras"]["targetNames"][2], "frame_00002");
        assert_eq!(root["meshes"][0]["weights"], json!([1.0, 0.0, 0.0]));
    }

    #[test]
    fn bad_input_is_refused() {
        let g = grid(2, 2, 1.0);
        let f3 = frames_of(&g, 3);
        let f2 = frames_of(&g, 2);
        let m = |f| AnimatedMesh {
            name: "a",
            faces: &g.faces,
            frames: f,
            uvs: None,
            color: BODY_COLOR,
        };
        let e = glb_bytes(
            &[
                m(&f3),
                AnimatedMesh {
                    name: "b",
                    ..m(&f2)
                },
            ],
            GlbOptions::default(),
        )
        .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("mesh `b` has 2 frames but `a` has 3"),
            "{e}"
        );
        let e = glb_bytes(
            &[m(&f3)],
            GlbOptions {
                fps: 0.0,
                normals: true,
            },
        )
        .unwrap_err();
        assert!(matches!(e, ExportError::Fps { .. }));
        let bad_faces = [[0, 1, 9]];
        let e = glb_bytes(
            &[AnimatedMesh {
                faces: &bad_faces,
                ..m(&f3)
            }],
            GlbOptions::default(),
        )
        .unwrap_err();
        assert!(matches!(e, ExportError::FaceIndex { vertex: 9, .. }));
        let mut nan = f3.clone();
        nan.positions_mut_for_test()[5][0] = f32::NAN;
        let e = glb_bytes(&[m(&nan)], GlbOptions::default()).unwrap_err();
        assert!(e.to_string().starts_with("frame 1, vertex 1"), "{e}");
        assert!(glb_bytes(&[], GlbOptions::default()).is_err());
    }

    #[test]
    fn reader_rejects_garbage_without_panicking() {
        let p = Path::new("x.glb");
        assert!(parse_glb(b"", p).is_err());
        assert!(parse_glb(b"glTF\x02\0\0\0\x0c\0\0\0", p).is_err());
        let g = grid(2, 2, 1.0);
        let f = frames_of(&g, 2);
        let good = glb_bytes(
            &[AnimatedMesh {
                name: "g",
                faces: &g.faces,
                frames: &f,
                uvs: None,
                color: BODY_COLOR,
            }],
            GlbOptions::default(),
        )
        .unwrap();
        for cut in [13, 30, good.len() - 4] {
            let mut b = good[..cut].to_vec();
            let n = b.len() as u32;
            if b.len() >= 12 {
                b[8..12].copy_from_slice(&n.to_le_bytes());
            }
            assert!(parse_glb(&b, p).is_err(), "cut {cut}");
        }
    }

    /// A valid file with its JSON changed by `edit`, re-encoded as a `.glb`.
    fn with_json(good: &[u8], edit: impl FnOnce(&mut Value)) -> Vec<u8> {
        let len = u32::from_le_bytes([good[12], good[13], good[14], good[15]]) as usize;
        let mut root: Value = serde_json::from_slice(&good[20..20 + len]).unwrap();
        edit(&mut root);
        let mut json = serde_json::to_vec(&root).unwrap();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let bin = &good[20 + len..];
        let total = (12 + 8 + json.len() + bin.len()) as u32;
        let mut out = Vec::new();
        for x in [GLB_MAGIC, 2, total, json.len() as u32, CHUNK_JSON] {
            out.extend_from_slice(&x.to_le_bytes());
        }
        out.extend_from_slice(&json);
        out.extend_from_slice(bin);
        out
    }

    #[test]
    fn reader_rejects_hostile_json_without_panicking() {
        let g = grid(2, 2, 1.0);
        let f = frames_of(&g, 2);
        let good = glb_bytes(
            &[AnimatedMesh {
                name: "g",
                faces: &g.faces,
                frames: &f,
                uvs: None,
                color: BODY_COLOR,
            }],
            GlbOptions::default(),
        )
        .unwrap();
        let p = Path::new("h.glb");
        assert!(parse_glb(&with_json(&good, |_| {}), p).is_ok());
        type Edit = Box<dyn Fn(&mut Value)>;
        let edits: Vec<Edit> = vec![
            Box::new(|r| r["accessors"][0]["count"] = json!(u64::MAX / 2)),
            Box::new(|r| r["bufferViews"][0]["byteStride"] = json!(0)),
            Box::new(|r| r["bufferViews"][0]["byteOffset"] = json!(u64::MAX)),
            Box::new(|r| r["bufferViews"][0]["byteLength"] = json!(u64::MAX)),
            Box::new(|r| r["accessors"][0]["byteOffset"] = json!(u64::MAX - 3)),
            Box::new(|r| r["accessors"][0]["bufferView"] = json!(999)),
            Box::new(|r| r["accessors"][0]["componentType"] = json!(5120)),
            Box::new(|r| r["meshes"][0]["primitives"][0]["indices"] = json!(0)),
            Box::new(|r| r["animations"][0]["samplers"][0]["output"] = json!(999)),
            Box::new(|r| r["scenes"] = json!("x")),
        ];
        for (k, edit) in edits.iter().enumerate() {
            assert!(parse_glb(&with_json(&good, edit), p).is_err(), "edit {k}");
        }
    }

    #[test]
    fn normals_are_unit_even_for_isolated_vertices() {
        let n = vertex_normals(
            &[[0., 0., 0.], [1., 0., 0.], [0., 0., -1.], [5., 5., 5.]],
            &[[0, 1, 2]],
        );
        assert_eq!(n[0], [0.0, 1.0, 0.0]);
        assert_eq!(n[3], [0.0, 1.0, 0.0]);
    }
}
