//! Fitting to a real body: weft's default body. No garment vertex may be inside the rest
//! body.

use weft_body::BodyModel;
use weft_garment::{DressTop, FitBody, GarmentKind, Style};

fn default_body() -> Option<BodyModel> {
    Some(weft_body::default_body().expect("default body loads"))
}

#[test]
fn garments_lie_outside_the_default_body() {
    let Some(model) = default_body() else { return };
    let mut failures = 0;
    for betas in [vec![], vec![1.5, -1.0], vec![-1.5, 1.0, 0.5]] {
        let fit = FitBody::new(&model, &betas).expect("fit body");
        let m = &fit.measurements;
        let surface = &fit.surface;
        eprintln!("{m:?}");
        for kind in GarmentKind::ALL {
            let mut style = Style::from_seed(kind, 3);
            if kind == GarmentKind::Dress {
                style.dress_top = DressTop::Sleeves;
            }
            let g = fit.generate(kind, &style, 3000).expect("generate");
            let err = (g.mesh.vertex_count() as f64 - 3000.0).abs() / 3000.0;
            assert!(
                err <= 0.15,
                "{}: {} vertices",
                kind.name(),
                g.mesh.vertex_count()
            );
            assert!(
                weft_mesh::validate::validate(&g.mesh).is_empty(),
                "{}: invalid after push-out",
                kind.name()
            );
            let mut inside = Vec::new();
            let mut worst = 0.0f64;
            for &p in &g.mesh.positions {
                let d = surface.signed_distance(p).expect("distance");
                if d < 0.0 {
                    inside.push(p);
                    worst = worst.min(d);
                }
            }
            let range = |a: usize| {
                let lo = inside.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min);
                let hi = inside
                    .iter()
                    .map(|p| p[a])
                    .fold(f64::NEG_INFINITY, f64::max);
                format!("{lo:.3}..{hi:.3}")
            };
            eprintln!(
                "{} β={betas:?}: {} of {} vertices inside, deepest {:.4} m, x {} y {} z {}",
                kind.name(),
                inside.len(),
                g.mesh.vertex_count(),
                worst,
                range(0),
                range(1),
                range(2)
            );
            failures += usize::from(!inside.is_empty());
        }
    }
    assert_eq!(failures, 0, "garments penetrate the body");
}

#[test]
fn transferred_weights_follow_the_limbs() {
    let Some(model) = default_body() else { return };
    let fit = FitBody::new(&model, &[]).expect("fit body");
    let mut g = fit
        .generate(
            GarmentKind::LongSleeve,
            &Style::from_seed(GarmentKind::LongSleeve, 0),
            2000,
        )
        .expect("generate");
    fit.transfer_weights(&model, &mut g).expect("transfer");
    let w = g.weights.as_ref().expect("weights");
    assert_eq!(w.vertex_count(), g.mesh.vertex_count());
    assert_eq!(w.joint_count(), model.joint_count());
    for v in 0..w.vertex_count() {
        let sum: f64 = w.row(v).iter().sum();
        assert!((sum - 1.0).abs() < 1e-9, "row {v} sums to {sum}");
    }
    // The vertex farthest out on the left sleeve follows the left forearm/wrist/hand.
    let cuff = (0..g.mesh.vertex_count())
        .max_by(|&a, &b| g.mesh.positions[a][0].total_cmp(&g.mesh.positions[b][0]))
        .expect("vertices");
    let arm: f64 = [18usize, 20, 22].iter().map(|&j| w.row(cuff)[j]).sum();
    assert!(arm > 0.5, "cuff vertex weights {:?}", w.row(cuff));
}
