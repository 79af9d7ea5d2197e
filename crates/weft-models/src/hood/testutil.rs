//! Test fixtures shared by the HOOD modules: a skirt fitted to the default body and a
//! still clip.

use weft_body::{BodyModel, Pose};
use weft_mesh::TriMesh;

/// The default body and a skirt of about `vertices` vertices fitted to its rest pose.
pub(crate) fn body_and_skirt(vertices: usize) -> (BodyModel, TriMesh) {
    let body = BodyModel::load_or_default(None).unwrap();
    let fit = weft_garment::FitBody::new(&body, &[]).unwrap();
    let kind = weft_garment::GarmentKind::Skirt;
    let skirt = fit
        .generate(kind, &weft_garment::Style::from_seed(kind, 1), vertices)
        .unwrap()
        .mesh;
    (body, skirt)
}

/// `frames` frames of the rest pose at the origin: poses and root translations.
pub(crate) fn still(frames: usize) -> (Vec<Pose>, Vec<[f32; 3]>) {
    (vec![[[0.0f32; 3]; 24]; frames], vec![[0.0f32; 3]; frames])
}

/// `poses` and `trans` on the mean body shape at 30 fps.
pub(crate) fn clip<'a>(poses: &'a [Pose], trans: &'a [[f32; 3]]) -> crate::deformer::Clip<'a> {
    crate::deformer::Clip {
        betas: &[],
        poses,
        trans,
        fps: 30.0,
    }
}
