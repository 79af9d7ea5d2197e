//! How far one HOOD step is from the step its objective asks for, from given states.
//!
//! ```sh
//! cargo run --release -p weft-models --example hood_one_step -- RUN G.obj MOTION.npz DIR [PAIRS.json UNBUTTON_AT]
//! ```
//!
//! `DIR` holds a rollout of garment `G.obj` on `MOTION` as an OBJ sequence (`weft animate
//! --format obj`, or `weft simulate --obj`'s `obj/`). From each of its frames 5 onwards
//! the run's network takes one step, and weft-sim's implicit Euler takes the step of the
//! same incremental potential the network is trained on (`Scene::implicit_step`). Printed:
//! the hem's motion relative to the hips (mm a step) for the network, the implicit step
//! and inertia alone (`x + v`); each step's acceleration over inertia (mm a step²) and
//! how much of the implicit one the network's carries (its projection); and the part of
//! the accelerations that is a vertex's own, not its neighbours' (jitter, not sag).
//! docs/hood.md item 13 reads these for the network's own rollouts and the simulator's.
//!
//! With `PAIRS.json UNBUTTON_AT` (a top's button pairs; `DIR` a rollout unbuttoned at
//! that frame): the fronts from the release on instead (`measure_fronts`; item 18).

use std::error::Error;
use std::path::{Path, PathBuf};

use weft_models::deformer::Clip;
use weft_models::hood::rollout::{step_batch, Corrector};
use weft_models::hood::{HoodPredictor, Scene, StateRef, StepAt};

use weft_mesh::vec3::{dot, norm, sub};
use weft_mesh::TriMesh;

type P = [f64; 3];

fn mean(x: &[P], of: &[u32]) -> P {
    let n = of.len().max(1) as f64;
    std::array::from_fn(|k| of.iter().map(|&i| x[i as usize][k]).sum::<f64>() / n)
}

/// Sums over the steps of one quantity for the network, the implicit step and inertia.
#[derive(Default)]
struct Sums {
    hem: [f64; 3],
    accel: [f64; 2],
    own: [f64; 2],
    projection: [f64; 2],
    hem_count: f64,
    free_count: f64,
}

/// The step from one frame of a rollout: its state and place, the network's step and
/// inertia's.
struct OneStep<'a> {
    state: StateRef<'a>,
    at: StepAt,
    net: Vec<P>,
    inertia: Vec<P>,
}

/// The [`OneStep`] from frame `t` of `xs`.
fn network_step<'a>(
    hood: &HoodPredictor,
    scene: &Scene,
    xs: &'a [Vec<P>],
    t: usize,
    buttoned: bool,
) -> Result<OneStep<'a>, Box<dyn Error>> {
    let state = StateRef {
        prev: &xs[t - 1],
        cur: &xs[t],
    };
    let at = StepAt {
        t,
        settle: false,
        dt: scene.dt,
        buttoned,
    };
    let (graph, advance) = scene.step(state, at, &hood.config)?;
    let batch = [(&graph, &advance)];
    let net = step_batch(&hood.model, &hood.stats, &batch, &weft_nn::backend::cpu())?.remove(0);
    Ok(OneStep {
        state,
        at,
        net,
        inertia: advance.inertial_target(),
    })
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (run, garment, motion, dir, fronts) = match args.as_slice() {
        [run, garment, motion, dir] => (run, garment, motion, dir, None),
        [run, garment, motion, dir, pairs, at] => (
            run,
            garment,
            motion,
            dir,
            Some((pairs.clone(), at.parse::<usize>()?)),
        ),
        _ => {
            return Err(
                "usage: hood_one_step RUN G.obj MOTION.npz|.bvh DIR [PAIRS.json UNBUTTON_AT]"
                    .into(),
            )
        }
    };
    let body = weft_body::BodyModel::load_or_default(None)?;
    let g = weft_mesh::load_mesh(Path::new(garment))?.mesh;
    let joints = weft_motion::body_rest_joints(&body, &[])?;
    let options = weft_motion::MotionFileOptions::for_body(joints, None);
    let m = weft_motion::load_motion(Path::new(motion), &options, None)?.motion;
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()?;
    files.retain(|p| p.extension().is_some_and(|e| e == "obj"));
    files.sort();
    let n = files.len().min(m.frame_count());
    if n < 7 {
        return Err(format!(
            "{dir}: {n} frames of the rollout and the motion; expected at least 7"
        )
        .into());
    }
    let xs = files[..n]
        .iter()
        .map(|f| weft_mesh::load_mesh(f).map(|r| r.mesh.positions))
        .collect::<Result<Vec<_>, _>>()?;
    let clip = Clip {
        betas: &[],
        poses: &m.poses()[..n],
        trans: &m.trans()[..n],
        fps: m.fps(),
    };
    let mut hood = HoodPredictor::load(Path::new(run))?;
    if let Some((pairs, at)) = &fronts {
        hood.buttons = serde_json::from_str(&std::fs::read_to_string(pairs)?)?;
        let scene = hood.scene(&g, &body, &clip)?;
        return measure_fronts(&hood, &scene, &g, &xs, *at);
    }
    let scene = hood.scene(&g, &body, &clip)?;
    if scene.steps_per_frame() != 1.0 {
        return Err(format!(
            "{run} steps at {} fps, the motion is at {}",
            hood.config.step_fps,
            m.fps()
        )
        .into());
    }
    // The hem: the lowest 15 % of the garment; the hips: body vertices at its height.
    let (lo, hi) = g
        .positions
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p[1]), b.max(p[1])));
    let hem: Vec<usize> = (0..g.vertex_count())
        .filter(|&i| g.positions[i][1] < lo + 0.15 * (hi - lo))
        .collect();
    let hips: Vec<u32> = (0..scene.body[0].len() as u32)
        .filter(|&i| (lo..hi).contains(&scene.body[0][i as usize][1]))
        .collect();
    let mesh_graph = g.graph();
    let mut s = Sums::default();
    for t in 5..n - 1 {
        let OneStep {
            state,
            at,
            net,
            inertia,
        } = network_step(&hood, &scene, &xs, t, true)?;
        let implicit = scene.implicit_step(state, at, scene.contact_body(at)?.as_ref())?;
        let hips_moved = sub(mean(&scene.body[t + 1], &hips), mean(&scene.body[t], &hips));
        for &i in &hem {
            for (k, x) in [&net, &implicit, &inertia].into_iter().enumerate() {
                let d = sub(sub(x[i], xs[t][i]), hips_moved);
                s.hem[k] += d[0].hypot(d[2]);
            }
            s.hem_count += 1.0;
        }
        let accel =
            |x: &[P]| -> Vec<P> { x.iter().zip(&inertia).map(|(a, b)| sub(*a, *b)).collect() };
        let (a_net, a_imp) = (accel(&net), accel(&implicit));
        for i in
            (0..g.vertex_count()).filter(|&i| !scene.garment.pinned[i] && mesh_graph.degree(i) > 0)
        {
            for (k, a) in [&a_net, &a_imp].into_iter().enumerate() {
                s.accel[k] += norm(a[i]);
                s.own[k] += norm(sub(a[i], mean(a, mesh_graph.neighbors(i))));
            }
            s.projection[0] += dot(a_net[i], a_imp[i]);
            s.projection[1] += dot(a_imp[i], a_imp[i]);
            s.free_count += 1.0;
        }
    }
    let mm = |x: f64, n: f64| 1000.0 * x / n;
    println!(
        "hem relative to the hips, mm a step: network {:.2}, implicit step {:.2}, inertia alone {:.2}",
        mm(s.hem[0], s.hem_count),
        mm(s.hem[1], s.hem_count),
        mm(s.hem[2], s.hem_count)
    );
    println!(
        "acceleration over inertia, mm a step²: network {:.2}, implicit step {:.2}; the network's projection on it {:.2}",
        mm(s.accel[0], s.free_count),
        mm(s.accel[1], s.free_count),
        s.projection[0] / s.projection[1].max(1e-30)
    );
    println!(
        "of which a vertex's own (less its neighbours' mean), mm a step²: network {:.2}, implicit step {:.2}",
        mm(s.own[0], s.free_count),
        mm(s.own[1], s.free_count)
    );
    Ok(())
}

