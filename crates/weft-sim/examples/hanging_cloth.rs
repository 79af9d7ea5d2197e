//! Times the simulator on a square of cloth pinned at two corners.
//!
//! `cargo run --release -p weft-sim --example hanging_cloth -- [vertices per side] [frames] [material]`

use std::time::Instant;

use weft_mesh::primitives::grid;
use weft_sim::{ClothSimulator, Material, SimOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let side: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(32);
    let frames: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(30);
    let material = Material::preset(args.get(3).map(String::as_str).unwrap_or("cotton"))?;
    if side < 2 {
        return Err("need at least 2 vertices per side".into());
    }
    let rest = grid(side, side, 1.0 / (side - 1) as f64);
    let mut sim = ClothSimulator::new(&rest, &material, SimOptions::default())?;
    sim.pin(&[0, (side - 1) as u32])?;
    let (mut newton, mut cg) = (0, 0);
    let start = Instant::now();
    for _ in 0..frames {
        let r = sim.step(1.0 / 30.0, None)?;
        newton += r.newton.iterations;
        cg += r.newton.cg_iterations;
    }
    let t = start.elapsed().as_secs_f64();
    println!(
        "{} vertices, {} (1 m square, 2 pins, 1/30 s), {frames} frames: {:.1} ms/frame, {:.1} Newton iterations/frame, {:.0} PCG iterations/Newton iteration",
        rest.vertex_count(),
        material.name,
        1e3 * t / frames as f64,
        newton as f64 / frames as f64,
        cg as f64 / newton.max(1) as f64
    );
    Ok(())
}
