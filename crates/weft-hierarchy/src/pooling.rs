//! Structure-preserving pooling (seed 000 §3.3, Appendix A, Algorithm 1).
//!
//! Keep the vertices at even hop distance from the component's center, drop the odd ones,
//! and reconnect: every removed vertex joins each neighbour one hop closer to the center
//! ("from") with each neighbour one hop farther ("to"); edges between kept vertices stay.
//! Every kept vertex at distance `2k > 0` keeps a path to the center through its BFS
//! parent, so pooling never splits a component.
//!
//! The seed pools a single connected garment graph. Garments often have several
//! components (a shirt and its separate pocket), so each component gets its own center,
//! chosen by the same rule: the first vertex by index among those of minimum
//! eccentricity within the component. [`pool_from`] takes the centres from the caller
//! instead (HOOD draws one per training sample among the tied minimum-eccentricity
//! vertices, as an augmentation).

use weft_mesh::eccentricity::component_centers;
use weft_mesh::{Graph, UNREACHED};

use crate::error::HierarchyError;

/// The result of pooling a fine graph into a coarse one.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pooling {
    /// Fine indices of the kept vertices, ascending; coarse vertex `c` is `kept[c]`.
    pub kept: Vec<u32>,
    /// The coarse graph over `0..kept.len()`.
    pub coarse: Graph,
    /// Hop distance of every fine vertex from the center of its component.
    pub distance: Vec<u32>,
    /// The center (fine index) of each component, in component order.
    pub centers: Vec<u32>,
}

/// Pools `fine` by Algorithm 1, one center per connected component.
pub fn pool(fine: &Graph) -> Pooling {
    let centers: Vec<u32> = component_centers(fine).iter().map(|c| c.center).collect();
    pool_around(fine, centers)
}

/// Pools `fine` by Algorithm 1 from the given `centers`: one vertex per connected
/// component, in component order (components numbered by their smallest vertex, as
/// [`weft_mesh::eccentricity::component_center_sets`] lists them). Any vertex will do,
/// but the rule's minimum-eccentricity vertices keep the coarse graph shallowest.
pub fn pool_from(fine: &Graph, centers: &[u32]) -> Result<Pooling, HierarchyError> {
    let components = fine.components();
    if centers.len() != components.count {
        return Err(HierarchyError::BadCenters(format!(
            "expected one per connected component ({}), got {}",
            components.count,
            centers.len()
        )));
    }
    for (k, &c) in centers.iter().enumerate() {
        match components.label.get(c as usize) {
            None => {
                return Err(HierarchyError::BadCenters(format!(
                    "centre {k} is vertex {c}, but the graph has {} vertices",
                    fine.vertex_count()
                )))
            }
            Some(&label) if label as usize != k => {
                return Err(HierarchyError::BadCenters(format!(
                    "centre {k} (vertex {c}) lies in component {label}, not {k}"
                )))
            }
            Some(_) => {}
        }
    }
    Ok(pool_around(fine, centers.to_vec()))
}

/// Algorithm 1 around valid centres.
fn pool_around(fine: &Graph, centers: Vec<u32>) -> Pooling {
    let distance = multi_source_bfs(fine, &centers);
    let n = fine.vertex_count();
    let mut coarse_index = vec![u32::MAX; n];
    let mut kept = Vec::with_capacity(n / 2 + centers.len());
    for v in 0..n {
        if distance[v] % 2 == 0 {
            coarse_index[v] = kept.len() as u32;
            kept.push(v as u32);
        }
    }
    let mut edges = Vec::with_capacity(fine.edge_count());
    let mut from = Vec::new();
    let mut to = Vec::new();
    for v in 0..n {
        let d = distance[v];
        if d % 2 == 0 {
            // Fine edges between kept vertices (kept neighbours are at the same distance).
            for &u in fine.neighbors(v) {
                if (v as u32) < u && distance[u as usize] % 2 == 0 {
                    edges.push([coarse_index[v], coarse_index[u as usize]]);
                }
            }
            continue;
        }
        from.clear();
        to.clear();
        for &u in fine.neighbors(v) {
            let du = distance[u as usize];
            if du + 1 == d {
                from.push(coarse_index[u as usize]);
            } else if du == d + 1 {
                to.push(coarse_index[u as usize]);
            }
        }
        for &j in &from {
            for &k in &to {
                edges.push([j, k]);
            }
        }
    }
    Pooling {
        coarse: Graph::from_edges(kept.len(), &edges),
        kept,
        distance,
        centers,
    }
}

