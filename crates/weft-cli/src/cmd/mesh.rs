//! `weft mesh info` and `weft mesh hierarchy`.

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use weft_hierarchy::Hierarchy;
use weft_mesh::io::{load_mesh, write_ply_colored, write_ply_graph};
use weft_mesh::validate::{summarize, validate, Severity};
use weft_mesh::{primitives, Topology, TriMesh};

use super::emit;

#[derive(Subcommand)]
pub enum MeshCommand {
    /// Counts, components, boundary loops, bounding box and validation findings of a mesh.
    Info(InfoArgs),
    /// Pool a mesh graph into levels by structure-preserving pooling (seed 000, Alg. 1).
    Hierarchy(HierarchyArgs),
}

#[derive(Args)]
pub struct InfoArgs {
    /// An .obj or .ply mesh.
    file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
pub struct HierarchyArgs {
    /// An .obj or .ply mesh; without it, the built-in garment (an open cylinder of
    /// 40 rings × 100 vertices).
    file: Option<PathBuf>,
    /// Number of levels, the finest (the mesh itself) included.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(1..=32))]
    levels: u8,
    /// Print one JSON object: {"levels":[{"vertices","edges","components","kept"}...]}.
    #[arg(long)]
    json: bool,
    /// Write each level as level_<l>.ply into this directory, the vertices the next
    /// level keeps coloured orange.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(command: MeshCommand) -> Result<()> {
    match command {
        MeshCommand::Info(a) => info(&a),
        MeshCommand::Hierarchy(a) => hierarchy(&a),
    }
}

fn info(args: &InfoArgs) -> Result<()> {
    let report = load_mesh(&args.file)?;
    let mesh = &report.mesh;
    let topology = Topology::new(mesh);
    let components = mesh.graph().components().count;
    let loops = topology.boundary_loops().len();
    let bbox = mesh.bounding_box();
    let findings = summarize(&validate(mesh));
    if args.json {
        let out = json!({
            "file": args.file,
            "format": report.format.to_string(),
            "vertices": mesh.vertex_count(),
            "faces": mesh.face_count(),
            "edges": topology.edges.len(),
            "components": components,
            "boundary_loops": loops,
            "bounding_box": bbox.map(|b| json!({"min": b.min, "max": b.max})),
            "triangulated_polygons": report.triangulated_polygons,
            "findings": findings.iter().map(|s| json!({
                "kind": format!("{:?}", s.kind),
                "severity": match s.kind.severity() { Severity::Error => "error", Severity::Warning => "warning" },
                "count": s.count,
                "summary": s.to_string(),
            })).collect::<Vec<_>>(),
        });
        return emit(&serde_json::to_string_pretty(&out)?);
    }
    let mut out = String::new();
    writeln!(out, "{}: {}", args.file.display(), report.format)?;
    writeln!(
        out,
        "  {} vertices, {} faces, {} edges",
        mesh.vertex_count(),
        mesh.face_count(),
        topology.edges.len()
    )?;
    writeln!(
        out,
        "  {components} connected components, {loops} boundary loops"
    )?;
    if let Some(b) = bbox {
        writeln!(
            out,
            "  bounding box [{:.4}, {:.4}, {:.4}] – [{:.4}, {:.4}, {:.4}]",
            b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]
        )?;
    }
    if report.triangulated_polygons > 0 {
        writeln!(
            out,
            "  {} polygons with more than 3 corners were triangulated as fans on load",
            report.triangulated_polygons
        )?;
    }
    if findings.is_empty() {
        writeln!(out, "  validation: no findings")?;
    }
    for s in &findings {
        let tag = match s.kind.severity() {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        writeln!(out, "  {tag}: {s}")?;
    }
    emit(&out)
}

fn hierarchy(args: &HierarchyArgs) -> Result<()> {
    let mesh = match &args.file {
        Some(path) => load_mesh(path)?.mesh,
        None => primitives::builtin_garment(),
    };
    let source = args
        .file
        .as_deref()
        .map_or("built-in garment (cylinder 40 × 100)".into(), |p| {
            p.display().to_string()
        });
    let h = Hierarchy::build(mesh.graph(), usize::from(args.levels))
        .with_context(|| format!("{source}: building the hierarchy"))?;
    if let Some(dir) = &args.out {
        write_levels(dir, &mesh, &h)?;
    }
    if args.json {
        let levels: Vec<_> = h
            .levels()
            .iter()
            .enumerate()
            .map(|(l, level)| {
                let mut o = json!({
                    "vertices": level.graph.vertex_count(),
                    "edges": level.graph.edge_count(),
                    "components": level.graph.components().count,
                });
                if l > 0 {
                    o["kept"] = json!(level.kept);
                }
                o
            })
            .collect();
        return emit(&json!({ "levels": levels }).to_string());
    }
    let mut out = String::new();
    writeln!(out, "{source}: {} levels", h.len())?;
    writeln!(out, "  level  vertices     edges  components")?;
    for (l, level) in h.levels().iter().enumerate() {
        writeln!(
            out,
            "  {l:>5}  {:>8}  {:>8}  {:>10}",
            level.graph.vertex_count(),
            level.graph.edge_count(),
            level.graph.components().count
        )?;
    }
    if usize::from(args.levels) > h.len() {
        writeln!(
            out,
            "  stopped at {} levels: every component is down to one vertex",
            h.len()
        )?;
    }
    if let Some(dir) = &args.out {
        writeln!(
            out,
            "  wrote level_0.ply … level_{}.ply to {}",
            h.len() - 1,
            dir.display()
        )?;
    }
    emit(&out)
}

/// Level 0 as the coloured mesh, coarser levels as coloured graphs (they have no faces);
/// orange marks the vertices the next level keeps.
fn write_levels(dir: &Path, mesh: &TriMesh, h: &Hierarchy) -> Result<()> {
    const KEPT: [u8; 3] = [240, 120, 20];
    const DROPPED: [u8; 3] = [150, 150, 160];
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create the output directory", dir.display()))?;
    for l in 0..h.len() {
        let n = h.levels()[l].graph.vertex_count();
        let mut colors = vec![DROPPED; n];
        if let Some(next) = h.levels().get(l + 1) {
            for &k in &next.kept {
                colors[k as usize] = KEPT;
            }
        } else {
            colors.fill(KEPT);
        }
        let path = dir.join(format!("level_{l}.ply"));
        if l == 0 {
            write_ply_colored(&path, mesh, &colors)?;
        } else {
            let positions: Vec<[f64; 3]> = h
                .finest_indices(l)
                .iter()
                .map(|&v| mesh.positions[v as usize])
                .collect();
            write_ply_graph(
                &path,
                &positions,
                &h.levels()[l].graph.edges(),
                Some(&colors),
            )?;
        }
    }
    Ok(())
}
