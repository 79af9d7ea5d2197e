//! The default body's left arm posed by linear blend skinning, dual quaternion skinning
//! and weft-sim's elastic skin, side by side, with the arm's volume about the elbow:
//! `cargo run --release -p weft-render --example elastic_skin -- docs/img`
//! writes `elastic_skin_elbow.png` (elbow flexed 120°) and `elastic_skin_twist.png`
//! (forearm twisted 120° at the elbow) and prints the volumes and solve times.

use std::path::PathBuf;
use std::time::Instant;

use weft_body::default_body::default_body;
use weft_body::skinning::{dqs, lbs};
use weft_render::{render, Paint, RenderOptions, SceneMesh, View};
use weft_sim::elastic_skin::cone_volume_sum;
use weft_sim::{ElasticSkin, ElasticSkinParams};

const LEFT_SHOULDER: usize = 16;
const LEFT_ELBOW: usize = 18;
/// Arm bones drawn: the left shoulder's (upper arm) and elbow's (forearm).
const ARM: [usize; 2] = [LEFT_SHOULDER, LEFT_ELBOW];
/// Faces within this distance of the rest elbow joint make the measured arm section, m.
const SECTION_RADIUS: f64 = 0.12;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "docs/img".into()));
    std::fs::create_dir_all(&out)?;
    let model = default_body()?;
    let shaped = model.shaped(&[])?;
    let (rest, faces, weights) = (&shaped.vertices, model.faces(), model.weights());
    let t0 = Instant::now();
    let params = ElasticSkinParams::default();
    let skin = ElasticSkin::new(rest, faces, weights, &params)?;
    println!(
        "setup {:.2} s, {} vertices, {} solved",
        t0.elapsed().as_secs_f64(),
        rest.len(),
        skin.free_vertex_count()
    );
    let dominant: Vec<usize> = (0..rest.len())
        .map(|v| {
            weights
                .influences(v)
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(0, |(j, _)| j)
        })
        .collect();
    let elbow = shaped.joints[LEFT_ELBOW];
    let section: Vec<[u32; 3]> = faces
        .iter()
        .filter(|f| {
            f.iter().all(|&v| {
                let d = dominant[v as usize];
                d == LEFT_SHOULDER || d == LEFT_ELBOW
            }) && f
                .iter()
                .all(|&v| weft_mesh::vec3::dist(rest[v as usize], elbow) < SECTION_RADIUS)
        })
        .copied()
        .collect();
    let arm: Vec<[u32; 3]> = faces
        .iter()
        .filter(|f| f.iter().all(|&v| ARM.contains(&dominant[v as usize])))
        .copied()
        .collect();
    let rest_volume = cone_volume_sum(rest, &section, elbow);

    for (name, axis_angle, label) in [
        (
            "elbow",
            [0.0, -120f64.to_radians(), 0.0],
            "elbow flexed 120°",
        ),
        (
            "twist",
            [120f64.to_radians(), 0.0, 0.0],
            "forearm twisted 120°",
        ),
    ] {
        let mut pose = vec![[0.0; 3]; model.joint_count()];
        pose[LEFT_ELBOW] = axis_angle;
        let a = model
            .skeleton()
            .skinning_transforms_axis_angle(&shaped.joints, &pose, [0.0; 3])?;
        let t = Instant::now();
        let (truth, report) = skin.deform_with_report(&a)?;
        let secs = t.elapsed().as_secs_f64();
        let center = a[LEFT_ELBOW].apply(elbow);
        let results = [
            ("LBS", lbs(rest, weights, &a)),
            ("DQS", dqs(rest, weights, &a)),
            ("elastic", truth),
        ];
        let mut title = format!("{label}; arm volume about the elbow / rest:");
        println!(
            "{name}: solve {secs:.2} s, {} Newton iterations, {} CG, converged {}",
            report.newton.iterations, report.newton.cg_iterations, report.newton.converged
        );
        // Side by side along +X, a tenth of the arm's length apart.
        let xs = arm.iter().flatten().map(|&v| results[0].1[v as usize][0]);
        let (lo, hi) = xs.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
        let step = 1.1 * (hi - lo);
        let mut shifted = Vec::new();
        for (k, (method, x)) in results.iter().enumerate() {
            let ratio = cone_volume_sum(x, &section, center) / rest_volume;
            println!("  {method}: volume ratio {ratio:.4}");
            title.push_str(&format!("  {method} {ratio:.3}"));
            shifted.push(
                x.iter()
                    .map(|p| [p[0] + step * k as f64, p[1], p[2]])
                    .collect::<Vec<_>>(),
            );
        }
        let colors = [[200, 120, 110], [110, 150, 200], [120, 180, 120]];
        let scene: Vec<SceneMesh> = shifted
            .iter()
            .zip(colors)
            .zip(&results)
            .map(|((x, c), (method, _))| SceneMesh::from_parts(*method, x, &arm, Paint::Solid(c)))
            .collect();
        let mut opts = RenderOptions::new(1800, 700);
        opts.view = View::Orbit {
            azimuth_deg: 0.0,
            elevation_deg: 70.0,
        };
        opts.title = Some(format!("{title}   (left to right: LBS, DQS, elastic)"));
        let path = out.join(format!("elastic_skin_{name}.png"));
        render(&scene, &opts)?.image.write_png(&path)?;
        println!("  wrote {}", path.display());
    }
    Ok(())
}
