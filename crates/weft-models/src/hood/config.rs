//! HOOD's settings (`[model]` of a run): widths, the levels of the garment hierarchy,
//! the multi-level message-passing schedule, and the body-edge radius.
//!
//! The schedule is data: `"0,1 x3 | 1,2 x3 | 2 x3 | 1,2 x3 | 0,1 x3"` lists, step by
//! step, the mesh levels whose edges a message-passing step reads (0 is the garment
//! mesh, 1 and 2 the coarser levels of weft-hierarchy's nested pooling); `x3` repeats a
//! step. Body edges are read by every step. Fine15 and Fine48 of seed 004 Table 1 are
//! `"0 x15"` and `"0 x48"` with the same network.

use burn::config::Config;
use burn::module::Param;
use burn::tensor::Device;
use weft_motion::MAX_FPS;
use weft_nn::{MlpConfig, ProcessorConfig};
use weft_sim::MaterialRanges;

use super::model::Hood;
use crate::error::ModelError;

/// The network's input widths (seed 004 §3, hood-reference §1.2; fixed by the features).
pub mod widths {
    /// Material inputs (bending, μ, λ in [0, 1]), read raw by nodes and edges.
    pub const MATERIAL: usize = 3;
    /// Node types: free garment vertex, pinned garment vertex, body vertex.
    pub const NODE_TYPES: usize = 3;
    /// Normalised node features besides the level one-hot: velocity (3), normal (3),
    /// node type (3), time step (1), log mass (1).
    pub const NODE_BASE: usize = 3 + 3 + NODE_TYPES + 1 + 1;
    /// Normalised mesh-edge features: current relative position and its length, rest
    /// relative position and its length, time step.
    pub const MESH_EDGE: usize = 3 + 1 + 3 + 1 + 1;
    /// Body-edge features: garment minus body at t and its length, garment at t minus
    /// body at t + 1 and its length, time step.
    pub const BODY_EDGE: usize = 3 + 1 + 3 + 1 + 1;
}

/// Configuration of [`Hood`].
#[derive(Config, Debug, PartialEq)]
pub struct HoodConfig {
    /// Latent width of every node and edge (seed 004: 128).
    #[config(default = 128)]
    pub latent: usize,
    /// Hidden layers of every MLP (seed 004: 2).
    #[config(default = 2)]
    pub hidden_layers: usize,
    /// Levels of the garment hierarchy, the mesh included (seed 004: the mesh and three
    /// coarser levels, of which the schedule reads two).
    #[config(default = 3)]
    pub levels: usize,
    /// The message-passing schedule (module documentation).
    #[config(default = "String::from(\"0,1 x3 | 1,2 x3 | 2 x3 | 1,2 x3 | 0,1 x3\")")]
    pub schedule: String,
    /// A garment vertex is joined to its nearest body vertex when that is closer than
    /// this (m). HOOD's code: 3 cm.
    #[config(default = 0.03)]
    pub body_radius: f64,
    /// A rollout's first step holds the body still for this long (s) so the skinned
    /// garment drapes before the motion starts (HOOD: 1/3 s); 0: no settling step, the
    /// rollout starts from the skinned garment at rest.
    #[config(default = "1.0 / 3.0")]
    pub settle_dt: f64,
    /// Body vertices whose skinning weight on the hands and wrists exceeds 0.5 take no
    /// body edges (HOOD omits the hands "to avoid body self-penetrations").
    #[config(default = true)]
    pub omit_hands: bool,
    /// Node velocities relative to the body's median velocity (features module; not in
    /// HOOD, which reads them in the world frame). Off for runs written before it.
    #[config(default = false)]
    pub relative_velocity: bool,
    /// Contacts of the loss and of the solver's reference step against the body swept
    /// from t to t + 1 (weft-sim's `SweptBody`; not in HOOD, which pairs the garment at
    /// t with the body at t + 1 and so lets a fast limb tunnel through the cloth). Off
    /// for runs written before it.
    #[config(default = false)]
    pub swept_contacts: bool,
    /// Network steps per second (seed 004: 30, one a frame of its motions). A rollout
    /// steps at this rate whatever the motion's ([`HoodConfig::steps`]): a network
    /// trained at 1/30 s and stepped at the 1/120 s of an AMASS file is outside what it
    /// learnt (docs/hood.md item 13). Training resamples its motions to this rate.
    #[config(default = 30.0)]
    pub step_fps: f64,
    /// The step's projection, stretch bound (not in HOOD; docs/hood.md item 15): after
    /// the network's step, edges longer than `1 + project_stretch` rest lengths are
    /// shortened to it, as `weft animate --strain-limit` does. With any `project_*`
    /// field set the projection is part of the model: training goes on from the
    /// projected garment (the loss stays the potential of the network's own step), and
    /// a rollout projects every step unless told otherwise. `None` (HOOD, runs written
    /// before it): no stretch bound.
    #[config(default = "None")]
    pub project_stretch: Option<f64>,
    /// The step's projection, compression bound: edges shorter than
    /// `1 − project_compression` rest lengths are lengthened to it (`--compression-limit`).
    #[config(default = "None")]
    pub project_compression: Option<f64>,
    /// The step's projection, contact margin (m): the garment is moved out of the body
    /// to this distance against the collision term's contact planes, with friction
    /// (`--push-out`).
    #[config(default = "None")]
    pub project_margin: Option<f64>,
    /// The material space (`[model.materials]`): where training draws its materials and
    /// the scale the network reads a material on. Default HOOD's ranges (runs written
    /// before it). A material outside is read as the nearest one inside
    /// ([`Materials::inputs`](super::scene::Materials::inputs)).
    #[config(default = "MaterialRanges::hood()")]
    pub materials: MaterialRanges,
}

