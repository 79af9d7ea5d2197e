//! Strain limiting (Provot 1995, "Deformation constraints in a mass-spring model to
//! describe rigid cloth behavior"): after a step, every mesh edge stretched beyond
//! `(1 + stretch)` times its rest length is shortened back to that length, and, when
//! asked, every edge shorter than `(1 − compression)` rest lengths is lengthened to it,
//! its two ends moving in inverse proportion to their masses (a pinned end does not
//! move), in Gauss–Seidel sweeps over the edges.
//!
//! The implicit step bounds stretching through the potential's minimiser; a step that is
//! not one (a learned step, HOOD's) can stretch cloth far beyond what its material
//! allows, and an autoregressive rollout carries that stretch forward as sag. The limit
//! bounds it after the fact. A learned step also shortens edges, a vertex-to-vertex
//! jitter of a few millimetres (docs/hood.md item 10) where cloth, which hardly
//! shortens, would buckle out of its plane; the compression bound turns that into
//! buckling as position-based cloth does, its edges held near their rest length both
//! ways (Müller et al. 2007).
//!
//! Button pairs ([`StrainLimit::with_buttons`]) are held together in the same sweeps, as
//! edges of rest length zero: the simulator's buttons are zero-length springs as stiff as
//! the fabric (crate::buttons), so a projection that bounds the fabric's stretch closes
//! them too, and the cloth around a button follows it within the same sweeps.

use weft_mesh::vec3::{dist, sub};
use weft_mesh::TriMesh;

use crate::error::{check_len, check_nonneg, SimError};

/// A garment's edges, their rest lengths, its button pairs and its vertices' inverse
/// masses.
#[derive(Clone, Debug)]
pub struct StrainLimit {
    edges: Vec<[u32; 2]>,
    rest: Vec<f64>,
    buttons: Vec<[u32; 2]>,
    inverse_mass: Vec<f64>,
}

/// The gap (m) under which a button pair counts as closed: a pair closed in one sweep
/// and left a rounding error apart does not keep the sweeps going.
const BUTTON_CLOSED: f64 = 1e-6;

/// How far an edge may stretch and shorten, as fractions of its rest length (`None`:
/// unbounded that way).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrainBounds {
    /// Longest: `(1 + stretch)` rest lengths (`>= 0`).
    pub stretch: Option<f64>,
    /// Shortest: `(1 − compression)` rest lengths (in `[0, 1)`).
    pub compression: Option<f64>,
}

impl StrainBounds {
    /// Stretch bounded, compression left alone (Provot's limit).
    pub fn stretch(limit: f64) -> Self {
        StrainBounds {
            stretch: Some(limit),
            compression: None,
        }
    }

    /// Whether either way is bounded.
    pub fn any(&self) -> bool {
        self.stretch.is_some() || self.compression.is_some()
    }
}

