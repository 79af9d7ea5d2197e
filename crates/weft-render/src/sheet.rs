//! Many pictures of one thing: a sequence of frames or a turntable of views, as a contact
//! sheet (a grid of tiles with labels) or as animation frames.
//!
//! Every tile shares one camera framing (the union of all frames' bounding boxes) and one
//! colour scale (automatic ranges are taken over all frames), so motion and error growth
//! read across tiles instead of being normalised away per frame. The legend is drawn
//! once, beside the grid.

use crate::camera::{Camera, View};
use crate::error::RenderError;
use crate::font::{Align, TextStyle};
use crate::image::{check_size, Image, Rgb};
use crate::legend::{Legend, INK};
use crate::render::{draw_meshes, empty, legend_of, overlay_text, RenderOptions, Rendered};
use crate::scene::{drawn_points, prepare, shared_ranges, MeshStats, Prepared, SceneMesh};

/// Colour of the lines between tiles.
const GRID_LINE: Rgb = [222, 222, 226];

/// Frames drawn with one camera and one colour scale, each a full picture with legend:
/// the frames of an animation (see [`encode_apng`](crate::encode_apng)).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderedFrames {
    /// One picture per frame, all `opts.width × opts.height`.
    pub frames: Vec<Image>,
    /// Per mesh index, summed over frames.
    pub meshes: Vec<MeshStats>,
}

/// Everything the frames of one sheet or animation share.
struct Shared<'a> {
    prepared: Vec<Vec<Prepared<'a>>>,
    ranges: Vec<Option<(f64, f64)>>,
    legend: Option<Legend<'a>>,
    /// Every drawn vertex of every frame: one framing for all.
    points: Vec<[f64; 3]>,
    stats: Vec<MeshStats>,
}

fn share<'a>(
    frames: &'a [Vec<SceneMesh<'a>>],
    opts: &RenderOptions,
) -> Result<Shared<'a>, RenderError> {
    opts.check()?;
    if frames.is_empty() {
        return Err(RenderError::Empty("the sequence has no frames".into()));
    }
    let prepared = frames
        .iter()
        .map(|f| prepare(f))
        .collect::<Result<Vec<_>, _>>()?;
    let views: Vec<&[SceneMesh<'a>]> = frames.iter().map(Vec::as_slice).collect();
    let ranges = shared_ranges(&views);
    let legend = opts
        .legend
        .then(|| frames.iter().find_map(|f| legend_of(f, &ranges)))
        .flatten();
    let points = drawn_points(prepared.iter().flatten());
    if points.is_empty() {
        let all: Vec<SceneMesh<'_>> = frames.iter().flatten().cloned().collect();
        return Err(empty(&all));
    }
    let stats = sum_stats(&prepared);
    Ok(Shared {
        prepared,
        ranges,
        legend,
        points,
        stats,
    })
}

impl Shared<'_> {
    /// The camera for `view` that frames every frame's drawn vertices.
    fn frame(&self, view: View, aspect: f64) -> Result<Camera, RenderError> {
        Camera::frame_points(view, &self.points, aspect)
            .ok_or_else(|| RenderError::Empty("no face has a finite vertex position".into()))
    }
}

