//! Graph eccentricity and the minimum-eccentricity vertex (the graph center) of every
//! connected component, computed exactly without one breadth-first search per vertex.
//!
//! Structure-preserving pooling (seed 000, Algorithm 1) starts from "the first vertex of
//! minimum eccentricity". The eccentricity of a vertex is the largest hop distance from it
//! to any vertex of its component. Computing all of them takes a BFS per vertex, O(n·m),
//! hours on a million-vertex mesh. Instead we keep a lower and an upper bound on every
//! eccentricity and tighten them with a few well-chosen searches, as in Takes & Kosters,
//! "Computing the eccentricity distribution of large graphs" (Algorithms 2013, 6(1)):
//! a BFS from `v` with eccentricity `e(v)` gives, for every `w` at distance `d`,
//!
//! ```text
//! max(d, e(v) - d) <= e(w) <= e(v) + d
//! ```
//!
//! Let `R` be the smallest upper bound. Once every lower bound is at least `R`, the
//! radius is exactly `R`, and the center is the first vertex (by index) whose lower bound
//! equals `R` and whose eccentricity is confirmed to be `R`.
//!
//! Cost: a handful of searches on irregular meshes and grids. Graphs with many tied
//! centers need a witness search for each of them: a rotationally symmetric open cylinder
//! has a whole ring of centers, and each needs a BFS from its antipode on a boundary ring
//! to prove it is not below the radius. `docs/benchmarks.md` records both cases.

use crate::graph::{Bfs, Graph};

/// The center of one connected component.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ComponentCenter {
    /// The first vertex (smallest index) of minimum eccentricity in the component.
    pub center: u32,
    /// The component's radius: the eccentricity of `center`.
    pub radius: u32,
    /// How many breadth-first searches the bounds needed (1 per vertex would be brute force).
    pub searches: usize,
}

/// The center of every connected component, in the order of
/// [`Graph::components`] (components numbered by their smallest vertex).
pub fn component_centers(graph: &Graph) -> Vec<ComponentCenter> {
    let components = graph.components();
    let mut bounds = Bounds::new(graph.vertex_count());
    components
        .members()
        .iter()
        .map(|members| bounds.center(graph, members))
        .collect()
}

/// Every vertex of minimum eccentricity of each component, ascending, in the order of
/// [`Graph::components`]: the centres HOOD draws from, one per training sample, as an
/// augmentation of its hierarchy (seed 004 code, `nx.center`). The first of each list is
/// [`component_centers`]' centre. Tied candidates each need their own search to be
/// confirmed, so a graph with a ring of centres (an open cylinder) costs a search per
/// ring vertex.
pub fn component_center_sets(graph: &Graph) -> Vec<Vec<u32>> {
    let components = graph.components();
    let mut bounds = Bounds::new(graph.vertex_count());
    components
        .members()
        .iter()
        .map(|members| {
            let r = bounds.center(graph, members).radius;
            // Every lower bound is now at least r: the centres are the vertices whose
            // eccentricity is exactly r, confirmed by their own search where the bounds
            // do not already meet.
            members
                .iter()
                .copied()
                .filter(|&w| {
                    if bounds.lo[w as usize] != r {
                        return false;
                    }
                    if !bounds.resolved(w) {
                        bounds.search(graph, w);
                    }
                    bounds.hi[w as usize] == r
                })
                .collect()
        })
        .collect()
}

/// Eccentricity of every vertex by one BFS per vertex: O(n·m). The reference the bounded
/// search is tested against; fine for meshes of a few thousand vertices.
pub fn eccentricities_brute_force(graph: &Graph) -> Vec<u32> {
    let mut bfs = Bfs::new(graph.vertex_count());
    (0..graph.vertex_count())
        .map(|v| bfs.run(graph, v))
        .collect()
}

/// Eccentricity bounds, shared across components so buffers are allocated once.
struct Bounds {
    lo: Vec<u32>,
    hi: Vec<u32>,
    bfs: Bfs,
}

impl Bounds {
    fn new(n: usize) -> Self {
        Bounds {
            lo: vec![0; n],
            hi: vec![u32::MAX; n],
            bfs: Bfs::new(n),
        }
    }

    /// Runs a BFS from `v` and tightens the bounds of every vertex in its component.
    fn search(&mut self, graph: &Graph, v: u32) {
        let ecc = self.bfs.run(graph, v as usize);
        for &w in &self.bfs.order {
            let w = w as usize;
            let d = self.bfs.dist[w];
            self.lo[w] = self.lo[w].max(d).max(ecc - d);
            self.hi[w] = self.hi[w].min(ecc + d);
        }
        self.lo[v as usize] = ecc;
        self.hi[v as usize] = ecc;
    }

    fn resolved(&self, w: u32) -> bool {
        self.lo[w as usize] == self.hi[w as usize]
    }

