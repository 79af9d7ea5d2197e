//! Writes one of each picture weft-render makes into a directory, for looking at them:
//! `cargo run -p weft-render --example gallery -- OUT_DIR`.

use std::path::PathBuf;

use weft_render::{
    render, render_frames, render_sequence, render_turntable, write_apng, Colormap, Histogram,
    HistogramSeries, LinePlot, Paint, RenderOptions, Report, ScalarPaint, ScalarRange, SceneMesh,
    Series, View, BODY_COLOR,
};

/// A 1-D little-endian float64 `.npy` file.
fn write_npy_f64(path: &std::path::Path, values: &[f64]) -> std::io::Result<()> {
    let mut header = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({},), }}",
        values.len()
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    weft_mesh::io::write_atomic(path, |w| w.write_all(&bytes))
}

#[path = "../tests/support/mod.rs"]
mod support;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "gallery".into()));
    std::fs::create_dir_all(&out)?;
    let body = support::mannequin();
    let skirt = support::skirt(60, 160);
    let error = support::fake_error_mm(&skirt);
    let paint = |values, colormap, label| {
        Paint::Scalars(ScalarPaint {
            values,
            colormap,
            range: ScalarRange::Auto,
            label,
        })
    };
    let scene = [
        SceneMesh::new("body", &body, Paint::Solid(BODY_COLOR)),
        SceneMesh::new(
            "skirt",
            &skirt,
            paint(&error, Colormap::Viridis, "vertex error (mm)"),
        ),
    ];
    for (name, view) in [
        ("three_quarter", View::ThreeQuarter),
        ("front", View::Front),
        ("side", View::Side),
    ] {
        let opts = RenderOptions {
            view,
            title: Some(format!("skirt over body, {name}")),
            ..RenderOptions::default()
        };
        render(&scene, &opts)?
            .image
            .write_png(&out.join(format!("{name}.png")))?;
    }

    let signed: Vec<f64> = skirt
        .positions
        .iter()
        .map(|p| p[0] * 40.0 - p[2] * 10.0)
        .collect();
    let attribution = [
        SceneMesh::new("body", &body, Paint::Solid(BODY_COLOR)),
        SceneMesh::new(
            "skirt",
            &skirt,
            paint(&signed, Colormap::Diverging, "attribution"),
        ),
    ];
    render(&attribution, &RenderOptions::new(800, 800))?
        .image
        .write_png(&out.join("diverging.png"))?;

    let mut broken = error.clone();
    for v in broken.iter_mut().skip(3000).take(400) {
        *v = f64::NAN;
    }
    let mut bad_skirt = skirt.clone();
    bad_skirt.positions[5000][1] = f64::INFINITY;
    let nan_scene = [
        SceneMesh::new("body", &body, Paint::Solid(BODY_COLOR)),
        SceneMesh::new(
            "skirt",
            &bad_skirt,
            paint(&broken, Colormap::Viridis, "vertex error (mm)"),
        ),
    ];
    let r = render(&nan_scene, &RenderOptions::new(600, 600))?;
    println!("nan.png: {} non-finite values", r.nonfinite_values());
    r.image.write_png(&out.join("nan.png"))?;

    render_turntable(&scene, 8, &RenderOptions::new(300, 400), Some(4))?
        .image
        .write_png(&out.join("turntable.png"))?;

    // A swinging skirt: 12 frames.
    let frames: Vec<_> = (0..12)
        .map(|f| {
            let mut m = skirt.clone();
            let a = 0.25 * (f as f64 * 0.6).sin();
            for p in &mut m.positions {
                let t = (1.0 - p[1]) / 0.5;
                p[0] += a * t * t * 0.3;
                p[1] += a.abs() * t * t * 0.05;
            }
            m
        })
        .collect();
    let errors: Vec<Vec<f64>> = frames
        .iter()
        .enumerate()
        .map(|(f, m)| {
            support::fake_error_mm(m)
                .iter()
                .map(|e| e * (0.5 + f as f64 / 12.0))
                .collect()
        })
        .collect();
    let scenes: Vec<Vec<SceneMesh<'_>>> = frames
        .iter()
        .zip(&errors)
        .map(|(m, e)| {
            vec![
                SceneMesh::new("body", &body, Paint::Solid(BODY_COLOR)),
                SceneMesh::new("skirt", m, paint(e, Colormap::Viridis, "vertex error (mm)")),
            ]
        })
        .collect();
    let sheet_opts = RenderOptions {
        view: View::Front,
        title: Some("swinging skirt, frames 0-11".into()),
        ..RenderOptions::new(256, 320)
    };
    render_sequence(&scenes, &[], &sheet_opts, Some(6))?
        .image
        .write_png(&out.join("sequence.png"))?;
    let anim = render_frames(&scenes, &[], &RenderOptions::new(400, 400))?;
    write_apng(&out.join("sequence_anim.png"), &anim.frames, 8)?;

    let curves = LinePlot {
        title: "training losses".into(),
        x_label: "step".into(),
        y_label: "loss".into(),
        series: ["vertex", "edge", "normal", "collision"]
            .iter()
            .enumerate()
            .map(|(k, name)| {
                Series::new(
                    *name,
                    (0..400)
                        .map(|s| {
                            let s = f64::from(s) * 25.0;
                            let noise = 1.0 + 0.15 * ((s * 0.37 + k as f64).sin());
                            (
                                s,
                                (0.5 / (k as f64 + 1.0))
                                    * (1.0 + s / 500.0).powf(-1.2 - 0.2 * k as f64)
                                    * noise,
                            )
                        })
                        .collect(),
                )
            })
            .collect(),
        log_y: true,
    };
    curves
        .render(900, 540)?
        .write_png(&out.join("curves.png"))?;
    let per_frame = LinePlot::per_frame(
        "per-frame vertex error",
        "E_verts (mm)",
        vec![
            Series::from_values(
                "multilevel",
                &(0..200)
                    .map(|f| 8.0 + 3.0 * (f64::from(f) * 0.1).sin())
                    .collect::<Vec<_>>(),
            ),
            Series::from_values(
                "single-level",
                &(0..200)
                    .map(|f| 12.0 + 4.0 * (f64::from(f) * 0.1 + 0.5).sin())
                    .collect::<Vec<_>>(),
            ),
            Series::from_values(
                "TopKPool",
                &(0..200)
                    .map(|f| 15.0 + 5.0 * (f64::from(f) * 0.07).cos())
                    .collect::<Vec<_>>(),
            ),
        ],
    );
    per_frame
        .render(900, 400)?
        .write_png(&out.join("per_frame.png"))?;
    let hist = Histogram {
        title: "per-vertex error".into(),
        x_label: "error (mm)".into(),
        y_label: "fraction of vertices".into(),
        series: vec![
            HistogramSeries {
                name: "multilevel".into(),
                values: error.clone(),
            },
            HistogramSeries {
                name: "single-level".into(),
                values: error.iter().map(|e| e * 1.4 + 2.0).collect(),
            },
        ],
        normalize: true,
        ..Histogram::default()
    };
    hist.render(900, 500)?
        .write_png(&out.join("histogram.png"))?;

    let mut report = Report::new("weft-render gallery");
    report.paragraph("Every kind of picture weft-render draws, in one self-contained page.");
    report.heading("Garment over body");
    report.image(
        &render(&scene, &RenderOptions::new(640, 640))?.image,
        "vertex error, three-quarter view",
    )?;
    report.heading("Training");
    report.image(&curves.render(900, 540)?, "training losses (log scale)")?;
    report.table(
        ["method", "E_verts (mm)", "E_norm (°)"],
        [
            ["multilevel", "8.1", "6.2"],
            ["single-level", "12.3", "8.9"],
        ],
    );
    report.png(
        weft_render::encode_apng(&anim.frames[..6], 6)?,
        "animation (APNG)",
    )?;
    report.write(&out.join("report.html"))?;

    // Inputs for trying `weft render` by hand.
    weft_mesh::io::write_obj(&out.join("body.obj"), &body)?;
    weft_mesh::io::write_obj(&out.join("skirt.obj"), &skirt)?;
    write_npy_f64(&out.join("skirt_error_mm.npy"), &error)?;
    println!("wrote {}", out.display());
    Ok(())
}
