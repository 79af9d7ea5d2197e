//! From a config to the list of sequences: ids, derived seeds, drawn body shapes, the
//! garment × body × motion assignment, and the no-overlap check of seed 000 §4.
//!
//! Everything here is a pure function of the config and the seed, so every
//! `--shard i/n` job and every resumed run computes the same plan, and sequence `index`
//! means the same sequence everywhere.

use weft_mesh::rng::SplitMix64;
use weft_motion::MotionKind;

use crate::config::{DataConfig, FORMAT_VERSION};
use crate::error::DataError;
use crate::manifest::{
    garment_path, shard_path, stats_path, BodyRecord, GarmentRecord, Manifest, MotionOrigin,
    MotionRecord, SequenceRecord, Status, MANIFEST_FORMAT,
};
use crate::split::Split;

/// Mixed into every generator seeded here ("WEFTGARM", the salt of the garment
/// generator plans first drew from), so that plans keep drawing the same numbers.
const PLAN_SALT: u64 = 0x5745_4654_4741_524d;

/// Streams of derived seeds, one per kind of thing drawn.
const STREAM_GARMENT: u64 = 1;
const STREAM_BODY: u64 = 2;
const STREAM_MOTION: u64 = 3;

/// A seed for item `index` of `stream`, independent of the other streams and items.
pub fn derive_seed(seed: u64, stream: u64, index: u64) -> u64 {
    let mut r = SplitMix64::new(
        seed ^ stream.wrapping_mul(0x9e37_79b9_7f4a_7c15)
            ^ index.wrapping_mul(0xd1b5_4a32_d192_ed03)
            ^ PLAN_SALT,
    );
    r.next_u64()
}