/// A parsed schedule: for each message-passing step, the mesh levels it reads.
pub type Schedule = Vec<Vec<usize>>;

impl HoodConfig {
    /// The preset `name`: `paper` (seed 004: latent 128, two hidden layers, 15 steps over
    /// the mesh and two coarse levels) or `cpu` (latent 32, one hidden layer, seven steps
    /// over the same levels: a propagation radius of 24 mesh edges instead of 48, so a
    /// usable model trains on two cores in half an hour; no settling step, velocities
    /// relative to the body and swept contacts, which the broad pool needs:
    /// docs/hood.md item 9; a step that ends in a projection to 5 % stretch and
    /// compression and 2 mm outside the body, which the network does not learn to do
    /// itself: item 15).
    pub fn preset(name: &str) -> Result<Self, ModelError> {
        match name {
            "paper" => Ok(Self::new()),
            "cpu" => Ok(Self::new()
                .with_latent(32)
                .with_hidden_layers(1)
                .with_schedule("0,1 | 1,2 x2 | 2 | 1,2 x2 | 0,1".into())
                .with_settle_dt(0.0)
                .with_relative_velocity(true)
                .with_swept_contacts(true)
                .with_project_stretch(Some(0.05))
                .with_project_compression(Some(0.05))
                .with_project_margin(Some(0.002))),
            other => Err(ModelError::Config(format!(
                "unknown preset `{other}`; expected cpu or paper"
            ))),
        }
    }

    /// The schedule as level lists; errors name the step.
    pub fn parse_schedule(&self) -> Result<Schedule, ModelError> {
        parse_schedule(&self.schedule, self.levels)
    }

    /// How far information travels in one forward pass, in mesh edges: a step that
    /// reads level `l` moves it `2^l` edges (each level's edges span twice the last's).
    pub fn propagation_radius(&self) -> Result<usize, ModelError> {
        Ok(self
            .parse_schedule()?
            .iter()
            .map(|levels| 1usize << levels.iter().copied().max().unwrap_or(0))
            .sum())
    }

    /// Network steps over a motion of `frames` frames at `fps`: the whole number nearest
    /// its duration times `step_fps`, at least one; so a step lasts about `1/step_fps`.
    pub fn steps(&self, frames: usize, fps: f64) -> usize {
        let duration = frames.saturating_sub(1) as f64 / fps;
        (duration * self.step_fps).round().max(1.0) as usize
    }

    /// Checks the values; errors name the field.
    pub fn validate(&self) -> Result<(), ModelError> {
        ModelError::check_positive(&[
            ("latent", self.latent),
            ("hidden_layers", self.hidden_layers),
            ("levels", self.levels),
        ])?;
        if !(self.settle_dt.is_finite() && self.settle_dt >= 0.0) {
            return Err(ModelError::Config(format!(
                "settle_dt = {}: expected seconds >= 0 (0: no settling step)",
                self.settle_dt
            )));
        }
        if !(self.step_fps.is_finite() && self.step_fps > 0.0 && self.step_fps <= MAX_FPS) {
            return Err(ModelError::Config(format!(
                "step_fps = {}: expected network steps per second above 0 and at most {MAX_FPS}",
                self.step_fps
            )));
        }
        if !(self.body_radius.is_finite() && self.body_radius > 0.0) {
            return Err(ModelError::Config(format!(
                "body_radius = {}: expected a positive number of metres",
                self.body_radius
            )));
        }
        for (name, value) in [
            ("project_stretch", self.project_stretch),
            ("project_compression", self.project_compression),
            ("project_margin", self.project_margin),
        ] {
            if let Some(v) = value.filter(|v| !(v.is_finite() && *v >= 0.0 && *v < 1.0)) {
                return Err(ModelError::Config(format!(
                    "{name} = {v}: expected a fraction of the rest length (a margin in metres) >= 0 and below 1"
                )));
            }
        }
        self.materials.validate().map_err(ModelError::Config)?;
        self.parse_schedule().map(|_| ())
    }

