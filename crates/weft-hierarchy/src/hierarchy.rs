//! Multilevel graphs: structure-preserving pooling applied recursively, with the
//! unpooling of every level (seed 000) and the nested view HOOD's multi-level message
//! passing uses (seed 004 §3.2: coarser node sets are subsets of finer ones, each level
//! with its own edges).

use crate::error::HierarchyError;
use crate::pooling::{pool, pool_from};
use crate::unpooling::Unpooling;
use weft_mesh::Graph;

/// One level of a [`Hierarchy`].
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    /// The level's graph over its own vertex numbering `0..n_l`.
    pub graph: Graph,
    /// For levels below the finest: indices into the previous (finer) level of the
    /// vertices kept here, ascending. Empty for level 0.
    pub kept: Vec<u32>,
    /// For levels below the finest: the centers (previous-level indices) the pooling
    /// started from, one per component. Empty for level 0.
    pub centers: Vec<u32>,
    /// For levels below the finest: unpooling from this level to the previous one.
    pub unpooling: Option<Unpooling>,
}

/// A stack of graphs from the finest (level 0, the mesh graph) to the coarsest.
#[derive(Clone, Debug, PartialEq)]
pub struct Hierarchy {
    levels: Vec<Level>,
}

impl Hierarchy {
    /// Pools `fine` recursively into `levels` levels in total (level 0 included).
    ///
    /// Pooling stops early, with fewer levels, once a level has one vertex per
    /// component: pooling it again would change nothing.
    pub fn build(fine: Graph, levels: usize) -> Result<Self, HierarchyError> {
        Self::grow(fine, levels, None)
    }

    /// [`Hierarchy::build`] from given `centers` (one per component, as
    /// [`pool_from`] takes them), carried down to every coarser level, where each stays a
    /// vertex (it is at distance 0), as HOOD's code does: the levels differ with the
    /// centre, which HOOD draws at random per training sample. [`Hierarchy::build`]
    /// instead takes each level's own first minimum-eccentricity vertex (seed 000).
    pub fn build_from_centers(
        fine: Graph,
        levels: usize,
        centers: &[u32],
    ) -> Result<Self, HierarchyError> {
        Self::grow(fine, levels, Some(centers.to_vec()))
    }

    /// Pools until `levels` levels, around `carried` centres if given.
    fn grow(
        fine: Graph,
        levels: usize,
        mut carried: Option<Vec<u32>>,
    ) -> Result<Self, HierarchyError> {
        if levels == 0 {
            return Err(HierarchyError::NoLevels);
        }
        let mut out = vec![Level {
            graph: fine,
            kept: Vec::new(),
            centers: Vec::new(),
            unpooling: None,
        }];
        while out.len() < levels {
            let finer = &out[out.len() - 1].graph;
            let p = match &carried {
                Some(centers) => pool_from(finer, centers)?,
                None => pool(finer),
            };
            if p.kept.len() == finer.vertex_count() {
                break;
            }
            if let Some(centers) = carried.as_mut() {
                for c in centers.iter_mut() {
                    *c = p.kept.binary_search(c).map_err(|_| {
                        HierarchyError::BadCenters(format!("centre {c} was not kept"))
                    })? as u32;
                }
                // Coarse components are numbered by their smallest kept vertex, which
                // can order them differently from the fine ones.
                let label = p.coarse.components().label;
                centers.sort_by_key(|&c| label[c as usize]);
            }
            let unpooling = Unpooling::new(finer, &p.kept)?;
            out.push(Level {
                graph: p.coarse,
                kept: p.kept,
                centers: p.centers,
                unpooling: Some(unpooling),
            });
        }
        Ok(Hierarchy { levels: out })
    }

    /// The levels, finest first.
    pub fn levels(&self) -> &[Level] {
        &self.levels
    }

    /// Number of levels.
    pub fn len(&self) -> usize {
        self.levels.len()
    }

    /// Always false: a hierarchy has at least its finest level.
    pub fn is_empty(&self) -> bool {
        self.levels.is_empty()
    }

    /// The level-0 index of every vertex of level `l` (nesting: `V_l ⊂ V_{l-1} ⊂ … ⊂ V_0`).
    pub fn finest_indices(&self, l: usize) -> Vec<u32> {
        let mut idx: Vec<u32> = (0..self.levels[l].graph.vertex_count() as u32).collect();
        for level in self.levels[1..=l].iter().rev() {
            for v in &mut idx {
                *v = level.kept[*v as usize];
            }
        }
        idx
    }

    /// Level `l`'s edges in level-0 numbering: HOOD's per-level edge sets over the shared
    /// level-0 node features.
    pub fn edges_in_finest(&self, l: usize) -> Vec<[u32; 2]> {
        let map = self.finest_indices(l);
        self.levels[l]
            .graph
            .edges()
            .into_iter()
            .map(|[a, b]| [map[a as usize], map[b as usize]])
            .collect()
    }

