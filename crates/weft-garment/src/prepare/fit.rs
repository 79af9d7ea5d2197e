//! A garment made for one body, as it really sits on another body of the same model.
//!
//! A garment's pattern (its rest shape: edge lengths, flat triangles) is fixed when it
//! is made for a body. On a fuller body the same pattern is stretched tight, on a
//! slimmer one it hangs loose: that difference in fit is what GarFitNet (seed 001
//! ch. 4) learns. [`fit_onto`] produces it in two steps:
//!
//! 1. [`resize`]: move the pattern from the body it was made for onto the new body by
//!    the body surface's own displacement, so every part keeps its place and ease
//!    relative to the body it covers (a start without penetrations; on a fuller body its
//!    edges are now longer than the pattern's, on a slimmer one shorter).
//! 2. [`drape_from`] with the **pattern** as rest shape: the stretched cloth pulls in
//!    against the body, the compressed cloth relaxes outwards and sags under gravity,
//!    with the top opening (waistband, neckline) held where the resize put it.
//!
//! `weft garment prepare` instead drapes the resized garment as its own rest shape: a
//! garment re-made for the new body, which fits every body the same way.

use weft_mesh::TriMesh;
use weft_sim::Material;

use super::drape::{drape_from, DrapeOptions, DrapeReport};
use super::resize::{resize, ResizeOptions, ResizeReport};
use super::PrepareError;
use crate::FitBody;

/// Parameters of [`fit_onto`]: its two steps' own options.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FitOntoOptions {
    /// The resize from the body the garment was made for to the new body.
    pub resize: ResizeOptions,
    /// The drape on the new body (pattern as rest shape).
    pub drape: DrapeOptions,
}

/// What [`fit_onto`] did: both steps' reports.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOntoReport {
    /// The resize (its `positions` are the drape's start).
    pub resize: ResizeReport,
    /// The drape (its `positions` are the fitted garment, as returned).
    pub drape: DrapeReport,
}

/// The garment whose rest shape is `pattern`, made for the body `from`, as it sits on
/// the body `to` (the same body model at another shape) in the rest pose: resized from
/// `from` to `to`, then draped on `to` from there with `pattern` as the rest shape (see
/// the module docs). Returns the fitted positions (in `pattern`'s vertex order and
/// faces, in the body model's rest frame) and both steps' reports.
///
/// These are the `start_positions` of a `weft_sim::sequence::SequenceOptions` that
/// simulates `pattern` on `to`. `from == to` drapes the pattern where it is.
///
/// Errors: the bodies are not one model ([`PrepareError::BodyMismatch`]), a non-finite
/// pattern, a garment far from the body, options out of range, a diverged drape.
pub fn fit_onto(
    pattern: &TriMesh,
    from: &FitBody,
    to: &FitBody,
    material: &Material,
    options: &FitOntoOptions,
) -> Result<(Vec<[f64; 3]>, FitOntoReport), PrepareError> {
    let resized = resize(pattern, from, to, &options.resize)?;
    let draped = drape_from(pattern, &resized.positions, to, material, &options.drape)?;
    Ok((
        draped.positions.clone(),
        FitOntoReport {
            resize: resized,
            drape: draped,
        },
    ))
}
