//! Garment preparation: getting a garment (a template or any OBJ) ready to be simulated
//! or skinned on a particular body (issue 4 part 3).
//!
//! * [`resize`]: move a garment fitted to shape β0 onto shape β1 of the same body model,
//!   by the body surface's own displacement between the two shapes, blended over nearby
//!   body points so loose parts move as one piece, then pushed outside the new body.
//! * [`drape`]: settle a garment on the rest-pose body with the simulator (push-out of
//!   penetrations, gravity ramp, stop when still), reporting penetrations before and
//!   after and the frames used; [`drape_from`] does so for a garment whose rest shape
//!   (pattern) differs from where it starts.
//! * [`fit_onto`]: a garment made for one body as it really sits on another: resized,
//!   then draped with its pattern kept as the rest shape, so it is stretched tight on a
//!   fuller body and hangs loose on a slimmer one (GarFitNet's fit data, issue 14).
//! * Skinning-weight transfer for any garment positions is [`FitBody::weights_at`];
//!   [`write_positions_into_obj`] writes new positions into the garment's own OBJ text so
//!   its UVs, groups and face corners survive preparation.
//!
//! [`FitBody::weights_at`]: crate::FitBody::weights_at

pub mod drape;
pub mod error;
pub mod fit;
pub mod objtext;
pub mod resize;

pub use drape::{drape, drape_from, DrapeOptions, DrapeReport};
pub use error::PrepareError;
pub use fit::{fit_onto, FitOntoOptions, FitOntoReport};
pub use objtext::write_positions_into_obj;
pub use resize::{resize, ResizeOptions, ResizeReport};
// The simulator types of the drape's interface, so callers need no weft-sim dependency
// of their own (and never a second version of it).
pub use weft_sim::{Material, Penetration, SimOptions};

#[cfg(test)]
mod tests;
