//! Refinement runs (DenseGATs, MultiResGNet) and the LBS and DQS baselines against the
//! ground truth of a character dataset split, in centimetres as seed 001 reports them:
//! per character the mean, max and min per-vertex distance over every pose (Table 3.2),
//! every method side by side (Tables 3.3 and 3.4), and the error histogram of Fig. 3.9.
//!
//! Baselines use the same coarse deformation the models start from: LBS (and DQS) with
//! the top-k influences renormalised, k from each run (8 for DenseGATs, 4 for
//! MultiResGNet). `translation` moves the root of every pose (Fig. 3.23's test: the same
//! poses away from the origin; the truth moves rigidly with it).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use weft_body::Skinning;
use weft_data::characters::CharacterSet;
use weft_data::Split;
use weft_eval::metrics::vertex_errors_mm;
use weft_eval::pictures::{comparison_sheet, MethodFrames};
use weft_models::refine::{Character, RefinePredictor};
use weft_render::Image;
use weft_train::tasks::refine::rig_of;

use crate::error::PipelineError;

/// Upper edges of the histogram bins, cm (the last bin holds everything above 2 cm).
pub const HISTOGRAM_EDGES_CM: [f64; 8] = [0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 2.0];

/// The joints whose blend regions the tables report apart (SMPL's numbering, left and
/// right): where LBS collapses and bulges, which the thesis's corrections are about, so
/// their error is not drowned by the rest of the mesh.
pub const JOINT_REGIONS: [(&str, [usize; 2]); 4] = [
    ("elbows", [18, 19]),
    ("knees", [4, 5]),
    ("shoulders", [16, 17]),
    ("hips", [1, 2]),
];

/// A vertex belongs to a joint's region when both the joint and its parent weigh at
/// least this on it: the blend ring around the joint.
pub const REGION_MIN_WEIGHT: f32 = 0.1;

/// The vertices of each of [`JOINT_REGIONS`] on a rig with `parents` and dense
/// `weights` (row-major `N × S`); empty regions for a skeleton other than SMPL's 24
/// joints.
pub fn joint_regions(weights: &[f32], parents: &[Option<usize>]) -> Vec<Vec<usize>> {
    let s = parents.len();
    JOINT_REGIONS
        .iter()
        .map(|(_, joints)| {
            if s != 24 {
                return Vec::new();
            }
            (0..weights.len() / s)
                .filter(|&v| {
                    let row = &weights[v * s..(v + 1) * s];
                    joints.iter().any(|&j| {
                        parents[j].is_some_and(|p| {
                            row[j] >= REGION_MIN_WEIGHT && row[p] >= REGION_MIN_WEIGHT
                        })
                    })
                })
                .collect()
        })
        .collect()
}

/// Errors of one method on one character, cm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CharacterErrors {
    /// The character's id.
    pub id: String,
    /// Its vertices.
    pub vertices: usize,
    /// Poses evaluated.
    pub poses: usize,
    /// Mean per-vertex distance over every pose.
    pub mean_cm: f64,
    /// Largest per-vertex distance.
    pub max_cm: f64,
    /// Smallest per-vertex distance.
    pub min_cm: f64,
}

/// One method over the split.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodErrors {
    /// Its name in the tables.
    pub name: String,
    /// Per character.
    pub characters: Vec<CharacterErrors>,
    /// Over every vertex of every pose of every character.
    pub mean_cm: f64,
    /// Largest.
    pub max_cm: f64,
    /// Smallest.
    pub min_cm: f64,
    /// Vertex counts per bin of [`HISTOGRAM_EDGES_CM`] (one more bin above the last edge).
    pub histogram: Vec<u64>,
    /// Milliseconds per frame (whole mesh), for learned methods.
    pub ms_per_frame: Option<f64>,
    /// Mean per-vertex distance over the vertices of each of [`JOINT_REGIONS`], in its
    /// order (NaN where no character has the region).
    pub regions_cm: Vec<f64>,
}

/// Every method on one split.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CharacterTable {
    /// The dataset directory.
    pub data: PathBuf,
    /// The split.
    pub split: String,
    /// Root translation applied to every pose (m).
    pub translation: [f64; 3],
    /// The methods, baselines first.
    pub methods: Vec<MethodErrors>,
}

