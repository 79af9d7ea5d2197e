//! Procedural garment templates for weft: skirts, dresses, t-shirts, tank tops,
//! long-sleeve tops, shorts, pants and jumpsuits, fitted to a body in rest pose, at any
//! resolution from about 500 to 12 000 vertices, with per-corner UVs for rest frames.
//!
//! Every garment is a union of tubes and panels around body parts (torso tube, shoulder
//! straps or panels, sleeves, trouser legs joined by a crotch seam, a flared skirt cone),
//! sized from [`Measurements`] plus an ease, and welded by construction into one
//! manifold, consistently oriented open surface whose boundary loops are the garment's
//! openings. A seed draws the small style parameters ([`Style`]); the same kind, seed,
//! body and vertex count always give the same mesh. See docs/garments.md.

mod assemble;
mod build;
pub mod error;
pub mod fit;
pub mod kind;
pub mod obj;
pub mod onbody;
pub mod open_front;
mod pants;
pub mod prepare;
pub mod skirt;
mod top;
mod tube;

pub use error::GarmentError;
pub use fit::{Measurements, TorsoSection};
pub use kind::{DressTop, GarmentKind, Style};
pub use onbody::FitBody;
pub use open_front::OpenFront;
pub use skirt::SkirtLength;

use weft_mesh::TriMesh;

/// Smallest vertex count [`generate`] accepts.
pub const MIN_VERTICES: usize = 300;
/// Largest vertex count [`generate`] accepts.
pub const MAX_VERTICES: usize = 50_000;

/// A garment template.
#[derive(Clone, Debug, PartialEq)]
pub struct Garment {
    /// The mesh (metres, rest pose of the body it was fitted to).
    pub mesh: TriMesh,
    /// UVs of each face corner, in metres (arc length around × length along each tube):
    /// the flat pattern for `RestFrames::from_corner_uvs`.
    pub corner_uvs: Vec<[[f64; 2]; 3]>,
    /// What it is.
    pub kind: GarmentKind,
    /// The style it was built with.
    pub style: Style,
    /// Skinning weights transferred from the body (joint count per row), if requested by
    /// [`Garment::transfer_weights`].
    pub weights: Option<weft_body::features::SkinningWeights>,
}

/// Builds `kind` with `style` around `m` so its vertex count is as close as the
/// construction allows to `vertices` (within ±15% from 500 to 12 000).
///
/// The edge length is bisected on a log scale: the vertex count falls monotonically (up
/// to rounding of ring counts) as edges lengthen, and a build takes milliseconds.
pub fn generate(
    kind: GarmentKind,
    style: &Style,
    m: &Measurements,
    vertices: usize,
) -> Result<Garment, GarmentError> {
    if !(MIN_VERTICES..=MAX_VERTICES).contains(&vertices) {
        return Err(GarmentError::VertexCount {
            got: vertices,
            min: MIN_VERTICES,
            max: MAX_VERTICES,
        });
    }
    style.check()?;
    m.check()?;
    let target = vertices as f64;
    let (mut lo, mut hi) = (0.002f64.ln(), 0.3f64.ln());
    let mut best: Option<(f64, build::Builder)> = None;
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        let b = assemble::assemble(kind, style, m, mid.exp());
        let count = b.positions.len() as f64;
        let err = (count - target).abs() / target;
        if best.as_ref().map_or(true, |(e, _)| err < *e) {
            best = Some((err, b));
        }
        if count > target {
            lo = mid;
        } else {
            hi = mid;
        }
        if err < 0.01 {
            break;
        }
    }
    let Some((_, b)) = best else {
        return Err(GarmentError::VertexCount {
            got: vertices,
            min: MIN_VERTICES,
            max: MAX_VERTICES,
        });
    };
    Ok(Garment {
        mesh: TriMesh::new(b.positions, b.faces),
        corner_uvs: b.corner_uvs,
        kind,
        style: *style,
        weights: None,
    })
}

impl Garment {
    /// Transfers the body's skinning weights to the garment vertices (closest surface
    /// point, barycentric), for the LBS baselines and for initialising sequences. The body
    /// is the rest-pose `body` mesh with one weight row per vertex.
    pub fn transfer_weights(
        &mut self,
        body: &TriMesh,
        body_weights: &weft_body::features::SkinningWeights,
    ) -> Result<(), GarmentError> {
        let surface = weft_body::query::BodySurface::from_mesh(body)
            .map_err(|e| GarmentError::Measurements(format!("body surface: {e}")))?;
        let t = weft_body::features::transfer::transfer_weights(
            &surface,
            body_weights,
            &self.mesh.positions,
        )
        .map_err(|e| GarmentError::Measurements(format!("weight transfer: {e}")))?;
        self.weights = Some(t.weights);
        Ok(())
    }
}
