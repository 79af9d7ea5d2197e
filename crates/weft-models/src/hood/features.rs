//! One rollout step's graph with its input features (seed 004 §3; hood-reference §1.2,
//! §1.5), on the host: garment nodes, the body vertices that some garment node reaches,
//! the mesh edges of every level and the body edges in both directions.
//!
//! Nodes (per row, before normalisation): velocity `x_t − x_{t−1}` (per frame, as HOOD),
//! unit vertex normal, node type one-hot (free, pinned, body), time step, log mass, the
//! level one-hot (body: none), then the raw material inputs (body: −1). Mesh edges:
//! `x_s − x_r` now and at rest with their lengths, time step, then the mean material of
//! the two ends. Body edges: garment minus body at t and at t + 1 with their lengths, time
//! step; the body-to-garment direction negates the vectors. Button edges join the mesh
//! level with a rest vector of zero (the pair is held together).
//!
//! Pinned vertices enter with their target at t + 1 as position and `target − x_t` as
//! velocity, as HOOD does, so the network sees where the pins go.
//!
//! With [`HoodConfig::relative_velocity`] (not in HOOD) every node's velocity is taken
//! relative to the body's median velocity from t − 1 to t (per axis, over its vertices:
//! the bulk of the body, which moving arms or a kicking leg do not shift). The
//! potential is the same in any frame moving at constant velocity (inertia, gravity,
//! friction and collisions all follow the body), so the step's answer should be too;
//! HOOD's world-frame velocities instead put a walk at 4 cm and a run at 10 cm per
//! frame, far outside what in-place motions teach the network (docs/hood.md).

use weft_body::query::{BodyEdgeRule, VertexTree};
use weft_mesh::vec3::{norm, sub};
use weft_mesh::vertex_normals_of;

use super::config::{widths, HoodConfig};
use super::garment::HoodGarment;
use crate::error::ModelError;

/// The body at the three instants a step reads.
#[derive(Clone, Copy, Debug)]
pub struct BodyStep<'a> {
    /// Vertices at t − 1.
    pub prev: &'a [[f64; 3]],
    /// Vertices at t.
    pub cur: &'a [[f64; 3]],
    /// Vertices at t + 1.
    pub next: &'a [[f64; 3]],
    /// The body's triangles (for normals).
    pub faces: &'a [[u32; 3]],
    /// Body vertices that take no body edges (the hands), or empty.
    pub omit: &'a [bool],
}

/// A garment's state at the start of a step.
#[derive(Clone, Copy, Debug)]
pub struct GarmentStep<'a> {
    /// Positions at t − 1.
    pub prev: &'a [[f64; 3]],
    /// Positions at t.
    pub cur: &'a [[f64; 3]],
    /// Where pinned vertices are at t + 1 (read only at pinned vertices; any length-N
    /// array, e.g. the skinned garment).
    pub pin_targets: &'a [[f64; 3]],
    /// Whether the button edges are in the graph.
    pub buttoned: bool,
}

/// One step's graph and features; see the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct StepGraph {
    /// Garment nodes (the first rows of `nodes`).
    pub garment_nodes: usize,
    /// Body vertex of every body node (node `garment_nodes + k` is body vertex
    /// `body_vertices[k]`).
    pub body_vertices: Vec<u32>,
    /// Node features, row-major, [`StepGraph::node_width`] columns.
    pub nodes: Vec<f32>,
    /// Per mesh level: directed edges (sender, receiver) in node numbering and their
    /// features, row-major, [`StepGraph::MESH_WIDTH`] columns.
    pub mesh: Vec<(Vec<[u32; 2]>, Vec<f32>)>,
    /// Body edges in both directions and their features, [`StepGraph::BODY_WIDTH`]
    /// columns.
    pub body: (Vec<[u32; 2]>, Vec<f32>),
}

fn push3(out: &mut Vec<f32>, v: [f64; 3]) {
    out.extend(v.map(|x| x as f32));
}

impl StepGraph {
    /// Columns of a mesh-edge row.
    pub const MESH_WIDTH: usize = widths::MESH_EDGE + widths::MATERIAL;
    /// Columns of a body-edge row.
    pub const BODY_WIDTH: usize = widths::BODY_EDGE;

    /// Columns of a node row for a hierarchy of `levels` levels.
    pub fn node_width(levels: usize) -> usize {
        widths::NODE_BASE + levels + widths::MATERIAL
    }

