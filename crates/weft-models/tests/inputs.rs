//! Bad input is a typed error naming the mismatch (issue 6 item 9); configs round-trip
//! through TOML.

mod common;

use common::{case, model};
use weft_mesh::TriMesh;
use weft_models::multilevel::{FrameInputs, GarmentInput, MultilevelConfig, NO_DRAPE};
use weft_models::Clip;
use weft_models::ModelError;

fn message<T>(r: Result<T, ModelError>) -> String {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn skeleton_and_feature_mismatches_are_named() {
    let c = case();
    let cfg = MultilevelConfig::new();
    // A config for another skeleton.
    let other = MultilevelConfig::new().with_joints(22);
    let m = message(GarmentInput::new(&c.garment, &c.body, &c.betas, &other));
    assert!(
        m.contains("joints") && m.contains("22") && m.contains("24"),
        "{m}"
    );
    let g = GarmentInput::new(&c.garment, &c.body, &c.betas, &cfg).unwrap();
    let m = message(FrameInputs::new(
        &c.body,
        &g,
        &Clip {
            betas: &c.betas,
            poses: &c.poses,
            trans: &c.trans,
            fps: c.fps,
        },
        0..2,
        &other,
    ));
    assert!(m.contains("joints"), "{m}");
    // Inputs built for one config fed to a model of another.
    let f = FrameInputs::new(
        &c.body,
        &g,
        &Clip {
            betas: &c.betas,
            poses: &c.poses,
            trans: &c.trans,
            fps: c.fps,
        },
        0..2,
        &cfg,
    )
    .unwrap();
    let narrow = model(&cfg.clone().with_body_samples(64), 1, false);
    let m = message(narrow.encode_pair(&g));
    assert!(
        m.contains("body samples") && m.contains("64") && m.contains("128"),
        "{m}"
    );
    let short = model(&cfg.clone().with_history(3), 1, false);
    let pair = short.encode_pair(&g).unwrap();
    let m = message(short.forward(&pair, &g, &f));
    assert!(m.contains("history"), "{m}");
    let fewer = model(&cfg.clone().with_nystrom_landmarks(16), 1, false);
    let m = message(fewer.encode_pair(&g));
    assert!(m.contains("nystrom_landmarks"), "{m}");
}

#[test]
fn non_finite_and_out_of_range_inputs_are_refused() {
    let c = case();
    let cfg = MultilevelConfig::new();
    let mut garment = c.garment.clone();
    garment.positions[5][1] = f64::NAN;
    let m = message(GarmentInput::new(&garment, &c.body, &c.betas, &cfg));
    assert!(m.contains("garment positions") && m.contains("16"), "{m}");
    let m = message(GarmentInput::new(&c.garment, &c.body, &[f32::NAN], &cfg));
    assert!(m.contains("betas"), "{m}");

    let g = GarmentInput::new(&c.garment, &c.body, &c.betas, &cfg).unwrap();
    let mut poses = c.poses.clone();
    poses[1][2][1] = f32::INFINITY;
    let m = message(FrameInputs::new(
        &c.body,
        &g,
        &Clip {
            betas: &c.betas,
            poses: &poses,
            trans: &c.trans,
            fps: c.fps,
        },
        0..3,
        &cfg,
    ));
    assert!(m.contains("poses") && m.contains("non-finite"), "{m}");
    let mut trans = c.trans.clone();
    trans[2][0] = f32::NAN;
    let m = message(FrameInputs::new(
        &c.body,
        &g,
        &Clip {
            betas: &c.betas,
            poses: &c.poses,
            trans: &trans,
            fps: c.fps,
        },
        0..3,
        &cfg,
    ));
    assert!(m.contains("translations"), "{m}");
    let m = message(FrameInputs::new(
        &c.body,
        &g,
        &Clip {
            betas: &c.betas,
            poses: &c.poses,
            trans: &c.trans[..4],
            fps: c.fps,
        },
        0..3,
        &cfg,
    ));
    assert!(m.contains("root translations"), "{m}");
    let m = message(FrameInputs::new(
        &c.body,
        &g,
        &Clip {
            betas: &c.betas,
            poses: &c.poses,
            trans: &c.trans,
            fps: c.fps,
        },
        5..20,
        &cfg,
    ));
    assert!(m.contains("frame window"), "{m}");
    let m = message(FrameInputs::new(
        &c.body,
        &g,
        &Clip {
            betas: &c.betas,
            poses: &c.poses,
            trans: &c.trans,
            fps: 0.0,
        },
        0..2,
        &cfg,
    ));
    assert!(m.contains("frame rate"), "{m}");
}

#[test]
fn garments_too_small_or_broken_are_refused() {
    let c = case();
    let cfg = MultilevelConfig::new();
    let triangle = TriMesh::new(
        vec![[0.0, 1.0, 0.1], [0.1, 1.0, 0.1], [0.0, 1.1, 0.1]],
        vec![[0, 1, 2]],
    );
    let m = message(GarmentInput::new(&triangle, &c.body, &c.betas, &cfg));
    assert!(m.contains("mp_levels"), "{m}");
    let broken = TriMesh::new(triangle.positions.clone(), vec![[0, 1, 7]]);
    let m = message(GarmentInput::new(&broken, &c.body, &c.betas, &cfg));
    assert!(m.contains("face 0"), "{m}");
    let empty = TriMesh::default();
    assert!(GarmentInput::new(&empty, &c.body, &c.betas, &cfg).is_err());
}

#[test]
fn configs_round_trip_through_toml_with_defaults() {
    for name in ["paper", "cpu"] {
        let cfg = MultilevelConfig::preset(name).unwrap();
        let text = cfg.to_toml().unwrap();
        assert_eq!(MultilevelConfig::from_toml(&text).unwrap(), cfg, "{name}");
    }
    let partial = MultilevelConfig::from_toml("feature_width = 8\npooling = \"top_k\"\n").unwrap();
    assert_eq!(partial.feature_width, 8);
    assert_eq!(partial.gg_widths, MultilevelConfig::cpu().gg_widths);
    assert_eq!(partial.pooling, weft_models::multilevel::PoolingKind::TopK);
    // The cpu preset drapes in silk; a run's table without `drape` did not drape (runs
    // from before the preset draped have no such key), and "none" says off.
    assert_eq!(MultilevelConfig::cpu().drape_material(), Some("silk"));
    assert_eq!(partial.drape_material(), None);
    let off = MultilevelConfig::cpu().with_drape(Some(NO_DRAPE.into()));
    assert_eq!(off.drape_material(), None);
    off.validate().unwrap();
    let text = off.to_toml().unwrap();
    assert!(text.contains("drape = \"none\""), "{text}");
    assert_eq!(MultilevelConfig::from_toml(&text).unwrap(), off);
    let m = message(MultilevelConfig::preset("gpu"));
    assert!(m.contains("paper") && m.contains("gpu"), "{m}");
    let m = message(MultilevelConfig::from_toml("gg_widths = [8, 0]"));
    assert!(m.contains("gg_widths"), "{m}");
    let m = message(MultilevelConfig::from_toml("pool_ratio = 1.5"));
    assert!(m.contains("pool_ratio"), "{m}");
}

/// `drape`: the template the model skins is the garment settled on the rest body (the
/// silk skirt settles and its flare narrows), same vertices and faces; an unknown material
/// is refused by name.
#[test]
fn drape_settles_the_template() {
    let c = case();
    let cfg = MultilevelConfig::cpu();
    let g = GarmentInput::new(&c.garment, &c.body, &c.betas, &cfg).unwrap();
    let plain = GarmentInput::new(&c.garment, &c.body, &c.betas, &MultilevelConfig::new()).unwrap();
    assert_eq!(g.vertex_count(), plain.vertex_count());
    let lowest = |rest: &[f32]| rest.chunks(3).map(|p| p[1]).fold(f32::INFINITY, f32::min);
    let widest = |rest: &[f32]| {
        rest.chunks(3)
            .map(|p| (p[0] * p[0] + p[2] * p[2]).sqrt())
            .fold(0.0f32, f32::max)
    };
    let moved = g
        .rest
        .chunks(3)
        .zip(plain.rest.chunks(3))
        .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f32>().sqrt())
        .sum::<f32>()
        / g.vertex_count() as f32;
    eprintln!(
        "mean move {moved}, lowest {} vs {}, widest {} vs {}",
        lowest(&g.rest),
        lowest(&plain.rest),
        widest(&g.rest),
        widest(&plain.rest)
    );
    assert!(
        moved > 0.001,
        "the drape moves the cloth: {moved} m on average"
    );
    assert!(
        lowest(&g.rest) <= lowest(&plain.rest),
        "the hem does not rise"
    );
    assert!(widest(&g.rest) < widest(&plain.rest), "the flare narrows");
    let m = message(cfg.clone().with_drape(Some("chainmail".into())).validate());
    assert!(m.contains("drape") && m.contains("chainmail"), "{m}");
}
