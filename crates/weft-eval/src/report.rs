//! What `weft eval` finds, as data ([`EvalReport`], written as `eval.json`) and as text
//! (`eval.md`), plus the Table 1 comparison of several runs ([`Comparison`]).
//!
//! The JSON is the source of truth: the comparison table is built from the `eval.json`
//! files of the runs it compares, so a table can be remade without evaluating again, and
//! every number in it can be traced to a file.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use serde::{Deserialize, Serialize};

use weft_models::Timing;

use crate::error::EvalError;
use crate::metrics::MetricsSummary;

/// Version of the `eval.json` layout.
pub const REPORT_VERSION: u32 = 2;

pub use weft_models::LBS_NAME;

/// One method's figures on the evaluated split.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MethodResult {
    /// Display name ("Multilevel (structure-preserving)", "LBS only").
    pub name: String,
    /// The learned system (`multilevel`, `hood`, …); absent for a baseline.
    pub model: Option<String>,
    /// Its variant settings (preset, pooling, checkpoint; skinning for a baseline).
    pub variant: BTreeMap<String, String>,
    /// Over every evaluated frame.
    pub overall: MetricsSummary,
    /// Per garment kind (skirt, dress, …).
    pub per_kind: BTreeMap<String, MetricsSummary>,
    /// Inference speed per batch size (timed on the first sequence; empty when the
    /// method has nothing to time apart from animating).
    pub fps: Vec<Timing>,
}

/// Everything `weft eval` measured on one run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    /// [`REPORT_VERSION`].
    pub version: u32,
    /// The run directory.
    pub run: String,
    /// The dataset directory.
    pub data: String,
    /// The split evaluated.
    pub split: String,
    /// Sequences evaluated.
    pub sequences: usize,
    /// Frames evaluated (per method).
    pub frames: u64,
    /// The evaluated run's model first, then the other methods in the order given.
    pub methods: Vec<MethodResult>,
    /// Each sequence's mean vertex error per method, so tables can group them (by body
    /// shape, garment, motion: seed 001 Tables 4.1–4.2). Absent in reports written
    /// before it was kept.
    #[serde(default)]
    pub per_sequence: Vec<SequenceScore>,
    /// The command that reproduces this report.
    pub command: String,
}

/// One sequence of an [`EvalReport`]: what it is and each method's mean vertex error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceScore {
    /// The sequence id.
    pub id: String,
    /// Its garment's id.
    pub garment: String,
    /// Its body's id.
    pub body: String,
    /// Its motion's id.
    pub motion: String,
    /// Its body's shape.
    pub betas: Vec<f32>,
    /// Frames scored.
    pub frames: usize,
    /// Mean vertex error (mm) of each method, in the order of [`EvalReport::methods`].
    pub e_verts_mm: Vec<f64>,
    /// Share of each method's vertices inside the body over the sequence (`None` without
    /// the collision check; empty in reports written before it was recorded).
    #[serde(default)]
    pub collision_rate: Vec<Option<f64>>,
}

/// `1 − E_model / E_base` of the mean vertex errors: the share by which `model` is below
/// `base` (negative when worse).
pub fn reduction(model: &MetricsSummary, base: &MetricsSummary) -> Option<f64> {
    (base.e_verts_mm.count > 0 && base.e_verts_mm.mean > 0.0 && model.e_verts_mm.count > 0)
        .then(|| 1.0 - model.e_verts_mm.mean / base.e_verts_mm.mean)
}

/// A share as a percentage with `decimals` decimals, "–" when there is none.
fn pct(x: Option<f64>, decimals: usize) -> String {
    x.map_or("–".to_owned(), |v| {
        format!("{:.*} %", decimals, 100.0 * v)
    })
}

impl EvalReport {
    /// The result named `name`.
    pub fn method(&self, name: &str) -> Option<&MethodResult> {
        self.methods.iter().find(|m| m.name == name)
    }

