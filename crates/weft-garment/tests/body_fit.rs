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
