#!/usr/bin/env python3
"""Generate a weft dataset on Slurm: a job array of `--shard i/N` jobs, then a merge job.

    slurm_generate.py --weft /shared/weft/target/release/weft --config paper.toml \
        --out /shared/data/paper --workers 64 [--cpus-per-task 4] [--time 24:00:00] \
        [--partition P] [--account A] [--max-parallel K] [--verify] [--dry-run]

Writes two batch scripts into DIR/slurm/ (`--script-dir` to choose):

- generate.sbatch, a job array `--array=0-(N-1)`: task i runs
  `weft data generate ... --out DIR --shard $SLURM_ARRAY_TASK_ID/N`, with `--requeue`
  so a preempted task, or one on a node that failed, is requeued; weft resumes, so the
  rerun keeps every sequence finished before and simulates the rest;
- merge.sbatch: `weft data merge DIR` (and `weft data info DIR --verify`), submitted
  with `--dependency=afterok:<array job id> --kill-on-invalid-dep=yes`, so it runs once
  every array task has succeeded and is cancelled if one fails;

then submits them with `sbatch --parsable` and prints the job ids. `--dry-run` prints
the scripts and the sbatch commands and writes and submits nothing. `--indices 3,17`
resubmits only those array tasks (after a failure; they resume), with the merge again.

DIR, the config and the weft binary must be at the same paths on every node (a shared
filesystem); the paths are made absolute here. Only the standard library is needed, so
this runs on any login node with Python 3.8+. See docs/cluster.md.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path


def parse_args(argv):
    p = argparse.ArgumentParser(
        description="Write (and submit) a Slurm job array of weft --shard i/N jobs and a merge job.",
    )
    p.add_argument("--weft", default=os.environ.get("WEFT_BIN", "weft"),
                   help="the weft binary, at this path on every node (default $WEFT_BIN or weft on PATH)")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--preset", help="tiny, small or paper")
    src.add_argument("--config", help="a dataset config (TOML) on the shared filesystem")
    p.add_argument("--seed", type=int, help="override the config's seed")
    p.add_argument("--out", required=True, help="the dataset directory (shared filesystem)")
    p.add_argument("--workers", type=int, required=True, help="number of shards N (array tasks)")
    p.add_argument("--indices", help="submit only these array indices, e.g. 3,17 or 0-9 "
                   "(to rerun failed tasks; default all of 0-(N-1))")
    p.add_argument("--cpus-per-task", type=int, default=1,
                   help="CPUs per array task, also weft's threads (default 1)")
    p.add_argument("--mem", help="memory per array task (sbatch --mem), e.g. 4G")
    p.add_argument("--time", default="24:00:00", help="time limit per array task (default 24:00:00)")
    p.add_argument("--merge-time", default="1:00:00", help="time limit of the merge job (default 1:00:00)")
    p.add_argument("--partition", help="sbatch --partition")
    p.add_argument("--account", help="sbatch --account")
    p.add_argument("--max-parallel", type=int, help="at most K array tasks at once (--array=...%%K)")
    p.add_argument("--job-name", default="weft-gen", help="job name (default weft-gen; merge: NAME-merge)")
    p.add_argument("--sbatch-option", action="append", default=[], metavar="OPT",
                   help="an extra #SBATCH option for both scripts, e.g. --qos=low (repeatable)")
    p.add_argument("--script-dir", help="where the scripts and logs go (default DIR/slurm)")
    p.add_argument("--verify", action="store_true",
                   help="the merge job also runs `weft data info DIR --verify`")
    p.add_argument("--dry-run", action="store_true",
                   help="print the scripts and sbatch commands; write and submit nothing")
    a = p.parse_args(argv)
    if a.workers < 1:
        p.error("--workers must be at least 1")
    if a.cpus_per_task < 1:
        p.error("--cpus-per-task must be at least 1")
    if a.max_parallel is not None and a.max_parallel < 1:
        p.error("--max-parallel must be at least 1")
    for opt in a.sbatch_option:
        if not opt.startswith("-") or "\n" in opt:
            p.error(f"--sbatch-option {opt!r}: expected one sbatch option such as --qos=low")
    if a.indices is not None:
        a.indices = check_indices(p, a.indices, a.workers)
    return a


def check_indices(p, text: str, n: int) -> str:
    """Validates an array index list (`3,17`, `0-9`, `0-9,20`) against 0..n-1."""
    for part in text.split(","):
        m = re.fullmatch(r"(\d+)(?:-(\d+))?", part.strip())
        if not m:
            p.error(f"--indices {text!r}: expected numbers and ranges such as 3,17 or 0-9")
        lo, hi = int(m.group(1)), int(m.group(2) or m.group(1))
        if lo > hi or hi >= n:
            p.error(f"--indices {text!r}: {part} is not within 0-{n - 1}")
    return ",".join(part.strip() for part in text.split(","))


def q(x) -> str:
    return shlex.quote(str(x))


def header(a, name: str, log: Path, extra: list) -> list:
    lines = ["#!/bin/bash", f"#SBATCH --job-name={name}"]
    lines += [f"#SBATCH {x}" for x in extra]
    if a.partition:
        lines.append(f"#SBATCH --partition={a.partition}")
    if a.account:
        lines.append(f"#SBATCH --account={a.account}")
    lines += [f"#SBATCH {opt}" for opt in a.sbatch_option]
    # sbatch reads double-quoted values in #SBATCH lines (a path with a space).
    log = f'"{log}"' if any(c.isspace() for c in str(log)) else str(log)
    lines.append(f"#SBATCH --output={log}")
    return lines


def scripts(a, weft: str, out: Path, gen_args: list, script_dir: Path) -> dict:
    n = a.workers
    logs = script_dir / "logs"
    array = a.indices if a.indices is not None else (f"0-{n - 1}" if n > 1 else "0")
    if a.max_parallel:
        array += f"%{a.max_parallel}"
    extra = [f"--array={array}", f"--cpus-per-task={a.cpus_per_task}", f"--time={a.time}"]
    if a.mem:
        extra.append(f"--mem={a.mem}")
    # A requeued task (preempted, node failure) appends to its log and resumes its shard.
    extra += ["--requeue", "--open-mode=append"]
    generate = header(a, a.job_name, logs / "generate-%A_%a.out", extra) + [
        "# One --shard i/N job of a weft dataset per array task (tools/cluster/slurm_generate.py).",
        "# A rerun of the same task resumes: finished sequences are kept.",
        "set -euo pipefail",
        'export RAYON_NUM_THREADS="${SLURM_CPUS_PER_TASK:-1}"',
        f'echo "weft shard ${{SLURM_ARRAY_TASK_ID}}/{n} on $(hostname), '
        f'restart ${{SLURM_RESTART_COUNT:-0}}, $(date -Is)"',
        "exec " + " ".join(q(x) for x in [weft, "data", "generate", *gen_args, "--out", out])
        + f' --shard "${{SLURM_ARRAY_TASK_ID}}/{n}"',
    ]
    merge_extra = ["--cpus-per-task=1", f"--time={a.merge_time}"]
    merge = header(a, f"{a.job_name}-merge", logs / "merge-%j.out", merge_extra) + [
        f"# Merges the {n} partial manifests into manifest.json once every array task succeeded.",
        "set -euo pipefail",
        " ".join(q(x) for x in [weft, "data", "merge", out]),
    ]
    if a.verify:
        merge.append(" ".join(q(x) for x in [weft, "data", "info", out, "--verify"]))
    return {
        script_dir / "generate.sbatch": "\n".join(generate) + "\n",
        script_dir / "merge.sbatch": "\n".join(merge) + "\n",
    }


def main(argv=None) -> int:
    a = parse_args(argv)
    found = shutil.which(a.weft)
    weft = os.path.abspath(found) if found else a.weft
    if found is None and not a.dry_run:
        sys.exit(f"slurm_generate: error: --weft {a.weft}: no such executable here "
                 "(it must exist at the same path on the compute nodes)")
    out = Path(a.out).resolve()
    if a.config:
        config = Path(a.config).resolve()
        if not config.is_file() and not a.dry_run:
            sys.exit(f"slurm_generate: error: --config {config}: no such file")
        gen_args = ["--config", str(config)]
    else:
        gen_args = ["--preset", a.preset]
    if a.seed is not None:
        gen_args += ["--seed", str(a.seed)]
    if found is not None:
        # Refuse a bad config or preset now, not in N array tasks.
        check = subprocess.run([weft, "data", "generate", *gen_args, "--print-config"],
                               capture_output=True, text=True)
        if check.returncode != 0:
            sys.exit(f"slurm_generate: error: {check.stderr.strip()}")
    script_dir = Path(a.script_dir).resolve() if a.script_dir else out / "slurm"
    files = scripts(a, weft, out, gen_args, script_dir)
    gen_path, merge_path = list(files)
    submit_array = ["sbatch", "--parsable", str(gen_path)]

    def submit_merge(job_id: str) -> list:
        return ["sbatch", "--parsable", f"--dependency=afterok:{job_id}",
                "--kill-on-invalid-dep=yes", str(merge_path)]

    if a.dry_run:
        for path, text in files.items():
            print(f"# ---- {path} ----")
            print(text, end="")
        print("# ---- commands ----")
        print(f"mkdir -p {q(script_dir / 'logs')}")
        print(f"ARRAY_JOB_ID=$({' '.join(q(x) for x in submit_array)} | cut -d';' -f1)")
        print(" ".join(q(x) for x in submit_merge("ID")).replace(
            "--dependency=afterok:ID", '--dependency=afterok:"$ARRAY_JOB_ID"'))
        return 0

    if shutil.which("sbatch") is None:
        sys.exit("slurm_generate: error: sbatch is not on PATH (run this on a Slurm login node, "
                 "or use --dry-run to see the scripts)")
    (script_dir / "logs").mkdir(parents=True, exist_ok=True)
    out.mkdir(parents=True, exist_ok=True)
    for path, text in files.items():
        path.write_text(text)
    array_id = sbatch(submit_array)
    merge_id = sbatch(submit_merge(array_id))
    print(f"submitted array job {array_id} ({a.indices or f'0-{a.workers - 1}'} of {a.workers} "
          f"shards) and merge job {merge_id} (after all of them succeed)")
    print(f"scripts and logs: {script_dir}; watch with `squeue -j {array_id},{merge_id}`")
    return 0


def sbatch(cmd: list) -> str:
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"slurm_generate: error: {' '.join(cmd)} failed: {r.stderr.strip()}")
    job_id = r.stdout.strip().split(";")[0]  # --parsable: "id" or "id;cluster"
    if not job_id.isdigit():
        sys.exit(f"slurm_generate: error: {' '.join(cmd)} printed {r.stdout.strip()!r}, not a job id")
    return job_id


if __name__ == "__main__":
    sys.exit(main())