#[derive(Default)]
struct Accumulator {
    sum: f64,
    count: usize,
    max: f64,
    min: f64,
    histogram: Vec<u64>,
    /// Summed distance and vertex count per joint region of [`JOINT_REGIONS`].
    regions: Vec<(f64, usize)>,
}

impl Accumulator {
    fn new() -> Self {
        Accumulator {
            min: f64::INFINITY,
            histogram: vec![0; HISTOGRAM_EDGES_CM.len() + 1],
            regions: vec![(0.0, 0); JOINT_REGIONS.len()],
            ..Default::default()
        }
    }

    /// Adds the distances of `predicted` to `truth` moved by `shift` (cm), over the
    /// whole mesh and over each region's vertices (`regions`, from [`joint_regions`]).
    fn add(
        &mut self,
        predicted: &[[f64; 3]],
        truth: &[[f32; 3]],
        shift: [f64; 3],
        regions: &[Vec<usize>],
    ) {
        let distances: Vec<f64> = predicted
            .iter()
            .zip(truth)
            .map(|(p, t)| {
                (0..3)
                    .map(|k| (p[k] - (f64::from(t[k]) + shift[k])).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    * 100.0
            })
            .collect();
        for &d in &distances {
            self.sum += d;
            self.count += 1;
            self.max = self.max.max(d);
            self.min = self.min.min(d);
            let bin = HISTOGRAM_EDGES_CM
                .iter()
                .position(|&e| d <= e)
                .unwrap_or(HISTOGRAM_EDGES_CM.len());
            self.histogram[bin] += 1;
        }
        for (region, (sum, count)) in regions.iter().zip(&mut self.regions) {
            *sum += region.iter().map(|&v| distances[v]).sum::<f64>();
            *count += region.len();
        }
    }

    fn merge(&mut self, other: &Accumulator) {
        self.sum += other.sum;
        self.count += other.count;
        self.max = self.max.max(other.max);
        self.min = self.min.min(other.min);
        for (a, b) in self.histogram.iter_mut().zip(&other.histogram) {
            *a += b;
        }
        for ((sum, count), (s, c)) in self.regions.iter_mut().zip(&other.regions) {
            *sum += s;
            *count += c;
        }
    }

    /// Mean distance per region, NaN where no vertex was in it.
    fn region_means(&self) -> Vec<f64> {
        self.regions
            .iter()
            .map(|&(sum, count)| {
                if count == 0 {
                    f64::NAN
                } else {
                    sum / count as f64
                }
            })
            .collect()
    }

    fn mean(&self) -> f64 {
        self.sum / self.count.max(1) as f64
    }
}

/// How a method deforms a character into a pose.
enum Method {
    Baseline(Skinning, usize),
    Run(Box<RefinePredictor>, String),
}

impl Method {
    fn name(&self) -> String {
        match self {
            Method::Baseline(s, k) => format!("{} ({k} influences)", s.to_string().to_uppercase()),
            Method::Run(_, name) => name.clone(),
        }
    }