/// What one [`StrainLimit::apply`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrainLimited {
    /// Edges the first sweep found outside the bounds (each as it reached it).
    pub edges_outside: usize,
    /// Sweeps that corrected an edge (the sweep after the last of them found none
    /// outside the bounds and stopped the loop, unless the sweeps asked for ran out
    /// first).
    pub sweeps: usize,
    /// The largest `l / l₀ − 1` left after the last sweep.
    pub strain_max: f64,
    /// The smallest `l / l₀ − 1` left after the last sweep.
    pub strain_min: f64,
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
            buttons: Vec::new(),
            inverse_mass,
        })
    }

    /// This limiter with `pairs` of vertices buttoned: each pair is brought together
    /// (to the inverse-mass-weighted point between them) in every sweep, whatever the
    /// bounds. Errors on a pair out of range or a vertex paired with itself.
    pub fn with_buttons(&self, pairs: &[[u32; 2]]) -> Result<Self, SimError> {
        crate::buttons::check_pairs(pairs, self.inverse_mass.len())?;
        Ok(StrainLimit {
            buttons: pairs.to_vec(),
            ..self.clone()
        })
    }

    /// Brings every edge of `x` longer than `(1 + stretch)` or shorter than
    /// `(1 − compression)` rest lengths back to that length, in at most `sweeps`
    /// Gauss–Seidel sweeps over the edges (in a fixed order, so the result is
    /// deterministic), and closes every button pair after the edges of each sweep. An
    /// edge corrected in one sweep can be pushed out of its bounds again by its
    /// neighbours' corrections in the same sweep; more sweeps converge. Button pairs
    /// count among the edges corrected.
    pub fn apply(
        &self,
        x: &mut [[f64; 3]],
        bounds: StrainBounds,
        sweeps: usize,
    ) -> Result<StrainLimited, SimError> {
        check_len("positions", self.inverse_mass.len(), x.len())?;
        if let Some(limit) = bounds.stretch {
            check_nonneg(|| "strain limit".into(), limit, false)?;
        }
        if let Some(limit) = bounds.compression {
            if !(limit.is_finite() && (0.0..1.0).contains(&limit)) {
                return Err(SimError::InvalidParameter {
                    what: "compression limit".into(),
                    value: limit,
                    expected: "a fraction of the rest length in [0, 1)",
                });
            }
        }
        let longest = bounds.stretch.map_or(f64::INFINITY, |s| 1.0 + s);
        let shortest = bounds.compression.map_or(0.0, |c| 1.0 - c);
        let mut report = StrainLimited::default();
        for sweep in 0..sweeps {
            let mut over = 0;
            for (&[a, b], &l0) in self.edges.iter().zip(&self.rest) {
                let (a, b) = (a as usize, b as usize);
                let (wa, wb) = (self.inverse_mass[a], self.inverse_mass[b]);
                let d = sub(x[b], x[a]);
                let l = dist(x[a], x[b]);
                // A relative tolerance, so that an edge left at a bound by rounding does
                // not count as outside it. An edge of length zero has no direction to
                // lengthen along.
                let target = if l > longest * l0 * (1.0 + 1e-9) {
                    longest * l0
                } else if l < shortest * l0 * (1.0 - 1e-9) && l > 0.0 {
                    shortest * l0
                } else {
                    continue;
                };
                if wa + wb == 0.0 {
                    continue;
                }
                over += 1;
                let s = (l - target) / (l * (wa + wb));
                for k in 0..3 {
                    x[a][k] += wa * s * d[k];
                    x[b][k] -= wb * s * d[k];
                }
            }
            for &[a, b] in &self.buttons {
                let (a, b) = (a as usize, b as usize);
                let (wa, wb) = (self.inverse_mass[a], self.inverse_mass[b]);
                if wa + wb == 0.0 || dist(x[a], x[b]) <= BUTTON_CLOSED {
                    continue;
                }
                over += 1;
                let d = sub(x[b], x[a]);
                let s = 1.0 / (wa + wb);
                for k in 0..3 {
                    x[a][k] += wa * s * d[k];
                    x[b][k] -= wb * s * d[k];
                }
            }
            if sweep == 0 {
                report.edges_outside = over;
            }
            if over == 0 {
                break;
            }
            report.sweeps = sweep + 1;
        }
        (report.strain_min, report.strain_max) = self
            .strains(x)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
                (lo.min(s), hi.max(s))
            });
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
        let report = limiter
            .apply(&mut x, StrainBounds::stretch(0.05), 200)
            .unwrap();
        assert!(report.edges_outside > 0, "{report:?}");
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
        let report = limiter
            .apply(&mut x, StrainBounds::stretch(0.05), 10)
            .unwrap();
        assert_eq!(report.edges_outside, 0);
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
        let report = limiter
            .apply(&mut x, StrainBounds::stretch(0.1), 50)
            .unwrap();
        assert!(report.edges_outside > 0);
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
        let err = limiter
            .apply(&mut x, StrainBounds::stretch(f64::NAN), 3)
            .unwrap_err();
        assert!(err.to_string().contains("strain limit"), "{err}");
        let err = limiter
            .apply(&mut x[..n - 1], StrainBounds::stretch(0.1), 3)
            .unwrap_err();
        assert!(err.to_string().contains("positions"), "{err}");
        for bad in [1.0, -0.1, f64::NAN] {
            let bounds = StrainBounds {
                stretch: None,
                compression: Some(bad),
            };
            let err = limiter.apply(&mut x, bounds, 3).unwrap_err();
            assert!(err.to_string().contains("compression limit"), "{err}");
        }
    }

    #[test]
    fn button_pairs_close_where_their_masses_put_them_and_the_sheet_follows() {
        // A strip bent into a ring with a 60° slit, its two ends buttoned together:
        // the ends meet (each moving in inverse proportion to its mass), the edges stay
        // within the bounds, and without buttons nothing moves.
        let (nx, nz) = (13, 2);
        let rest = grid(nx, nz, 0.05);
        let n = rest.vertex_count();
        let masses: Vec<f64> = (0..n)
            .map(|i| if i % nx == 0 { 0.03 } else { 0.01 })
            .collect();
        let plain = StrainLimit::new(&rest, &masses, &vec![false; n]).unwrap();
        let pairs: Vec<[u32; 2]> = (0..nz as u32)
            .map(|r| [r * nx as u32, r * nx as u32 + nx as u32 - 1])
            .collect();
        let buttoned = plain.with_buttons(&pairs).unwrap();
        let bounds = StrainBounds {
            stretch: Some(0.05),
            compression: Some(0.05),
        };
        let length = (nx - 1) as f64 * 0.05;
        let radius = length / (2.0 * std::f64::consts::PI) * 6.0 / 5.0;
        let start: Vec<[f64; 3]> = rest
            .positions
            .iter()
            .map(|p| {
                let a = p[0] / radius;
                [radius * a.sin(), radius * (1.0 - a.cos()), p[2]]
            })
            .collect();
        let mut x = start.clone();
        let report = plain.apply(&mut x, bounds, 50).unwrap();
        assert_eq!((report.edges_outside, x == start), (0, true));
        let report = buttoned.apply(&mut x, bounds, 2000).unwrap();
        assert!(report.edges_outside >= pairs.len(), "{report:?}");
        for &[a, b] in &pairs {
            let gap = dist(x[a as usize], x[b as usize]);
            assert!(gap < 0.01, "pair {a}-{b} still {gap} m apart");
        }
        assert!(report.strain_max <= 0.06, "{report:?}");
        // The heavier end moved a third as far as the lighter one.
        let moved = |i: usize| dist(x[i], start[i]);
        let (heavy, light) = (moved(0), moved(nx - 1));
        assert!(
            heavy < 0.6 * light,
            "heavy end {heavy} m, light end {light} m"
        );
        let err = plain.with_buttons(&[[0, n as u32]]).unwrap_err();
        assert!(err.to_string().contains("button"), "{err}");
    }

    #[test]
    fn a_sheet_compressed_between_pins_buckles_out_of_its_plane() {
        // A strip pinned along both short sides, its pins 20 % nearer than at rest, with
        // a millimetre of out-of-plane jitter: the stretch limit leaves it compressed;
        // the compression bound lifts it out of the plane, as cloth buckles (into waves
        // as short as the jitter: no bending energy here picks one arch).
        let (nx, nz) = (9, 3);
        let rest = grid(nx, nz, 0.05);
        let n = rest.vertex_count();
        let pinned: Vec<bool> = (0..n).map(|i| i % nx == 0 || i % nx == nx - 1).collect();
        let limiter = StrainLimit::new(&rest, &vec![0.01; n], &pinned).unwrap();
        let start: Vec<[f64; 3]> = rest
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| [0.8 * p[0], 1e-3 * (((i % nx) * 7 % 5) as f64 - 2.0), p[2]])
            .collect();
        let mut x = start.clone();
        let stretch_only = limiter
            .apply(&mut x, StrainBounds::stretch(0.05), 200)
            .unwrap();
        assert_eq!(stretch_only.edges_outside, 0, "{stretch_only:?}");
        assert!(stretch_only.strain_min < -0.19, "{stretch_only:?}");
        let bounds = StrainBounds {
            stretch: Some(0.05),
            compression: Some(0.05),
        };
        let report = limiter.apply(&mut x, bounds, 500).unwrap();
        assert!(report.edges_outside > 0, "{report:?}");
        assert!(report.strain_min >= -0.06, "{report:?}");
        assert!(report.strain_max <= 0.06, "{report:?}");
        for i in (0..n).filter(|&i| pinned[i]) {
            assert_eq!(x[i], start[i], "pinned vertex {i} moved");
        }
        let rise = x.iter().map(|p| p[1].abs()).fold(0.0, f64::max);
        assert!(rise > 0.01, "the strip rose {rise} m out of its plane");
    }
}
