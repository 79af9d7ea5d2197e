//! Resizing a garment from one body shape to another of the same body model.
//!
//! A garment fitted to shape β0 keeps its fit on shape β1 if every part of it moves with
//! the part of the body it covers. The body model gives that motion exactly: both shapes
//! share one mesh, so each body vertex `v` has a displacement `D_v = B1_v − B0_v`. A
//! garment vertex at distance `d` from the β0 body takes a Gaussian-weighted mean of the
//! displacements of the body vertices around its closest body point,
//!
//! `D(x) = Σ_v w_v D_v / Σ_v w_v`,  `w_v = exp(−((|x − v| − d) / σ)²)`,  `σ = σ0 + g d`,
//!
//! over the body vertices within `d + 2σ`. Why a blend and not just the closest point's
//! barycentric displacement: the closest point jumps where two body parts are about
//! equally near (a skirt between the legs, a sleeve under the arm), and a garment moved
//! by a field with jumps tears. The kernel widens with the distance to the body, so a
//! loose hem moves with the mean of both legs while a tight waistband follows its own
//! few centimetres of body. A few rounds of neighbour averaging over the garment graph
//! remove what is left of the kernel's noise. Last, the same push-out as template
//! generation ([`FitBody::push_out`], displacements spread to the neighbourhood, push-out
//! again) keeps the garment at least the margin outside the new body.

use weft_body::query::VertexTree;
use weft_mesh::vec3::{add, dist, scale, sub};
use weft_mesh::TriMesh;

use weft_sim::{Penetration, PosedBody};

use super::PrepareError;
use crate::onbody::{spread_displacements, PUSH_OUT_MARGIN};
use crate::FitBody;

/// Parameters of [`resize`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResizeOptions {
    /// Kernel width σ0 at the body surface, m.
    pub kernel_width: f64,
    /// Kernel widening g per metre of garment–body distance.
    pub kernel_growth: f64,
    /// Rounds of neighbour averaging of the displacement field over the garment graph.
    pub smoothing_rounds: usize,
    /// Distance kept between the resized garment and the new body, m.
    pub margin: f64,
}

impl Default for ResizeOptions {
    /// σ0 = 3 cm (a few body edges of the default body: smooth, but well below the size
    /// of a limb), g = 0.5, 5 smoothing rounds, the templates' 4 mm push-out margin.
    fn default() -> Self {
        ResizeOptions {
            kernel_width: 0.03,
            kernel_growth: 0.5,
            smoothing_rounds: 5,
            margin: PUSH_OUT_MARGIN,
        }
    }
}

impl ResizeOptions {
    fn check(&self) -> Result<(), PrepareError> {
        let bad = |name, value, expected| PrepareError::Option {
            name,
            value,
            expected,
        };
        if !(self.kernel_width.is_finite() && self.kernel_width > 0.0) {
            return Err(bad("kernel_width", self.kernel_width, "a positive length"));
        }
        if !(self.kernel_growth.is_finite() && self.kernel_growth >= 0.0) {
            return Err(bad("kernel_growth", self.kernel_growth, "0 or more"));
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return Err(bad("margin", self.margin, "0 m or more"));
        }
        Ok(())
    }
}

/// A resized garment and what the resize did.
#[derive(Clone, Debug, PartialEq)]
pub struct ResizeReport {
    /// The new vertex positions (same order and faces as the input).
    pub positions: Vec<[f64; 3]>,
    /// Mean vertex displacement, m.
    pub mean_displacement: f64,
    /// Largest vertex displacement, m.
    pub max_displacement: f64,
    /// Vertices inside the new body after the body-following move, before push-out.
    pub before_push_out: Penetration,
    /// Vertices the push-out moved by more than 0.1 mm (a vertex that was at the margin
    /// on the old body and ends a hair closer on the new one is not counted).
    pub pushed_out: usize,
    /// Largest push-out move, m.
    pub max_push: f64,
    /// Vertices inside the new body at the end.
    pub after: Penetration,
}