    fn influences(&self) -> usize {
        match self {
            Method::Baseline(_, k) => *k,
            Method::Run(p, _) => p.influences(),
        }
    }
}

/// Radius around a joint's rest position of the close-up pictures (m): the blend ring
/// and a few centimetres of each limb.
pub const CLOSE_UP_RADIUS: f64 = 0.12;

/// Evaluates `runs` (each named by its directory name) and the LBS/DQS baselines on the
/// `split` characters of the dataset in `data`, every pose moved by `translation`; with
/// the table, pictures named by file stem: `characters`, the split's first character in
/// the two poses where LBS is worst, and a close-up per joint pair of
/// [`JOINT_REGIONS`] (`elbows`, `knees`, …): the left joint's surroundings in the two
/// poses where LBS is worst there. Each shows the truth, then every method coloured by
/// its distance to the truth on one scale.
pub fn evaluate_characters(
    runs: &[PathBuf],
    data: &Path,
    split: Split,
    translation: [f64; 3],
) -> Result<(CharacterTable, Vec<(String, Image)>), PipelineError> {
    let set = CharacterSet::open(data)?;
    let records = set.records(split);
    if records.is_empty() {
        return Err(PipelineError::Invalid(format!(
            "{}: no {} characters",
            data.display(),
            split.name()
        )));
    }
    let mut methods = Vec::new();
    let mut ks: Vec<usize> = Vec::new();
    let mut learned = Vec::new();
    for run in runs {
        let p = RefinePredictor::load(run)?;
        if !ks.contains(&p.influences()) {
            ks.push(p.influences());
        }
        let name = run.file_name().map_or_else(
            || run.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        learned.push(Method::Run(Box::new(p), name));
    }
    if ks.is_empty() {
        ks.push(8);
    }
    for &k in &ks {
        methods.push(Method::Baseline(Skinning::Lbs, k));
        methods.push(Method::Baseline(Skinning::Dqs, k));
    }
    methods.extend(learned);
    let mut out: Vec<(Vec<CharacterErrors>, Accumulator, f64, usize)> = methods
        .iter()
        .map(|_| (Vec::new(), Accumulator::new(), 0.0, 0))
        .collect();
    // The first character's frames of every method, for the picture.
    let mut shown: Vec<Vec<Vec<[f32; 3]>>> = methods.iter().map(|_| Vec::new()).collect();
    let mut shown_truth: Vec<Vec<[f32; 3]>> = Vec::new();
    let mut shown_faces = Vec::new();
    let mut shown_rig = None;
    for (index, r) in records.iter().enumerate() {
        let data = set.load(r)?;
        let rig = rig_of(&data);
        let regions = joint_regions(&rig.weights, &rig.parents);
        if index == 0 {
            shown_faces = data.faces.clone();
            shown_rig = Some(rig.clone());
            shown_truth = data
                .truth
                .iter()
                .map(|t| {
                    t.iter()
                        .map(|p| std::array::from_fn(|k| p[k] + translation[k] as f32))
                        .collect()
                })
                .collect();
        }
        for ((m, (rows, total, seconds, frames)), kept) in
            methods.iter().zip(&mut out).zip(&mut shown)
        {
            let character = Character::new(rig.clone(), m.influences())?;
            let mut acc = Accumulator::new();
            for (pose, truth) in data.poses.iter().zip(&data.truth) {
                let predicted = match m {
                    Method::Baseline(skinning, _) => {
                        let t = character.transforms(pose, translation)?;
                        character.coarse(&t, *skinning)
                    }
                    Method::Run(p, _) => {
                        let t0 = Instant::now();
                        let x = p.predict(&character, pose, translation)?;
                        *seconds += t0.elapsed().as_secs_f64();
                        *frames += 1;
                        x
                    }
                };
                acc.add(&predicted, truth, translation, &regions);
                if index == 0 {
                    kept.push(predicted.iter().map(|p| p.map(|x| x as f32)).collect());
                }
            }
            rows.push(CharacterErrors {
                id: r.id.clone(),
                vertices: character.vertex_count(),
                poses: data.poses.len(),
                mean_cm: acc.mean(),
                max_cm: acc.max,
                min_cm: acc.min,
            });
            total.merge(&acc);
        }
    }
    let names: Vec<String> = methods.iter().map(Method::name).collect();
    let picture = worst_poses_sheet(
        &shown_faces,
        &shown_truth,
        &names,
        &shown,
        420,
        &format!(
            "{}: truth, then each method coloured by its distance to the truth",
            records[0].id
        ),
    )?;
    let table = CharacterTable {
        data: data.to_path_buf(),
        split: split.name().to_string(),
        translation,
        methods: methods
            .iter()
            .zip(out)
            .map(|(m, (characters, acc, seconds, frames))| MethodErrors {
                name: m.name(),
                characters,
                mean_cm: acc.mean(),
                max_cm: acc.max,
                min_cm: acc.min,
                regions_cm: acc.region_means(),
                histogram: acc.histogram,
                ms_per_frame: (frames > 0).then(|| 1000.0 * seconds / frames as f64),
            })
            .collect(),
    };
    let mut pictures = vec![("characters".to_string(), picture)];
    if let Some(rig) = shown_rig.filter(|r| r.joints.len() == 24) {
        for (name, [left, _]) in JOINT_REGIONS {
            let centre = rig.joints[left];
            let keep: Vec<usize> = rig
                .mesh
                .positions
                .iter()
                .enumerate()
                .filter(|(_, p)| {
                    (0..3)
                        .map(|k| (p[k] - centre[k]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                        <= CLOSE_UP_RADIUS
                })
                .map(|(v, _)| v)
                .collect();
            let faces = crop_faces(&shown_faces, &keep, rig.mesh.positions.len());
            if faces.is_empty() {
                continue;
            }
            // Each frame moved so the truth's crop is centred: the tiles share one camera,
            // and the joint is elsewhere in every pose.
            let centres: Vec<[f32; 3]> = shown_truth
                .iter()
                .map(|f| {
                    let n = keep.len() as f32;
                    std::array::from_fn(|k| keep.iter().map(|&v| f[v][k]).sum::<f32>() / n)
                })
                .collect();
            let crop = |frames: &[Vec<[f32; 3]>]| -> Vec<Vec<[f32; 3]>> {
                frames
                    .iter()
                    .zip(&centres)
                    .map(|(f, c)| {
                        keep.iter()
                            .map(|&v| std::array::from_fn(|k| f[v][k] - c[k]))
                            .collect()
                    })
                    .collect()
            };
            let truth = crop(&shown_truth);
            let cropped: Vec<Vec<Vec<[f32; 3]>>> = shown.iter().map(|m| crop(m)).collect();
            let image = worst_poses_sheet(
                &faces,
                &truth,
                &names,
                &cropped,
                360,
                &format!(
                    "{}: left {} (within {} cm), truth, then each method coloured by its distance to the truth",
                    records[0].id,
                    name.trim_end_matches('s'),
                    CLOSE_UP_RADIUS * 100.0
                ),
            )?;
            pictures.push((name.to_string(), image));
        }
    }
    Ok((table, pictures))
}

/// The faces of `faces` whose three vertices are all in `keep` (sorted), re-indexed into
/// `keep`.
fn crop_faces(faces: &[[u32; 3]], keep: &[usize], vertices: usize) -> Vec<[u32; 3]> {
    let mut index = vec![u32::MAX; vertices];
    for (i, &v) in keep.iter().enumerate() {
        index[v] = i as u32;
    }
    faces
        .iter()
        .filter_map(|f| {
            let g = f.map(|v| index[v as usize]);
            g.iter().all(|&v| v != u32::MAX).then_some(g)
        })
        .collect()
}

/// The truth and every method (`frames[m]`, named `names[m]`) in the two poses where the
/// first method (LBS) is worst, coloured by distance to the truth on one scale.
fn worst_poses_sheet(
    faces: &[[u32; 3]],
    truth: &[Vec<[f32; 3]>],
    names: &[String],
    frames: &[Vec<Vec<[f32; 3]>>],
    tile: u32,
    title: &str,
) -> Result<Image, PipelineError> {
    let columns: Vec<MethodFrames<'_>> = names
        .iter()
        .zip(frames)
        .map(|(name, frames)| MethodFrames { name, frames })
        .collect();
    let worst = worst_frames(&frames[0], truth);
    Ok(comparison_sheet(
        faces, truth, &columns, None, &worst, tile, title,
    )?)
}

/// The two frames where `method` is farthest from `truth` on average.
fn worst_frames(method: &[Vec<[f32; 3]>], truth: &[Vec<[f32; 3]>]) -> Vec<usize> {
    let mut order: Vec<(f64, usize)> = method
        .iter()
        .zip(truth)
        .enumerate()
        .map(|(t, (p, g))| {
            let e = vertex_errors_mm(p, g)
                .map(|e| e.iter().sum::<f64>())
                .unwrap_or(0.0);
            (e, t)
        })
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0));
    order.iter().take(2).map(|&(_, t)| t).collect()
}

impl CharacterTable {
    /// The tables as markdown: every method overall (Tables 3.3/3.4), then per character
    /// (Table 3.2), then the histogram (Fig. 3.9).
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "Per-vertex distance to the ground truth, cm, over every pose of the {} characters of {} (root moved by {:?} m).\n",
            self.split,
            self.data.display(),
            self.translation
        );
        let header: Vec<String> = ["method", "mean", "max", "min", "ms/frame"]
            .map(String::from)
            .to_vec();
        let rows: Vec<Vec<String>> = self
            .methods
            .iter()
            .map(|m| {
                vec![
                    m.name.clone(),
                    format!("{:.4}", m.mean_cm),
                    format!("{:.4}", m.max_cm),
                    format!("{:.4}", m.min_cm),
                    m.ms_per_frame.map_or("–".into(), |t| format!("{t:.1}")),
                ]
            })
            .collect();
        weft_eval::report::markdown_table(&mut s, &header, &rows);
        let _ = writeln!(
            s,
            "\nJoint regions (vertices where the joint and its parent both weigh at least {REGION_MIN_WEIGHT}, left and right), mean cm:\n"
        );
        let mut header = vec!["method".to_string()];
        header.extend(JOINT_REGIONS.iter().map(|(name, _)| name.to_string()));
        let rows: Vec<Vec<String>> = self
            .methods
            .iter()
            .map(|m| {
                let mut row = vec![m.name.clone()];
                row.extend(m.regions_cm.iter().map(|e| format!("{e:.4}")));
                row
            })
            .collect();
        weft_eval::report::markdown_table(&mut s, &header, &rows);
        let _ = writeln!(s, "\nPer character (mean / max / min):\n");
        let mut header = vec!["character".to_string(), "vertices".into()];
        header.extend(self.methods.iter().map(|m| m.name.clone()));
        let rows: Vec<Vec<String>> = (0..self.methods.first().map_or(0, |m| m.characters.len()))
            .map(|i| {
                let c = &self.methods[0].characters[i];
                let mut row = vec![c.id.clone(), c.vertices.to_string()];
                row.extend(self.methods.iter().map(|m| {
                    let e = &m.characters[i];
                    format!("{:.4} / {:.4} / {:.4}", e.mean_cm, e.max_cm, e.min_cm)
                }));
                row
            })
            .collect();
        weft_eval::report::markdown_table(&mut s, &header, &rows);
        let _ = writeln!(s, "\nShare of vertices per error bin (cm):\n");
        let mut header = vec!["method".to_string()];
        let mut lo = 0.0;
        for e in HISTOGRAM_EDGES_CM {
            header.push(format!("{lo}–{e}"));
            lo = e;
        }
        header.push(format!("> {lo}"));
        let rows: Vec<Vec<String>> = self
            .methods
            .iter()
            .map(|m| {
                let total: u64 = m.histogram.iter().sum::<u64>().max(1);
                let mut row = vec![m.name.clone()];
                row.extend(
                    m.histogram
                        .iter()
                        .map(|&c| format!("{:.1} %", 100.0 * c as f64 / total as f64)),
                );
                row
            })
            .collect();
        weft_eval::report::markdown_table(&mut s, &header, &rows);
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_regions_are_the_blend_rings_of_the_named_joints() {
        // A chain skeleton: joint j's parent is j − 1.
        let parents: Vec<Option<usize>> = (0..24usize).map(|j| j.checked_sub(1)).collect();
        let row = |pairs: &[(usize, f32)]| {
            let mut r = vec![0.0f32; 24];
            for &(j, w) in pairs {
                r[j] = w;
            }
            r
        };
        let weights: Vec<f32> = [
            row(&[(18, 0.5), (17, 0.5)]),   // left elbow's ring
            row(&[(18, 1.0)]),              // forearm only
            row(&[(19, 0.95), (18, 0.05)]), // too little of the parent
            row(&[(4, 0.3), (3, 0.7)]),     // left knee's ring
        ]
        .concat();
        let regions = joint_regions(&weights, &parents);
        assert_eq!(regions.len(), JOINT_REGIONS.len());
        assert_eq!(regions[0], vec![0]);
        assert_eq!(regions[1], vec![3]);
        assert!(regions[2].is_empty() && regions[3].is_empty());
        // Another skeleton has no named regions.
        assert!(joint_regions(&[1.0, 0.0], &[None, Some(0)])
            .iter()
            .all(Vec::is_empty));
    }
}
