//! The metrics log (`RUN/metrics.jsonl`, one JSON object per line) and the training
//! curves drawn from it (`RUN/curves.png`, through weft-render's plot API).
//!
//! A line per optimiser step: step, epoch, the task's stage, learning rate, the weighted
//! total and every evaluated term unweighted, the step's wall time, and the task's named
//! validation metrics on the steps that measured them. Steps whose loss was not finite get a line with
//! `"event": "non_finite"` and the offending term. On resume the log is cut back to the
//! checkpoint's step, so it reads as if the run had never stopped.

use std::collections::BTreeMap;
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use weft_mesh::io::write_atomic;
use weft_render::{Image, LinePlot, Series};

use crate::error::{Result, TrainError};
use crate::task::Metrics;

/// One line of metrics.jsonl.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// The step (1-based: the number of steps taken after it).
    pub step: usize,
    /// The epoch the step belongs to.
    pub epoch: usize,
    /// The task's stage (`phase` in logs written before tasks owned their stages).
    #[serde(alias = "phase")]
    pub stage: String,
    /// The learning rate of the step.
    pub lr: f64,
    /// The weighted total loss.
    pub loss: f64,
    /// Every evaluated term, unweighted.
    pub terms: BTreeMap<String, f64>,
    /// Wall time of the step, ms.
    pub step_ms: f64,
    /// The validation metrics (steps that measured them).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub validation: Metrics,
    /// `start` for the validation before the first step (step 0), `non_finite` for a
    /// skipped step, `stage:<name>` when the task's stage changed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub event: Option<String>,
    /// The term that was not finite, for `non_finite`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub term: Option<String>,
}

/// The log of a run: the file and the records so far (for the curves).
#[derive(Debug)]
pub struct MetricsLog {
    path: PathBuf,
    records: Vec<Record>,
}

impl MetricsLog {
    /// A new, empty log at `path` (replacing an old one).
    pub fn create(path: &Path) -> Result<Self> {
        write_atomic(path, |_| Ok(())).map_err(|e| TrainError::io(path, e))?;
        Ok(MetricsLog {
            path: path.to_path_buf(),
            records: Vec::new(),
        })
    }

    /// The log at `path` cut back to the records of steps `<= step` (resume).
    pub fn resume(path: &Path, step: usize) -> Result<Self> {
        let text = match weft_mesh::io::read_input_to_string(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => return Err(TrainError::io(path, e)),
        };
        let mut records = Vec::new();
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            // A torn last line (killed while appending) is dropped, not an error.
            let Ok(r) = serde_json::from_str::<Record>(line) else {
                if i + 1 == text.lines().count() {
                    break;
                }
                return Err(TrainError::Parse {
                    path: path.to_path_buf(),
                    message: format!("line {}: not a metrics record", i + 1),
                });
            };
            if r.step <= step {
                records.push(r);
            }
        }
        let mut text = String::new();
        for r in &records {
            text.push_str(&line_of(r)?);
        }
        write_atomic(path, |w| w.write_all(text.as_bytes()))
            .map_err(|e| TrainError::io(path, e))?;
        Ok(MetricsLog {
            path: path.to_path_buf(),
            records,
        })
    }

    /// Appends a record (one line, flushed).
    pub fn push(&mut self, record: Record) -> Result<()> {
        let line = line_of(&record)?;
        let mut f = OpenOptions::new()
            .append(true)
            .create(true)
            .open(&self.path)
            .map_err(|e| TrainError::io(&self.path, e))?;
        f.write_all(line.as_bytes())
            .map_err(|e| TrainError::io(&self.path, e))?;
        self.records.push(record);
        Ok(())
    }

    /// The records so far.
    pub fn records(&self) -> &[Record] {
        &self.records
    }

    /// Draws the loss terms (log scale, smoothed over epochs of `smooth` steps) and the
    /// validation metrics into one picture and writes it to `path` atomically.
    pub fn write_curves(&self, path: &Path, smooth: usize) -> Result<()> {
        let image = curves(&self.records, smooth)?;
        let png = image.encode_png()?;
        write_atomic(path, |w| w.write_all(&png)).map_err(|e| TrainError::io(path, e))
    }
}