/// Moves `garment`, fitted to the body `from`, onto the body `to` (the same body model
/// at another shape: same vertex count and faces). See the module docs.
pub fn resize(
    garment: &TriMesh,
    from: &FitBody,
    to: &FitBody,
    options: &ResizeOptions,
) -> Result<ResizeReport, PrepareError> {
    options.check()?;
    check_same_body(from, to)?;
    check_finite(&garment.positions)?;
    let body_disp: Vec<[f64; 3]> = to
        .mesh
        .positions
        .iter()
        .zip(&from.mesh.positions)
        .map(|(b1, b0)| sub(*b1, *b0))
        .collect();
    let closest = from.surface.closest_points(&garment.positions)?;
    weft_sim::check_garment_gap(closest.iter().map(|c| c.signed_distance))?;
    let tree = VertexTree::new(&from.mesh.positions)?;
    let mut field = Vec::with_capacity(garment.vertex_count());
    for (&x, c) in garment.positions.iter().zip(&closest) {
        let d = c.distance.max(0.0);
        let sigma = options.kernel_width + options.kernel_growth * d;
        let mut sum = [0.0; 3];
        let mut weight = 0.0;
        for (v, r) in tree.within_radius(x, d + 2.0 * sigma)? {
            let t = (r - d) / sigma;
            let w = (-t * t).exp();
            sum = add(sum, scale(body_disp[v as usize], w));
            weight += w;
        }
        field.push(if weight > 1e-12 {
            scale(sum, 1.0 / weight)
        } else {
            // Body triangles larger than the kernel: the closest point's own motion.
            let face = from.surface.faces()[c.triangle as usize];
            face.iter().zip(c.barycentric).fold([0.0; 3], |s, (&v, b)| {
                add(s, scale(body_disp[v as usize], b))
            })
        });
    }
    let field = garment
        .graph()
        .jacobi_smooth(&field, options.smoothing_rounds);

    let mut moved = TriMesh::new(
        garment
            .positions
            .iter()
            .zip(&field)
            .map(|(p, d)| add(*p, *d))
            .collect(),
        garment.faces.clone(),
    );
    let new_body = PosedBody::new(&to.mesh.positions, &to.mesh.faces)?;
    let penetration = |p: &[[f64; 3]]| {
        new_body
            .penetration(p, options.margin)
            .map_err(PrepareError::from)
    };
    let before_push_out = penetration(&moved.positions)?;
    let before = moved.positions.clone();
    to.push_out(&mut moved.positions, options.margin)?;
    spread_displacements(&mut moved, &before, 20);
    to.push_out(&mut moved.positions, options.margin)?;
    let pushes: Vec<f64> = moved
        .positions
        .iter()
        .zip(&before)
        .map(|(p, q)| dist(*p, *q))
        .collect();
    let pushed_out = pushes.iter().filter(|&&d| d > 1e-4).count();
    let max_push = pushes.iter().copied().fold(0.0, f64::max);
    let after = penetration(&moved.positions)?;
    let disp: Vec<f64> = moved
        .positions
        .iter()
        .zip(&garment.positions)
        .map(|(p, q)| dist(*p, *q))
        .collect();
    Ok(ResizeReport {
        mean_displacement: disp.iter().sum::<f64>() / disp.len().max(1) as f64,
        max_displacement: disp.iter().copied().fold(0.0, f64::max),
        positions: moved.positions,
        before_push_out,
        pushed_out,
        max_push,
        after,
    })
}

fn check_same_body(from: &FitBody, to: &FitBody) -> Result<(), PrepareError> {
    let (a, b) = (&from.mesh, &to.mesh);
    if a.vertex_count() != b.vertex_count() {
        return Err(PrepareError::BodyMismatch(format!(
            "{} vs {} vertices",
            a.vertex_count(),
            b.vertex_count()
        )));
    }
    if a.faces != b.faces {
        return Err(PrepareError::BodyMismatch("different faces".into()));
    }
    Ok(())
}

pub(crate) fn check_finite(points: &[[f64; 3]]) -> Result<(), PrepareError> {
    match points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        Some(index) => Err(PrepareError::NonFinite {
            index,
            position: points[index],
        }),
        None => Ok(()),
    }
}