    /// The model's result (the first method).
    pub fn model(&self) -> Option<&MethodResult> {
        self.methods.first()
    }

    /// How far the model's mean vertex error is below the LBS baseline's.
    pub fn reduction_vs_lbs(&self) -> Option<f64> {
        reduction(&self.model()?.overall, &self.method(LBS_NAME)?.overall)
    }

    /// Garment kinds seen by any method, sorted.
    pub fn kinds(&self) -> Vec<String> {
        let mut k: Vec<String> = self
            .methods
            .iter()
            .flat_map(|m| m.per_kind.keys().cloned())
            .collect();
        k.sort();
        k.dedup();
        k
    }

    /// Header and rows of the main table: one row per method.
    pub fn table(&self) -> (Vec<String>, Vec<Vec<String>>) {
        let kinds = self.kinds();
        let mut header = vec!["method".to_owned()];
        for k in &kinds {
            header.push(format!("{k}: E_verts (mm) / E_norm (°)"));
        }
        header.extend(
            [
                "all: E_verts (mm)",
                "all: E_norm (°)",
                "collisions",
                "edge strain mean / max",
                "vs LBS",
            ]
            .map(String::from),
        );
        // The steps' potential, when a judge scored them (a HOOD run's evaluation).
        let judged = self
            .methods
            .iter()
            .any(|m| m.overall.potential_gap_j.is_some());
        if judged {
            header.push("step potential above its minimum (J)".to_owned());
        }
        let lbs = self.method(LBS_NAME).map(|m| m.overall);
        let rows = self
            .methods
            .iter()
            .map(|m| {
                let mut row = vec![m.name.clone()];
                for k in &kinds {
                    row.push(m.per_kind.get(k).map_or("–".to_owned(), |s| {
                        format!(
                            "{} / {}",
                            s.e_verts_mm.mean_std(2),
                            s.e_norm_deg.mean_std(2)
                        )
                    }));
                }
                row.push(m.overall.e_verts_mm.mean_std(2));
                row.push(m.overall.e_norm_deg.mean_std(2));
                row.push(pct(m.overall.collision_rate, 2));
                row.push(format!(
                    "{:.4} / {:.3}",
                    m.overall.edge_strain.mean, m.overall.edge_strain.max
                ));
                row.push(if m.name == LBS_NAME {
                    "–".to_owned()
                } else {
                    pct(lbs.as_ref().and_then(|b| reduction(&m.overall, b)), 1)
                });
                if judged {
                    row.push(
                        m.overall
                            .potential_gap_j
                            .map_or("–".to_owned(), |s| s.mean_std(4)),
                    );
                }
                row
            })
            .collect();
        (header, rows)
    }

    /// Header and rows of the per-sequence table: one row per sequence, each method's
    /// mean vertex error and (when checked) share of vertices inside the body.
    pub fn sequence_table(&self) -> (Vec<String>, Vec<Vec<String>>) {
        let mut header = vec!["sequence".to_owned()];
        header.extend(
            self.methods
                .iter()
                .map(|m| format!("{}: E_verts (mm) / inside", m.name)),
        );
        let rows = self
            .per_sequence
            .iter()
            .map(|q| {
                let mut row = vec![q.id.clone()];
                row.extend(q.e_verts_mm.iter().enumerate().map(|(i, e)| {
                    let inside = q.collision_rate.get(i).copied().flatten();
                    format!("{e:.2} / {}", pct(inside, 2))
                }));
                row
            })
            .collect();
        (header, rows)
    }

    /// Header and rows of the speed table: one row per timed method and batch size.
    pub fn fps_table(&self) -> (Vec<String>, Vec<Vec<String>>) {
        let header = [
            "method",
            "batch (per pass: frames; HOOD: garments)",
            "vertices",
            "network fps",
            "with inputs fps",
            "frames timed",
        ]
        .map(String::from)
        .to_vec();
        let rows = self
            .methods
            .iter()
            .flat_map(|m| m.fps.iter().map(move |f| (m, f)))
            .map(|(m, f)| {
                vec![
                    m.name.clone(),
                    f.batch.to_string(),
                    f.vertices.to_string(),
                    format!("{:.1}", f.network_fps),
                    format!("{:.1}", f.end_to_end_fps),
                    f.frames.to_string(),
                ]
            })
            .collect();
        (header, rows)
    }

