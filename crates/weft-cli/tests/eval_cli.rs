//! `weft eval`, `weft attribute` and `weft animate` through the real binary, on a run
//! and dataset made by the demo pipeline's micro configuration with the stand-in
//! simulator (seconds, not the minutes of real simulation); bad input gives one line on
//! stderr and a non-zero exit.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use weft_data::Silent;
use weft_pipeline::demo::{run_demo, DemoOptions};
use weft_pipeline::stand_in::StandInSimulator;

mod common;
use common::{s, stderr, stdout, weft};

/// The micro demo's directory (data/, run/, animation/), made once per test process.
fn demo() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("eval_cli_demo");
        let _ = std::fs::remove_dir_all(&dir);
        let opts = DemoOptions {
            out: dir.clone(),
            quick: true,
            steps: None,
        };
        run_demo(&opts, &StandInSimulator, &Silent, &mut |_| {}).expect("micro demo");
        dir
    })
}

#[test]
fn eval_writes_the_report_and_the_comparison() {
    let d = demo();
    let (run, data) = (d.join("run"), d.join("data"));
    let o = weft(&["eval", s(&run), "--data", s(&data), "--json", "--no-timing"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    assert_eq!(r["split"], "test");
    assert_eq!(r["methods"][1]["name"], "LBS only");
    assert!(r["frames"].as_u64().unwrap() > 0);
    assert!(
        r["methods"][0]["overall"]["e_verts_mm"]["mean"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    assert!(r["command"].as_str().unwrap().contains("eval"));
    for f in ["eval.json", "eval.md", "eval.html", "comparison.png"] {
        assert!(run.join("report").join(f).is_file(), "{f}");
    }
    let table = d.join("table1");
    let o = weft(&[
        "eval",
        s(&run),
        s(&run),
        "--data",
        s(&data),
        "--compare",
        "--reuse",
        "--out",
        s(&table),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let md = std::fs::read_to_string(table.join("table1.md")).unwrap();
    assert!(md.contains("LBS only") && md.contains("Multilevel"), "{md}");
    assert!(table.join("table1.html").is_file());
}

#[test]
fn attribute_draws_the_map_and_is_complete() {
    let d = demo();
    let (png, data) = (d.join("attr.png"), d.join("data"));
    let o = weft(&[
        "attribute",
        s(&d.join("run")),
        "--data",
        s(&data),
        "--vertex",
        "7",
        "--frame",
        "2",
        "--samples",
        "6",
        "--size",
        "300",
        "--out",
        s(&png),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
    let change = r["output"].as_f64().unwrap() - r["baseline_output"].as_f64().unwrap();
    let gap = r["completeness_gap"].as_f64().unwrap();
    assert!(
        gap.abs() <= 0.05 * change.abs().max(1e-3),
        "gap {gap}, change {change}"
    );
    assert!(png.is_file());
}

#[test]
fn animate_exports_an_unseen_garment() {
    let d = demo();
    let garment = d.join("animation").join("garment.obj");
    let out = d.join("walk.pc2");
    let run = d.join("run");
    let animate = |args: &[&str]| {
        let mut all = vec!["animate", s(&run), "--garment", s(&garment)];
        all.extend_from_slice(args);
        weft(&all)
    };
    let o = animate(&[
        "--motion",
        "walk",
        "--frames",
        "5",
        "--format",
        "pc2",
        "--out",
        s(&out),
        "--betas",
        "0.8,-1.2",
        "--push-out",
        "4",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let pc2 = weft_mesh::export::pc2::read_pc2(&out).unwrap();
    assert_eq!(pc2.frames.frame_count(), 5);
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(report["pushed_out_vertices"].is_u64(), "{report}");
    // The check runs on what was written: after a 4 mm push-out nothing is inside.
    let check = &report["check"];
    assert_eq!(check["frames"], 5, "{report}");
    assert_eq!(check["inside"].as_f64(), Some(0.0), "{report}");
    assert!(
        check["strain_max"].as_f64().is_some_and(|m| m >= 0.0),
        "{report}"
    );
    let o = animate(&[
        "--motion",
        "walk",
        "--format",
        "pc2",
        "--out",
        s(&d.join("never.pc2")),
        "--push-out=-1",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--push-out"), "{}", stderr(&o));
    assert!(!d.join("never.pc2").exists());
    let glb = d.join("walk.glb");
    let o = animate(&[
        "--motion",
        "run",
        "--frames",
        "3",
        "--format",
        "glb",
        "--out",
        s(&glb),
        "--betas",
        "0.8,-1.2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(glb.is_file());
}

#[test]
fn bad_input_is_one_line_and_writes_nothing() {
    let d = demo();
    let run = d.join("run");
    let (data, garment) = (d.join("data"), d.join("animation/garment.obj"));
    let (never_png, never_pc2) = (d.join("never.png"), d.join("never.pc2"));
    let cases: [(Vec<&str>, &str); 8] = [
        (vec!["eval", s(&run)], "--data DIR is required"),
        (
            vec!["eval", s(&run), "--data", s(&data), "--strain-limit", "5"],
            "--strain-limit applies to hood runs",
        ),
        (
            vec!["eval", s(&run), "--data", s(&data), "--refine", "2"],
            "--refine applies to hood runs",
        ),
        (
            vec!["eval", s(&run), "--data", s(&data), "--objective"],
            "--objective applies to hood runs",
        ),
        (vec!["eval", "no/such/run", "--data", "x"], "config.toml"),
        (
            vec![
                "attribute",
                s(&run),
                "--vertex",
                "0",
                "--out",
                "a.jpg",
                "--data",
                "x",
            ],
            "must end in .png",
        ),
        (
            vec![
                "attribute",
                s(&run),
                "--vertex",
                "99999",
                "--data",
                s(&data),
                "--out",
                s(&never_png),
            ],
            "does not exist",
        ),
        (
            vec![
                "animate",
                s(&run),
                "--garment",
                s(&garment),
                "--motion",
                "moonwalk-not-a-file",
                "--format",
                "pc2",
                "--out",
                s(&never_pc2),
            ],
            "neither an existing",
        ),
    ];
    for (args, want) in cases {
        let o = weft(&args);
        assert!(!o.status.success(), "{args:?} succeeded");
        let e = stderr(&o);
        assert!(e.contains(want), "{args:?}: {e}");
        assert_eq!(
            e.trim_end()
                .lines()
                .filter(|l| l.starts_with("error"))
                .count(),
            1,
            "{e}"
        );
    }
    assert!(!d.join("never.png").exists() && !d.join("never.pc2").exists());
}