    /// For every level-0 vertex, the coarsest level it belongs to: vertex `v` is a node
    /// of levels `0..=coarsest_level()[v]`.
    pub fn coarsest_level(&self) -> Vec<u8> {
        let mut out = vec![0u8; self.levels[0].graph.vertex_count()];
        for l in 1..self.levels.len() {
            for v in self.finest_indices(l) {
                out[v as usize] = l as u8;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives::builtin_garment;

    #[test]
    fn builtin_garment_halves_twice_in_one_component() {
        let h = Hierarchy::build(builtin_garment().graph(), 3).unwrap();
        let counts: Vec<usize> = h.levels().iter().map(|l| l.graph.vertex_count()).collect();
        assert_eq!(counts[0], 4000);
        assert_eq!(counts[1], 2000);
        assert!((900..=1100).contains(&counts[2]), "{counts:?}");
        for l in h.levels() {
            assert_eq!(l.graph.components().count, 1);
        }
    }

    #[test]
    fn given_centres_stay_at_every_level_and_change_the_levels() {
        let g = builtin_garment().graph();
        let sets = weft_mesh::eccentricity::component_center_sets(&g);
        assert_eq!(sets.len(), 1);
        let first = Hierarchy::build_from_centers(g.clone(), 3, &[sets[0][0]]).unwrap();
        // The first centre at level 0 is `build`'s; `build` re-centres each coarser
        // level, so only level 1 must agree.
        let default = Hierarchy::build(g.clone(), 3).unwrap();
        assert_eq!(first.levels()[1], default.levels()[1]);
        // A vertex far from the centre: every level keeps it, and the levels differ.
        let far = 0u32;
        let h = Hierarchy::build_from_centers(g.clone(), 3, &[far]).unwrap();
        assert_eq!(h.len(), 3);
        for l in 0..3 {
            assert!(h.finest_indices(l).contains(&far), "level {l}");
        }
        assert_ne!(h.finest_indices(1), first.finest_indices(1));
        // Still nested and connected.
        let l2 = h.finest_indices(2);
        let l1 = h.finest_indices(1);
        assert!(l2.iter().all(|v| l1.binary_search(v).is_ok()));
        for l in h.levels() {
            assert_eq!(l.graph.components().count, 1);
        }
        assert!(Hierarchy::build_from_centers(g, 3, &[0, 1]).is_err());
    }

    #[test]
    fn carried_centres_follow_the_coarse_component_order() {
        // Two paths: A = 0-3-4-7-8 (smallest vertex 0) and B = 1-2-5-6-9 (smallest 1).
        // Around 4 and 1, A keeps 0, 4, 8 and B keeps 1, 5, 9: A still comes first.
        // Around 3 and 1, A keeps 3 and 7 and B keeps 1, 5, 9: on the coarse level B
        // (from fine 1) precedes A (from fine 3), and the carried centres must follow.
        let g = Graph::from_edges(
            10,
            &[
                [0, 3],
                [3, 4],
                [4, 7],
                [7, 8],
                [1, 2],
                [2, 5],
                [5, 6],
                [6, 9],
            ],
        );
        for centres in [[4, 1], [3, 1]] {
            let h = Hierarchy::build_from_centers(g.clone(), 3, &centres).unwrap();
            assert_eq!(h.len(), 3, "{centres:?}");
            for (l, level) in h.levels().iter().enumerate().skip(1) {
                // Each centre is a node of every level.
                let fine = h.finest_indices(l);
                for c in centres {
                    assert!(fine.contains(&c), "{centres:?}, level {l}");
                }
                assert_eq!(level.graph.components().count, 2);
            }
        }
    }

    #[test]
    fn nesting_maps_levels_into_the_finest() {
        let h = Hierarchy::build(builtin_garment().graph(), 3).unwrap();
        let l2 = h.finest_indices(2);
        let l1 = h.finest_indices(1);
        assert!(l2.iter().all(|v| l1.binary_search(v).is_ok()));
        let coarsest = h.coarsest_level();
        assert_eq!(coarsest.iter().filter(|&&c| c == 2).count(), l2.len());
        assert_eq!(coarsest.iter().filter(|&&c| c >= 1).count(), l1.len());
        assert_eq!(h.edges_in_finest(0), h.levels()[0].graph.edges());
    }

    #[test]
    fn stops_when_nothing_is_left_to_pool() {
        let g = Graph::from_edges(3, &[[0, 1], [1, 2]]);
        let h = Hierarchy::build(g, 10).unwrap();
        assert_eq!(h.len(), 2);
        assert_eq!(h.levels()[1].kept, vec![1]);
        assert_eq!(
            Hierarchy::build(Graph::from_edges(1, &[]), 0),
            Err(HierarchyError::NoLevels)
        );
    }
}
