//! Open-front garments: a top or dress cut down the middle of its front, from the
//! neckline to the hem, with button pairs across the cut (seed 004 Fig. 4 unbuttons such a
//! shirt). The procedural kinds are closed tubes; this makes the jacket-like variant that
//! HOOD's buttons and `weft simulate --buttons` need.

use weft_mesh::cut::{cut_along, shortest_path};
use weft_mesh::vec3::dist;
use weft_mesh::Topology;
use weft_sim::attachment::top_opening;

use crate::{Garment, GarmentError};

/// A garment opened down the front, and where to button it.
#[derive(Clone, Debug)]
pub struct OpenFront {
    /// The garment, cut: the original vertices (same indices) and one copy per vertex
    /// of the cut; faces, UVs, kind and style as before.
    pub garment: Garment,
    /// `[original, copy]` vertex pairs across the cut, evenly spaced along it from the
    /// neckline down (the button positions).
    pub buttons: Vec<[u32; 2]>,
    /// Every pair the cut separated, neckline to hem.
    pub seam: Vec<[u32; 2]>,
}

impl Garment {
    /// This garment cut open down the front with `buttons` button pairs across the cut.
    ///
    /// The cut follows the shortest chain of edges from the frontmost vertex (+z, the
    /// body's front) of the highest opening, the neckline, to the frontmost vertex of
    /// the lowest one, the hem. It starts at the chain's first vertex off every opening,
    /// which stays whole (the collar stays closed over one edge and the neckline stays an
    /// opening of its own), and ends at the next vertex on an opening, the hem, so the
    /// front edges join the hem's opening. Buttons sit nearest `(i + ½)/buttons` of the
    /// cut's length (fewer when the cut has fewer vertices). Errors on a garment with
    /// fewer than two openings, a neckline that touches the hem, or no button.
    pub fn open_front(&self, buttons: usize) -> Result<OpenFront, GarmentError> {
        let refuse = |why: String| GarmentError::OpenFront(why);
        if buttons == 0 {
            return Err(refuse("expected at least one button".into()));
        }
        let mesh = &self.mesh;
        let loops = Topology::new(mesh).boundary_loops();
        if loops.len() < 2 {
            return Err(refuse(format!(
                "the garment has {} opening(s); a cut from the neckline to the hem needs two",
                loops.len()
            )));
        }
        let height = |l: &Vec<u32>| {
            l.iter()
                .map(|&v| mesh.positions[v as usize][1])
                .sum::<f64>()
                / l.len() as f64
        };
        // The neckline is the opening the simulator holds on the body.
        let neck = top_opening(mesh);
        let hem = loops
            .iter()
            .min_by(|a, b| height(a).total_cmp(&height(b)))
            .unwrap_or(&loops[0]);
        let front = |l: &Vec<u32>| {
            l.iter()
                .copied()
                .max_by(|&a, &b| {
                    mesh.positions[a as usize][2].total_cmp(&mesh.positions[b as usize][2])
                })
                .unwrap_or(l[0])
        };
        let cut_error = |e: weft_mesh::cut::CutError| refuse(e.to_string());
        let full = shortest_path(mesh, front(&neck), front(hem)).map_err(cut_error)?;
        // Leave the neckline's own vertices out: the slit then ends inside the mesh, and
        // the neckline stays the opening the simulator holds on the body
        // (`Attachment::TopOpening` would otherwise take whichever opening is highest,
        // e.g. a cuff). The chain may also run along an opening's edge at either end.
        let mut on_boundary = vec![false; mesh.vertex_count()];
        for &v in loops.iter().flatten() {
            on_boundary[v as usize] = true;
        }
        let first_inside = full
            .iter()
            .position(|&v| !on_boundary[v as usize])
            .ok_or_else(|| refuse("the neckline and the hem touch".into()))?;
        let last = full[first_inside..]
            .iter()
            .position(|&v| on_boundary[v as usize])
            .map_or(full.len() - 1, |k| first_inside + k);
        let path = full[first_inside..=last].to_vec();
        let cut = cut_along(mesh, &path).map_err(cut_error)?;
        // Arc length along the cut at each split vertex.
        let mut along = vec![0.0; path.len()];
        for k in 1..path.len() {
            along[k] = along[k - 1]
                + dist(
                    mesh.positions[path[k - 1] as usize],
                    mesh.positions[path[k] as usize],
                );
        }
        let total = along.last().copied().unwrap_or(0.0);
        let at = |v: u32| along[path.iter().position(|&p| p == v).unwrap_or(0)];
        let mut chosen: Vec<[u32; 2]> = Vec::with_capacity(buttons);
        for i in 0..buttons {
            let want = total * (i as f64 + 0.5) / buttons as f64;
            let nearest = cut
                .pairs
                .iter()
                .copied()
                .min_by(|a, b| (at(a[0]) - want).abs().total_cmp(&(at(b[0]) - want).abs()));
            if let Some(pair) = nearest.filter(|p| !chosen.contains(p)) {
                chosen.push(pair);
            }
        }
        Ok(OpenFront {
            garment: Garment {
                mesh: cut.mesh,
                weights: None,
                ..self.clone()
            },
            buttons: chosen,
            seam: cut.pairs,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::{generate, GarmentKind, Measurements, Style};

    /// A long-sleeved top opened down the front: one copy per cut vertex, the cut from
    /// below the neckline to the hem down the front, buttons in order from the top, and
    /// as many openings as before (the front edges join the hem's; the neckline stays
    /// apart, and is still the highest).
    #[test]
    fn a_top_opens_down_its_front() {
        let g = generate(
            GarmentKind::LongSleeve,
            &Style::from_seed(GarmentKind::LongSleeve, 1),
            &Measurements::default(),
            1500,
        )
        .unwrap();
        let open = g.open_front(5).unwrap();
        let n = g.mesh.vertex_count();
        let m = &open.garment.mesh;
        assert_eq!(m.vertex_count(), n + open.seam.len());
        assert_eq!(m.faces.len(), g.mesh.faces.len());
        assert_eq!(open.garment.corner_uvs, g.corner_uvs);
        assert_eq!(open.buttons.len(), 5);
        for &[a, b] in &open.seam {
            assert_eq!(m.positions[a as usize], m.positions[b as usize]);
            // On the front: ahead of the garment's middle.
            assert!(
                m.positions[a as usize][2] > 0.0,
                "{:?}",
                m.positions[a as usize]
            );
        }
        // Buttons top to bottom.
        let y: Vec<f64> = open
            .buttons
            .iter()
            .map(|p| m.positions[p[0] as usize][1])
            .collect();
        assert!(y.windows(2).all(|w| w[0] > w[1]), "{y:?}");
        let loops = |mesh| weft_mesh::Topology::new(mesh).boundary_loops().len();
        assert_eq!(loops(m), loops(&g.mesh));
        let sorted = |mut v: Vec<u32>| {
            v.sort_unstable();
            v
        };
        // The simulator still pins the neckline, unchanged.
        let neck = sorted(weft_sim::attachment::top_opening(&g.mesh));
        assert_eq!(sorted(weft_sim::attachment::top_opening(m)), neck);
        assert!(g.open_front(0).is_err());
    }
}