/// Hop distance to the nearest of `sources`; with one source per component this is the
/// distance from each vertex's own component center.
pub(crate) fn multi_source_bfs(graph: &Graph, sources: &[u32]) -> Vec<u32> {
    let mut dist = vec![UNREACHED; graph.vertex_count()];
    let mut queue = Vec::with_capacity(graph.vertex_count());
    for &s in sources {
        if dist[s as usize] == UNREACHED {
            dist[s as usize] = 0;
            queue.push(s);
        }
    }
    let mut head = 0;
    while head < queue.len() {
        let v = queue[head] as usize;
        head += 1;
        for &u in graph.neighbors(v) {
            if dist[u as usize] == UNREACHED {
                dist[u as usize] = dist[v] + 1;
                queue.push(u);
            }
        }
    }
    dist
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn given_centres_move_the_parity_and_are_checked() {
        // 0-1-2-3-4 from centre 1: kept 1 and 3, joined across 2; 0 and 4 are odd.
        let g = Graph::from_edges(5, &[[0, 1], [1, 2], [2, 3], [3, 4]]);
        let p = pool_from(&g, &[1]).unwrap();
        assert_eq!(p.kept, vec![1, 3]);
        assert_eq!(p.coarse.edges(), vec![[0, 1]]);
        // The default centre through the same path gives `pool`'s result.
        assert_eq!(pool_from(&g, &[2]).unwrap(), pool(&g));
        // Two components (0-1, 2-3-4): one centre each, in component order.
        let g = Graph::from_edges(5, &[[0, 1], [2, 3], [3, 4]]);
        assert!(pool_from(&g, &[0, 3]).is_ok());
        for bad in [&[0][..], &[3, 0], &[0, 9], &[0, 1, 3]] {
            let e = pool_from(&g, bad).unwrap_err();
            assert!(matches!(e, HierarchyError::BadCenters(_)), "{bad:?}: {e}");
        }
    }

    #[test]
    fn path_keeps_every_other_vertex_and_bridges_the_gaps() {
        // 0-1-2-3-4: center 2, kept 0, 2, 4 joined across 1 and 3.
        let g = Graph::from_edges(5, &[[0, 1], [1, 2], [2, 3], [3, 4]]);
        let p = pool(&g);
        assert_eq!(p.centers, vec![2]);
        assert_eq!(p.kept, vec![0, 2, 4]);
        assert_eq!(p.coarse.edges(), vec![[0, 1], [1, 2]]);
    }

    #[test]
    fn five_cycle_keeps_the_fine_edge_between_kept_vertices() {
        // Center 0; distances 0,1,2,2,1: kept 0, 2, 3; 2-3 is a fine edge.
        let g = Graph::from_edges(5, &[[0, 1], [1, 2], [2, 3], [3, 4], [4, 0]]);
        let p = pool(&g);
        assert_eq!(p.distance, vec![0, 1, 2, 2, 1]);
        assert_eq!(p.kept, vec![0, 2, 3]);
        assert_eq!(p.coarse.edges(), vec![[0, 1], [0, 2], [1, 2]]);
    }

    #[test]
    fn each_component_pools_around_its_own_center() {
        let g = Graph::from_edges(6, &[[0, 1], [1, 2], [3, 4], [4, 5]]);
        let p = pool(&g);
        assert_eq!(p.centers, vec![1, 4]);
        assert_eq!(p.kept, vec![1, 4]);
        assert_eq!(p.coarse.edge_count(), 0);
        assert_eq!(p.coarse.components().count, 2);
    }
}