/// A standard normal draw (Box–Muller; the first of the pair).
fn normal(r: &mut SplitMix64) -> f64 {
    let u1 = 1.0 - r.uniform(0.0, 1.0); // (0, 1]: ln is finite
    let u2 = r.uniform(0.0, 1.0);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A normal draw with standard deviation `sigma`, redrawn until within ±`limit` (a
/// truncated normal: clamping instead would pile shapes up on the limits, and two
/// splits could then share one).
pub(crate) fn truncated_normal(r: &mut SplitMix64, sigma: f64, limit: f64) -> f64 {
    for _ in 0..10_000 {
        let x = sigma * normal(r);
        if x.abs() <= limit {
            return x;
        }
    }
    // Only reachable for sigma ≫ limit: fall back to a uniform draw.
    r.uniform(-limit, limit)
}

/// A motion file's stem as an id part: lowercase letters, digits and '-'.
fn slug(text: &str) -> String {
    let s: String = text
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect();
    let s = s.trim_matches('-');
    if s.is_empty() {
        "file".into()
    } else {
        s.chars().take(32).collect()
    }
}

/// The planned manifest of `config`: every garment, body shape, motion and sequence,
/// all sequences [`Status::Pending`]. `num_betas` is the body model's shape count (β
/// vectors are padded with zeros to it); `body_model` names the model.
pub fn plan(
    config: &DataConfig,
    num_betas: usize,
    body_model: &str,
) -> Result<Manifest, DataError> {
    config.validate()?;
    // Random shapes draw the first `beta_components` of β: more than the model has is
    // a mistake in the config, not a request to clamp.
    if config.beta_components > num_betas {
        return Err(DataError::config(
            "beta_components",
            format!(
                "{}; the body model ({body_model}) has {num_betas} shape components, so expected 0 to {num_betas}",
                config.beta_components
            ),
        ));
    }
    let mut garments = Vec::new();
    let mut bodies = Vec::new();
    let mut motions = Vec::new();
    let mut sequences = Vec::new();
    for (split_index, split) in Split::ALL.into_iter().enumerate() {
        let sc = config.split(split);
        let g0 = garments.len();
        for spec in &sc.garments {
            let gi = garments.len();
            let id = format!("g{gi:03}-{}", spec.kind);
            garments.push(GarmentRecord {
                file: garment_path(&id),
                id,
                split,
                kind: spec.kind.clone(),
                target_vertices: spec.vertices,
                seed: spec
                    .seed
                    .unwrap_or_else(|| derive_seed(config.seed, STREAM_GARMENT, gi as u64)),
                material: spec
                    .material
                    .clone()
                    .unwrap_or_else(|| config.material.clone()),
                length: spec.length.clone(),
            });
        }
        let b0 = bodies.len();
        if split_index == 0 {
            if let Some(b) = &config.garment_body {
                if b.len() > num_betas {
                    return Err(DataError::config(
                        "garment_body",
                        format!(
                            "{} values; the body model has {num_betas} shape components",
                            b.len()
                        ),
                    ));
                }
            }
        }
        let mut shapes: Vec<Vec<f32>> = Vec::new();
        for (i, b) in sc.betas.iter().enumerate() {
            if b.len() > num_betas {
                return Err(DataError::config(
                    format!("{split}.betas[{i}]"),
                    format!(
                        "{} values; the body model has {num_betas} shape components",
                        b.len()
                    ),
                ));
            }
            let mut betas: Vec<f32> = b.iter().map(|&x| x as f32).collect();
            betas.resize(num_betas, 0.0);
            shapes.push(betas);
        }
        // One normal stream per split: adding a validation body never changes the train
        // shapes.
        let mut rng =
            SplitMix64::new(derive_seed(config.seed, STREAM_BODY, split_index as u64) ^ PLAN_SALT);
        for _ in 0..sc.random_bodies {
            let mut betas = vec![0.0f32; num_betas];
            for b in betas.iter_mut().take(config.beta_components) {
                *b = truncated_normal(&mut rng, config.beta_sigma, config.beta_limit) as f32;
            }
            shapes.push(betas);
        }
        for (i, betas) in shapes.into_iter().enumerate() {
            bodies.push(BodyRecord {
                id: format!("b{:03}", b0 + i),
                split,
                betas,
            });
        }
        let m0 = motions.len();
        for spec in &sc.motions {
            let mi = motions.len();
            let (origin, name, frames) = match (&spec.kind, &spec.file) {
                (Some(kind), _) => {
                    let k = MotionKind::parse(kind).ok_or_else(|| {
                        DataError::config(format!("{split}.motions"), format!("kind {kind:?}"))
                    })?;
                    (
                        MotionOrigin::Procedural {
                            kind: k.name().to_string(),
                            seed: spec.seed.unwrap_or_else(|| {
                                derive_seed(config.seed, STREAM_MOTION, mi as u64)
                            }),
                            speed: spec.speed,
                            amplitude: spec.amplitude.unwrap_or(1.0),
                        },
                        k.name().to_string(),
                        Some(spec.frames.unwrap_or(config.frames)),
                    )
                }
                (None, Some(file)) => (
                    MotionOrigin::File {
                        path: file.display().to_string(),
                        start: spec.start,
                    },
                    slug(
                        &file
                            .file_stem()
                            .map(|s| s.to_string_lossy().into_owned())
                            .unwrap_or_default(),
                    ),
                    spec.frames,
                ),
                (None, None) => {
                    return Err(DataError::config(
                        format!("{split}.motions"),
                        "a motion names neither kind nor file",
                    ))
                }
            };
            motions.push(MotionRecord {
                id: format!("m{mi:03}-{name}"),
                split,
                origin,
                frames,
            });
        }
        // Garment-major pairs; pair p takes motions p·k, p·k+1, … (mod M), so consecutive
        // pairs see different motions and every motion is used about equally.
        let here_motions = &motions[m0..];
        let m = here_motions.len();
        let k = if sc.motions_per_pair == 0 {
            m
        } else {
            sc.motions_per_pair.min(m)
        };
        let mut pair = 0usize;
        for g in &garments[g0..] {
            for b in &bodies[b0..] {
                for j in 0..k {
                    let mo = &here_motions[(pair * k + j) % m];
                    let id = format!("{split}-{}-{}-{}", g.id, b.id, mo.id);
                    let frames = mo.frames.unwrap_or(0);
                    let start = match &mo.origin {
                        MotionOrigin::File { start, .. } => *start,
                        MotionOrigin::Procedural { .. } => 0,
                    };
                    sequences.push(SequenceRecord {
                        index: sequences.len(),
                        shard: shard_path(&id),
                        stats: stats_path(&id),
                        id,
                        split,
                        garment_id: g.id.clone(),
                        garment_kind: g.kind.clone(),
                        vertices: 0,
                        faces: 0,
                        body_id: b.id.clone(),
                        betas: b.betas.clone(),
                        motion_id: mo.id.clone(),
                        frame_range: [start, start + frames],
                        material: g.material.clone(),
                        fps: config.fps,
                        frames: 0,
                        sha256: None,
                        status: Status::Pending,
                        diverged_at: None,
                        message: None,
                    });
                }
                pair += 1;
            }
        }
    }
    let manifest = Manifest {
        format: MANIFEST_FORMAT.into(),
        version: FORMAT_VERSION,
        seed: config.seed,
        body_model: body_model.to_string(),
        fps: config.fps,
        job: None,
        config: Some(config.clone()),
        import: None,
        garments,
        bodies,
        motions,
        sequences,
    };
    check_no_overlap(&manifest)?;
    Ok(manifest)
}

/// Seed 000 §4: the splits share no garment, no body shape and no motion. Garments are
/// the same when kind, vertex count and style seed agree (they would build the same
/// mesh); shapes when their β agree; motions when kind, seed, speed, amplitude and
/// length agree, or when they read the same file (any window of it).
pub fn check_no_overlap(manifest: &Manifest) -> Result<(), DataError> {
    fn first_clash<T: PartialEq>(items: &[(Split, T, String)]) -> Result<(), DataError> {
        for (i, (sa, a, name)) in items.iter().enumerate() {
            for (sb, b, _) in &items[i + 1..] {
                if sa != sb && a == b {
                    return Err(DataError::SplitOverlap {
                        what: name.clone(),
                        first: sa.name(),
                        second: sb.name(),
                    });
                }
            }
        }
        Ok(())
    }
    let garments: Vec<_> = manifest
        .garments
        .iter()
        .map(|g| {
            (
                g.split,
                (g.kind.clone(), g.target_vertices, g.seed, g.length.clone()),
                format!(
                    "garment {} ({}, {} vertices, seed {}{})",
                    g.id,
                    g.kind,
                    g.target_vertices,
                    g.seed,
                    g.length
                        .as_deref()
                        .map(|l| format!(", {l}"))
                        .unwrap_or_default()
                ),
            )
        })
        .collect();
    first_clash(&garments)?;
    let bodies: Vec<_> = manifest
        .bodies
        .iter()
        .map(|b| {
            let bits: Vec<u32> = b.betas.iter().map(|x| x.to_bits()).collect();
            (
                b.split,
                bits,
                format!("body shape {} (β {:?})", b.id, b.betas),
            )
        })
        .collect();
    first_clash(&bodies)?;
    let motions: Vec<_> = manifest
        .motions
        .iter()
        .map(|m| {
            let key = match &m.origin {
                MotionOrigin::Procedural {
                    kind,
                    seed,
                    speed,
                    amplitude,
                } => format!(
                    "{kind}/{seed}/{:?}/{}/{:?}",
                    speed.map(f64::to_bits),
                    amplitude.to_bits(),
                    m.frames
                ),
                MotionOrigin::File { path, .. } => format!("file:{path}"),
            };
            (m.split, key, format!("motion {} ({:?})", m.id, m.origin))
        })
        .collect();
    first_clash(&motions)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiny_plan_ids_are_unique_and_splits_disjoint() {
        let c = DataConfig::tiny();
        let m = plan(&c, 10, "test body").unwrap();
        m.validate(std::path::Path::new("plan")).unwrap();
        assert_eq!(m.garments.len(), 8);
        assert!(m.bodies.iter().all(|b| b.betas.len() == 10));
        // Same plan twice.
        assert_eq!(plan(&c, 10, "test body").unwrap(), m);
        // Test contains a garment kind seen in train.
        let kinds = |s: Split| -> Vec<&str> {
            m.garments
                .iter()
                .filter(|g| g.split == s)
                .map(|g| g.kind.as_str())
                .collect()
        };
        assert!(kinds(Split::Test)
            .iter()
            .any(|k| kinds(Split::Train).contains(k)));
    }

    #[test]
    fn more_beta_components_than_the_model_has_are_refused() {
        let mut c = DataConfig::tiny();
        c.beta_components = 100;
        let err = plan(&c, 10, "default body").unwrap_err().to_string();
        for needle in ["beta_components", "100", "10 shape components", "0 to 10"] {
            assert!(err.contains(needle), "{needle:?} not in {err}");
        }
        // A body model with more components takes more.
        let m = plan(&c, 300, "my smpl.npz").unwrap();
        assert!(m.bodies.iter().all(|b| b.betas.len() == 300));
        c.beta_components = 10;
        plan(&c, 10, "default body").unwrap();
    }

    #[test]
    fn paper_plan_has_the_seed_000_pose_counts() {
        let m = plan(&DataConfig::paper(), 10, "b").unwrap();
        let poses = |s: Split| -> usize {
            m.sequences_in(s)
                .map(|r| r.frame_range[1] - r.frame_range[0])
                .sum()
        };
        assert_eq!(poses(Split::Train), 49_500);
        assert_eq!(poses(Split::Validation), 3_000);
        assert_eq!(poses(Split::Test), 8_000);
        assert_eq!(
            m.bodies.iter().filter(|b| b.split == Split::Train).count(),
            9
        );
    }

    #[test]
    fn round_robin_uses_every_motion() {
        let c = DataConfig::tiny();
        let m = plan(&c, 10, "b").unwrap();
        let train: Vec<_> = m.sequences_in(Split::Train).collect();
        assert_eq!(
            train.len(),
            c.train.garments.len() * c.train.betas.len() * c.train.motions_per_pair
        );
        for mo in m.motions.iter().filter(|x| x.split == Split::Train) {
            assert!(
                train.iter().any(|s| s.motion_id == mo.id),
                "{} unused",
                mo.id
            );
        }
    }

    #[test]
    fn overlapping_splits_are_refused() {
        let mut c = DataConfig::tiny();
        c.test.garments[0] = c.train.garments[0].clone();
        let err = plan(&c, 10, "b").unwrap_err().to_string();
        assert!(
            err.contains("garment") && err.contains("train") && err.contains("test"),
            "{err}"
        );

        let mut c = DataConfig::tiny();
        c.validation.betas = vec![c.train.betas[1].clone()];
        let err = plan(&c, 10, "b").unwrap_err().to_string();
        assert!(err.contains("body shape"), "{err}");

        let mut c = DataConfig::tiny();
        c.test.motions[0] = c.train.motions[2].clone();
        let err = plan(&c, 10, "b").unwrap_err().to_string();
        assert!(err.contains("motion"), "{err}");
    }

    #[test]
    fn random_shapes_are_seeded_and_within_the_limit() {
        let mut c = DataConfig::tiny();
        c.beta_sigma = 10.0;
        c.test.random_bodies = 5;
        let a = plan(&c, 10, "b").unwrap();
        let b = plan(&c, 10, "b").unwrap();
        assert_eq!(a.bodies, b.bodies);
        for body in a.bodies.iter().filter(|b| b.split == Split::Test) {
            assert!(body.betas[..2].iter().all(|x| x.abs() <= 2.0));
            assert!(body.betas[2..].iter().all(|&x| x == 0.0));
        }
        c.seed = 1;
        assert_ne!(plan(&c, 10, "b").unwrap().bodies, a.bodies);
    }

    /// The garfit presets pass the no-overlap rule (the regular test body is the body
    /// the garments are made for, but no training body); a garment differing only in
    /// length is another garment; a too long `garment_body` is refused naming it.
    #[test]
    fn garfit_plans_keep_the_splits_apart() {
        for c in [DataConfig::garfit_tiny(), DataConfig::garfit_paper()] {
            let m = plan(&c, 10, "b").unwrap();
            m.validate(std::path::Path::new("plan")).unwrap();
            assert!(m.garments.iter().all(|g| g.length.is_some()));
        }
        let m = plan(&DataConfig::garfit_tiny(), 10, "b").unwrap();
        let count = |s: Split| m.sequences_in(s).count();
        assert_eq!(
            [
                count(Split::Train),
                count(Split::Validation),
                count(Split::Test)
            ],
            [32, 1, 18]
        );

        let mut c = DataConfig::garfit_tiny();
        c.test.garments[0] = c.train.garments[0].clone();
        let err = plan(&c, 10, "b").unwrap_err().to_string();
        assert!(err.contains("garment") && err.contains("mini"), "{err}");
        c.test.garments[0].length = Some("maxi".into());
        plan(&c, 10, "b").unwrap();

        let mut c = DataConfig::garfit_tiny();
        c.garment_body = Some(vec![0.0; 11]);
        let err = plan(&c, 10, "b").unwrap_err().to_string();
        assert!(
            err.contains("garment_body") && err.contains("11 values"),
            "{err}"
        );
    }

    #[test]
    fn too_many_betas_name_the_field() {
        let mut c = DataConfig::tiny();
        c.train.betas[0] = vec![0.0; 11];
        let err = plan(&c, 10, "b").unwrap_err().to_string();
        assert!(err.contains("train.betas[0]"), "{err}");
    }
}
