//! Structure-preserving unpooling (seed 000 Appendix A, Algorithm 2) as a sparse
//! fine × coarse matrix whose rows sum to one.
//!
//! A kept vertex takes its coarse value unchanged. A removed vertex `i` takes a weighted
//! mean of its kept fine-graph neighbours `j`: `ŵ_ij = 1 / |N_j^r|`, where `N_j^r` is the
//! set of removed neighbours of `j`, normalised over `j` to `w_ij`. So a kept vertex that
//! borders many removed vertices spreads its value more thinly, which is what removes the
//! "wave-like artifacts" of copying the pre-pooling features (seed 000 Fig. 2).
//!
//! Reading of the seed: Algorithm 2 writes the denominator as a sum over `N_i^{r0}`, the
//! removed neighbours of `i` itself, which is zero whenever no removed neighbour of `i`
//! touches `j`; we read it as the removed-neighbour count of `j`, the only reading that is
//! always defined.
//!
//! A removed vertex with no kept neighbour cannot come out of [`crate::pool`] (each odd
//! vertex has a "from" neighbour one hop closer to the center). For kept sets from
//! elsewhere it is defined: the vertex takes the plain mean of the kept vertices nearest
//! to it in hops, and a component with no kept vertex at all is an error.

use crate::error::HierarchyError;
use weft_mesh::Graph;

/// Sparse unpooling matrix in CSR form: row `i` (a fine vertex) lists coarse columns and
/// weights that sum to one.
#[derive(Clone, Debug, PartialEq)]
pub struct Unpooling {
    offsets: Vec<usize>,
    columns: Vec<u32>,
    weights: Vec<f64>,
    coarse_count: usize,
}

impl Unpooling {
    /// The unpooling from the coarse graph made of `kept` (ascending fine indices) back
    /// to `fine`.
    pub fn new(fine: &Graph, kept: &[u32]) -> Result<Self, HierarchyError> {
        let n = fine.vertex_count();
        let mut coarse_index = vec![u32::MAX; n];
        for (c, &v) in kept.iter().enumerate() {
            coarse_index[v as usize] = c as u32;
        }
        let is_kept = |v: u32| coarse_index[v as usize] != u32::MAX;
        // |N_j^r| for every kept j.
        let removed_neighbours: Vec<u32> = kept
            .iter()
            .map(|&j| {
                fine.neighbors(j as usize)
                    .iter()
                    .filter(|&&u| !is_kept(u))
                    .count() as u32
            })
            .collect();
        let mut offsets = Vec::with_capacity(n + 1);
        let mut columns = Vec::with_capacity(n * 2);
        let mut weights = Vec::with_capacity(n * 2);
        offsets.push(0);
        for i in 0..n {
            if is_kept(i as u32) {
                columns.push(coarse_index[i]);
                weights.push(1.0);
            } else {
                let start = columns.len();
                for &j in fine.neighbors(i) {
                    let c = coarse_index[j as usize];
                    if c != u32::MAX {
                        columns.push(c);
                        weights.push(1.0 / f64::from(removed_neighbours[c as usize]));
                    }
                }
                if columns.len() == start {
                    for c in nearest_kept(fine, i, &coarse_index)? {
                        columns.push(c);
                        weights.push(1.0);
                    }
                }
                let total: f64 = weights[start..].iter().sum();
                weights[start..].iter_mut().for_each(|w| *w /= total);
            }
            offsets.push(columns.len());
        }
        Ok(Unpooling {
            offsets,
            columns,
            weights,
            coarse_count: kept.len(),
        })
    }

    /// Number of rows (fine vertices).
    pub fn fine_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of columns (coarse vertices).
    pub fn coarse_count(&self) -> usize {
        self.coarse_count
    }

