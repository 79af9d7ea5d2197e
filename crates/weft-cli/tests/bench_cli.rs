//! `weft bench`: each bench runs from the binary on a small configuration, prints one
//! JSON object per configuration with the fields scripts rely on, and a Markdown table
//! otherwise; bad options are refused naming them.

mod common;

use common::{stderr, stdout, weft};
use serde_json::Value;

fn json_lines(args: &[&str]) -> Vec<Value> {
    let out = weft(args);
    assert!(out.status.success(), "{}", stderr(&out));
    stdout(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

/// `weft bench simulate` of a 300-vertex skirt on the walk, then `extra`.
fn bench_simulate<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["bench", "simulate", "--vertices", "300", "--motion", "walk"];
    args.extend_from_slice(extra);
    args
}

/// The JSON rows of `weft bench MODEL` at the cpu preset on a 300-vertex garment, one
/// timed run, then `extra`.
fn bench_cpu_300(model: &str, extra: &[&str]) -> Vec<Value> {
    let mut args = vec![
        "bench",
        model,
        "--preset",
        "cpu",
        "--vertices",
        "300",
        "--reps",
        "1",
        "--json",
    ];
    args.extend_from_slice(extra);
    json_lines(&args)
}

fn number(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

#[test]
fn multilevel_reports_every_stage_per_configuration() {
    let rows = json_lines(&[
        "bench",
        "multilevel",
        "--vertices",
        "300",
        "--batch",
        "1,2",
        "--reps",
        "1",
        "--train",
        "--json",
    ]);
    assert_eq!(rows.len(), 2);
    for (row, batch) in rows.iter().zip([1.0, 2.0]) {
        assert_eq!(row["bench"], "multilevel");
        assert_eq!(row["device"], "cpu");
        assert_eq!(row["preset"], "cpu");
        assert_eq!(number(row, "batch"), batch);
        let n = number(row, "vertices");
        assert!((250.0..=400.0).contains(&n), "{n}");
        let stages = &row["stages"];
        let mut sum = 0.0;
        for stage in ["inputs", "t1", "t2", "mp", "lbs"] {
            let ms = number(stages, stage);
            assert!(ms > 0.0, "{stage}: {ms}");
            sum += ms;
        }
        // The stages are the forward pass's parts (timed apart, so only roughly).
        let total = number(row, "ms_per_frame");
        assert!(total > 0.0 && sum > 0.3 * total, "{sum} vs {total}");
        // The embedding GEMM is part of M^mp but timed on its own: with one timed run on
        // a shared machine it can come out longer than the whole, so only its presence
        // is checked.
        assert!(number(row, "mp_embed_ms_per_frame") > 0.0);
        // cpu preset: F·S = 768, heads·channels = 64, 2 submodules.
        let floor = 2.0 * n * 768.0 * 64.0 * 2.0 / 1e9;
        assert!((number(row, "gemm_floor_gflop") - floor).abs() < 1e-9);
        assert!(number(row, "gemm_gflops") > 0.0);
        assert!(number(row, "memory_gbs") > 0.0);
        assert!(number(row, "t2_floor_ms_per_frame") > 0.0);
        assert!(number(row, "t2_parameters") > 0.0);
        assert!(number(row, "train_ms_per_frame") > 0.0);
    }
}

#[test]
fn gat_compares_the_fused_kernel_with_the_reference() {
    let rows = json_lines(&["bench", "gat", "--vertices", "300", "--reps", "2", "--json"]);
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["implementation"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["fused", "reference"]);
    for r in &rows {
        assert_eq!(r["device"], "cpu");
        assert!(number(r, "edges") > number(r, "vertices"));
        assert!(number(r, "forward_ms") > 0.0);
        assert!(number(r, "forward_backward_ms") > 0.0);
    }
}

#[test]
fn refinement_models_report_their_stages() {
    for (model, stages) in [
        ("densegats", &["modules_ms"][..]),
        ("multiresgnet", &["local_ms", "global_ms"][..]),
    ] {
        let rows = bench_cpu_300(model, &[]);
        assert_eq!(rows.len(), 1);
        let row = &rows[0];
        assert_eq!(row["bench"], model);
        for key in [
            "inputs_ms",
            "input_mlp_ms",
            "output_mlp_ms",
            "network_ms",
            "frame_ms",
        ] {
            assert!(number(row, key) > 0.0, "{model}: {key} in {row}");
        }
        for key in stages {
            assert!(!row[key].is_null(), "{model}: {key} in {row}");
        }
        let out = weft(&["bench", model, "--preset", "huge"]);
        assert!(!out.status.success());
        assert!(stderr(&out).contains("--preset"), "{}", stderr(&out));
    }
}

/// `weft bench hood` with another schedule: Fine15 of seed 004 Table 1 reaches 15 mesh
/// edges per step, the cpu preset's hierarchy 24.
#[test]
fn hood_reports_its_schedule_and_propagation_radius() {
    for (schedule, radius) in [(None, 24.0), (Some("0 x15"), 15.0)] {
        let extra = match schedule {
            Some(s) => vec!["--schedule", s],
            None => Vec::new(),
        };
        let rows = bench_cpu_300("hood", &extra);
        assert_eq!(rows.len(), 1);
        let r = &rows[0];
        assert_eq!(r["bench"], "hood");
        assert_eq!(number(r, "propagation_radius"), radius, "{r}");
        if let Some(s) = schedule {
            assert_eq!(r["schedule"], s);
        }
        assert!(number(r, "step_ms") > 0.0, "{r}");
        // Both forms of the network: the inference form rollouts run, the burn layers
        // training differentiates.
        assert!(number(r, "network_ms") > 0.0, "{r}");
        assert!(number(r, "burn_network_ms") > 0.0, "{r}");
    }
}

#[test]
fn simulate_reports_cost_and_quality_and_a_table_by_default() {
    let rows = json_lines(&bench_simulate(&[
        "--frames", "3", "--warmup", "2", "--json",
    ]));
    assert_eq!(rows.len(), 1);
    let r = &rows[0];
    assert_eq!(r["material"], "silk");
    assert_eq!(number(r, "frames"), 2.0, "frame 0 is the warm-up");
    assert!(number(r, "seconds_per_frame") > 0.0);
    assert!(number(r, "newton_iterations") >= 1.0);
    assert!(number(r, "pcg_iterations") >= 1.0);
    let (mean, p99, max) = (
        number(r, "strain_mean"),
        number(r, "strain_p99"),
        number(r, "strain_max"),
    );
    assert!(0.0 < mean && mean <= p99 && p99 <= max && max < 0.5, "{r}");
    assert!(number(r, "max_penetration_mm") >= 0.0);

    let out = weft(&bench_simulate(&["--frames", "2", "--warmup", "1"]));
    assert!(out.status.success(), "{}", stderr(&out));
    let table = stdout(&out);
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines.len(), 3, "{table}");
    assert!(lines[0].starts_with("| N | material |"), "{table}");
}

#[test]
fn bad_options_are_named() {
    for (args, names) in [
        (&["bench", "multilevel", "--preset", "huge"][..], "--preset"),
        (&["bench", "multilevel", "--batch", "0"][..], "--batch"),
        (&["bench", "gat", "--heads", "0"][..], "--heads"),
        (&["bench", "hood", "--schedule", "0,7"][..], "--schedule"),
        (
            &[
                "bench",
                "simulate",
                "--motion",
                "walk",
                "--material",
                "kevlar",
            ][..],
            "--material",
        ),
        (
            &[
                "bench",
                "simulate",
                "--motion",
                "walk",
                "--substeps",
                "1000",
            ][..],
            "--substeps",
        ),
    ] {
        let out = weft(args);
        assert!(!out.status.success(), "{args:?}");
        let err = stderr(&out);
        assert!(err.contains(names), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    }
}

/// A binary built without the `wgpu` feature refuses `--device wgpu` in one line that
/// says so, before any work.
#[test]
#[cfg(not(feature = "wgpu"))]
fn wgpu_device_needs_the_feature() {
    for bench in ["multilevel", "gat"] {
        let out = weft(&["bench", bench, "--device", "wgpu", "--vertices", "300"]);
        assert!(!out.status.success(), "{bench}");
        let err = stderr(&out);
        assert!(
            err.contains("--device") && err.contains("without the `wgpu` feature"),
            "{bench}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{bench}: {err}");
    }
}

/// `--options` lays a TOML file of `SequenceOptions` over the defaults, for `weft
/// simulate` and its bench alike; an unknown key is refused naming the file and key.
#[test]
fn simulator_options_come_from_a_toml_file() {
    let dir = common::scratch("options");
    let options = dir.join("one-newton.toml");
    std::fs::write(&options, "substeps = 3\n[sim.newton]\nmax_iterations = 1\n").unwrap();
    let rows = json_lines(&bench_simulate(&[
        "--frames",
        "3",
        "--warmup",
        "1",
        "--options",
        common::s(&options),
        "--json",
    ]));
    assert_eq!(number(&rows[0], "substeps"), 3.0);
    assert_eq!(
        number(&rows[0], "newton_iterations"),
        3.0,
        "one per sub-step"
    );
    // The flag wins over the file.
    let rows = json_lines(&bench_simulate(&[
        "--frames",
        "2",
        "--warmup",
        "1",
        "--options",
        common::s(&options),
        "--substeps",
        "2",
        "--json",
    ]));
    assert_eq!(number(&rows[0], "newton_iterations"), 2.0);

    let typo = dir.join("typo.toml");
    std::fs::write(&typo, "[sim.newton]\nmax_iteration = 1\n").unwrap();
    let g = dir.join("g.obj");
    common::garment(&g, "skirt", 300, 1);
    for args in [
        vec![
            "bench",
            "simulate",
            "--motion",
            "walk",
            "--options",
            common::s(&typo),
        ],
        vec![
            "simulate",
            "--garment",
            common::s(&g),
            "--motion",
            "walk",
            "--options",
            common::s(&typo),
            "--out",
            common::s(&dir.join("sim")),
        ],
    ] {
        let out = weft(&args);
        assert!(!out.status.success());
        let err = stderr(&out);
        assert!(
            err.contains("typo.toml") && err.contains("sim.newton.max_iteration"),
            "{err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    assert!(!dir.join("sim").exists());
}