/// Validation metrics for a log line: `e_verts_mm 44.61, …`, or `not measured`.
pub fn describe(metrics: &Metrics) -> String {
    if metrics.is_empty() {
        return "not measured".into();
    }
    metrics
        .iter()
        .map(|(k, v)| format!("{k} {v:.2}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn line_of(r: &Record) -> Result<String> {
    let mut s = serde_json::to_string(r).map_err(|e| TrainError::Write {
        what: "metrics record".into(),
        source: Box::new(e),
    })?;
    s.push('\n');
    Ok(s)
}

/// Running mean over `window` points (the last `window` of each), so a per-step noisy
/// loss reads as a curve.
fn smoothed(points: &[(f64, f64)], window: usize) -> Vec<(f64, f64)> {
    let w = window.max(1);
    let mut out = Vec::with_capacity(points.len());
    let mut sum = 0.0;
    for (i, &(x, y)) in points.iter().enumerate() {
        sum += y;
        if i >= w {
            sum -= points[i - w].1;
        }
        out.push((x, sum / (i + 1).min(w) as f64));
    }
    out
}

/// The curves picture: losses on top, validation metrics below.
pub fn curves(records: &[Record], smooth: usize) -> Result<Image> {
    let steps: Vec<&Record> = records
        .iter()
        .filter(|r| r.event.as_deref() != Some("non_finite"))
        .collect();
    let mut names: Vec<&String> = steps.iter().flat_map(|r| r.terms.keys()).collect();
    names.sort();
    names.dedup();
    let mut series = vec![Series::new(
        "total (weighted)",
        smoothed(
            &steps
                .iter()
                .map(|r| (r.step as f64, r.loss))
                .collect::<Vec<_>>(),
            smooth,
        ),
    )];
    for name in names {
        let pts: Vec<(f64, f64)> = steps
            .iter()
            .filter_map(|r| r.terms.get(name).map(|&v| (r.step as f64, v)))
            .collect();
        series.push(Series::new(name.clone(), smoothed(&pts, smooth)));
    }
    let losses = LinePlot {
        title: "training losses (unweighted terms, running mean)".into(),
        x_label: "step".into(),
        y_label: "loss".into(),
        series,
        log_y: true,
    };
    let mut metrics: Vec<&String> = records.iter().flat_map(|r| r.validation.keys()).collect();
    metrics.sort();
    metrics.dedup();
    let validation = LinePlot {
        title: "validation".into(),
        x_label: "step".into(),
        y_label: "metric".into(),
        series: metrics
            .into_iter()
            .map(|name| {
                let pts = records
                    .iter()
                    .filter_map(|r| r.validation.get(name).map(|&v| (r.step as f64, v)))
                    .collect();
                Series::new(name.clone(), pts)
            })
            .collect(),
        log_y: false,
    };
    let (w, h) = (960, 420);
    let top = losses.render(w, h)?;
    let bottom = validation.render(w, h)?;
    let mut image = Image::new(w, 2 * h, [255, 255, 255]);
    image.blit(&top, 0, 0);
    image.blit(&bottom, 0, i64::from(h));
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(step: usize, loss: f64) -> Record {
        Record {
            step,
            epoch: step / 4,
            stage: "supervised".into(),
            lr: 1e-3,
            loss,
            terms: [("vertex".to_string(), loss / 100.0)].into_iter().collect(),
            step_ms: 3.0,
            validation: step
                .is_multiple_of(5)
                .then(|| ("e_verts_mm".to_string(), 10.0 / step as f64))
                .into_iter()
                .collect(),
            event: None,
            term: None,
        }
    }

    #[test]
    fn log_resumes_at_a_step_and_draws_curves() {
        let dir = std::env::temp_dir().join(format!("weft-train-metrics-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("metrics.jsonl");
        let mut log = MetricsLog::create(&path).unwrap();
        for s in 1..=10 {
            log.push(record(s, 1.0 / s as f64)).unwrap();
        }
        // A torn last line, as a kill in the middle of a write leaves.
        std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap()
            .write_all(b"{\"step\": 11, \"epo")
            .unwrap();
        let log = MetricsLog::resume(&path, 6).unwrap();
        assert_eq!(log.records().len(), 6);
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 6);
        let back: Record = serde_json::from_str(text.lines().last().unwrap()).unwrap();
        assert_eq!(back, record(6, 1.0 / 6.0));
        let png = dir.join("curves.png");
        log.write_curves(&png, 2).unwrap();
        assert!(std::fs::metadata(&png).unwrap().len() > 1000);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn running_mean() {
        let s = smoothed(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)], 2);
        assert_eq!(s, vec![(0.0, 1.0), (1.0, 2.0), (2.0, 4.0)]);
    }
}
