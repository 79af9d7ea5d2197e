//! One picture of a scene: framing, rasterising with supersampling, and the overlays
//! (colour-bar legend, title, a note when data was not finite).

use crate::camera::{Camera, View};
use crate::colormap::{normalize as norm_scalar, ERROR_COLOR};
use crate::error::RenderError;
use crate::font::{Align, TextStyle};
use crate::image::{check_size, Image, Rgb};
use crate::legend::{Legend, INK};
use crate::math::{dot, normalize, scale, sub};
use crate::raster::Target;
use crate::scene::{
    drawn_points, prepare, shared_ranges, FaceKind, MeshStats, Paint, Prepared, SceneMesh,
};
use crate::shading::{face_normal, lit, Shading};

/// Text colour of the note about non-finite data: a darker magenta than the error colour,
/// readable on white.
const NOTE_COLOR: Rgb = [176, 0, 176];

/// How to draw a picture.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Width in pixels (1 to [`MAX_SIDE`](crate::MAX_SIDE)).
    pub width: u32,
    /// Height in pixels (1 to [`MAX_SIDE`](crate::MAX_SIDE)).
    pub height: u32,
    /// Where the camera looks from; it frames all meshes automatically.
    pub view: View,
    /// Background colour.
    pub background: Rgb,
    /// Samples per pixel along each axis (1 to 4): 2 draws at twice the size and
    /// averages, which smooths silhouettes at four times the raster cost.
    pub supersample: u32,
    /// Draw a colour-bar legend when a mesh has scalar paint (the first such mesh's).
    pub legend: bool,
    /// A title at the top left.
    pub title: Option<String>,
}

impl Default for RenderOptions {
    /// 1024 × 1024, three-quarter view, white, 2 × 2 supersampling, legend on.
    fn default() -> Self {
        RenderOptions {
            width: 1024,
            height: 1024,
            view: View::ThreeQuarter,
            background: [255, 255, 255],
            supersample: 2,
            legend: true,
            title: None,
        }
    }
}

impl RenderOptions {
    /// The defaults at `width × height`.
    pub fn new(width: u32, height: u32) -> Self {
        RenderOptions {
            width,
            height,
            ..Self::default()
        }
    }

    pub(crate) fn check(&self) -> Result<(), RenderError> {
        check_size(self.width, self.height)?;
        if !(1..=4).contains(&self.supersample) {
            return Err(RenderError::Invalid(format!(
                "supersample is {}; expected 1 to 4 samples per pixel side",
                self.supersample
            )));
        }
        Ok(())
    }

    /// The text style for overlays on a picture of this height.
    pub(crate) fn text_style(&self) -> TextStyle {
        TextStyle::for_height(self.height, INK)
    }
}

/// A drawn picture and what drawing it found.
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    /// The picture.
    pub image: Image,
    /// Per mesh (in scene order; for sequences, summed over frames): non-finite data and
    /// what was done with it.
    pub meshes: Vec<MeshStats>,
    /// The camera used (for the first view of a sheet).
    pub camera: Camera,
}

impl Rendered {
    /// Non-finite positions and scalars over all meshes: what the magenta shows.
    pub fn nonfinite_values(&self) -> usize {
        self.meshes
            .iter()
            .map(|m| m.nonfinite_positions + m.nonfinite_scalars)
            .sum()
    }
}

/// Draws `meshes` (later ones may hide earlier ones; order does not matter for the depth
/// test) as one picture.
///
/// Fails on bad indices, a scalar count that is not the vertex count, bad options, or
/// when no face has a usable position. Non-finite data is drawn in
/// [`ERROR_COLOR`](crate::ERROR_COLOR) and counted in [`Rendered::meshes`].
pub fn render(meshes: &[SceneMesh<'_>], opts: &RenderOptions) -> Result<Rendered, RenderError> {
    opts.check()?;
    let prepared = prepare(meshes)?;
    let ranges = shared_ranges(&[meshes]);
    let style = opts.text_style();
    let legend = opts.legend.then(|| legend_of(meshes, &ranges)).flatten();
    let panel = legend.map_or(0, |l| l.width(&style, opts.height, opts.width));
    let vw = opts.width - panel;
    let points = drawn_points(&prepared);
    let camera = Camera::frame_points(opts.view, &points, f64::from(vw) / f64::from(opts.height))
        .ok_or_else(|| empty(meshes))?;
    let view = draw_meshes(&prepared, &ranges, &camera, vw, opts.height, opts);
    let mut image = Image::new(opts.width, opts.height, opts.background);
    image.blit(&view, 0, 0);
    if let Some(l) = legend {
        l.draw(&mut image, i64::from(vw), i64::from(panel), &style);
    }
    let stats: Vec<MeshStats> = prepared.into_iter().map(|p| p.stats).collect();
    overlay_text(&mut image, opts.title.as_deref(), &stats, &style);
    Ok(Rendered {
        image,
        meshes: stats,
        camera,
    })
}

/// The error for a scene without a single drawable face.
pub(crate) fn empty(meshes: &[SceneMesh<'_>]) -> RenderError {
    if meshes.iter().all(|m| m.faces.is_empty()) {
        RenderError::Empty("the scene has no faces".into())
    } else {
        RenderError::Empty("no face has a finite vertex position".into())
    }
}

/// The legend of the first mesh with scalar paint.
pub(crate) fn legend_of<'a>(
    meshes: &'a [SceneMesh<'a>],
    ranges: &[Option<(f64, f64)>],
) -> Option<Legend<'a>> {
    meshes.iter().zip(ranges).find_map(|(m, r)| {
        let s = m.scalars()?;
        Some(Legend {
            colormap: s.colormap,
            range: (*r)?,
            label: s.label,
        })
    })
}