    /// Whether any method was timed.
    pub fn timed(&self) -> bool {
        self.methods.iter().any(|m| !m.fps.is_empty())
    }

    /// One line naming each method with its model kind and variant settings.
    pub fn methods_line(&self) -> String {
        self.methods
            .iter()
            .map(|m| {
                let settings: Vec<String> =
                    m.variant.iter().map(|(k, v)| format!("{k} {v}")).collect();
                match &m.model {
                    Some(kind) => format!("{} ({kind}: {})", m.name, settings.join(", ")),
                    None => format!("{} ({})", m.name, settings.join(", ")),
                }
            })
            .collect::<Vec<_>>()
            .join("; ")
    }

    /// The report as Markdown.
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Evaluation of {}\n", self.run);
        let _ = writeln!(
            s,
            "Split `{}` of `{}`: {} sequences, {} frames. Methods: {}.\n",
            self.split,
            self.data,
            self.sequences,
            self.frames,
            self.methods_line()
        );
        if let Some(r) = self.reduction_vs_lbs() {
            let _ = writeln!(
                s,
                "Mean vertex error of the model is {:.1} % {} the LBS-only baseline.\n",
                100.0 * r.abs(),
                if r >= 0.0 { "below" } else { "above" }
            );
        }
        let (h, rows) = self.table();
        markdown_table(&mut s, &h, &rows);
        let _ = writeln!(
            s,
            "\nErrors are mean (± std) over every vertex of every frame; E_norm over vertices with a defined normal. Collisions: share of garment vertices inside the posed body.\n"
        );
        if !self.per_sequence.is_empty() {
            let _ = writeln!(s, "## Per sequence\n");
            let (h, rows) = self.sequence_table();
            markdown_table(&mut s, &h, &rows);
            let _ = writeln!(s);
        }
        if self.timed() {
            let _ = writeln!(s, "## Inference speed\n");
            let (h, rows) = self.fps_table();
            markdown_table(&mut s, &h, &rows);
            let _ = writeln!(s);
        }
        let _ = writeln!(s, "Reproduce with:\n\n```\n{}\n```", self.command);
        s
    }

    /// Reads an `eval.json`.
    pub fn read(path: &Path) -> Result<Self, EvalError> {
        let text = weft_mesh::io::read_input_to_string(path).map_err(|source| EvalError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let json = |source| EvalError::Json {
            path: path.to_path_buf(),
            source,
        };
        // The version first, so that an older report is named as such rather than as a
        // missing field.
        let value: serde_json::Value = serde_json::from_str(&text).map_err(json)?;
        let version = value.get("version").and_then(serde_json::Value::as_u64);
        if version != Some(u64::from(REPORT_VERSION)) {
            return Err(EvalError::Invalid(format!(
                "{}: eval.json version {}; this build reads version {REPORT_VERSION} (re-run weft eval)",
                path.display(),
                version.map_or("missing".to_string(), |v| v.to_string())
            )));
        }
        serde_json::from_value(value).map_err(json)
    }

    /// Writes the report as pretty JSON, atomically.
    pub fn write_json(&self, path: &Path) -> Result<(), EvalError> {
        let text = serde_json::to_string_pretty(self).map_err(|source| EvalError::Json {
            path: path.to_path_buf(),
            source,
        })?;
        write_text(path, &text)
    }
}