    /// The center of the component whose vertices, ascending, are `members`.
    fn center(&mut self, graph: &Graph, members: &[u32]) -> ComponentCenter {
        let mut searches = 0;
        // Start where a double sweep would: from the first vertex, which also makes every
        // upper bound finite.
        self.search(graph, members[0]);
        searches += 1;
        let mut pick_peripheral = true;
        loop {
            let r = members
                .iter()
                .map(|&w| self.hi[w as usize])
                .min()
                .unwrap_or(0);
            // A vertex whose lower bound is below `r` might still be the center (its
            // upper bound is at least `r`, so it is unresolved).
            let mut open = members.iter().copied().filter(|&w| self.lo[w as usize] < r);
            if let Some(first_open) = open.next() {
                let v = if pick_peripheral {
                    // A far vertex (largest upper bound) raises the lower bounds of the
                    // vertices across from it: the witnesses the candidates need.
                    members
                        .iter()
                        .copied()
                        .filter(|&w| !self.resolved(w))
                        .max_by_key(|&w| (self.hi[w as usize], std::cmp::Reverse(w)))
                        .unwrap_or(first_open)
                } else {
                    // The most central candidate: its search lowers every upper bound.
                    std::iter::once(first_open)
                        .chain(open)
                        .min_by_key(|&w| (self.lo[w as usize], self.hi[w as usize], w))
                        .unwrap_or(first_open)
                };
                pick_peripheral = !pick_peripheral;
                self.search(graph, v);
                searches += 1;
                continue;
            }
            // Every lower bound is >= r, so r is the radius. The center is the first
            // vertex whose eccentricity is r; unconfirmed ties need their own search.
            let first = members
                .iter()
                .copied()
                .find(|&w| self.lo[w as usize] == r)
                .expect("the vertex whose upper bound is r has lower bound r");
            if self.resolved(first) {
                return ComponentCenter {
                    center: first,
                    radius: r,
                    searches,
                };
            }
            self.search(graph, first);
            searches += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;
    use crate::primitives::{cylinder, grid};
    use proptest::prelude::*;

    /// Every minimum-eccentricity vertex of each component and the radius, by brute force.
    fn brute_center_sets_and_radii(graph: &Graph) -> Vec<(Vec<u32>, u32)> {
        let ecc = eccentricities_brute_force(graph);
        graph
            .components()
            .members()
            .iter()
            .map(|m| {
                let r = m.iter().map(|&w| ecc[w as usize]).min().unwrap();
                let set = m.iter().copied().filter(|&w| ecc[w as usize] == r);
                (set.collect(), r)
            })
            .collect()
    }

    fn brute_centers(graph: &Graph) -> Vec<(u32, u32)> {
        brute_center_sets_and_radii(graph)
            .into_iter()
            .map(|(set, r)| (set[0], r))
            .collect()
    }

    fn brute_center_sets(graph: &Graph) -> Vec<Vec<u32>> {
        brute_center_sets_and_radii(graph)
            .into_iter()
            .map(|(set, _)| set)
            .collect()
    }

    fn fast_centers(graph: &Graph) -> Vec<(u32, u32)> {
        component_centers(graph)
            .iter()
            .map(|c| (c.center, c.radius))
            .collect()
    }

    #[test]
    fn path_center_is_the_middle() {
        let edges: Vec<[u32; 2]> = (0..6).map(|i| [i, i + 1]).collect();
        let g = Graph::from_edges(7, &edges);
        assert_eq!(fast_centers(&g), vec![(3, 3)]);
        assert_eq!(component_center_sets(&g), vec![vec![3]]);
        // Even path: two centers, the first by index wins; both are in the set.
        let g = Graph::from_edges(6, &edges[..5]);
        assert_eq!(fast_centers(&g), vec![(2, 3)]);
        assert_eq!(component_center_sets(&g), vec![vec![2, 3]]);
    }

    #[test]
    fn isolated_vertices_are_their_own_centers() {
        let g = Graph::from_edges(3, &[[1, 2]]);
        assert_eq!(fast_centers(&g), vec![(0, 0), (1, 1)]);
    }

    #[test]
    fn grids_and_cylinders_match_brute_force() {
        for m in [
            grid(9, 7, 1.0),
            grid(20, 20, 1.0),
            cylinder(6, 10, 1.0, 1.0),
            cylinder(11, 16, 1.0, 1.0),
        ] {
            let g = m.graph();
            assert_eq!(fast_centers(&g), brute_centers(&g));
            let sets = component_center_sets(&g);
            assert_eq!(sets, brute_center_sets(&g));
            // The first of each set is the centre pooling uses.
            let firsts: Vec<u32> = sets.iter().map(|s| s[0]).collect();
            let centers: Vec<u32> = fast_centers(&g).iter().map(|c| c.0).collect();
            assert_eq!(firsts, centers);
        }
    }

    #[test]
    fn grid_needs_few_searches() {
        let g = grid(60, 45, 1.0).graph();
        let c = component_centers(&g);
        assert!(c[0].searches <= 12, "{} searches", c[0].searches);
    }

    /// A random mesh: a jittered-free grid with random faces dropped, so it has holes,
    /// several components and isolated vertices, and an irregular graph.
    fn random_mesh() -> impl Strategy<Value = TriMesh> {
        (
            3usize..14,
            3usize..14,
            proptest::collection::vec(any::<bool>(), 400),
        )
            .prop_map(|(nx, nz, keep)| {
                let mut m = grid(nx, nz, 1.0);
                let faces = std::mem::take(&mut m.faces);
                m.faces = faces
                    .into_iter()
                    .zip(keep.iter().cycle())
                    .filter(|(_, &k)| k)
                    .map(|(f, _)| f)
                    .collect();
                m
            })
    }

    proptest! {
        #[test]
        fn centers_match_brute_force_on_random_meshes(m in random_mesh()) {
            let g = m.graph();
            prop_assert_eq!(fast_centers(&g), brute_centers(&g));
            prop_assert_eq!(component_center_sets(&g), brute_center_sets(&g));
        }

        #[test]
        fn centers_match_brute_force_on_random_graphs(
            n in 1usize..40,
            edges in proptest::collection::vec((0u32..40, 0u32..40), 0..80),
        ) {
            let edges: Vec<[u32; 2]> = edges
                .into_iter()
                .filter(|&(a, b)| (a as usize) < n && (b as usize) < n)
                .map(|(a, b)| [a, b])
                .collect();
            let g = Graph::from_edges(n, &edges);
            prop_assert_eq!(fast_centers(&g), brute_centers(&g));
            prop_assert_eq!(component_center_sets(&g), brute_center_sets(&g));
        }
    }
}
