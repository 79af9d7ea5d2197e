//! Strain limiting (Provot 1995, "Deformation constraints in a mass-spring model to
//! describe rigid cloth behavior"): after a step, every mesh edge stretched beyond
//! `(1 + limit)` times its rest length is shortened back to that length, its two ends
//! moving in inverse proportion to their masses (a pinned end does not move), in
//! Gauss–Seidel sweeps over the edges.
//!
//! The implicit step bounds stretching through the potential's minimiser; a step that is
//! not one (a learned step, HOOD's) can stretch cloth far beyond what its material
//! allows, and an autoregressive rollout carries that stretch forward as sag. The limit
//! bounds it after the fact. Compression is left alone: cloth buckles rather than
//! shortens, and the bending energy, not a length, governs that.

use weft_mesh::vec3::{dist, sub};
use weft_mesh::TriMesh;

use crate::error::{check_len, check_nonneg, SimError};

/// A garment's edges, their rest lengths and its vertices' inverse masses.
#[derive(Clone, Debug)]
pub struct StrainLimit {
    edges: Vec<[u32; 2]>,
    rest: Vec<f64>,
    inverse_mass: Vec<f64>,
}

/// What one [`StrainLimit::apply`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrainLimited {
    /// Edges the first sweep found beyond the limit (each as it reached it).
    pub edges_over: usize,
    /// Sweeps that shortened an edge (the sweep after the last of them found none over
    /// the limit and stopped the loop, unless the sweeps asked for ran out first).
    pub sweeps: usize,
    /// The largest `l / l₀ − 1` left after the last sweep.
    pub strain_max: f64,
}

impl StrainLimit {
    /// The limiter of `rest` (the garment's rest shape) with lumped `masses` (kg, `> 0`)
    /// and `pinned` vertices, which keep their positions.
    pub fn new(rest: &TriMesh, masses: &[f64], pinned: &[bool]) -> Result<Self, SimError> {
        let n = rest.vertex_count();
        check_len("vertex masses", n, masses.len())?;
        check_len("pinned flags", n, pinned.len())?;
        for (i, &m) in masses.iter().enumerate() {
            check_nonneg(|| format!("mass of vertex {i}"), m, true)?;
        }
        let edges = rest.edges();
        let rest_len: Vec<f64> = edges
            .iter()
            .map(|&[a, b]| dist(rest.positions[a as usize], rest.positions[b as usize]))
            .collect();
        if let Some(e) = rest_len.iter().position(|&l| !(l > 0.0 && l.is_finite())) {
            let [a, b] = edges[e];
            return Err(SimError::InvalidParameter {
                what: format!("rest length of edge {a}-{b}"),
                value: rest_len[e],
                expected: "> 0 (no two vertices of an edge at the same place)",
            });
        }
        let inverse_mass = masses
            .iter()
            .zip(pinned)
            .map(|(&m, &p)| if p { 0.0 } else { 1.0 / m })
            .collect();
        Ok(StrainLimit {
            edges,
            rest: rest_len,
            inverse_mass,
        })
    }

    /// Shortens every edge of `x` longer than `(1 + limit)` rest lengths back to that
    /// length, in at most `sweeps` Gauss–Seidel sweeps over the edges (in a fixed order,
    /// so the result is deterministic). An edge shortened in one sweep can be stretched
    /// again by its neighbours' corrections in the same sweep; more sweeps converge.
    pub fn apply(
        &self,
        x: &mut [[f64; 3]],
        limit: f64,
        sweeps: usize,
    ) -> Result<StrainLimited, SimError> {
        check_len("positions", self.inverse_mass.len(), x.len())?;
        check_nonneg(|| "strain limit".into(), limit, false)?;
        let mut report = StrainLimited::default();
        for sweep in 0..sweeps {
            let mut over = 0;
            for (&[a, b], &l0) in self.edges.iter().zip(&self.rest) {
                let (a, b) = (a as usize, b as usize);
                let (wa, wb) = (self.inverse_mass[a], self.inverse_mass[b]);
                let target = (1.0 + limit) * l0;
                let d = sub(x[b], x[a]);
                let l = dist(x[a], x[b]);
                // A relative tolerance, so that an edge left at the limit by rounding
                // does not count as over it.
                if l <= target * (1.0 + 1e-9) || wa + wb == 0.0 {
                    continue;
                }
                over += 1;
                let s = (l - target) / (l * (wa + wb));
                for k in 0..3 {
                    x[a][k] += wa * s * d[k];
                    x[b][k] -= wb * s * d[k];
                }
            }
            if sweep == 0 {
                report.edges_over = over;
            }
            if over == 0 {
                break;
            }
            report.sweeps = sweep + 1;
        }
        report.strain_max = self.strains(x).fold(f64::NEG_INFINITY, f64::max);
        Ok(report)
    }