/// The fronts of an unbuttoned top, from `from` (the release) on: the button pairs' mean
/// gap after one step of inertia, the network, the network with the run's corrections,
/// the network refined by four Newton iterations and the implicit step; and the front
/// vertices' (free, within 6 cm of a button vertex at rest) acceleration over inertia.
fn measure_fronts(
    hood: &HoodPredictor,
    scene: &Scene,
    g: &TriMesh,
    xs: &[Vec<P>],
    from: usize,
) -> Result<(), Box<dyn Error>> {
    let corrector = Corrector::new(scene, &hood.options.over(&hood.config))?;
    let pairs = &hood.buttons;
    let gap = |x: &[P]| {
        let sum: f64 = pairs
            .iter()
            .map(|&[a, b]| norm(sub(x[a as usize], x[b as usize])))
            .sum();
        1000.0 * sum / pairs.len() as f64
    };
    let ends: Vec<P> = pairs
        .iter()
        .flatten()
        .map(|&e| g.positions[e as usize])
        .collect();
    let fronts: Vec<usize> = (0..g.vertex_count())
        .filter(|&i| !scene.garment.pinned[i])
        .filter(|&i| ends.iter().any(|&e| norm(sub(g.positions[i], e)) < 0.06))
        .collect();
    println!(
        "{} front vertices; the pairs' mean gap, mm: the state | after one step of inertia, \
         the network, corrected, refined (4 Newton iterations), the implicit step",
        fronts.len()
    );
    let (mut a_net, mut a_imp, mut along, mut asked, mut up) = (0.0, 0.0, 0.0, 0.0, [0.0; 2]);
    let steps = from.max(2)..(from + 12).min(xs.len() - 1);
    let count = (steps.len() * fronts.len()).max(1) as f64;
    for t in steps {
        let OneStep {
            state,
            at,
            net,
            inertia,
        } = network_step(hood, scene, xs, t, false)?;
        let mut corrected = net.clone();
        corrector.correct(&xs[t], at, &mut corrected)?;
        let body = scene.contact_body(at)?;
        let refined = scene.refine_step(state, at, body.as_ref(), &net, 4)?;
        let implicit = scene.implicit_step(state, at, body.as_ref())?;
        println!(
            "frame {t}: {:.1} | {:.1} {:.1} {:.1} {:.1} {:.1}",
            gap(&xs[t]),
            gap(&inertia),
            gap(&net),
            gap(&corrected),
            gap(&refined),
            gap(&implicit)
        );
        for &i in &fronts {
            let (n, m) = (sub(net[i], inertia[i]), sub(implicit[i], inertia[i]));
            a_net += norm(n);
            a_imp += norm(m);
            along += dot(n, m);
            asked += dot(m, m);
            up[0] += n[1];
            up[1] += m[1];
        }
    }
    let mm = |x: f64| 1000.0 * x / count;
    println!(
        "the fronts' acceleration over inertia, mm a step²: network {:.2}, implicit step {:.2}; \
         the network's projection on it {:.2}; upwards: network {:.2}, implicit step {:.2}",
        mm(a_net),
        mm(a_imp),
        along / asked.max(1e-30),
        mm(up[0]),
        mm(up[1])
    );
    Ok(())
}
