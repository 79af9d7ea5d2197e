//! The pictures of an evaluation report, drawn with weft-render: prediction, ground truth
//! and the LBS baseline side by side on a few frames, coloured by vertex error on one
//! shared scale; per-frame error curves; the attribution heat map of §4.1.
//!
//! One colour scale for every tile of a sheet (weft-render's shared ranges) is the point:
//! a reader compares colours across methods and frames, so the same millimetres must be
//! the same colour everywhere.

use weft_mesh::TriMesh;
use weft_render::{
    render, render_sequence, Colormap, Image, LinePlot, Paint, RenderOptions, ScalarPaint,
    ScalarRange, SceneMesh, Series, View, BODY_COLOR,
};

use crate::error::EvalError;
use crate::metrics::vertex_errors_mm;

/// Legend of error maps.
pub const ERROR_LABEL: &str = "vertex error (mm)";

fn f64s(p: &[[f32; 3]]) -> Vec<[f64; 3]> {
    p.iter().map(|v| v.map(f64::from)).collect()
}

/// One method's frames for [`comparison_sheet`].
pub struct MethodFrames<'a> {
    /// Column label ("Multilevel", "LBS only").
    pub name: &'a str,
    /// Vertices per frame (all frames of the sequence).
    pub frames: &'a [Vec<[f32; 3]>],
}

/// A sheet with one row per chosen frame and one column per method plus the ground
/// truth (first column), each garment over the posed body and coloured by its vertex
/// error against the truth in mm (zero for the truth itself), one scale for all tiles.
pub fn comparison_sheet(
    faces: &[[u32; 3]],
    truth: &[Vec<[f32; 3]>],
    methods: &[MethodFrames<'_>],
    bodies: Option<&[TriMesh]>,
    frames: &[usize],
    tile: u32,
    title: &str,
) -> Result<Image, EvalError> {
    let mut positions: Vec<Vec<[f64; 3]>> = Vec::new();
    let mut errors: Vec<Vec<f64>> = Vec::new();
    let mut labels = Vec::new();
    let mut body_index = Vec::new();
    for (row, &t) in frames.iter().enumerate() {
        let gt = truth.get(t).ok_or(EvalError::Count {
            what: "picture frame index vs ground-truth frames",
            expected: truth.len(),
            found: t,
        })?;
        positions.push(f64s(gt));
        errors.push(vec![0.0; gt.len()]);
        labels.push(format!("ground truth, frame {t}"));
        body_index.push(row);
        for m in methods {
            let p = m.frames.get(t).ok_or(EvalError::Count {
                what: "picture frame index vs predicted frames",
                expected: m.frames.len(),
                found: t,
            })?;
            positions.push(f64s(p));
            errors.push(vertex_errors_mm(p, gt)?);
            labels.push(format!("{}, frame {t}", m.name));
            body_index.push(row);
        }
    }
    let body_meshes: Vec<&TriMesh> = match bodies {
        Some(b) => frames
            .iter()
            .map(|&t| {
                b.get(t).ok_or(EvalError::Count {
                    what: "picture frame index vs posed bodies",
                    expected: b.len(),
                    found: t,
                })
            })
            .collect::<Result<_, _>>()?,
        None => Vec::new(),
    };
    let scenes: Vec<Vec<SceneMesh<'_>>> = positions
        .iter()
        .zip(&errors)
        .zip(&body_index)
        .map(|((p, e), &row)| {
            let mut scene = vec![SceneMesh::from_parts(
                "garment",
                p,
                faces,
                Paint::Scalars(ScalarPaint {
                    values: e,
                    colormap: Colormap::Viridis,
                    range: ScalarRange::Auto,
                    label: ERROR_LABEL,
                }),
            )];
            if let Some(b) = body_meshes.get(row) {
                scene.push(SceneMesh::new("body", b, Paint::Solid(BODY_COLOR)));
            }
            scene
        })
        .collect();
    let mut opts = RenderOptions::new(tile, tile);
    opts.view = View::Front;
    opts.title = Some(title.to_owned());
    let columns = 1 + methods.len() as u32;
    Ok(render_sequence(&scenes, &labels, &opts, Some(columns))?.image)
}

/// One garment over an optional body, coloured by per-vertex `values` (the error map of
/// one frame, an attribution), with `label` on the legend.
#[allow(clippy::too_many_arguments)]
pub fn heat_map(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    values: &[f64],
    colormap: Colormap,
    label: &str,
    body: Option<&TriMesh>,
    size: u32,
    title: &str,
) -> Result<Image, EvalError> {
    let mut scene = vec![SceneMesh::from_parts(
        "garment",
        positions,
        faces,
        Paint::Scalars(ScalarPaint {
            values,
            colormap,
            range: ScalarRange::Auto,
            label,
        }),
    )];
    if let Some(b) = body {
        scene.push(SceneMesh::new("body", b, Paint::Solid(BODY_COLOR)));
    }
    let mut opts = RenderOptions::new(size, size);
    opts.title = Some(title.to_owned());
    Ok(render(&scene, &opts)?.image)
}

/// The attribution heat map (§4.1, Fig. 3): `scores` per vertex on the diverging map
/// (white = no influence), with the analysed vertex marked by a small dark octahedron.
pub fn attribution_map(
    garment: &TriMesh,
    scores: &[f64],
    vertex: usize,
    size: u32,
    title: &str,
) -> Result<Image, EvalError> {
    let centre = *garment.positions.get(vertex).ok_or(EvalError::Count {
        what: "analysed vertex index vs garment vertices",
        expected: garment.vertex_count(),
        found: vertex,
    })?;
    let r = garment
        .bounding_box()
        .map_or(0.01, |b| 0.012 * weft_mesh::vec3::dist(b.min, b.max));
    let marker = TriMesh::new(
        [
            [r, 0.0, 0.0],
            [-r, 0.0, 0.0],
            [0.0, r, 0.0],
            [0.0, -r, 0.0],
            [0.0, 0.0, r],
            [0.0, 0.0, -r],
        ]
        .iter()
        .map(|d| weft_mesh::vec3::add(centre, *d))
        .collect(),
        vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ],
    );
    let scene = [
        SceneMesh::new(
            "garment",
            garment,
            Paint::Scalars(ScalarPaint {
                values: scores,
                colormap: Colormap::Diverging,
                range: ScalarRange::Auto,
                label: "attribution (normals)",
            }),
        ),
        SceneMesh::new("analysed vertex", &marker, Paint::Solid([20, 20, 20])),
    ];
    let mut opts = RenderOptions::new(size, size);
    opts.view = View::Front;
    opts.title = Some(title.to_owned());
    Ok(render(&scene, &opts)?.image)
}