    /// Whether the model's step ends in a projection (any `project_*` field set).
    pub fn projects(&self) -> bool {
        self.project_stretch.is_some()
            || self.project_compression.is_some()
            || self.project_margin.is_some()
    }

    /// An MLP of this config: hidden layers of the latent width, LayerNorm on the output
    /// unless it is the decoder.
    fn mlp(&self, input: usize, output: usize, layer_norm: bool) -> MlpConfig {
        let mut widths = vec![self.latent; self.hidden_layers];
        widths.push(output);
        MlpConfig::new(input, widths)
            .with_output_activation(weft_nn::Activation::None)
            .with_layer_norm(layer_norm)
    }

    /// Builds the network; errors name the field.
    pub fn init(&self, device: &Device) -> Result<Hood, ModelError> {
        self.validate()?;
        let schedule = self.parse_schedule()?;
        let body_set = self.levels;
        // Edge sets: one per mesh level, then the body edges (read by every step).
        let steps: Vec<Vec<usize>> = schedule
            .into_iter()
            .map(|mut levels| {
                levels.push(body_set);
                levels
            })
            .collect();
        let node_width = widths::NODE_BASE + self.levels + widths::MATERIAL;
        let mesh_width = widths::MESH_EDGE + widths::MATERIAL;
        Ok(Hood {
            node_encoder: self.mlp(node_width, self.latent, true).init(device)?,
            mesh_encoders: (0..self.levels)
                .map(|_| self.mlp(mesh_width, self.latent, true).init(device))
                .collect::<Result<_, _>>()?,
            body_encoder: self
                .mlp(widths::BODY_EDGE, self.latent, true)
                .init(device)?,
            processor: ProcessorConfig::new(self.latent, self.levels + 1, steps)
                .with_hidden_layers(self.hidden_layers)
                .init(device)?,
            decoder: zero_last_layer(self.mlp(self.latent, 3, false).init(device)?),
            levels: self.levels,
        })
    }
}

/// `mlp` with its output layer's weights and bias at zero: an untrained HOOD predicts
/// the mean acceleration, so its first rollouts coast (`x_t + v_t`) instead of adding
/// noise that a rollout integrates twice into an exploding garment.
fn zero_last_layer(mut mlp: weft_nn::Mlp) -> weft_nn::Mlp {
    // New parameters (not `Param::map`, which would keep the zeros out of autodiff).
    if let Some(last) = mlp.layers.last_mut() {
        last.weight = Param::from_tensor(last.weight.val().zeros_like());
        last.bias = last
            .bias
            .take()
            .map(|b| Param::from_tensor(b.val().zeros_like()));
    }
    mlp
}

