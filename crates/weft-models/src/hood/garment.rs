//! What HOOD keeps of a garment between steps: its rest shape, the edges of every level
//! of its nested hierarchy, which vertices are pinned, their masses and materials.
//!
//! Built once per garment (and material); every rollout step reads it. Levels come from
//! weft-hierarchy's structure-preserving pooling, which takes one centre per connected
//! component, so a garment of several pieces (a top and a skirt as one mesh) works as it
//! is; HOOD's code needs a connected mesh. A garment too small to pool into every level
//! the config asks for reuses its coarsest level for the missing ones.

use weft_hierarchy::Hierarchy;
use weft_mesh::TriMesh;

use crate::error::ModelError;

/// A garment prepared for HOOD; see the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct HoodGarment {
    /// Rest shape (the stretching and bending energies' reference; the rest-relative
    /// edge features).
    pub rest: TriMesh,
    /// Directed edges (sender, receiver) of each level, both directions, in the
    /// garment's vertex numbering; `levels[0]` is the mesh.
    pub levels: Vec<Vec<[u32; 2]>>,
    /// For each vertex, the coarsest level it belongs to (the level one-hot).
    pub level_of: Vec<u8>,
    /// Pinned vertices (they follow targets given each step instead of the network).
    pub pinned: Vec<bool>,
    /// Lumped vertex masses (kg).
    pub masses: Vec<f64>,
    /// Per-vertex material inputs in [0, 1] over the training range (bending, μ, λ).
    pub material: Vec<[f32; 3]>,
    /// Extra edges (button pairs), both directions, joined to the mesh level while
    /// buttoned.
    pub buttons: Vec<[u32; 2]>,
}

impl HoodGarment {
    /// Prepares `rest` with a hierarchy of `levels` levels; `pinned` lists pinned
    /// vertices, `masses` and `material` give one entry per vertex.
    pub fn new(
        rest: &TriMesh,
        levels: usize,
        pinned: &[u32],
        masses: Vec<f64>,
        material: Vec<[f32; 3]>,
    ) -> Result<Self, ModelError> {
        let n = rest.vertex_count();
        if n == 0 || rest.faces.is_empty() {
            return Err(ModelError::Garment(
                "HOOD needs a garment with at least one triangle".into(),
            ));
        }
        for (what, len) in [
            ("vertex masses", masses.len()),
            ("materials", material.len()),
        ] {
            if len != n {
                return Err(ModelError::mismatch(
                    what,
                    format!("one per garment vertex ({n})"),
                    len,
                ));
            }
        }
        if let Some(&v) = pinned.iter().find(|&&v| v as usize >= n) {
            return Err(ModelError::Garment(format!(
                "pinned vertex {v} is out of range: the garment has {n} vertices"
            )));
        }
        let hierarchy = Hierarchy::build(rest.graph(), levels.max(1))
            .map_err(|e| ModelError::Garment(format!("garment hierarchy: {e}")))?;
        let (level_edges, level_of) = nested_levels(&hierarchy, levels.max(1));
        let mut flags = vec![false; n];
        for &v in pinned {
            flags[v as usize] = true;
        }
        Ok(HoodGarment {
            rest: rest.clone(),
            levels: level_edges,
            level_of,
            pinned: flags,
            masses,
            material,
            buttons: Vec::new(),
        })
    }

    /// The same garment with its hierarchy pooled around `centers` (one vertex per
    /// connected component, in component order; [`Hierarchy::build_from_centers`]):
    /// HOOD's augmentation, a centre drawn per training sample among each component's
    /// minimum-eccentricity vertices
    /// ([`weft_mesh::eccentricity::component_center_sets`]).
    pub fn recentred(mut self, centers: &[u32]) -> Result<Self, ModelError> {
        let levels = self.levels.len();
        let hierarchy = Hierarchy::build_from_centers(self.rest.graph(), levels, centers)
            .map_err(|e| ModelError::Garment(format!("garment hierarchy: {e}")))?;
        (self.levels, self.level_of) = nested_levels(&hierarchy, levels);
        Ok(self)
    }