/// Per mesh index, the statistics summed over frames (named after the first frame).
fn sum_stats(prepared: &[Vec<Prepared<'_>>]) -> Vec<MeshStats> {
    let mut out: Vec<MeshStats> = Vec::new();
    for frame in prepared {
        for (k, p) in frame.iter().enumerate() {
            if out.len() <= k {
                out.push(MeshStats {
                    name: p.stats.name.clone(),
                    ..MeshStats::default()
                });
            }
            let s = &mut out[k];
            s.nonfinite_positions += p.stats.nonfinite_positions;
            s.nonfinite_scalars += p.stats.nonfinite_scalars;
            s.error_faces += p.stats.error_faces;
            s.skipped_faces += p.stats.skipped_faces;
        }
    }
    out
}

/// A contact sheet of a sequence: `frames[i]` is the scene of frame `i` (mesh `k` of
/// every frame is the same object), drawn as `opts.width × opts.height` tiles in a grid
/// of `columns` (default: about square), each labelled with `labels[i]` (default:
/// `frame i`). `opts.title` heads the sheet.
pub fn render_sequence(
    frames: &[Vec<SceneMesh<'_>>],
    labels: &[String],
    opts: &RenderOptions,
    columns: Option<u32>,
) -> Result<Rendered, RenderError> {
    let shared = share(frames, opts)?;
    let aspect = f64::from(opts.width) / f64::from(opts.height);
    let camera = shared.frame(opts.view, aspect)?;
    let tiles: Vec<Tile<'_, '_>> = shared
        .prepared
        .iter()
        .enumerate()
        .map(|(i, p)| Tile {
            prepared: p,
            camera,
            label: labels
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("frame {i}")),
        })
        .collect();
    draw_sheet(&tiles, &shared, opts, columns, camera)
}

/// A turntable of one scene: `views` pictures from evenly spaced angles around the Y
/// axis (see [`View::turntable`]), as a contact sheet labelled with the azimuth.
pub fn render_turntable(
    meshes: &[SceneMesh<'_>],
    views: u32,
    opts: &RenderOptions,
    columns: Option<u32>,
) -> Result<Rendered, RenderError> {
    if !(1..=360).contains(&views) {
        return Err(RenderError::Invalid(format!(
            "a turntable of {views} views; expected 1 to 360"
        )));
    }
    let frames = vec![meshes.to_vec()];
    let shared = share(&frames, opts)?;
    let aspect = f64::from(opts.width) / f64::from(opts.height);
    let tiles: Vec<Tile<'_, '_>> = View::turntable(views)
        .into_iter()
        .map(|view| {
            let label = match view {
                View::Orbit { azimuth_deg, .. } => format!("{}°", azimuth_deg.round()),
                _ => String::new(),
            };
            Ok(Tile {
                prepared: &shared.prepared[0],
                camera: shared.frame(view, aspect)?,
                label,
            })
        })
        .collect::<Result<_, RenderError>>()?;
    let first = tiles[0].camera;
    draw_sheet(&tiles, &shared, opts, columns, first)
}

/// The frames of a sequence as separate full pictures (legend on each) with one camera
/// and one colour scale: for an animated PNG.
pub fn render_frames(
    frames: &[Vec<SceneMesh<'_>>],
    labels: &[String],
    opts: &RenderOptions,
) -> Result<RenderedFrames, RenderError> {
    let shared = share(frames, opts)?;
    let style = opts.text_style();
    let panel = shared
        .legend
        .map_or(0, |l| l.width(&style, opts.height, opts.width));
    let vw = opts.width - panel;
    let camera = shared.frame(opts.view, f64::from(vw) / f64::from(opts.height))?;
    let mut out = Vec::with_capacity(frames.len());
    for (i, p) in shared.prepared.iter().enumerate() {
        let view = draw_meshes(p, &shared.ranges, &camera, vw, opts.height, opts);
        let mut image = Image::new(opts.width, opts.height, opts.background);
        image.blit(&view, 0, 0);
        if let Some(l) = shared.legend {
            l.draw(&mut image, i64::from(vw), i64::from(panel), &style);
        }
        let stats: Vec<MeshStats> = p.iter().map(|q| q.stats.clone()).collect();
        let label = labels
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("frame {i}"));
        let title = match &opts.title {
            Some(t) => format!("{t} - {label}"),
            None => label,
        };
        overlay_text(&mut image, Some(&title), &stats, &style);
        out.push(image);
    }
    Ok(RenderedFrames {
        frames: out,
        meshes: shared.stats,
    })
}

/// One tile of a sheet.
struct Tile<'p, 'a> {
    prepared: &'p [Prepared<'a>],
    camera: Camera,
    label: String,
}

fn draw_sheet(
    tiles: &[Tile<'_, '_>],
    shared: &Shared<'_>,
    opts: &RenderOptions,
    columns: Option<u32>,
    camera: Camera,
) -> Result<Rendered, RenderError> {
    let n = u32::try_from(tiles.len()).unwrap_or(u32::MAX);
    let cols = columns
        .unwrap_or_else(|| (f64::from(n).sqrt().ceil()) as u32)
        .clamp(1, n.max(1));
    let rows = n.div_ceil(cols);
    let (tw, th) = (opts.width, opts.height);
    let tile_style = TextStyle::for_height(th.max(300), INK);
    let grid_h = rows.saturating_mul(th);
    let header = if opts.title.is_some() {
        tile_style.line_height() * 2
    } else {
        0
    };
    let sheet_style = TextStyle::for_height(grid_h, INK);
    let panel = shared.legend.map_or(0, |l| {
        l.width(
            &sheet_style,
            grid_h,
            cols.saturating_mul(tw).saturating_mul(3) / 2,
        )
    });
    let width = cols.saturating_mul(tw).saturating_add(panel);
    let height = grid_h.saturating_add(header);
    check_size(width, height)?;
    let mut sheet = Image::new(width, height, opts.background);
    let header = i64::from(header);
    for (i, tile) in tiles.iter().enumerate() {
        let (c, r) = (i as u32 % cols, i as u32 / cols);
        let (x, y) = (i64::from(c * tw), header + i64::from(r * th));
        let img = draw_meshes(tile.prepared, &shared.ranges, &tile.camera, tw, th, opts);
        sheet.blit(&img, x, y);
        let m = i64::from(tile_style.char_width());
        tile_style.draw(
            &mut sheet,
            x + m / 2 + 2,
            y + m / 2,
            Align::Left,
            &tile.label,
        );
        if c > 0 {
            sheet.fill_rect(x, y, 1, i64::from(th), GRID_LINE);
        }
        if r > 0 {
            sheet.fill_rect(x, y, i64::from(tw), 1, GRID_LINE);
        }
    }
    if let Some(l) = shared.legend {
        // The legend panel spans the grid, below the header.
        let mut panel_img = Image::new(panel.max(1), grid_h.max(1), opts.background);
        l.draw(&mut panel_img, 0, i64::from(panel), &sheet_style);
        sheet.blit(&panel_img, i64::from(cols * tw), header);
    }
    if let Some(t) = &opts.title {
        let m = i64::from(tile_style.char_width());
        tile_style.draw(&mut sheet, m, header / 4, Align::Left, t);
    }
    overlay_text(&mut sheet, None, &shared.stats, &sheet_style);
    Ok(Rendered {
        image: sheet,
        meshes: shared.stats.clone(),
        camera,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colormap::{Colormap, ScalarRange};
    use crate::scene::{Paint, ScalarPaint, GARMENT_COLOR};
    use weft_mesh::primitives::cylinder;
    use weft_mesh::TriMesh;

    fn frames(n: usize) -> Vec<TriMesh> {
        (0..n)
            .map(|f| {
                let mut m = cylinder(8, 20, 0.3, 0.05);
                for p in &mut m.positions {
                    p[0] += 0.05 * f as f64;
                }
                m
            })
            .collect()
    }

    #[test]
    fn sheet_has_a_tile_per_frame_and_a_shared_legend() {
        let meshes = frames(5);
        let values: Vec<Vec<f64>> = (0..5)
            .map(|f| {
                (0..meshes[0].vertex_count())
                    .map(|i| (i * f) as f64)
                    .collect()
            })
            .collect();
        let scenes: Vec<Vec<SceneMesh<'_>>> = meshes
            .iter()
            .zip(&values)
            .map(|(m, v)| {
                vec![SceneMesh::new(
                    "g",
                    m,
                    Paint::Scalars(ScalarPaint {
                        values: v,
                        colormap: Colormap::Viridis,
                        range: ScalarRange::Auto,
                        label: "e",
                    }),
                )]
            })
            .collect();
        let opts = RenderOptions::new(60, 80);
        let r = render_sequence(&scenes, &[], &opts, None).unwrap();
        // 3 columns × 2 rows of 60 × 80, plus a legend panel.
        assert!(r.image.width() > 180 && r.image.width() <= 180 + 120);
        assert_eq!(r.image.height(), 160);
        assert_eq!(r.meshes.len(), 1);
        let again = render_sequence(&scenes, &[], &opts, None).unwrap();
        assert_eq!(r.image, again.image);
        let anim = render_frames(&scenes, &[], &opts).unwrap();
        assert_eq!(anim.frames.len(), 5);
        assert_ne!(anim.frames[0], anim.frames[4]);
    }

    #[test]
    fn turntable_and_errors() {
        let m = cylinder(8, 20, 0.3, 0.05);
        let scene = [SceneMesh::new("g", &m, Paint::Solid(GARMENT_COLOR))];
        let r = render_turntable(&scene, 4, &RenderOptions::new(50, 50), Some(4)).unwrap();
        assert_eq!((r.image.width(), r.image.height()), (200, 50));
        assert!(render_turntable(&scene, 0, &RenderOptions::new(50, 50), None).is_err());
        let e = render_sequence(&[], &[], &RenderOptions::new(50, 50), None).unwrap_err();
        assert!(e.to_string().contains("no frames"));
        let big = render_sequence(
            &[scene.to_vec(), scene.to_vec()],
            &[],
            &RenderOptions::new(16_000, 100),
            Some(2),
        );
        assert!(matches!(big, Err(RenderError::Size { .. })));
    }
}
