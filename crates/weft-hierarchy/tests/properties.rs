//! Property tests of the hierarchy on random meshes: jittered grids and cylinders with
//! random faces removed, so they have holes, several components and isolated vertices.

use proptest::prelude::*;
use weft_hierarchy::Hierarchy;
use weft_mesh::eccentricity::eccentricities_brute_force;
use weft_mesh::primitives::{cylinder, grid};
use weft_mesh::{Graph, TriMesh};

fn random_mesh() -> impl Strategy<Value = TriMesh> {
    (
        any::<bool>(),
        3usize..16,
        3usize..16,
        proptest::collection::vec(0u8..10, 1..64),
    )
        .prop_map(|(tube, a, b, keep)| {
            let mut m = if tube {
                cylinder(a, b, 1.0, 0.3)
            } else {
                grid(a, b, 0.1)
            };
            // Drop about one face in ten, in a pattern drawn by proptest.
            let faces = std::mem::take(&mut m.faces);
            m.faces = faces
                .into_iter()
                .zip(keep.iter().cycle())
                .filter(|(_, &k)| k != 0)
                .map(|(f, _)| f)
                .collect();
            m
        })
}

/// The first minimum-eccentricity vertex of every component, by brute force.
fn brute_centers(g: &Graph) -> Vec<u32> {
    let ecc = eccentricities_brute_force(g);
    g.components()
        .members()
        .iter()
        .map(|m| *m.iter().min_by_key(|&&v| (ecc[v as usize], v)).unwrap())
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn pooling_follows_algorithm_1(m in random_mesh(), levels in 2usize..5) {
        let h = Hierarchy::build(m.graph(), levels).unwrap();
        for l in 1..h.len() {
            let fine = &h.levels()[l - 1].graph;
            let level = &h.levels()[l];
            // Centers: the first minimum-eccentricity vertex of each component.
            prop_assert_eq!(&level.centers, &brute_centers(fine));
            // Kept set = even hop distance from the component's center.
            let mut dist = vec![u32::MAX; fine.vertex_count()];
            for &c in &level.centers {
                for (v, d) in fine.bfs_distances(c as usize).into_iter().enumerate() {
                    if d != u32::MAX {
                        dist[v] = d;
                    }
                }
            }
            let even: Vec<u32> = (0..fine.vertex_count() as u32)
                .filter(|&v| dist[v as usize] % 2 == 0)
                .collect();
            prop_assert_eq!(&level.kept, &even);
            // Pooling never splits or merges components.
            prop_assert_eq!(level.graph.components().count, fine.components().count);
            // Coarse edges join kept vertices one or two fine hops apart.
            for [a, b] in level.graph.edges() {
                let (fa, fb) = (level.kept[a as usize], level.kept[b as usize]);
                let d = fine.bfs_distances(fa as usize)[fb as usize];
                prop_assert!(d == 1 || d == 2, "coarse edge {fa}-{fb} spans {d} fine hops");
            }
        }
    }

    #[test]
    fn levels_are_nested(m in random_mesh()) {
        let h = Hierarchy::build(m.graph(), 4).unwrap();
        let coarsest = h.coarsest_level();
        for l in 1..h.len() {
            let kept = &h.levels()[l].kept;
            prop_assert!(kept.windows(2).all(|w| w[0] < w[1]));
            let finer = h.finest_indices(l - 1);
            let here = h.finest_indices(l);
            prop_assert!(here.iter().all(|v| finer.binary_search(v).is_ok()));
            prop_assert!(here.iter().all(|&v| coarsest[v as usize] as usize >= l));
        }
    }

    #[test]
    fn unpooling_keeps_kept_values_and_averages_neighbours(
        m in random_mesh(),
        values in proptest::collection::vec(-10.0f64..10.0, 1..600),
    ) {
        let h = Hierarchy::build(m.graph(), 3).unwrap();
        for l in 1..h.len() {
            let fine = &h.levels()[l - 1].graph;
            let level = &h.levels()[l];
            let u = level.unpooling.as_ref().unwrap();
            let coarse: Vec<f64> = (0..u.coarse_count()).map(|c| values[c % values.len()]).collect();
            let out = u.apply(&coarse, 1);
            let mut coarse_of = vec![None; fine.vertex_count()];
            for (c, &v) in level.kept.iter().enumerate() {
                coarse_of[v as usize] = Some(c as u32);
            }
            for i in 0..fine.vertex_count() {
                let (cols, ws) = u.row(i);
                prop_assert!((ws.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                prop_assert!(ws.iter().all(|&w| w > 0.0));
                match coarse_of[i] {
                    Some(c) => prop_assert_eq!(out[i], coarse[c as usize]),
                    None => {
                        // Exactly the kept fine neighbours, and a convex combination of them.
                        let nb: Vec<u32> = fine.neighbors(i).iter().filter_map(|&j| coarse_of[j as usize]).collect();
                        prop_assert_eq!(cols, &nb[..]);
                        let vals: Vec<f64> = nb.iter().map(|&c| coarse[c as usize]).collect();
                        let lo = vals.iter().cloned().fold(f64::INFINITY, f64::min);
                        let hi = vals.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                        prop_assert!(out[i] >= lo - 1e-12 && out[i] <= hi + 1e-12);
                    }
                }
            }
            // A constant field unpools to the same constant.
            let ones = u.apply(&vec![1.0; u.coarse_count()], 1);
            prop_assert!(ones.iter().all(|&x| (x - 1.0).abs() < 1e-12));
        }
    }
}