/// Writes `text` to `path` atomically (temporary file, then rename).
pub fn write_text(path: &Path, text: &str) -> Result<(), EvalError> {
    weft_mesh::io::write_atomic(path, |w| w.write_all(text.as_bytes())).map_err(|source| {
        EvalError::Io {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// Appends a Markdown table.
pub fn markdown_table(s: &mut String, header: &[String], rows: &[Vec<String>]) {
    let _ = writeln!(s, "| {} |", header.join(" | "));
    let _ = writeln!(s, "|{}", header.iter().map(|_| "---|").collect::<String>());
    for r in rows {
        let _ = writeln!(s, "| {} |", r.join(" | "));
    }
}

/// Table 1: several runs (one per pooling variant, or one per system) and the
/// baselines on the same split, per garment kind.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// The runs' reports, in the order given.
    pub reports: Vec<EvalReport>,
    /// The command that reproduces the comparison.
    pub command: String,
}

impl Comparison {
    /// Checks that the reports are comparable: same data and split.
    pub fn new(reports: Vec<EvalReport>, command: String) -> Result<Self, EvalError> {
        let Some(first) = reports.first() else {
            return Err(EvalError::Invalid(
                "a comparison needs at least one evaluated run".to_owned(),
            ));
        };
        for r in &reports[1..] {
            if r.data != first.data || r.split != first.split {
                return Err(EvalError::Invalid(format!(
                    "run {} was evaluated on {} ({}), run {} on {} ({}); compare runs on the same data and split",
                    first.run, first.data, first.split, r.run, r.data, r.split
                )));
            }
        }
        Ok(Comparison { reports, command })
    }

    /// Header and rows: one row per run (its model) plus the baselines of the first run.
    pub fn table(&self) -> (Vec<String>, Vec<Vec<String>>) {
        let mut kinds: Vec<String> = self.reports.iter().flat_map(|r| r.kinds()).collect();
        kinds.sort();
        kinds.dedup();
        let mut header = vec!["method".to_owned(), "run".to_owned()];
        for k in &kinds {
            header.push(format!("{k}: E_verts (mm) / E_norm (°)"));
        }
        header.extend(
            ["all: E_verts (mm) / E_norm (°)", "vs LBS", "fps (batch 1)"].map(String::from),
        );
        let lbs = self
            .reports
            .first()
            .and_then(|r| r.method(LBS_NAME))
            .cloned();
        let row = |name: String, run: &str, m: &MethodResult, fps: String| {
            let mut row = vec![name, run.to_owned()];
            for k in &kinds {
                row.push(m.per_kind.get(k).map_or("–".to_owned(), |s| {
                    format!(
                        "{} / {}",
                        s.e_verts_mm.mean_std(2),
                        s.e_norm_deg.mean_std(2)
                    )
                }));
            }
            row.push(format!(
                "{} / {}",
                m.overall.e_verts_mm.mean_std(2),
                m.overall.e_norm_deg.mean_std(2)
            ));
            row.push(if m.name == LBS_NAME {
                "–".to_owned()
            } else {
                pct(
                    lbs.as_ref().and_then(|b| reduction(&m.overall, &b.overall)),
                    1,
                )
            });
            row.push(fps);
            row
        };
        let fps = |m: &MethodResult| {
            m.fps
                .iter()
                .find(|f| f.batch == 1)
                .map_or("–".to_owned(), |f| format!("{:.1}", f.network_fps))
        };
        let mut rows: Vec<Vec<String>> = self
            .reports
            .iter()
            .filter_map(|r| {
                let m = r.model()?;
                Some(row(m.name.clone(), &r.run, m, fps(m)))
            })
            .collect();
        if let Some(first) = self.reports.first() {
            for b in first.methods.iter().skip(1).filter(|m| m.model.is_none()) {
                rows.push(row(b.name.clone(), &first.run, b, fps(b)));
            }
        }
        (header, rows)
    }

    /// The table as Markdown with the reproducing command.
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Table 1: methods against the no-learning baselines\n");
        if let Some(first) = self.reports.first() {
            let _ = writeln!(
                s,
                "Split `{}` of `{}`; mean (± std) over every vertex of every frame.\n",
                first.split, first.data
            );
        }
        let (h, rows) = self.table();
        markdown_table(&mut s, &h, &rows);
        let _ = writeln!(s, "\nReproduce with:\n\n```\n{}\n```", self.command);
        s
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::stats::Accumulator;

    pub(crate) fn summary(mean: f64) -> MetricsSummary {
        let mut a = Accumulator::new();
        a.extend([mean - 1.0, mean + 1.0]);
        MetricsSummary {
            e_verts_mm: a.summary(),
            e_norm_deg: a.summary(),
            frames: 1,
            ..MetricsSummary::default()
        }
    }

    pub(crate) fn report(pooling: &str, model: f64, lbs: f64) -> EvalReport {
        let kinds = |m: f64| BTreeMap::from([("skirt".to_owned(), summary(m))]);
        let label = weft_models::multilevel::PoolingKind::ALL
            .into_iter()
            .find(|p| p.name() == pooling)
            .map_or(pooling, |p| p.label());
        EvalReport {
            version: REPORT_VERSION,
            run: format!("runs/{pooling}"),
            data: "data/tiny".into(),
            split: "test".into(),
            sequences: 1,
            frames: 1,
            per_sequence: Vec::new(),
            methods: vec![
                MethodResult {
                    name: label.into(),
                    model: Some("multilevel".into()),
                    variant: BTreeMap::from([
                        ("preset".into(), "cpu".into()),
                        ("pooling".into(), pooling.into()),
                    ]),
                    overall: summary(model),
                    per_kind: kinds(model),
                    fps: vec![Timing {
                        batch: 1,
                        vertices: 600,
                        network_fps: 100.0,
                        end_to_end_fps: 50.0,
                        frames: 16,
                    }],
                },
                MethodResult {
                    name: LBS_NAME.into(),
                    model: None,
                    variant: BTreeMap::from([("skinning".into(), "lbs".into())]),
                    overall: summary(lbs),
                    per_kind: kinds(lbs),
                    fps: Vec::new(),
                },
            ],
            command: "weft eval runs/x --data data/tiny".into(),
        }
    }

    #[test]
    fn reduction_and_tables() {
        let r = report("structure", 20.0, 40.0);
        assert!((r.reduction_vs_lbs().unwrap() - 0.5).abs() < 1e-12);
        let md = r.to_markdown();
        assert!(md.contains("50.0 % below"), "{md}");
        assert!(md.contains("| LBS only |"), "{md}");
        assert!(md.contains("weft eval runs/x"), "{md}");
        assert!(
            md.contains("(multilevel: pooling structure, preset cpu)"),
            "{md}"
        );
        assert!(
            md.contains("| Multilevel (structure-preserving) | 1 | 600 | 100.0"),
            "{md}"
        );
        let dir = std::env::temp_dir().join(format!("weft-eval-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("eval.json");
        r.write_json(&path).unwrap();
        assert_eq!(EvalReport::read(&path).unwrap(), r);
        let c = Comparison::new(
            vec![r, report("none", 30.0, 40.0)],
            "weft eval --compare runs/structure runs/none --out t1".into(),
        )
        .unwrap();
        let (_, rows) = c.table();
        assert_eq!(rows.len(), 3);
        assert_eq!(rows[1][0], "Single-level");
        assert_eq!(rows[2][0], LBS_NAME);
        assert!(c.to_markdown().contains("25.0 %"));
        assert!(EvalReport::read(&path).is_ok());
        let old = r#"{"version": 1}"#;
        std::fs::write(&path, old).unwrap();
        let e = EvalReport::read(&path).unwrap_err().to_string();
        assert!(e.contains("eval.json"), "{e}");
        let mut other = report("top_k", 1.0, 2.0);
        other.split = "validation".into();
        assert!(Comparison::new(vec![report("none", 1.0, 2.0), other], String::new()).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