/// Title at the top left; at the bottom left, how many values were not finite.
pub(crate) fn overlay_text(
    img: &mut Image,
    title: Option<&str>,
    stats: &[MeshStats],
    style: &TextStyle,
) {
    let m = i64::from(style.char_width());
    if let Some(t) = title {
        style.draw(img, m, m / 2 + 2, Align::Left, t);
    }
    let positions: usize = stats.iter().map(|s| s.nonfinite_positions).sum();
    let scalars: usize = stats.iter().map(|s| s.nonfinite_scalars).sum();
    let mut parts = Vec::new();
    if positions > 0 {
        parts.push(format!("{positions} non-finite positions"));
    }
    if scalars > 0 {
        parts.push(format!("{scalars} non-finite values"));
    }
    if !parts.is_empty() {
        let note = format!("{} (magenta)", parts.join(", "));
        let y = i64::from(img.height()) - i64::from(style.line_height()) - m / 2;
        TextStyle {
            color: NOTE_COLOR,
            ..*style
        }
        .draw(img, m, y, Align::Left, &note);
    }
}

/// Rasterises the prepared meshes through `camera` into a `width × height` picture
/// (supersampled as `opts` says) on the background colour.
pub(crate) fn draw_meshes(
    prepared: &[Prepared<'_>],
    ranges: &[Option<(f64, f64)>],
    camera: &Camera,
    width: u32,
    height: u32,
    opts: &RenderOptions,
) -> Image {
    let ss = opts.supersample.clamp(1, 4);
    let (tw, th) = (width.max(1) * ss, height.max(1) * ss);
    let mut target = Target::new(tw, th, opts.background);
    let proj = camera.projector(f64::from(tw), f64::from(th));
    let to_eye = scale(proj.forward, -1.0);
    for (k, p) in prepared.iter().enumerate() {
        let screen: Vec<Option<[f64; 3]>> = p.positions.iter().map(|&q| proj.project(q)).collect();
        let range = ranges.get(k).copied().flatten().unwrap_or((0.0, 1.0));
        let (lut, ts) = match &p.mesh.paint {
            Paint::Scalars(s) => (
                Some(s.colormap.lut()),
                s.values.iter().map(|&v| norm_scalar(v, range)).collect(),
            ),
            Paint::Solid(_) => (None, Vec::new()),
        };
        let solid = match p.mesh.paint {
            Paint::Solid(c) => c,
            Paint::Scalars(_) => ERROR_COLOR,
        };
        for (f, kind) in p.mesh.faces.iter().zip(&p.face_kind) {
            if *kind == FaceKind::Skip {
                continue;
            }
            let idx = f.map(|i| i as usize);
            let (Some(a), Some(b), Some(c)) = (screen[idx[0]], screen[idx[1]], screen[idx[2]])
            else {
                continue;
            };
            if *kind == FaceKind::Error {
                // Unlit, so it cannot be mistaken for a shaded colour of any map.
                target.triangle([a, b, c], |_| ERROR_COLOR);
                continue;
            }
            let corners = idx.map(|i| p.positions[i]);
            let fnrm = normalize(face_normal(corners[0], corners[1], corners[2]));
            let back = dot(fnrm, sub(proj.eye, corners[0])) < 0.0;
            let sign = if back { -1.0 } else { 1.0 };
            let vn = idx.map(|i| p.normals[i]);
            let vt = if lut.is_some() {
                idx.map(|i| ts[i])
            } else {
                [0.0; 3]
            };
            target.triangle([a, b, c], |w| {
                let base = match &lut {
                    Some(lut) => {
                        let t = (w[0] * vt[0] + w[1] * vt[1] + w[2] * vt[2]).clamp(0.0, 1.0);
                        lut[(t * 255.0).round() as usize]
                    }
                    None => solid,
                };
                let n = match p.mesh.shading {
                    Shading::Flat => fnrm,
                    Shading::Smooth => {
                        let s =
                            [0, 1, 2].map(|k| w[0] * vn[0][k] + w[1] * vn[1][k] + w[2] * vn[2][k]);
                        let s = normalize(s);
                        if s == [0.0; 3] {
                            fnrm
                        } else {
                            s
                        }
                    }
                };
                lit(base, sign * dot(n, to_eye), back)
            });
        }
    }
    target.resolve(ss)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colormap::{Colormap, ScalarRange};
    use crate::scene::{ScalarPaint, GARMENT_COLOR};
    use weft_mesh::primitives::{cylinder, grid};

    fn opts(w: u32, h: u32) -> RenderOptions {
        RenderOptions {
            view: View::Front,
            ..RenderOptions::new(w, h)
        }
    }

    fn count(img: &Image, pred: impl Fn(&[u8]) -> bool) -> usize {
        img.as_bytes().chunks(3).filter(|p| pred(p)).count()
    }

    #[test]
    fn a_solid_cylinder_fills_the_middle_and_not_the_corners() {
        let m = cylinder(10, 24, 0.3, 0.05);
        let r = render(
            &[SceneMesh::new("c", &m, Paint::Solid(GARMENT_COLOR))],
            &opts(64, 64),
        )
        .unwrap();
        let img = &r.image;
        assert_eq!(img.get(0, 0), Some([255; 3]));
        let mid = img.get(32, 32).unwrap();
        assert!(mid != [255; 3] && mid[2] > mid[0], "{mid:?}");
        assert_eq!(r.nonfinite_values(), 0);
    }

    #[test]
    fn rendering_is_deterministic() {
        let m = cylinder(12, 30, 0.3, 0.04);
        let v: Vec<f64> = (0..m.vertex_count())
            .map(|i| (i as f64 * 0.37).sin())
            .collect();
        let scene = [SceneMesh::new(
            "c",
            &m,
            Paint::Scalars(ScalarPaint {
                values: &v,
                colormap: Colormap::Diverging,
                range: ScalarRange::Auto,
                label: "signed (m)",
            }),
        )];
        let o = RenderOptions::new(160, 120);
        let a = render(&scene, &o).unwrap().image.encode_png().unwrap();
        let b = render(&scene, &o).unwrap().image.encode_png().unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn the_garment_hides_the_body_behind_it() {
        let garment = cylinder(10, 40, 0.3, 0.05);
        let body = cylinder(10, 40, 0.2, 0.05);
        let scene = [
            SceneMesh::new("body", &body, Paint::Solid([255, 0, 0])),
            SceneMesh::new("garment", &garment, Paint::Solid([0, 0, 255])),
        ];
        let img = render(&scene, &opts(80, 80)).unwrap().image;
        // The body's red never shows through the closed front of the tube.
        let red = count(&img, |p| u16::from(p[0]) > u16::from(p[2]) + 30);
        assert_eq!(red, 0);
        // Drawn alone, it does.
        let img = render(&scene[..1], &opts(80, 80)).unwrap().image;
        assert!(count(&img, |p| u16::from(p[0]) > u16::from(p[2]) + 30) > 100);
    }

    #[test]
    fn nan_scalars_and_positions_show_magenta_and_are_counted() {
        let mut m = grid(20, 20, 0.05);
        for p in &mut m.positions {
            // Stand the grid up to face the front camera.
            p.swap(1, 2);
        }
        let mut v: Vec<f64> = (0..m.vertex_count()).map(|i| i as f64).collect();
        v[45] = f64::NAN;
        m.positions[300][0] = f64::NAN;
        let scene = [SceneMesh::new(
            "g",
            &m,
            Paint::Scalars(ScalarPaint {
                values: &v,
                colormap: Colormap::Viridis,
                range: ScalarRange::Auto,
                label: "v",
            }),
        )];
        let r = render(&scene, &opts(200, 160)).unwrap();
        assert_eq!(r.meshes[0].nonfinite_scalars, 1);
        assert_eq!(r.meshes[0].nonfinite_positions, 1);
        assert_eq!(r.nonfinite_values(), 2);
        let magenta = count(&r.image, |p| p == ERROR_COLOR);
        assert!(magenta > 20, "{magenta}");
    }

    #[test]
    fn bad_options_and_empty_scenes_are_errors() {
        let m = grid(2, 2, 1.0);
        let scene = [SceneMesh::new("g", &m, Paint::Solid(GARMENT_COLOR))];
        assert!(render(&scene, &opts(0, 10)).is_err());
        let o = RenderOptions {
            supersample: 9,
            ..opts(10, 10)
        };
        assert!(render(&scene, &o)
            .unwrap_err()
            .to_string()
            .contains("supersample"));
        let e = render(&[], &opts(10, 10)).unwrap_err();
        assert_eq!(e.to_string(), "nothing to draw: the scene has no faces");
        let mut bad = grid(2, 2, 1.0);
        bad.positions.iter_mut().for_each(|p| p[1] = f64::NAN);
        let scene = [SceneMesh::new("g", &bad, Paint::Solid(GARMENT_COLOR))];
        let e = render(&scene, &opts(10, 10)).unwrap_err();
        assert!(e.to_string().contains("no face has a finite"), "{e}");
    }
}