    /// Coarse columns and weights of fine vertex `i`.
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let r = self.offsets[i]..self.offsets[i + 1];
        (&self.columns[r.clone()], &self.weights[r])
    }

    /// Every non-zero as `(fine row, coarse column, weight)`, row by row: the COO form
    /// network layers build their sparse products from.
    pub fn triplets(&self) -> impl Iterator<Item = (u32, u32, f64)> + '_ {
        (0..self.fine_count()).flat_map(move |i| {
            let (cols, ws) = self.row(i);
            cols.iter().zip(ws).map(move |(&c, &w)| (i as u32, c, w))
        })
    }

    /// Unpools row-major coarse features (`coarse_count × channels`) to the fine graph.
    ///
    /// # Panics
    /// If `coarse.len() != coarse_count * channels`.
    pub fn apply(&self, coarse: &[f64], channels: usize) -> Vec<f64> {
        assert_eq!(
            coarse.len(),
            self.coarse_count * channels,
            "coarse feature shape"
        );
        let mut fine = vec![0.0; self.fine_count() * channels];
        for (i, out) in fine.chunks_exact_mut(channels.max(1)).enumerate() {
            let (cols, ws) = self.row(i);
            for (&c, &w) in cols.iter().zip(ws) {
                let src = &coarse[c as usize * channels..(c as usize + 1) * channels];
                for (o, s) in out.iter_mut().zip(src) {
                    *o += w * s;
                }
            }
        }
        fine
    }
}

/// Coarse indices of the kept vertices nearest to `start` in hops (all ties).
fn nearest_kept(
    fine: &Graph,
    start: usize,
    coarse_index: &[u32],
) -> Result<Vec<u32>, HierarchyError> {
    let mut seen = std::collections::HashSet::from([start as u32]);
    let mut frontier = vec![start as u32];
    while !frontier.is_empty() {
        let mut next = Vec::new();
        let mut found = Vec::new();
        for &v in &frontier {
            for &u in fine.neighbors(v as usize) {
                if seen.insert(u) {
                    match coarse_index[u as usize] {
                        u32::MAX => next.push(u),
                        c => found.push(c),
                    }
                }
            }
        }
        if !found.is_empty() {
            found.sort_unstable();
            return Ok(found);
        }
        frontier = next;
    }
    Err(HierarchyError::NoKeptVertex { vertex: start })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_unpooling_averages_the_two_neighbours() {
        let g = Graph::from_edges(5, &[[0, 1], [1, 2], [2, 3], [3, 4]]);
        let u = Unpooling::new(&g, &[0, 2, 4]).unwrap();
        // Vertex 2 borders two removed vertices, 0 and 4 only one: ŵ = 1, 1/2 → 2/3, 1/3.
        let (cols, ws) = u.row(1);
        assert_eq!(cols, &[0, 1]);
        assert!((ws[0] - 2.0 / 3.0).abs() < 1e-12 && (ws[1] - 1.0 / 3.0).abs() < 1e-12);
        let fine = u.apply(&[0.0, 3.0, 6.0], 1);
        assert_eq!(fine[0], 0.0);
        assert_eq!(fine[2], 3.0);
        assert!((fine[1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn removed_vertex_without_kept_neighbour_takes_the_nearest_kept_mean() {
        // 0-1-2-3 with only 0 kept... and a branch 3-4 where 4 is kept: vertex 2 has no
        // kept neighbour; 0 and 4 are both two hops away.
        let g = Graph::from_edges(5, &[[0, 1], [1, 2], [2, 3], [3, 4]]);
        let u = Unpooling::new(&g, &[0, 4]).unwrap();
        assert_eq!(u.row(2), (&[0u32, 1][..], &[0.5, 0.5][..]));
        let fine = u.apply(&[2.0, 4.0], 1);
        assert_eq!(fine, vec![2.0, 2.0, 3.0, 4.0, 4.0]);
    }

    #[test]
    fn component_without_kept_vertex_is_an_error() {
        let g = Graph::from_edges(4, &[[0, 1], [2, 3]]);
        let err = Unpooling::new(&g, &[0]).unwrap_err();
        assert!(
            matches!(err, HierarchyError::NoKeptVertex { vertex: 2 }),
            "{err}"
        );
    }
}