/// Mean vertex error per frame, one line per method.
pub fn per_frame_plot(series: &[(&str, Vec<f64>)], title: &str) -> Result<Image, EvalError> {
    let plot = LinePlot::per_frame(
        title,
        "mean E_verts (mm)",
        series
            .iter()
            .map(|(name, v)| Series::from_values(*name, v))
            .collect(),
    );
    Ok(plot.render(900, 420)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use weft_mesh::primitives;

    #[test]
    fn sheet_and_maps_draw() {
        let m = primitives::cylinder(6, 12, 0.3, 0.05);
        let faces = m.faces.clone();
        let truth: Vec<Vec<[f32; 3]>> = (0..3)
            .map(|t| {
                m.positions
                    .iter()
                    .map(|p| [p[0] as f32, p[1] as f32 + 0.01 * t as f32, p[2] as f32])
                    .collect()
            })
            .collect();
        let pred: Vec<Vec<[f32; 3]>> = truth
            .iter()
            .map(|f| f.iter().map(|p| [p[0] + 0.004, p[1], p[2]]).collect())
            .collect();
        let methods = [MethodFrames {
            name: "model",
            frames: &pred,
        }];
        let img = comparison_sheet(&faces, &truth, &methods, None, &[0, 2], 160, "test").unwrap();
        assert!(img.width() >= 320 && img.height() >= 320);
        assert!(comparison_sheet(&faces, &truth, &methods, None, &[5], 160, "t").is_err());
        let scores: Vec<f64> = (0..m.vertex_count()).map(|i| i as f64 - 30.0).collect();
        let a = attribution_map(&m, &scores, 3, 200, "attribution").unwrap();
        assert_eq!(a.width(), 200);
        assert!(attribution_map(&m, &scores, 10_000, 200, "x").is_err());
        let p = per_frame_plot(&[("a", vec![1.0, 2.0, 1.5])], "errors").unwrap();
        assert_eq!(p.width(), 900);
    }
}