    /// Garment vertices.
    pub fn vertex_count(&self) -> usize {
        self.rest.vertex_count()
    }

    /// Joins vertex pairs by button edges (they enter the mesh level's message passing
    /// while buttoned); errors on an index out of range or a vertex paired with itself.
    pub fn with_buttons(mut self, pairs: &[[u32; 2]]) -> Result<Self, ModelError> {
        weft_sim::buttons::check_pairs(pairs, self.vertex_count())
            .map_err(|e| ModelError::Garment(e.to_string()))?;
        self.buttons = pairs.iter().flat_map(|&[a, b]| [[a, b], [b, a]]).collect();
        Ok(self)
    }
}

/// The directed edges (both directions, level-0 numbering) of `levels` levels of
/// `hierarchy`, its coarsest repeated where it has fewer, and each vertex's coarsest
/// level.
fn nested_levels(hierarchy: &Hierarchy, levels: usize) -> (Vec<Vec<[u32; 2]>>, Vec<u8>) {
    let both = |edges: Vec<[u32; 2]>| -> Vec<[u32; 2]> {
        edges.iter().flat_map(|&[a, b]| [[a, b], [b, a]]).collect()
    };
    let built = hierarchy.len();
    let edges = (0..levels)
        .map(|l| both(hierarchy.edges_in_finest(l.min(built - 1))))
        .collect();
    (edges, hierarchy.coarsest_level())
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives::grid;

    #[test]
    fn levels_nest_and_inputs_are_checked() {
        let g = grid(9, 9, 0.05);
        let n = g.vertex_count();
        let h = HoodGarment::new(&g, 3, &[0, 8], vec![0.01; n], vec![[0.5; 3]; n]).unwrap();
        assert_eq!(h.levels.len(), 3);
        // Every edge appears in both directions.
        for level in &h.levels {
            for &[a, b] in level {
                assert!(level.contains(&[b, a]));
            }
        }
        // Coarser levels have fewer vertices touched and longer edges.
        let touched = |l: &[[u32; 2]]| {
            let mut v: Vec<u32> = l.iter().map(|e| e[0]).collect();
            v.sort_unstable();
            v.dedup();
            v.len()
        };
        assert!(touched(&h.levels[1]) < touched(&h.levels[0]));
        assert!(touched(&h.levels[2]) < touched(&h.levels[1]));
        assert!(h.pinned[0] && h.pinned[8] && !h.pinned[1]);
        assert!(HoodGarment::new(&g, 3, &[n as u32], vec![0.01; n], vec![[0.5; 3]; n]).is_err());
        assert!(HoodGarment::new(&g, 3, &[], vec![0.01; n - 1], vec![[0.5; 3]; n]).is_err());
        let b = h.clone().with_buttons(&[[1, 70]]).unwrap();
        assert_eq!(b.buttons, vec![[1, 70], [70, 1]]);
        assert!(h.clone().with_buttons(&[[1, 1]]).is_err());
        assert!(h.with_buttons(&[[1, n as u32]]).is_err());
    }

    #[test]
    fn recentring_moves_the_levels_and_keeps_the_rest() {
        let g = grid(9, 9, 0.05);
        let n = g.vertex_count();
        let h = HoodGarment::new(&g, 3, &[0, 8], vec![0.01; n], vec![[0.5; 3]; n]).unwrap();
        let centres = weft_mesh::eccentricity::component_center_sets(&g.graph());
        // Around the default centre the fine and first coarse levels are unchanged.
        let same = h.clone().recentred(&[centres[0][0]]).unwrap();
        assert_eq!(same.levels[..2], h.levels[..2]);
        // Around a corner, the corner is a node of every level and level 1 changes.
        let corner = h.clone().recentred(&[80]).unwrap();
        assert_eq!(corner.levels.len(), 3);
        assert_eq!(corner.level_of[80], 2);
        assert_ne!(corner.levels[1], h.levels[1]);
        assert_eq!(corner.levels[0], h.levels[0]);
        assert_eq!(
            (corner.pinned, corner.masses),
            (h.pinned.clone(), h.masses.clone())
        );
        assert!(h.recentred(&[0, 1]).is_err());
    }
}
