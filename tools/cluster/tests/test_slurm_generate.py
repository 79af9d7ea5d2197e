"""tools/cluster/slurm_generate.py: the dry run's scripts and sbatch commands, and the
written scripts run as Slurm would run them (one process per array index, one index
killed and run again as a requeue does, then the merge job) under a fake sbatch."""

import os
import re
import signal
import stat
import subprocess
import sys
import time

from conftest import CONFIG, SEQUENCES, TOOLS, check_dataset, run

GEN = TOOLS / "slurm_generate.py"


def test_dry_run_prints_the_array_the_merge_and_the_commands(weft, tmp_path):
    out = tmp_path / "data"
    r = run([sys.executable, GEN, "--weft", weft, "--config", CONFIG, "--out", out,
             "--workers", 4, "--cpus-per-task", 2, "--partition", "cpu", "--verify", "--dry-run"])
    assert r.returncode == 0, r.stderr
    text = r.stdout
    gen, merge = out / "slurm" / "generate.sbatch", out / "slurm" / "merge.sbatch"
    assert f"# ---- {gen} ----" in text and f"# ---- {merge} ----" in text
    for line in [
        "#SBATCH --array=0-3",
        "#SBATCH --cpus-per-task=2",
        "#SBATCH --requeue",
        "#SBATCH --open-mode=append",
        "#SBATCH --partition=cpu",
        f"#SBATCH --output={out}/slurm/logs/generate-%A_%a.out",
        'export RAYON_NUM_THREADS="${SLURM_CPUS_PER_TASK:-1}"',
        f'exec {weft} data generate --config {CONFIG} --out {out} --shard "${{SLURM_ARRAY_TASK_ID}}/4"',
        f"{weft} data merge {out}",
        f"{weft} data info {out} --verify",
        f"ARRAY_JOB_ID=$(sbatch --parsable {gen} | cut -d';' -f1)",
        f'sbatch --parsable --dependency=afterok:"$ARRAY_JOB_ID" --kill-on-invalid-dep=yes {merge}',
    ]:
        assert line in text.splitlines(), line
    assert not out.exists(), "a dry run writes nothing"


def test_dry_run_resubmits_chosen_indices_and_refuses_bad_ones(weft, tmp_path):
    base = [sys.executable, GEN, "--weft", weft, "--preset", "paper", "--out", tmp_path / "d",
            "--workers", 1000, "--dry-run"]
    r = run(base + ["--indices", "3,17,990-999", "--max-parallel", 200])
    assert r.returncode == 0 and "#SBATCH --array=3,17,990-999%200" in r.stdout.splitlines()
    assert '--shard "${SLURM_ARRAY_TASK_ID}/1000"' in r.stdout
    r = run(base + ["--indices", "1000"])
    assert r.returncode == 2 and "1000 is not within 0-999" in r.stderr
    r = run([sys.executable, GEN, "--weft", weft, "--preset", "nope", "--out", tmp_path / "d",
             "--workers", 2])
    assert r.returncode == 1 and "nope" in r.stderr


def first_sequence_done(part):
    try:
        return '"status": "done"' in part.read_text()
    except OSError:
        return False


def test_the_scripts_run_as_slurm_would_with_a_requeued_task(weft, tmp_path):
    # A fake sbatch on PATH records its arguments and answers job ids as --parsable does.
    bin_dir, calls = tmp_path / "bin", tmp_path / "sbatch-calls"
    bin_dir.mkdir()
    sbatch = bin_dir / "sbatch"
    sbatch.write_text(
        "#!/bin/sh\n"
        f'echo "$*" >> "{calls}"\n'
        f'n=$(wc -l < "{calls}")\n'
        'if [ "$n" = 1 ]; then echo 4242; else echo "4243;cluster"; fi\n'
    )
    sbatch.chmod(sbatch.stat().st_mode | stat.S_IXUSR)
    env = {**os.environ, "PATH": f"{bin_dir}:{os.environ['PATH']}"}
    out = tmp_path / "data"
    r = run([sys.executable, GEN, "--weft", weft, "--config", CONFIG, "--out", out,
             "--workers", 2, "--verify"], env=env)
    assert r.returncode == 0, r.stderr
    assert "submitted array job 4242 (0-1 of 2 shards) and merge job 4243" in r.stdout
    gen, merge = out / "slurm" / "generate.sbatch", out / "slurm" / "merge.sbatch"
    assert calls.read_text().splitlines() == [
        f"--parsable {gen}",
        f"--parsable --dependency=afterok:4242 --kill-on-invalid-dep=yes {merge}",
    ]
    assert (out / "slurm" / "logs").is_dir()

    # Slurm's part: each array index runs the script with its SLURM_ARRAY_TASK_ID.
    def task(i, restart=0):
        return subprocess.Popen(
            ["bash", gen], env={**os.environ, "SLURM_ARRAY_TASK_ID": str(i),
                                "SLURM_CPUS_PER_TASK": "1", "SLURM_RESTART_COUNT": str(restart)},
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)

    # Index 1 is preempted after its first finished sequence (SIGKILL), then requeued.
    t1 = task(1)
    part = out / "manifest.part-1-of-2.json"
    deadline = time.time() + 120
    while t1.poll() is None and not first_sequence_done(part) and time.time() < deadline:
        time.sleep(0.05)
    assert t1.poll() is None, "task 1 finished before it could be preempted: " + t1.stdout.read()
    os.killpg(t1.pid, signal.SIGKILL)
    t1.wait()
    t0 = task(0)
    assert t0.wait(timeout=240) == 0, t0.stdout.read()
    t1 = task(1, restart=1)
    assert t1.wait(timeout=240) == 0
    log1 = t1.stdout.read()
    print(log1)
    assert "weft shard 1/2" in log1 and "restart 1" in log1
    kept = re.search(r"4 sequences in this job, (\d+) kept from an earlier run, (\d+) simulated", log1)
    assert kept and int(kept.group(1)) >= 1 and int(kept.group(1)) + int(kept.group(2)) == 4

    # The merge job, once both succeeded.
    m = run(["bash", merge])
    assert m.returncode == 0, m.stderr
    assert f"verified: {SEQUENCES} shards" in m.stdout
    check_dataset(weft, out)
