//! `weft data characters`: builds (or resumes) a character dataset.
//!
//! Plan: character `k` of the config gets id `c{k:03}`, its split by position (train
//! first, then validation, then test), a shape β and an outfit drawn from the dataset
//! seed and `k`, and its poses: `random_poses` drawn in the joint limits, then
//! `frames_per_motion` frames of each clip (a fresh variation per character). Then per
//! character: dress the body ([`super::dressed`]), solve the ground truth of every pose
//! in parallel, write the file atomically and rewrite the manifest. A resumed build keeps
//! every recorded character whose file still has its recorded SHA-256 and rebuilds the
//! rest, so a kill loses at most the character in flight. The same config and seed give
//! byte-identical files.

use std::path::Path;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use weft_body::kinematics::Skeleton;
use weft_body::skinning::SkinWeights;
use weft_body::{BodyModel, Pose, Skinning};
use weft_garment::Style;
use weft_mesh::io::lock::{remove_stale_temps, Access, DirLock, LOCK_FILE};
use weft_mesh::rng::SplitMix64;
use weft_sim::ElasticSkin;

use super::config::{CharacterConfig, TruthSource};
use super::dressed::{dress, DressedCharacter};
use super::file::{self, CharacterData};
use super::manifest::{CharacterManifest, CharacterRecord, CHARACTER_FORMAT};
use super::poses::{clip_poses, random_pose};
use crate::error::DataError;
use crate::plan::truncated_normal;
use crate::split::Split;

/// Mixed into the dataset seed for character draws ("WEFTCHAR").
const CHARACTER_SALT: u64 = 0x5745_4654_4348_4152;

/// What a build did.
#[derive(Clone, Debug, PartialEq)]
pub struct CharacterReport {
    /// Characters built now.
    pub built: usize,
    /// Characters kept from an earlier run.
    pub kept: usize,
    /// Poses solved now.
    pub poses: usize,
    /// Wall time, seconds.
    pub seconds: f64,
}

/// One planned character.
#[derive(Clone, Debug)]
struct Planned {
    id: String,
    split: Split,
    betas: Vec<f64>,
    outfit: Vec<(weft_garment::GarmentKind, Style)>,
    poses: Vec<Pose>,
}

