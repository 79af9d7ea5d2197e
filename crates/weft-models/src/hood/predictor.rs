//! A trained HOOD run opened for rollouts: its network at the latest checkpoint, its
//! `[model]`, its normalisers, and the run-time choices HOOD adds (materials, buttons,
//! when to unbutton, which vertices are pinned).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use burn::tensor::Device;
use weft_body::BodyModel;
use weft_mesh::TriMesh;
use weft_sim::{Attachment, Energy, Material};

use super::config::HoodConfig;
use super::model::InferHood;
use super::rollout::{roll_out, Rollout, RolloutOptions};
use super::scene::{Materials, Scene, StateRef, StepAt};
use super::stats::{HoodStats, STATS_FILE};
use crate::deformer::{Clip, Deformer, Frames, StepJudge, Timing};
use crate::error::ModelError;
use crate::kind::ModelKind;
use crate::refine::predictor::load_record;
use crate::run::{latest_checkpoint, model_config, RunLayout};

/// A trained HOOD run ready to roll out on the CPU.
pub struct HoodPredictor {
    /// The network at the run's latest checkpoint, in its inference form.
    pub model: InferHood,
    /// The run's `[model]`.
    pub config: HoodConfig,
    /// The run's normalisers.
    pub stats: HoodStats,
    /// What garments are made of (default: HOOD's material).
    pub materials: Materials,
    /// Button vertex pairs of the garment (none by default).
    pub buttons: Vec<[u32; 2]>,
    /// Which garment vertices follow the body (default: the top opening, as `weft
    /// simulate` attaches them).
    pub attachment: Attachment,
    /// Settling, unbuttoning and the divergence guard.
    pub options: RolloutOptions,
    device: Device,
    checkpoint: PathBuf,
}

impl HoodPredictor {
    /// Loads the run in `dir`. Errors name the file: a run of another kind, a `[model]`
    /// that does not validate, a checkpoint that does not fit, missing normalisers.
    pub fn load(dir: &Path) -> Result<Self, ModelError> {
        let config = model_config(
            dir,
            ModelKind::Hood,
            &HoodConfig::new(),
            HoodConfig::validate,
        )?;
        let path = RunLayout::new(dir).config();
        let run_err = |message: String| ModelError::Run {
            path: path.clone(),
            message,
        };
        let device = weft_nn::backend::cpu();
        let checkpoint = latest_checkpoint(dir)?;
        let model = InferHood::from(&load_record(config.init(&device)?, &checkpoint)?);
        let stats = HoodStats::read(dir)?;
        if stats.levels() != config.levels {
            return Err(run_err(format!(
                "{STATS_FILE} was fitted for {} hierarchy levels, [model] levels = {}",
                stats.levels(),
                config.levels
            )));
        }
        Ok(HoodPredictor {
            model,
            config,
            stats,
            materials: Materials::Uniform(Material::hood()),
            buttons: Vec::new(),
            attachment: Attachment::TopOpening,
            options: RolloutOptions::default(),
            device,
            checkpoint,
        })
    }

