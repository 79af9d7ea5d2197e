//! Dataset generation fanned out over a cluster (tools/cluster, docs/cluster.md), driven
//! by this weft binary:
//!
//! - `ray_generate.py` on a local Ray instance of 2 CPUs: a 2-shard dataset where the
//!   first attempt of shard 1 is killed after its first finished sequence (weft and its
//!   Ray worker); the retry resumes, the merged manifest is byte-identical to one job's,
//!   `weft data info --verify` passes; a shard that stays failed is named, nothing is
//!   merged, and a rerun resumes;
//! - `slurm_generate.py`: the dry run's array and merge scripts and sbatch commands, and
//!   the written scripts run as Slurm would (one index preempted and requeued) under a
//!   fake `sbatch`, then the merge job.
//!
//! Runs `tools/cluster/tests` with pytest from `tools/cluster/.venv` (ray and pytest,
//! pinned in `tools/cluster/requirements.txt`; `.ci/run` installs them), `WEFT_BIN` set
//! to this binary. When that environment or pytest is missing the test prints how to
//! make it and passes; without ray the Slurm tests still run and the Ray ones are
//! reported skipped.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

#[test]
fn cluster_drivers_generate_merge_and_resume() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let tools = root.join("tools/cluster");
    let python = tools.join(".venv/bin/python");
    let how = format!(
        "run `python3 -m venv {0}/.venv && {0}/.venv/bin/pip install -r {0}/requirements.txt`",
        tools.display()
    );
    if !python.is_file() {
        eprintln!("SKIPPED cluster drivers check: tools/cluster/.venv is missing; {how}");
        return;
    }
    let imports = |module: &str| {
        Command::new(&python)
            .args(["-c", &format!("import {module}")])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if !imports("pytest") {
        eprintln!(
            "SKIPPED cluster drivers check: {} cannot import pytest; {how}",
            python.display()
        );
        return;
    }
    if !imports("ray") {
        eprintln!(
            "SKIPPED Ray driver check: {} cannot import ray (the Slurm checks still run); {how}",
            python.display()
        );
    }
    let started = Instant::now();
    let out = Command::new(&python)
        .args([
            "-m",
            "pytest",
            "tools/cluster/tests",
            "-q",
            "-rs",
            "-p",
            "no:cacheprovider",
        ])
        .current_dir(&root)
        .env("WEFT_BIN", env!("CARGO_BIN_EXE_weft"))
        .output()
        .expect("run pytest");
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!(
        "{stdout}{}\npytest took {:.1} s",
        String::from_utf8_lossy(&out.stderr),
        started.elapsed().as_secs_f64()
    );
    assert!(out.status.success(), "tools/cluster/tests failed");
    assert!(stdout.contains("passed"), "pytest ran no test");
}
