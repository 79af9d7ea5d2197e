//! Times a skirt on the default body walking: `cargo run --release -p weft-sim
//! --example skirt_walk -- AROUND RINGS FRAMES [MATERIAL] [SUBSTEPS]`, a cone skirt of
//! AROUND × RINGS vertices, or any garment OBJ fitted to the default body with
//! `WEFT_GARMENT=G.obj` (e.g. from `weft garment generate --kind skirt`); `WEFT_SAVE=DIR`
//! writes the frames as an OBJ sequence; `WEFT_MOTION=run|jump|kick|…` picks another
//! procedural motion. Prints one line
//! per frame and the mean time per frame after the warm-up.

use weft_motion::{generate, MotionKind, ProceduralParams};
use weft_sim::sequence::test_skirt;
use weft_sim::{simulate_sequence, Material, SequenceOptions, SequenceProgress};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, d: usize| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(d);
    let (around, rings, frames) = (num(0, 96), num(1, 40), num(2, 30));
    let mut material = Material::preset(args.get(3).map_or("cotton", String::as_str))?;
    if let Some(mu) = std::env::var("WEFT_FRICTION")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        material.friction = mu;
    }
    let body = weft_body::default_body()?;
    let rest = body.shaped(&[])?.vertices;
    let skirt = match std::env::var_os("WEFT_GARMENT") {
        Some(path) => weft_mesh::io::load_mesh(std::path::Path::new(&path))?.mesh,
        None => test_skirt(&rest, around, rings),
    };
    let kind = std::env::var("WEFT_MOTION")
        .ok()
        .and_then(|m| MotionKind::parse(&m))
        .unwrap_or(MotionKind::Walk);
    let mut p = ProceduralParams::new(kind);
    p.frames = frames;
    let motion = generate(&p)?;
    let mut opts = SequenceOptions {
        substeps: num(4, SequenceOptions::default().substeps),
        ..SequenceOptions::default()
    };
    if let Some(n) = std::env::var("WEFT_NEWTON_MAX")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        opts.sim.newton.max_iterations = n;
    }
    if let Some(w) = std::env::var("WEFT_WARMUP")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        opts.warmup_frames = w;
    }
    if std::env::var("WEFT_HESSIAN").as_deref() == Ok("projected") {
        opts.sim.newton.hessian = weft_sim::HessianKind::Projected;
    }
    if let Some(r) = std::env::var("WEFT_CG_LOOSE")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        opts.sim.newton.cg_rtol_loose = r;
    }
    println!(
        "{} vertices, {} faces",
        skirt.vertex_count(),
        skirt.face_count()
    );
    let seq = simulate_sequence(&skirt, &material, &body, &[], &motion, &opts, &mut |p| {
        let SequenceProgress::Frame(s) = p else {
            return;
        };
        println!(
            "frame {:3}: {:.3} s, newton {:4}, cg {:6}, strain max {:.4} mean {:.5}, inside {} ({:.2e} m)",
            s.frame, s.seconds, s.newton_iterations, s.cg_iterations, s.max_edge_strain,
            s.mean_edge_strain, s.penetrations, s.max_penetration
        )
    })?;
    if let Some(dir) = std::env::var_os("WEFT_SAVE") {
        // The frames as an OBJ sequence, for `weft render`.
        let frames = weft_mesh::export::Frames::from_frames(&seq.frames)?;
        let dir = std::path::Path::new(&dir);
        std::fs::create_dir_all(dir)?;
        weft_mesh::export::write_obj_sequence(&dir.join("garment"), &skirt.faces, None, &frames)?;
        // The body at the last frame.
        let last = motion.frame_count() - 1;
        let pose: Vec<[f64; 3]> = motion.poses()[last]
            .iter()
            .map(|w| w.map(f64::from))
            .collect();
        let shaped = body.shaped(&[])?;
        let t = motion.trans()[last].map(f64::from);
        let v = body.pose_vertices(&shaped, &pose, t, weft_body::Skinning::Lbs)?;
        weft_mesh::io::write_obj(&dir.join("body_last.obj"), &body.mesh(v))?;
    }
    let after: Vec<f64> = seq.stats.iter().skip(1).map(|s| s.seconds).collect();
    println!(
        "warm-up {:.2} s; mean {:.4} s per frame over {} frames",
        seq.stats[0].seconds,
        after.iter().sum::<f64>() / after.len().max(1) as f64,
        after.len()
    );
    Ok(())
}