    /// The scene of `garment` on `body` moving through `clip`, with this predictor's
    /// materials, buttons and attachment.
    pub fn scene(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Scene, ModelError> {
        self.scene_in(garment, body, clip, &self.materials)
    }

    /// The garment's materials that lie outside the run's material space, with what
    /// lies outside; the network reads each as the nearest material inside
    /// ([`Materials::inputs`]). Empty when all lie inside.
    pub fn materials_outside(&self) -> Vec<String> {
        self.materials.outside(&self.config.materials)
    }

    /// [`HoodPredictor::materials_outside`] for garments made of each weft-sim preset
    /// of `names` in turn (a dataset's materials); names that are no preset are left to
    /// the rollout, which refuses them.
    pub fn presets_outside(&self, names: &[&str]) -> Vec<String> {
        names
            .iter()
            .filter_map(|name| preset(name).ok())
            .flat_map(|m| m.outside(&self.config.materials))
            .collect()
    }

    /// The [`HoodPredictor::scene`] with `materials` in place of the predictor's.
    fn scene_in(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        materials: &Materials,
    ) -> Result<Scene, ModelError> {
        let mut scene = Scene::new(
            garment,
            body,
            clip,
            materials,
            self.attachment,
            &self.config,
        )?;
        if !self.buttons.is_empty() {
            scene = scene.with_buttons(&self.buttons)?;
        }
        Ok(scene)
    }

    /// `garment` on `body` through `clip` (the [`HoodPredictor::scene`]) rolled out: every
    /// frame reached, and where it stopped if it diverged.
    pub fn roll_out_clip(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Rollout, ModelError> {
        self.roll_out_scene(&self.scene(garment, body, clip)?)
    }

    fn roll_out_scene(&self, scene: &Scene) -> Result<Rollout, ModelError> {
        self.roll_out(&[scene])?
            .pop()
            .ok_or_else(|| ModelError::Config("HOOD returned no rollout".into()))
    }

    /// A rollout's frames as [`Deformer::animate`] returns them: a divergence is an error
    /// naming the frame.
    fn frames(rollout: Rollout) -> Result<Frames, ModelError> {
        if let Some((frame, why)) = rollout.stopped {
            return Err(ModelError::Diverged {
                frame,
                message: why,
            });
        }
        Ok(rollout
            .frames
            .into_iter()
            .map(|f| f.into_iter().map(|p| p.map(|x| x as f32)).collect())
            .collect())
    }

    /// Rolls out several scenes together (one forward pass per frame for all of them).
    pub fn roll_out(&self, scenes: &[&Scene]) -> Result<Vec<Rollout>, ModelError> {
        roll_out(
            &self.model,
            &self.stats,
            &self.config,
            scenes,
            &self.options,
            &self.device,
        )
    }
}

/// What a material outside the run's material space means for a rollout: the warning
/// `weft animate` and `weft eval` give after [`HoodPredictor::materials_outside`] and
/// [`HoodPredictor::presets_outside`].
pub const OUTSIDE_MATERIAL_SPACE: &str = "outside the materials the run was trained on; \
the network reads it as the nearest material inside, its physics (loss, --refine, \
--objective) stays its own";

/// Every vertex made of the weft-sim preset `name` (a dataset's recorded material).
fn preset(name: &str) -> Result<Materials, ModelError> {
    Material::preset(name)
        .map(Materials::Uniform)
        .map_err(|e| ModelError::Config(format!("the garment's material: {e}")))
}

/// The run's objective as the judge of any method's steps (`weft eval` of a HOOD run):
/// the scene in the sequence's material, the potential of each step from the method's
/// own state. Unbuttoned throughout (a dataset's garments have no buttons).
impl StepJudge for HoodPredictor {
    fn potential_gaps(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        material: &str,
        frames: &Frames,
    ) -> Result<Vec<f64>, ModelError> {
        let scene = Scene::new(
            garment,
            body,
            clip,
            &preset(material)?,
            self.attachment,
            &self.config,
        )?;
        if scene.steps_per_frame() != 1.0 {
            return Err(ModelError::Config(format!(
                "the steps' potential needs one step a frame: the motion is at {} fps, the run steps at {}",
                clip.fps, self.config.step_fps
            )));
        }
        let x: Vec<Vec<[f64; 3]>> = frames
            .iter()
            .map(|f| f.iter().map(|p| p.map(f64::from)).collect())
            .collect();
        let steps = x.len().min(scene.frames()).saturating_sub(1);
        (1..steps)
            .map(|t| {
                let state = StateRef {
                    prev: &x[t - 1],
                    cur: &x[t],
                };
                let at = StepAt {
                    t,
                    settle: false,
                    dt: scene.dt,
                    buttoned: false,
                };
                let body = scene.contact_body(at)?;
                let potential = scene.step_potential(state, at, body.as_ref())?;
                let best = scene.implicit_step(state, at, body.as_ref())?;
                // The method's step with its pinned vertices where the potential holds them.
                let taken: Vec<[f64; 3]> = (0..x[t + 1].len())
                    .map(|i| match scene.garment.pinned[i] {
                        true => best[i],
                        false => x[t + 1][i],
                    })
                    .collect();
                let value = |y: &[[f64; 3]]| {
                    potential.value(y).map_err(|e| {
                        ModelError::Garment(format!("the potential of frame {}: {e}", t + 1))
                    })
                };
                Ok(value(&taken)? - value(&best)?)
            })
            .collect()
    }
}

impl Deformer for HoodPredictor {
    /// "HOOD", with the run-time corrections when they are on, the run's own step
    /// projection included (they change the frames, so a table must not mistake them for
    /// the network's own).
    fn name(&self) -> String {
        let o = &self.options.over(&self.config);
        // The flags' own units, rounded so that 0.07 reads 7, not 7.000000000000001.
        let shown = |x: f64| (x * 1e6).round() / 1e6;
        let mut on = Vec::new();
        if o.refine > 0 && !o.objective {
            on.push(format!("{} Newton iterations", o.refine));
        }
        if let Some(limit) = o.strain_limit.stretch {
            on.push(format!("strain limit {} %", shown(100.0 * limit)));
        }
        if let Some(limit) = o.strain_limit.compression {
            on.push(format!("compression limit {} %", shown(100.0 * limit)));
        }
        if let Some(margin) = o.contact_margin {
            on.push(format!("push-out {} mm", shown(1000.0 * margin)));
        }
        // The objective is the solver's rollout, not the network's: named apart.
        let method = match o.objective {
            true => "HOOD's objective, implicit Euler",
            false => "HOOD",
        };
        match on.is_empty() {
            true => method.into(),
            false => format!("{method} ({})", on.join(", ")),
        }
    }

    fn kind(&self) -> Option<ModelKind> {
        Some(ModelKind::Hood)
    }

    fn variant(&self) -> BTreeMap<String, String> {
        let mut v = BTreeMap::from([
            ("checkpoint".into(), self.checkpoint.display().to_string()),
            ("schedule".into(), self.config.schedule.clone()),
            ("latent".into(), self.config.latent.to_string()),
            ("step_fps".into(), self.config.step_fps.to_string()),
        ]);
        if self.options.objective {
            let newton = super::rollout::OBJECTIVE_ITERATIONS.max(self.options.refine);
            v.insert(
                "objective".into(),
                format!("{newton} Newton iterations a step"),
            );
        }
        v
    }

    /// The rollout's frames; a rollout that diverges is an error naming the frame (the
    /// CLI's `weft animate` keeps the finished frames through [`HoodPredictor::roll_out`]).
    fn animate(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
    ) -> Result<Frames, ModelError> {
        Self::frames(self.roll_out_clip(garment, body, clip)?)
    }

    /// The rollout with every vertex made of the preset `material` (the material a
    /// dataset's sequence was simulated in, which `weft eval` rolls HOOD out in).
    fn animate_in(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        material: &str,
    ) -> Result<Frames, ModelError> {
        let scene = self.scene_in(garment, body, clip, &preset(material)?)?;
        Self::frames(self.roll_out_scene(&scene)?)
    }

    /// Garment frames per second with `batch` copies of the garment advanced in one
    /// forward pass per frame (HOOD's batch: garments, not frames), over the first
    /// `frames` frames of `clip`, after one untimed rollout. The rollout is timed whole
    /// (step graphs, network, integration), so both rates are the same figure: the
    /// network alone is `weft bench hood`'s.
    fn time(
        &self,
        garment: &TriMesh,
        body: &BodyModel,
        clip: &Clip,
        batches: &[usize],
        frames: usize,
    ) -> Result<Option<Vec<Timing>>, ModelError> {
        clip.check()?;
        // The start frame and `frames` steps; a clip too short for a step is refused by
        // the scene.
        let end = (frames + 1).max(2).min(clip.len());
        let cut = Clip {
            poses: &clip.poses[..end],
            trans: &clip.trans[..end],
            ..*clip
        };
        let scene = self.scene(garment, body, &cut)?;
        self.roll_out(&[&scene])?;
        let mut out = Vec::with_capacity(batches.len());
        for &batch in batches {
            let batch = batch.max(1);
            let scenes = vec![&scene; batch];
            let t0 = std::time::Instant::now();
            let rollouts = self.roll_out(&scenes)?;
            let seconds = t0.elapsed().as_secs_f64().max(1e-12);
            let reached: usize = rollouts.iter().map(|r| r.frames.len()).sum();
            let fps = reached as f64 / seconds;
            out.push(Timing {
                batch,
                vertices: garment.vertex_count(),
                network_fps: fps,
                end_to_end_fps: fps,
                frames: reached,
            });
        }
        Ok(Some(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An untrained cpu-preset network with pass-through normalisers: timing does not
    /// depend on the weights.
    fn predictor() -> HoodPredictor {
        let config = HoodConfig::preset("cpu").unwrap();
        let device = weft_nn::backend::cpu();
        HoodPredictor {
            model: InferHood::from(&config.init(&device).unwrap()),
            stats: HoodStats::identity(config.levels),
            config,
            materials: Materials::Uniform(Material::hood()),
            buttons: Vec::new(),
            attachment: Attachment::TopOpening,
            options: RolloutOptions::default(),
            device,
            checkpoint: PathBuf::from("untrained"),
        }
    }

    /// `weft eval` rolls HOOD out in the material a sequence was simulated in: in HOOD's
    /// own material (the predictor's default) the frames are `animate`'s, in silk the
    /// objective's steps differ (the untrained network's zero output does not read its
    /// inputs), and a name that is no preset is an error.
    #[test]
    fn a_sequence_is_rolled_out_in_its_own_material() {
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let (poses, trans) = crate::hood::testutil::still(3);
        let clip = crate::hood::testutil::clip(&poses, &trans);
        let mut p = predictor();
        p.options.objective = true;
        let own = p.animate(&skirt, &body, &clip).unwrap();
        assert!(p.animate_in(&skirt, &body, &clip, "hood").unwrap() == own);
        let silk = p.animate_in(&skirt, &body, &clip, "silk").unwrap();
        assert_eq!(silk.len(), own.len());
        assert!(silk != own, "silk rolled out as HOOD's material");
        let e = p.animate_in(&skirt, &body, &clip, "tweed").unwrap_err();
        assert!(e.to_string().contains("tweed"), "{e}");
    }

    /// The presets a dataset names, checked against the run's material space (what
    /// `weft eval` warns of): silk and denim lie outside HOOD's ranges, HOOD's own
    /// material and an unknown name give nothing; a space that reaches silk takes it in.
    #[test]
    fn presets_outside_the_material_space_are_named() {
        let mut p = predictor();
        let notes = p.presets_outside(&["denim", "hood", "silk", "tweed"]);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(
            notes[0].starts_with("denim: μ") && notes[1].starts_with("silk: μ"),
            "{notes:?}"
        );
        p.config.materials.mu[1] = 300_000.0;
        p.config.materials.lambda[1] = 300_000.0;
        assert!(p.presets_outside(&["silk"]).is_empty());
        p.materials = Materials::Uniform(Material::silk());
        assert!(p.materials_outside().is_empty());
    }

    /// The judge of `weft eval`: the objective's own frames (no projection) lie at the
    /// minimum of every step's potential, the untrained network's coasting ones above
    /// it, and steps at another rate than the run's are refused.
    #[test]
    fn the_objective_judges_steps_by_their_potential() {
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let (poses, trans) = crate::hood::testutil::still(5);
        let clip = crate::hood::testutil::clip(&poses, &trans);
        let mut p = predictor();
        p.options.projection = false;
        let coasting = p.animate(&skirt, &body, &clip).unwrap();
        p.options.objective = true;
        let solved = p.animate(&skirt, &body, &clip).unwrap();
        let gaps = |frames: &Frames| p.potential_gaps(&skirt, &body, &clip, "hood", frames);
        let (coast, best) = (gaps(&coasting).unwrap(), gaps(&solved).unwrap());
        assert_eq!((coast.len(), best.len()), (3, 3));
        assert!(best.iter().all(|g| g.abs() < 1e-6), "{best:?}");
        assert!(coast.iter().all(|&g| g > 1e-4), "{coast:?}");
        let fast = Clip { fps: 60.0, ..clip };
        assert!(p
            .potential_gaps(&skirt, &body, &fast, "hood", &solved)
            .is_err());
    }

    #[test]
    fn timing_advances_a_batch_of_garments_per_pass() {
        let (body, skirt) = crate::hood::testutil::body_and_skirt(320);
        let (poses, trans) = crate::hood::testutil::still(6);
        let clip = Clip {
            betas: &[],
            poses: &poses,
            trans: &trans,
            fps: 30.0,
        };
        let p = predictor();
        let t = p.time(&skirt, &body, &clip, &[1, 3], 3).unwrap().unwrap();
        assert_eq!(t.iter().map(|x| x.batch).collect::<Vec<_>>(), vec![1, 3]);
        // The first 3 frames after the start (4 of the clip), every garment of the batch.
        assert_eq!(t[0].frames, 4);
        assert_eq!(t[1].frames, 12);
        for x in &t {
            assert_eq!(x.vertices, skirt.vertex_count());
            assert!(x.network_fps > 0.0 && x.network_fps == x.end_to_end_fps);
        }
        // A one-frame clip cannot be rolled out: an error, not a figure.
        let one = Clip {
            poses: &poses[..1],
            trans: &trans[..1],
            ..clip
        };
        assert!(p.time(&skirt, &body, &one, &[1], 3).is_err());
    }

    #[test]
    fn the_name_says_which_corrections_are_on() {
        let mut p = predictor();
        // The cpu preset's own step projection, then without it.
        assert_eq!(
            p.name(),
            "HOOD (strain limit 5 %, compression limit 5 %, push-out 2 mm)"
        );
        p.options.projection = false;
        assert_eq!(p.name(), "HOOD");
        p.options.strain_limit.stretch = Some(7.0 / 100.0);
        p.options.contact_margin = Some(2.5 / 1000.0);
        assert_eq!(p.name(), "HOOD (strain limit 7 %, push-out 2.5 mm)");
        p.options.strain_limit.compression = Some(3.0 / 100.0);
        assert_eq!(
            p.name(),
            "HOOD (strain limit 7 %, compression limit 3 %, push-out 2.5 mm)"
        );
        p.options.refine = 2;
        assert_eq!(
            p.name(),
            "HOOD (2 Newton iterations, strain limit 7 %, compression limit 3 %, push-out 2.5 mm)"
        );
        p.options.objective = true;
        assert_eq!(
            p.name(),
            "HOOD's objective, implicit Euler (strain limit 7 %, compression limit 3 %, push-out 2.5 mm)"
        );
    }
}