/// Parses `text` (module documentation) for a hierarchy of `levels` levels.
pub fn parse_schedule(text: &str, levels: usize) -> Result<Schedule, ModelError> {
    let bad = |step: &str, why: String| {
        ModelError::Config(format!("schedule step `{}`: {why}", step.trim()))
    };
    let mut out = Vec::new();
    for step in text.split('|') {
        let mut parts = step.split_whitespace();
        let Some(list) = parts.next() else {
            return Err(bad(step, "empty; expected levels like `0,1`".into()));
        };
        let repeat = match parts.next() {
            None => 1,
            Some(r) => r
                .strip_prefix('x')
                .and_then(|n| n.parse::<usize>().ok())
                .filter(|&n| n > 0)
                .ok_or_else(|| bad(step, format!("`{r}` is not a repeat like `x3`")))?,
        };
        if let Some(extra) = parts.next() {
            return Err(bad(step, format!("unexpected `{extra}`")));
        }
        let mut set = Vec::new();
        for l in list.split(',') {
            let l: usize = l
                .parse()
                .map_err(|_| bad(step, format!("`{l}` is not a level number")))?;
            if l >= levels {
                return Err(bad(
                    step,
                    format!("level {l}, but the hierarchy has levels 0..{levels} (`levels`)"),
                ));
            }
            if set.contains(&l) {
                return Err(bad(step, format!("level {l} twice")));
            }
            set.push(l);
        }
        out.extend(std::iter::repeat_n(set, repeat));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `[model.materials]`: absent (runs written before it) gives HOOD's ranges; a
    /// partial table keeps HOOD's for the fields it leaves out; a bad range and an
    /// unknown key name the field.
    #[test]
    fn material_space_reads_from_model_and_defaults_to_hoods() {
        let read = |text: &str| {
            let file: toml::Table = toml::from_str(text).unwrap();
            weft_config::overlay(
                &HoodConfig::preset("cpu").unwrap(),
                &file,
                "run.toml",
                "model",
            )
        };
        assert_eq!(read("").unwrap().materials, MaterialRanges::hood());
        let wide = read("[materials]\nmu = [15909.0, 300000.0]\n").unwrap();
        assert_eq!(wide.materials.mu, [15_909.0, 300_000.0]);
        assert_eq!(wide.materials.lambda, MaterialRanges::hood().lambda);
        let e = read("[materials]\nmu = [3.0, 1.0]\n")
            .unwrap()
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("materials.mu = [3, 1]"), "{e}");
        let e = read("[materials]\nmus = [1.0, 3.0]\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("materials.mus"), "{e}");
    }

    #[test]
    fn the_untrained_decoder_outputs_zero_and_learns() {
        use burn::tensor::{Distribution, Tensor};
        let device = weft_nn::backend::cpu_autodiff();
        let cfg = HoodConfig::preset("cpu").unwrap();
        let model = cfg.init(&device).unwrap();
        let h = Tensor::<2>::random([5, cfg.latent], Distribution::Normal(0.0, 1.0), &device);
        let out = model.decoder.forward(h).unwrap();
        assert_eq!(out.clone().abs().sum().into_scalar::<f32>(), 0.0);
        // The zeroed layer still takes gradients (a constant would never leave zero).
        let grads = (out.sum() + 1.0).backward();
        let last = model.decoder.layers.last().unwrap();
        let g = last
            .bias
            .as_ref()
            .unwrap()
            .grad(&grads)
            .expect("bias gradient");
        assert!(g.abs().sum().into_scalar::<f32>() > 0.0);
    }

    #[test]
    fn network_steps_per_motion_frame() {
        let c = HoodConfig::new();
        assert_eq!(c.step_fps, 30.0);
        // A 30 fps motion of 41 frames: a step a frame.
        assert_eq!(c.steps(41, 30.0), 40);
        // 120 fps (AMASS): a step every four frames; 25 fps: 1/30 s steps rounded.
        assert_eq!(c.steps(161, 120.0), 40);
        assert_eq!(c.steps(26, 25.0), 30);
        // Never no step.
        assert_eq!(c.steps(2, 1000.0), 1);
        let c = c.with_step_fps(60.0);
        assert_eq!(c.steps(41, 30.0), 80);
        for bad in [0.0, -30.0, f64::NAN, 2000.0] {
            let e = c.clone().with_step_fps(bad).validate().unwrap_err();
            assert!(e.to_string().contains("step_fps"), "{e}");
        }
    }

    #[test]
    fn schedules_parse_and_give_the_papers_radius() {
        let paper = HoodConfig::preset("paper").unwrap();
        let s = paper.parse_schedule().unwrap();
        assert_eq!(s.len(), 15);
        assert_eq!(s[0], vec![0, 1]);
        assert_eq!(s[6], vec![2]);
        // Seed 004 Table 1: the hierarchical model's radius is 48 mesh edges.
        assert_eq!(paper.propagation_radius().unwrap(), 48);
        let fine15 = paper.clone().with_schedule("0 x15".into());
        assert_eq!(fine15.propagation_radius().unwrap(), 15);
        assert_eq!(
            HoodConfig::preset("cpu")
                .unwrap()
                .propagation_radius()
                .unwrap(),
            24
        );
        for (text, needle) in [
            ("0,3", "level 3"),
            ("0,0", "twice"),
            ("0 x0", "repeat"),
            ("a", "not a level"),
            ("0 | ", "empty"),
            ("0 x2 y", "unexpected"),
        ] {
            let e = parse_schedule(text, 3).unwrap_err().to_string();
            assert!(e.contains(needle), "{text}: {e}");
        }
        assert!(HoodConfig::preset("huge").is_err());
        let e = paper
            .with_body_radius(0.0)
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("body_radius"), "{e}");
        let cpu = HoodConfig::preset("cpu").unwrap();
        assert!(cpu.projects());
        assert!(!HoodConfig::preset("paper").unwrap().projects());
        for bad in [-0.1, 1.0, f64::NAN] {
            let e = HoodConfig {
                project_margin: Some(bad),
                ..cpu.clone()
            }
            .validate()
            .unwrap_err()
            .to_string();
            assert!(e.contains("project_margin"), "{e}");
        }
        let unprojected = HoodConfig {
            project_stretch: None,
            project_compression: None,
            project_margin: None,
            ..cpu
        };
        assert!(!unprojected.projects());
        assert!(HoodConfig {
            project_stretch: Some(0.05),
            ..unprojected
        }
        .projects());
    }
}
