//! A static bounding-volume hierarchy of axis-aligned boxes (an AABB tree), the spatial
//! index under every body query: closest point, signed distance, points within a radius.
//!
//! Why our own tree and not parry3d: the queries the systems need are few (nearest
//! primitive, primitives within a ball) and parry3d would pull a large dependency tree
//! into a geometry crate that is meant to build in seconds. This one is ~200 lines.
//!
//! Layout. Nodes live in one `Vec`; node 0 is the root; an internal node's two children
//! are stored next to each other and always after their parent, so a reverse sweep over
//! the nodes visits children before parents, which is all a refit needs. Leaves own a
//! contiguous range of a permutation of the primitive indices (at most [`LEAF_SIZE`]).
//!
//! Build: top-down median split on the longest axis of the primitive centroids
//! (`O(n log n)`, depth `⌈log2(n / LEAF_SIZE)⌉ + 1`). Median splits keep the tree balanced
//! whatever the input, which matters more here than the slightly tighter trees of a
//! surface-area heuristic: a posed body moves every frame, and a balanced topology stays
//! good under [`AabbTree::refit`].
//!
//! Refit vs rebuild: when the primitives move but keep their identity (a posed body with
//! fixed faces), [`AabbTree::refit`] recomputes the boxes bottom-up in `O(n)` and keeps
//! the topology; boxes may then overlap more than a fresh build's, so queries slow down
//! a little for large motions. Rebuild from the rest pose's tree once in a while, or
//! every frame when speed of the queries matters more than that of the update (see the
//! benchmark in `benches/queries.rs`).

use weft_mesh::Aabb;

/// Most primitives per leaf.
pub const LEAF_SIZE: usize = 8;

/// Traversal stack size: above the largest possible depth of a median-split tree over
/// `u32`-indexed primitives (33), with room to spare.
const STACK: usize = 64;

/// One node: its box, and either its children (`count == 0`: children at `first` and
/// `first + 1`) or its primitives (`order[first..first + count]`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    bounds: Aabb,
    first: u32,
    count: u32,
}

/// A static AABB tree over `n` primitives given by their boxes.
#[derive(Clone, Debug, PartialEq)]
pub struct AabbTree {
    nodes: Vec<Node>,
    order: Vec<u32>,
    /// `leaf_boxes[k]` is the box of primitive `order[k]`: leaves test each primitive's
    /// own box before the caller's exact (and dearer) distance.
    leaf_boxes: Vec<Aabb>,
}

/// The empty box (contains nothing; the identity of [`union`]).
const EMPTY: Aabb = Aabb {
    min: [f64::INFINITY; 3],
    max: [f64::NEG_INFINITY; 3],
};

#[inline]
fn union(a: Aabb, b: Aabb) -> Aabb {
    Aabb {
        min: std::array::from_fn(|k| a.min[k].min(b.min[k])),
        max: std::array::from_fn(|k| a.max[k].max(b.max[k])),
    }
}

/// Squared distance from `p` to the box (zero inside).
#[inline]
pub(crate) fn box_distance_sq(b: &Aabb, p: [f64; 3]) -> f64 {
    let mut d = 0.0;
    for ((&lo, &hi), &x) in b.min.iter().zip(&b.max).zip(&p) {
        let e = (lo - x).max(x - hi).max(0.0);
        d += e * e;
    }
    d
}