fn plan(config: &CharacterConfig) -> Result<Vec<Planned>, DataError> {
    let tops = config.top_kinds()?;
    let bottoms = config.bottom_kinds()?;
    let motions = config.motion_kinds()?;
    let c = config.characters;
    let split_of = |k: usize| {
        if k < c.train {
            Split::Train
        } else if k < c.train + c.validation {
            Split::Validation
        } else {
            Split::Test
        }
    };
    (0..c.total())
        .map(|k| {
            let seed =
                config.seed ^ CHARACTER_SALT ^ (k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            let mut rng = SplitMix64::new(seed);
            let betas = (0..config.beta_components)
                .map(|_| truncated_normal(&mut rng, config.beta_sigma, config.beta_limit))
                .collect();
            let mut outfit = Vec::new();
            for list in [&tops, &bottoms] {
                if !list.is_empty() {
                    let kind = list[rng.below(list.len())];
                    outfit.push((kind, Style::from_seed(kind, rng.next_u64())));
                }
            }
            let mut poses: Vec<Pose> = (0..config.random_poses)
                .map(|_| random_pose(&mut rng, config.pose_range))
                .collect();
            for &m in &motions {
                poses.extend(clip_poses(m, rng.next_u64(), config.frames_per_motion)?);
            }
            Ok(Planned {
                id: format!("c{k:03}"),
                split: split_of(k),
                betas,
                outfit,
                poses,
            })
        })
        .collect()
}

/// Builds (or resumes) the character dataset of `config` in `out`; `progress` draws a
/// bar with an ETA on stderr.
pub fn build_characters(
    config: &CharacterConfig,
    out: &Path,
    progress: bool,
) -> Result<CharacterReport, DataError> {
    config.validate()?;
    let started = Instant::now();
    std::fs::create_dir_all(out)
        .map_err(|e| DataError::io(out, "cannot create the dataset directory", e))?;
    let _lock = DirLock::acquire(out, LOCK_FILE, Access::Exclusive, "weft data characters")?;
    remove_stale_temps(out, 1)
        .map_err(|e| DataError::io(out, "cannot remove stale temporary files", e))?;
    let model = BodyModel::load_or_default(config.body.as_deref())
        .map_err(|e| DataError::config("body", e.to_string()))?;
    if config.truth == TruthSource::PoseCorrectives && !model.has_pose_blend_shapes() {
        return Err(DataError::config(
            "truth",
            format!(
                "pose_correctives needs a body with posedirs; {} has none (use truth = \"elastic\")",
                model.source()
            ),
        ));
    }
    let planned = plan(config)?;
    let earlier = match CharacterManifest::load(out) {
        Ok(m) if m.config == *config => m.characters,
        Ok(_) => {
            return Err(DataError::config(
                "config",
                format!(
                    "{} holds a character dataset of another config; use a new directory",
                    out.display()
                ),
            ))
        }
        Err(_) => Vec::new(),
    };
    let mut manifest = CharacterManifest {
        format_version: CHARACTER_FORMAT,
        config: config.clone(),
        characters: Vec::new(),
    };
    let mut todo = Vec::new();
    for p in &planned {
        let kept = earlier
            .iter()
            .find(|r| r.id == p.id)
            .filter(|r| file::read(&out.join(&r.file), Some(&r.sha256)).is_ok());
        match kept {
            Some(r) => manifest.characters.push(r.clone()),
            None => todo.push(p),
        }
    }
    let kept = manifest.characters.len();
    let total_poses: usize = todo.iter().map(|p| p.poses.len()).sum();
    let bar = if progress {
        ProgressBar::new(total_poses as u64)
    } else {
        ProgressBar::with_draw_target(Some(total_poses as u64), ProgressDrawTarget::hidden())
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} poses ({per_sec}, ETA {eta}) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    for p in todo {
        bar.set_message(p.id.clone());
        let t0 = Instant::now();
        let character = dress(
            &model,
            &p.betas,
            &p.outfit,
            config.garment_vertices,
            config.layer_offset,
        )?;
        let truth = solve_truth(config, &model, &p.betas, &character, &p.poses, &p.id, &bar)?;
        let data = CharacterData {
            rest_positions: character
                .mesh
                .positions
                .iter()
                .map(|q| q.map(|x| x as f32))
                .collect(),
            faces: character.mesh.faces.clone(),
            parts: character.parts.clone(),
            weights: character
                .weights
                .to_dense()
                .iter()
                .map(|&w| w as f32)
                .collect(),
            joint_distances: character.joint_distances.clone(),
            joints: character
                .joints
                .iter()
                .map(|j| j.map(|x| x as f32))
                .collect(),
            parents: character.parents.clone(),
            betas: p.betas.iter().map(|&b| b as f32).collect(),
            poses: p.poses.clone(),
            truth,
        };
        let name = format!("{}.safetensors", p.id);
        let sha256 = file::write(&out.join(&name), &p.id, &data)?;
        let record = CharacterRecord {
            id: p.id.clone(),
            split: p.split,
            betas: p.betas.clone(),
            outfit: p.outfit.iter().map(|(k, _)| k.name().to_string()).collect(),
            vertices: data.vertex_count(),
            body_vertices: character.parts.iter().filter(|&&x| x == 0).count(),
            poses: data.poses.len(),
            file: name,
            sha256,
            seconds: t0.elapsed().as_secs_f64(),
        };
        manifest.characters.push(record);
        manifest
            .characters
            .sort_by_key(|r| planned.iter().position(|q| q.id == r.id));
        manifest.save(out)?;
    }
    bar.finish_and_clear();
    manifest.save(out)?;
    Ok(CharacterReport {
        built: planned.len() - kept,
        kept,
        poses: total_poses,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// The ground truth of every pose, in parallel over poses.
fn solve_truth(
    config: &CharacterConfig,
    model: &BodyModel,
    betas: &[f64],
    character: &DressedCharacter,
    poses: &[Pose],
    id: &str,
    bar: &ProgressBar,
) -> Result<Vec<Vec<[f32; 3]>>, DataError> {
    let fail = |m: String| DataError::Simulation {
        id: id.to_string(),
        message: m,
    };
    let to_f32 = |v: Vec<[f64; 3]>| v.into_iter().map(|p| p.map(|x| x as f32)).collect();
    match config.truth {
        TruthSource::Elastic => {
            // The body is solved; tight layers ride on the deformed skin.
            let (body_n, body_faces) = character.body_counts;
            let s = character.joint_count();
            let body_weights =
                SkinWeights::from_dense(&character.weights.to_dense()[..body_n * s], s);
            let skin = ElasticSkin::new(
                &character.mesh.positions[..body_n],
                &character.mesh.faces[..body_faces],
                &body_weights,
                &config.elastic,
            )
            .map_err(|e| fail(format!("elastic skinning setup: {e}")))?;
            let skeleton = Skeleton::new(character.parents.clone())
                .map_err(|e| fail(format!("skeleton: {e}")))?;
            poses
                .par_iter()
                .enumerate()
                .map(|(i, pose)| {
                    let pose: Vec<[f64; 3]> = pose.iter().map(|r| r.map(f64::from)).collect();
                    let transforms = skeleton
                        .skinning_transforms_axis_angle(&character.joints, &pose, [0.0; 3])
                        .map_err(|e| fail(format!("pose {i}: {e}")))?;
                    let body = skin
                        .deform(&transforms)
                        .map_err(|e| fail(format!("pose {i}: elastic skinning: {e}")))?;
                    bar.inc(1);
                    Ok(to_f32(character.place_layers(&body)))
                })
                .collect()
        }
        TruthSource::PoseCorrectives => {
            let shaped = model.shaped(betas).map_err(|e| fail(e.to_string()))?;
            poses
                .par_iter()
                .map(|pose| {
                    let pose: Vec<[f64; 3]> = pose.iter().map(|r| r.map(f64::from)).collect();
                    let x = model
                        .pose_vertices(&shaped, &pose, [0.0; 3], Skinning::Lbs)
                        .map_err(|e| fail(e.to_string()))?;
                    bar.inc(1);
                    Ok(to_f32(x))
                })
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plans_are_seeded_split_and_sized() {
        let c = CharacterConfig::tiny();
        let a = plan(&c).unwrap();
        let b = plan(&c).unwrap();
        assert_eq!(a.len(), 6);
        assert_eq!(
            a.iter().map(|p| p.split).collect::<Vec<_>>(),
            [
                Split::Train,
                Split::Train,
                Split::Train,
                Split::Train,
                Split::Validation,
                Split::Test
            ]
        );
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(
                (x.betas.clone(), x.poses.clone()),
                (y.betas.clone(), y.poses.clone())
            );
            assert_eq!(x.poses.len(), c.poses_per_character());
            assert_eq!(x.outfit.len(), 2);
        }
        assert_ne!(a[0].betas, a[1].betas);
        let mut other = c.clone();
        other.seed = 1;
        assert_ne!(plan(&other).unwrap()[0].betas, a[0].betas);
    }
}