    /// The graph of one step of `garment` in state `state` against `body`, with time
    /// step `dt` (s), body edges within `config.body_radius` (m) and velocities as
    /// `config.relative_velocity` says.
    pub fn build(
        garment: &HoodGarment,
        state: &GarmentStep,
        body: &BodyStep,
        dt: f64,
        config: &HoodConfig,
    ) -> Result<Self, ModelError> {
        let n = garment.vertex_count();
        for (what, len) in [
            ("garment positions at t - 1", state.prev.len()),
            ("garment positions at t", state.cur.len()),
            ("pin targets", state.pin_targets.len()),
        ] {
            if len != n {
                return Err(ModelError::mismatch(what, format!("{n} vertices"), len));
            }
        }
        let nb = body.cur.len();
        for (what, len) in [
            ("body vertices at t - 1", body.prev.len()),
            ("body vertices at t + 1", body.next.len()),
        ] {
            if len != nb {
                return Err(ModelError::mismatch(what, format!("{nb} (as at t)"), len));
            }
        }
        if !body.omit.is_empty() && body.omit.len() != nb {
            return Err(ModelError::mismatch(
                "omitted body vertices",
                format!("one flag per body vertex ({nb})"),
                body.omit.len(),
            ));
        }
        if let Some(i) = state
            .prev
            .iter()
            .chain(state.cur)
            .flatten()
            .position(|x| !x.is_finite())
        {
            return Err(ModelError::NonFinite {
                what: "garment positions",
                index: i,
            });
        }
        // Pinned vertices sit at their target, moving there from x_t.
        let cur: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                if garment.pinned[i] {
                    state.pin_targets[i]
                } else {
                    state.cur[i]
                }
            })
            .collect();
        let prev: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                if garment.pinned[i] {
                    state.cur[i]
                } else {
                    state.prev[i]
                }
            })
            .collect();

        // Body edges: each garment node's nearest body vertex within the radius.
        let tree = VertexTree::new(body.cur).map_err(|e| ModelError::Body(e.to_string()))?;
        let found = tree
            .body_edges(&cur, config.body_radius, BodyEdgeRule::Nearest)
            .map_err(|e| ModelError::Body(e.to_string()))?;
        let found: Vec<_> = found
            .into_iter()
            .filter(|e| body.omit.get(e.body as usize) != Some(&true))
            .collect();
        let mut slot = vec![u32::MAX; nb];
        let mut body_vertices = Vec::new();
        for e in &found {
            if slot[e.body as usize] == u32::MAX {
                slot[e.body as usize] = (n + body_vertices.len()) as u32;
                body_vertices.push(e.body);
            }
        }

        let frame = if config.relative_velocity && nb > 0 {
            // The median, not the mean: raised arms move the body's mean, not its bulk.
            let mut d: Vec<f64> = Vec::with_capacity(nb);
            std::array::from_fn(|k| {
                d.clear();
                d.extend(body.cur.iter().zip(body.prev).map(|(c, p)| c[k] - p[k]));
                *d.select_nth_unstable_by(nb / 2, f64::total_cmp).1
            })
        } else {
            [0.0; 3]
        };
        let velocity = |now: [f64; 3], before: [f64; 3]| sub(sub(now, before), frame);

        let levels = garment.levels.len();
        let node_width = Self::node_width(levels);
        let mut nodes = Vec::with_capacity((n + body_vertices.len()) * node_width);
        let normals = vertex_normals_of(&cur, &garment.rest.faces);
        for i in 0..n {
            push3(&mut nodes, velocity(cur[i], prev[i]));
            push3(&mut nodes, normals[i]);
            let pinned = garment.pinned[i];
            nodes.extend([f32::from(!pinned), f32::from(pinned), 0.0]);
            nodes.push(dt as f32);
            nodes.push(garment.masses[i].max(1e-12).ln() as f32);
            let l = garment.level_of[i] as usize;
            nodes.extend((0..levels).map(|k| f32::from(k == l)));
            nodes.extend(garment.material[i]);
        }
        let body_normals = vertex_normals_of(body.cur, body.faces);
        for &b in &body_vertices {
            let b = b as usize;
            push3(&mut nodes, velocity(body.cur[b], body.prev[b]));
            push3(&mut nodes, body_normals[b]);
            nodes.extend([0.0, 0.0, 1.0]);
            nodes.push(dt as f32);
            nodes.push(-1.0);
            nodes.extend(std::iter::repeat_n(0.0, levels));
            nodes.extend([-1.0; widths::MATERIAL]);
        }

        let rest = &garment.rest.positions;
        let mesh_rows = |edges: &[[u32; 2]], buttons: &[[u32; 2]]| {
            let mut feats = Vec::with_capacity((edges.len() + buttons.len()) * Self::MESH_WIDTH);
            let mut all = Vec::with_capacity(edges.len() + buttons.len());
            for (list, is_button) in [(edges, false), (buttons, true)] {
                for &[s, r] in list {
                    let (su, ru) = (s as usize, r as usize);
                    let d = sub(cur[su], cur[ru]);
                    let d0 = if is_button {
                        [0.0; 3]
                    } else {
                        sub(rest[su], rest[ru])
                    };
                    push3(&mut feats, d);
                    feats.push(norm(d) as f32);
                    push3(&mut feats, d0);
                    feats.push(norm(d0) as f32);
                    feats.push(dt as f32);
                    let (ms, mr) = (garment.material[su], garment.material[ru]);
                    feats.extend((0..3).map(|k| 0.5 * (ms[k] + mr[k])));
                    all.push([s, r]);
                }
            }
            (all, feats)
        };
        let mesh: Vec<(Vec<[u32; 2]>, Vec<f32>)> = garment
            .levels
            .iter()
            .enumerate()
            .map(|(l, edges)| {
                let buttons: &[[u32; 2]] = if l == 0 && state.buttoned {
                    &garment.buttons
                } else {
                    &[]
                };
                mesh_rows(edges, buttons)
            })
            .collect();

        let mut body_edges = Vec::with_capacity(2 * found.len());
        let mut body_feats = Vec::with_capacity(2 * found.len() * Self::BODY_WIDTH);
        for sign in [1.0, -1.0] {
            for e in &found {
                let (g, b) = (e.garment as usize, e.body as usize);
                let now = sub(cur[g], body.cur[b]);
                let ahead = sub(cur[g], body.next[b]);
                push3(&mut body_feats, now.map(|x| sign * x));
                body_feats.push(norm(now) as f32);
                push3(&mut body_feats, ahead.map(|x| sign * x));
                body_feats.push(norm(ahead) as f32);
                body_feats.push(dt as f32);
                let node = slot[b];
                body_edges.push(if sign > 0.0 {
                    [g as u32, node]
                } else {
                    [node, g as u32]
                });
            }
        }
        Ok(StepGraph {
            garment_nodes: n,
            body_vertices,
            nodes,
            mesh,
            body: (body_edges, body_feats),
        })
    }

    /// Nodes in the graph (garment and body).
    pub fn node_count(&self) -> usize {
        self.garment_nodes + self.body_vertices.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives::grid;

    /// A 5 × 5 grid garment of two levels, vertex 0 pinned, and its positions at t and
    /// at t − 1 (1 cm lower).
    fn grid_garment() -> (HoodGarment, Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let g = grid(5, 5, 0.1);
        let n = g.vertex_count();
        let garment =
            HoodGarment::new(&g, 2, &[0], vec![0.01; n], vec![[0.25, 0.5, 0.75]; n]).unwrap();
        let cur = g.positions.clone();
        let prev = cur.iter().map(|p| [p[0], p[1] - 0.01, p[2]]).collect();
        (garment, cur, prev)
    }

    #[test]
    fn features_follow_the_state_and_the_body() {
        let (garment, cur, prev) = grid_garment();
        let n = garment.vertex_count();
        let mut targets = cur.clone();
        targets[0] = [cur[0][0], cur[0][1] + 0.02, cur[0][2]];
        // A body of three vertices: one 1 cm under vertex 12, one far, one omitted.
        let c = cur[12];
        let body_cur = vec![
            [c[0], c[1], c[2] - 0.01],
            [5.0, 5.0, 5.0],
            [cur[24][0], cur[24][1], cur[24][2] - 0.01],
        ];
        let body_next: Vec<[f64; 3]> = body_cur
            .iter()
            .map(|p| [p[0], p[1], p[2] + 0.005])
            .collect();
        let faces = [[0u32, 1, 2]];
        let omit = [false, false, true];
        let build = |prev: &[[f64; 3]]| {
            StepGraph::build(
                &garment,
                &GarmentStep {
                    prev,
                    cur: &cur,
                    pin_targets: &targets,
                    buttoned: false,
                },
                &BodyStep {
                    prev: &body_cur,
                    cur: &body_cur,
                    next: &body_next,
                    faces: &faces,
                    omit: &omit,
                },
                1.0 / 30.0,
                &HoodConfig::new(),
            )
        };
        let step = build(&prev).unwrap();
        let w = StepGraph::node_width(2);
        assert_eq!(step.body_vertices, vec![0]);
        assert_eq!(step.nodes.len(), (n + 1) * w);
        // Vertex 12 moved up 1 cm; pinned vertex 0 moves to its target (2 cm up).
        assert!((step.nodes[12 * w + 1] - 0.01).abs() < 1e-6);
        assert!((step.nodes[1] - 0.02).abs() < 1e-6);
        assert_eq!(&step.nodes[6..9], &[0.0, 1.0, 0.0]);
        assert_eq!(&step.nodes[12 * w + 6..12 * w + 9], &[1.0, 0.0, 0.0]);
        // Material is raw at the end; the body node reads -1.
        assert_eq!(&step.nodes[w - 3..w], &[0.25, 0.5, 0.75]);
        assert_eq!(&step.nodes[(n + 1) * w - 3..], &[-1.0; 3]);
        // One body edge each way, garment 12 <-> node n; vectors negated, lengths kept.
        assert_eq!(step.body.0, vec![[12, n as u32], [n as u32, 12]]);
        let bw = StepGraph::BODY_WIDTH;
        let (a, b) = (&step.body.1[..bw], &step.body.1[bw..]);
        assert!((a[2] - 0.01).abs() < 1e-6 && (b[2] + 0.01).abs() < 1e-6);
        assert_eq!(a[3], b[3]);
        // The body moves 5 mm towards the garment by t + 1.
        assert!((a[7] - 0.005).abs() < 1e-6);
        // Mesh edges of both levels, with rest vectors.
        assert_eq!(step.mesh.len(), 2);
        assert_eq!(
            step.mesh[0].1.len(),
            step.mesh[0].0.len() * StepGraph::MESH_WIDTH
        );
        let bad = build(&prev[1..]);
        assert!(bad.unwrap_err().to_string().contains("t - 1"));
    }

    /// Relative velocities: the same graph for a scene and for the scene moving at a
    /// constant velocity, and the garment's velocity is its own minus the body's.
    #[test]
    fn relative_velocities_do_not_see_a_uniform_motion() {
        let (garment, cur, prev) = grid_garment();
        let c = cur[12];
        let body_cur = vec![
            [c[0], c[1], c[2] - 0.01],
            [c[0] + 0.02, c[1], c[2] - 0.01],
            [5.0, 5.0, 5.0],
        ];
        // The body moves 2 cm along z from t - 1 to t, and on to t + 1; its far vertex
        // (an arm) 50 cm, which does not move the median.
        let mut body_prev: Vec<[f64; 3]> =
            body_cur.iter().map(|p| [p[0], p[1], p[2] - 0.02]).collect();
        body_prev[2][2] = 4.5;
        let body_next: Vec<[f64; 3]> = body_cur.iter().map(|p| [p[0], p[1], p[2] + 0.02]).collect();
        let faces = [[0u32, 1, 2]];
        let config = HoodConfig::new().with_relative_velocity(true);
        let build = |shift: [f64; 3], config: &HoodConfig| {
            // Every position moved by `shift` per frame: t - 1 by nothing, t by one
            // shift, t + 1 by two.
            let at = |p: &[[f64; 3]], k: f64| -> Vec<[f64; 3]> {
                p.iter()
                    .map(|p| std::array::from_fn(|i| p[i] + k * shift[i]))
                    .collect()
            };
            StepGraph::build(
                &garment,
                &GarmentStep {
                    prev: &at(&prev, 0.0),
                    cur: &at(&cur, 1.0),
                    pin_targets: &at(&cur, 2.0),
                    buttoned: false,
                },
                &BodyStep {
                    prev: &at(&body_prev, 0.0),
                    cur: &at(&body_cur, 1.0),
                    next: &at(&body_next, 2.0),
                    faces: &faces,
                    omit: &[],
                },
                1.0 / 30.0,
                config,
            )
            .unwrap()
        };
        let still = build([0.0; 3], &config);
        let moving = build([0.1, 0.0, -0.05], &config);
        assert_eq!(still.nodes.len(), moving.nodes.len());
        for (a, b) in still.nodes.iter().zip(&moving.nodes) {
            assert!((a - b).abs() < 1e-6, "{a} against {b}");
        }
        // Vertex 12 moved 1 cm up while the body moved 2 cm along z.
        let w = StepGraph::node_width(2);
        let v = &still.nodes[12 * w..12 * w + 3];
        assert!(
            (v[1] - 0.01).abs() < 1e-6 && (v[2] + 0.02).abs() < 1e-6,
            "{v:?}"
        );
        // In the world frame (HOOD's), the uniform motion shows.
        let world = build([0.1, 0.0, -0.05], &HoodConfig::new());
        assert!((world.nodes[12 * w] - 0.1).abs() < 1e-6);
    }
}