impl AabbTree {
    /// A tree over the primitives whose boxes are `boxes` (primitive `i` has box
    /// `boxes[i]`). An empty slice gives an empty tree, which every query answers with
    /// nothing. Boxes must be finite (the callers in this module check positions).
    pub fn build(boxes: &[Aabb]) -> Self {
        let n = boxes.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        if n == 0 {
            return AabbTree {
                nodes: Vec::new(),
                order,
                leaf_boxes: Vec::new(),
            };
        }
        let centroid: Vec<[f64; 3]> = boxes
            .iter()
            .map(|b| std::array::from_fn(|k| 0.5 * (b.min[k] + b.max[k])))
            .collect();
        let mut nodes = Vec::with_capacity(2 * n / LEAF_SIZE + 1);
        nodes.push(Node {
            bounds: EMPTY,
            first: 0,
            count: n as u32,
        });
        // (node, lo, hi) ranges of `order` still to split.
        let mut todo = vec![(0usize, 0usize, n)];
        while let Some((node, lo, hi)) = todo.pop() {
            if hi - lo <= LEAF_SIZE {
                nodes[node].first = lo as u32;
                nodes[node].count = (hi - lo) as u32;
                continue;
            }
            let mut cmin = [f64::INFINITY; 3];
            let mut cmax = [f64::NEG_INFINITY; 3];
            for &i in &order[lo..hi] {
                let c = centroid[i as usize];
                for k in 0..3 {
                    cmin[k] = cmin[k].min(c[k]);
                    cmax[k] = cmax[k].max(c[k]);
                }
            }
            let extent: [f64; 3] = std::array::from_fn(|k| cmax[k] - cmin[k]);
            let axis = if extent[0] >= extent[1] && extent[0] >= extent[2] {
                0
            } else if extent[1] >= extent[2] {
                1
            } else {
                2
            };
            let mid = lo + (hi - lo) / 2;
            order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
                centroid[a as usize][axis]
                    .total_cmp(&centroid[b as usize][axis])
                    .then(a.cmp(&b))
            });
            let left = nodes.len();
            let child = Node {
                bounds: EMPTY,
                first: 0,
                count: 0,
            };
            nodes.push(child);
            nodes.push(child);
            nodes[node].first = left as u32;
            nodes[node].count = 0;
            todo.push((left + 1, mid, hi));
            todo.push((left, lo, mid));
        }
        let mut tree = AabbTree {
            nodes,
            order,
            leaf_boxes: Vec::new(),
        };
        tree.refit_unchecked(boxes);
        tree
    }

    /// Recomputes every box from the primitives' new boxes, keeping the topology.
    ///
    /// `boxes` must hold one box per primitive, as at build time; returns `false` and
    /// leaves the tree untouched when the length differs.
    pub fn refit(&mut self, boxes: &[Aabb]) -> bool {
        if boxes.len() != self.order.len() {
            return false;
        }
        self.refit_unchecked(boxes);
        true
    }

    fn refit_unchecked(&mut self, boxes: &[Aabb]) {
        self.leaf_boxes.clear();
        self.leaf_boxes
            .extend(self.order.iter().map(|&p| boxes[p as usize]));
        for i in (0..self.nodes.len()).rev() {
            let Node { first, count, .. } = self.nodes[i];
            let (first, count) = (first as usize, count as usize);
            self.nodes[i].bounds = if count == 0 {
                union(self.nodes[first].bounds, self.nodes[first + 1].bounds)
            } else {
                self.leaf_boxes[first..first + count]
                    .iter()
                    .fold(EMPTY, |acc, &b| union(acc, b))
            };
        }
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Whether the tree holds no primitive.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// The box of all primitives, `None` for an empty tree.
    pub fn bounds(&self) -> Option<Aabb> {
        self.nodes.first().map(|n| n.bounds)
    }

    /// Number of levels (1 for a single leaf, 0 when empty).
    pub fn depth(&self) -> usize {
        fn go(t: &AabbTree, i: usize) -> usize {
            let n = t.nodes[i];
            if n.count > 0 {
                1
            } else {
                1 + go(t, n.first as usize).max(go(t, n.first as usize + 1))
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            go(self, 0)
        }
    }

    /// The primitive nearest to `p` under a caller's exact distance, best-first with box
    /// pruning.
    ///
    /// `eval(prim, best_sq)` returns the squared distance from `p` to primitive `prim`
    /// and whatever the caller wants to keep about it, or `None` to skip it; `best_sq` is
    /// the best squared distance so far (for the caller's own early outs). Only
    /// candidates strictly closer than `max_sq` are considered; pass `f64::INFINITY` for
    /// no bound. Ties keep the first primitive found. Returns
    /// `(primitive, squared distance, payload)`.
    pub fn nearest<T>(
        &self,
        p: [f64; 3],
        max_sq: f64,
        mut eval: impl FnMut(u32, f64) -> Option<(f64, T)>,
    ) -> Option<(u32, f64, T)> {
        let root = self.nodes.first()?;
        let mut best: Option<(u32, f64, T)> = None;
        let mut best_sq = max_sq;
        // (node, squared distance to its box). Each pop pushes at most two, so the stack
        // never holds more than depth + 1 entries, and median splits bound the depth by
        // ⌈log2 n⌉ + 1 ≤ 33 for u32 indices: a fixed array suffices (no allocation).
        let mut stack = [(0u32, 0.0f64); STACK];
        let mut top = 0usize;
        let d0 = box_distance_sq(&root.bounds, p);
        if d0 < best_sq {
            stack[0] = (0, d0);
            top = 1;
        }
        while top > 0 {
            top -= 1;
            let (i, d) = stack[top];
            if d >= best_sq {
                continue;
            }
            let node = self.nodes[i as usize];
            if node.count > 0 {
                let (first, count) = (node.first as usize, node.count as usize);
                for k in first..first + count {
                    if box_distance_sq(&self.leaf_boxes[k], p) >= best_sq {
                        continue;
                    }
                    let prim = self.order[k];
                    if let Some((dsq, payload)) = eval(prim, best_sq) {
                        if dsq < best_sq {
                            best_sq = dsq;
                            best = Some((prim, dsq, payload));
                        }
                    }
                }
            } else {
                let (a, b) = (node.first, node.first + 1);
                let da = box_distance_sq(&self.nodes[a as usize].bounds, p);
                let db = box_distance_sq(&self.nodes[b as usize].bounds, p);
                // Push the farther child first so the nearer one is visited first.
                let (near, dn, far, df) = if da <= db {
                    (a, da, b, db)
                } else {
                    (b, db, a, da)
                };
                if df < best_sq && top < STACK {
                    stack[top] = (far, df);
                    top += 1;
                }
                if dn < best_sq && top < STACK {
                    stack[top] = (near, dn);
                    top += 1;
                }
            }
        }
        best
    }

    /// Calls `visit(prim)` for every primitive whose own box comes within `radius` of
    /// `p` (box distance `<= radius`); the caller tests the primitive itself.
    pub fn for_each_near(&self, p: [f64; 3], radius: f64, mut visit: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let r_sq = radius * radius;
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(i) = stack.pop() {
            let node = self.nodes[i as usize];
            if box_distance_sq(&node.bounds, p) > r_sq {
                continue;
            }
            if node.count > 0 {
                let (first, count) = (node.first as usize, node.count as usize);
                for k in first..first + count {
                    if box_distance_sq(&self.leaf_boxes[k], p) <= r_sq {
                        visit(self.order[k]);
                    }
                }
            } else {
                stack.push(node.first + 1);
                stack.push(node.first);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point_box(p: [f64; 3]) -> Aabb {
        Aabb { min: p, max: p }
    }

    #[test]
    fn empty_tree_answers_nothing() {
        let t = AabbTree::build(&[]);
        assert!(t.is_empty());
        assert_eq!(t.depth(), 0);
        assert!(t
            .nearest([0.0; 3], f64::INFINITY, |_, _| Some((0.0, ())))
            .is_none());
        let mut hits = 0;
        t.for_each_near([0.0; 3], 1.0, |_| hits += 1);
        assert_eq!(hits, 0);
    }

    #[test]
    fn nearest_point_on_a_line_and_refit() {
        let pts: Vec<[f64; 3]> = (0..100).map(|i| [i as f64, 0.0, 0.0]).collect();
        let boxes: Vec<Aabb> = pts.iter().map(|&p| point_box(p)).collect();
        let mut t = AabbTree::build(&boxes);
        assert_eq!(t.len(), 100);
        assert!(t.depth() <= 6, "depth {}", t.depth());
        let d = |q: [f64; 3], pts: &[[f64; 3]]| {
            t.nearest(q, f64::INFINITY, |i, _| {
                let p = pts[i as usize];
                Some(((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2), ()))
            })
            .map(|(i, _, _)| i)
        };
        assert_eq!(d([41.2, 3.0, 0.0], &pts), Some(41));
        // Move every point; the refit tree must still find the right one.
        let moved: Vec<[f64; 3]> = pts.iter().map(|p| [-p[0], 5.0, 0.0]).collect();
        let boxes: Vec<Aabb> = moved.iter().map(|&p| point_box(p)).collect();
        assert!(t.refit(&boxes));
        let q = [-41.2, 5.0, 0.0];
        let got = t
            .nearest(q, f64::INFINITY, |i, _| {
                let p = moved[i as usize];
                Some(((p[0] - q[0]).powi(2), ()))
            })
            .map(|(i, _, _)| i);
        assert_eq!(got, Some(41));
        assert!(!t.refit(&boxes[..3]));
    }

    #[test]
    fn ball_visits_every_box_within_the_radius() {
        let pts: Vec<[f64; 3]> = (0..20)
            .flat_map(|i| (0..20).map(move |j| [i as f64, j as f64, 0.0]))
            .collect();
        let boxes: Vec<Aabb> = pts.iter().map(|&p| point_box(p)).collect();
        let t = AabbTree::build(&boxes);
        let mut hits = Vec::new();
        t.for_each_near([5.0, 5.0, 0.0], 1.0, |i| hits.push(i));
        hits.retain(|&i| {
            let p = pts[i as usize];
            (p[0] - 5.0).powi(2) + (p[1] - 5.0).powi(2) <= 1.0
        });
        hits.sort_unstable();
        assert_eq!(hits, vec![85, 104, 105, 106, 125]);
    }

    #[test]
    fn coincident_primitives_still_split() {
        let boxes = vec![point_box([1.0; 3]); 33];
        let t = AabbTree::build(&boxes);
        assert!(t.depth() <= 5);
        let mut hits = 0;
        t.for_each_near([1.0; 3], 0.0, |_| hits += 1);
        assert_eq!(hits, 33);
    }
}