    /// `l / l₀ − 1` of every edge of `x`, in edge order.
    fn strains<'a>(&'a self, x: &'a [[f64; 3]]) -> impl Iterator<Item = f64> + 'a {
        self.edges
            .iter()
            .zip(&self.rest)
            .map(|(&[a, b], &l0)| dist(x[a as usize], x[b as usize]) / l0 - 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives::grid;

    #[test]
    fn a_stretched_sheet_comes_back_within_the_limit_and_pins_stay() {
        let rest = grid(6, 6, 0.1);
        let n = rest.vertex_count();
        let mut pinned = vec![false; n];
        pinned[0] = true;
        let limiter = StrainLimit::new(&rest, &vec![0.01; n], &pinned).unwrap();
        // 30 % longer along x, a little shear, and one vertex pulled far out.
        let mut x: Vec<[f64; 3]> = rest
            .positions
            .iter()
            .map(|p| [1.3 * p[0] + 0.05 * p[2], p[1], p[2]])
            .collect();
        x[n - 1][1] += 0.2;
        let before = limiter.strains(&x).collect::<Vec<_>>();
        assert!(before.iter().cloned().fold(0.0, f64::max) > 0.29);
        let pin = x[0];
        let report = limiter.apply(&mut x, 0.05, 200).unwrap();
        assert!(report.edges_over > 0, "{report:?}");
        // Gauss–Seidel converges, slowly where the diagonals and the pin pull against
        // each other: within a tenth of a point of the limit.
        assert!(report.strain_max <= 0.051, "{report:?}");
        assert_eq!(x[0], pin, "a pinned vertex moved");
        let after = limiter.strains(&x).collect::<Vec<_>>();
        assert_eq!(
            after.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            report.strain_max
        );
    }

    #[test]
    fn edges_within_the_limit_and_compressed_ones_are_left_alone() {
        let rest = grid(4, 4, 0.1);
        let n = rest.vertex_count();
        let limiter = StrainLimit::new(&rest, &vec![0.01; n], &vec![false; n]).unwrap();
        // 3 % longer (within a 5 % limit) along x, 20 % shorter along z.
        let mut x: Vec<[f64; 3]> = rest
            .positions
            .iter()
            .map(|p| [1.03 * p[0], p[1], 0.8 * p[2]])
            .collect();
        let before = x.clone();
        let report = limiter.apply(&mut x, 0.05, 10).unwrap();
        assert_eq!(report.edges_over, 0);
        assert_eq!(report.sweeps, 0);
        assert_eq!(x, before);
    }

    #[test]
    fn corrections_split_by_inverse_mass_so_the_centre_of_mass_stays() {
        let rest = grid(3, 3, 0.1);
        let n = rest.vertex_count();
        let masses: Vec<f64> = (0..n).map(|i| 0.01 * (1.0 + i as f64)).collect();
        let limiter = StrainLimit::new(&rest, &masses, &vec![false; n]).unwrap();
        let mut x: Vec<[f64; 3]> = rest
            .positions
            .iter()
            .map(|p| [1.5 * p[0], p[1], p[2]])
            .collect();
        let centre = |x: &[[f64; 3]]| -> [f64; 3] {
            std::array::from_fn(|k| x.iter().zip(&masses).map(|(p, m)| m * p[k]).sum::<f64>())
        };
        let before = centre(&x);
        let report = limiter.apply(&mut x, 0.1, 50).unwrap();
        assert!(report.edges_over > 0);
        let after = centre(&x);
        for k in 0..3 {
            assert!(
                (after[k] - before[k]).abs() < 1e-12,
                "{before:?} -> {after:?}"
            );
        }
    }

    #[test]
    fn bad_inputs_are_refused_by_name() {
        let rest = grid(2, 2, 0.1);
        let n = rest.vertex_count();
        let err = StrainLimit::new(&rest, &vec![0.01; n - 1], &vec![false; n]).unwrap_err();
        assert!(err.to_string().contains("vertex masses"), "{err}");
        let mut masses = vec![0.01; n];
        masses[3] = 0.0;
        let err = StrainLimit::new(&rest, &masses, &vec![false; n]).unwrap_err();
        assert!(err.to_string().contains("mass of vertex 3"), "{err}");
        let limiter = StrainLimit::new(&rest, &vec![0.01; n], &vec![false; n]).unwrap();
        let mut x = rest.positions.clone();
        let err = limiter.apply(&mut x, f64::NAN, 3).unwrap_err();
        assert!(err.to_string().contains("strain limit"), "{err}");
        let err = limiter.apply(&mut x[..n - 1], 0.1, 3).unwrap_err();
        assert!(err.to_string().contains("positions"), "{err}");
    }
}
