#!/usr/bin/env python3
"""Generate a weft dataset over a Ray cluster: one Ray task per `--shard i/N` job.

    ray_generate.py --weft target/release/weft --config paper.toml --out /shared/paper \
        --workers 64 [--address auto] [--cpus-per-task 4] [--retries 3] [--verify]

Each task runs `weft data generate ... --out DIR --shard i/N` as a subprocess on some
node of the cluster. A task whose worker dies (node lost, worker killed, out of memory)
or whose `weft` exits non-zero is retried up to `--retries` times; `weft data generate`
resumes, so a retry keeps every sequence the dead attempt finished and simulates the
rest. When every task has succeeded the driver runs `weft data merge DIR` (and
`weft data info DIR --verify` with `--verify`) on its own node and prints a summary;
it exits non-zero naming the shards that stayed failed (then it does not merge: rerun
the same command, which resumes every shard).

DIR, the config file and the weft binary must be at the same paths on every node: on a
real cluster DIR is a shared filesystem (NFS, Lustre, ...). See docs/cluster.md.

Without `--address` the driver starts a local Ray instance (`--num-cpus`, default all).
Progress lines with an ETA go to stderr; the summary to stdout (`--summary-json F` for
scripts). Needs only `ray` on the nodes; the task code travels with the driver.

Test hook: WEFT_RAY_TEST_KILL_SHARD=i makes the first attempt of shard i kill its weft
process as soon as its partial manifest records one finished sequence and then end its
own Ray worker (os._exit), as a node failure would.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

STATE_DIR = ".weft-ray"  # inside DIR: attempt markers and logs of each task


def log(text: str) -> None:
    print(f"weft-ray: {text}", file=sys.stderr, flush=True)


def fmt_seconds(s: float) -> str:
    s = max(0, int(round(s)))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"


# --------------------------------------------------------------------------- the task


def _parent_death_signal():
    """A preexec_fn giving the child SIGKILL when the Ray worker that started it dies
    (Linux prctl PR_SET_PDEATHSIG), so an orphaned weft never holds the shard's lock
    against the retry; None elsewhere. prctl is looked up here, in the parent, so the
    forked child only makes the call."""
    try:
        import ctypes

        prctl = ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None
    return lambda: prctl(1, signal.SIGKILL)  # 1 = PR_SET_PDEATHSIG


def _claim_attempt(state: Path, index: int) -> int:
    """The number of this attempt at shard `index`: the first free marker file."""
    state.mkdir(parents=True, exist_ok=True)
    attempt = 0
    while True:
        marker = state / f"shard-{index}.attempt-{attempt}"
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            attempt += 1
            continue
        os.write(fd, f"{socket.gethostname()} pid {os.getpid()} at {time.time():.0f}\n".encode())
        os.close(fd)
        return attempt


def _finished_in_part(out: Path, index: int, count: int) -> int:
    """Sequences the job's partial manifest records as no longer pending."""
    try:
        m = json.loads((out / f"manifest.part-{index}-of-{count}.json").read_text())
    except (OSError, ValueError):
        return 0
    return sum(
        1 for s in m["sequences"] if s["index"] % count == index and s["status"] != "pending"
    )


def run_shard(
    weft: str,
    gen_args: list,
    out: str,
    index: int,
    count: int,
    cpus: int,
    test_kill: bool,
) -> dict:
    """Runs one `weft data generate --shard index/count` job; raises when it fails."""
    out_dir = Path(out)
    state = out_dir / STATE_DIR
    attempt = _claim_attempt(state, index)
    log_path = state / f"shard-{index}.attempt-{attempt}.log"
    cmd = [weft, "data", "generate", *gen_args, "--out", out, "--shard", f"{index}/{count}"]
    env = dict(os.environ)
    # weft parallelises over rayon; keep it to the CPUs Ray granted this task.
    env.setdefault("RAYON_NUM_THREADS", str(cpus))
    started = time.time()
    with open(log_path, "w") as logf:
        logf.write(" ".join(cmd) + "\n")
        logf.flush()
        proc = subprocess.Popen(
            cmd, stdout=logf, stderr=subprocess.STDOUT, env=env, preexec_fn=_parent_death_signal()
        )
        if test_kill and attempt == 0:
            while proc.poll() is None and _finished_in_part(out_dir, index, count) < 1:
                time.sleep(0.05)
            if proc.poll() is None:
                proc.kill()
                proc.wait()
                logf.write("test hook: weft killed after its first finished sequence\n")
                logf.flush()
                os._exit(1)  # the Ray worker dies: a system failure, retried by max_retries
        code = proc.wait()
    text = log_path.read_text(errors="replace")
    tail = "\n".join(text.strip().splitlines()[-5:])
    result = {
        "shard": index,
        "attempt": attempt,
        "returncode": code,
        "seconds": time.time() - started,
        "node": socket.gethostname(),
        "log": str(log_path),
        "tail": tail,
    }
    if code != 0:
        raise RuntimeError(
            f"shard {index}/{count} attempt {attempt} on {result['node']}: weft exited "
            f"with {code}: {tail.splitlines()[-1] if tail else '(no output)'}"
        )
    return result


# --------------------------------------------------------------------------- progress


class Progress:
    """Sequences finished, from the shard files in DIR/shards (cheap: one listing)."""

    def __init__(self, out: Path, count: int):
        self.out = out
        self.count = count
        self.total = None  # sequences in the plan, once a partial manifest exists
        self.baseline = self._shards()
        self.started = time.time()

    def _shards(self) -> int:
        try:
            return sum(
                1
                for e in os.scandir(self.out / "shards")
                if e.name.endswith(".safetensors") and not e.name.startswith(".")
            )
        except OSError:
            return 0

    def _plan_size(self):
        if self.total is None:
            for i in range(self.count):
                try:
                    m = json.loads((self.out / f"manifest.part-{i}-of-{self.count}.json").read_text())
                    self.total = len(m["sequences"])
                    break
                except (OSError, ValueError, KeyError):
                    continue
        return self.total

    def line(self, finished: int, failed: int, retried: int) -> str:
        elapsed = time.time() - self.started
        done = self._shards()
        total = self._plan_size()
        text = f"{fmt_seconds(elapsed)}: shards {finished}/{self.count} finished"
        if failed:
            text += f", {failed} failed"
        if retried:
            text += f", {retried} retried"
        if total:
            text += f"; sequences {done}/{total} ({100.0 * done / total:.0f} %)"
            new = done - self.baseline
            if new > 0 and done < total:
                text += f", ETA {fmt_seconds(elapsed / new * (total - done))}"
        return text


# --------------------------------------------------------------------------- driver


def parse_args(argv):
    p = argparse.ArgumentParser(
        description="Generate a weft dataset with one Ray task per --shard i/N job, then merge.",
    )
    p.add_argument("--weft", default=os.environ.get("WEFT_BIN", "weft"),
                   help="the weft binary (same path on every node; default $WEFT_BIN or weft on PATH)")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--preset", help="tiny, small or paper")
    src.add_argument("--config", help="a dataset config (TOML), same path on every node")
    p.add_argument("--seed", type=int, help="override the config's seed")
    p.add_argument("--out", required=True, help="the dataset directory (shared by every node)")
    p.add_argument("--workers", type=int, required=True, help="number of shards N (Ray tasks)")
    p.add_argument("--address", help="an existing Ray cluster (e.g. auto or ray://head:10001); "
                   "default: start a local one")
    p.add_argument("--num-cpus", type=int, help="CPUs of the local Ray instance (default: all)")
    p.add_argument("--cpus-per-task", type=int, default=1,
                   help="CPUs each task reserves and weft's threads (RAYON_NUM_THREADS); default 1")
    p.add_argument("--retries", type=int, default=3,
                   help="retries of a task whose worker died or whose weft failed (default 3)")
    p.add_argument("--verify", action="store_true",
                   help="after merging, run `weft data info DIR --verify`")
    p.add_argument("--progress-interval", type=float, default=10.0,
                   help="seconds between progress lines on stderr (default 10)")
    p.add_argument("--summary-json", help="also write the summary as JSON to this file")
    a = p.parse_args(argv)
    if a.workers < 1:
        p.error("--workers must be at least 1")
    if a.cpus_per_task < 1:
        p.error("--cpus-per-task must be at least 1")
    if a.retries < 0:
        p.error("--retries must be 0 or more")
    return a


def resolve_weft(path: str) -> str:
    found = shutil.which(path)
    if found is None:
        sys.exit(f"weft-ray: error: --weft {path}: no such executable")
    return os.path.abspath(found)


def main(argv=None) -> int:
    a = parse_args(argv)
    weft = resolve_weft(a.weft)
    out = Path(a.out).resolve()
    gen_args = ["--config", str(Path(a.config).resolve())] if a.config else ["--preset", a.preset]
    if a.seed is not None:
        gen_args += ["--seed", str(a.seed)]
    # Refuse a bad config or preset here, in one line, rather than in N tasks.
    check = subprocess.run([weft, "data", "generate", *gen_args, "--print-config"],
                           capture_output=True, text=True)
    if check.returncode != 0:
        sys.exit(f"weft-ray: error: {check.stderr.strip()}")
    out.mkdir(parents=True, exist_ok=True)
    state = out / STATE_DIR
    shutil.rmtree(state, ignore_errors=True)
    state.mkdir()
    test_kill = os.environ.get("WEFT_RAY_TEST_KILL_SHARD")
    test_kill = int(test_kill) if test_kill not in (None, "") else None

    import logging

    import ray

    if __name__ != "__main__":  # imported: send the task code by value, not by module name
        ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    if a.address:
        ray.init(address=a.address, logging_level=logging.WARNING)
    else:
        ray.init(num_cpus=a.num_cpus, include_dashboard=False, logging_level=logging.WARNING)
    try:
        return drive(a, ray, weft, out, gen_args, test_kill)
    finally:
        ray.shutdown()


def drive(a, ray, weft, out, gen_args, test_kill) -> int:
    n = a.workers
    task = ray.remote(run_shard).options(
        num_cpus=a.cpus_per_task, max_retries=a.retries, retry_exceptions=True
    )
    started = time.time()
    log(f"{n} shards of `weft data generate {' '.join(gen_args)} --out {out}` "
        f"({a.cpus_per_task} CPU each, up to {a.retries} retries)")
    refs = {task.remote(weft, gen_args, str(out), i, n, a.cpus_per_task, test_kill == i): i
            for i in range(n)}
    results, failures = {}, {}
    progress = Progress(out, n)
    pending = list(refs)
    last = 0.0
    while pending:
        ready, pending = ray.wait(pending, num_returns=len(pending), timeout=1.0)
        for ref in ready:
            i = refs[ref]
            try:
                results[i] = ray.get(ref)
            except Exception as e:  # RayTaskError, WorkerCrashedError, ...
                lines = [x.strip() for x in str(e).splitlines() if x.strip()]
                failures[i] = lines[-1] if lines else repr(e)
                log(f"shard {i}/{n} failed for good: {failures[i]}")
        now = time.time()
        if now - last >= a.progress_interval or not pending:
            log(progress.line(len(results) + len(failures), len(failures), retried(out, n)))
            last = now

    attempts = attempt_counts(out, n)
    shards = []
    for i in range(n):
        r = results.get(i, {})
        shards.append({
            "shard": f"{i}/{n}",
            "status": "ok" if i in results else "failed",
            "attempts": attempts.get(i, 0),
            "seconds": round(r.get("seconds", 0.0), 2),
            "node": r.get("node"),
            "last_line": r.get("tail", "").splitlines()[-1] if r.get("tail") else None,
            "error": failures.get(i),
        })
    summary = {"out": str(out), "workers": n, "shards": shards, "merged": False}

    code = 0
    if failures:
        names = ", ".join(f"{i}/{n}" for i in sorted(failures))
        log(f"error: shard(s) {names} failed after {a.retries + 1} attempts (logs in "
            f"{out / STATE_DIR}); not merging. Rerun the same command: finished shards are kept.")
        code = 1
    else:
        merge = subprocess.run([weft, "data", "merge", str(out)], capture_output=True, text=True)
        if merge.returncode != 0:
            log(f"error: weft data merge failed: {merge.stderr.strip()}")
            code = 1
        else:
            summary["merged"] = True
            m = json.loads((out / "manifest.json").read_text())
            by_status = {}
            for s in m["sequences"]:
                by_status[s["status"]] = by_status.get(s["status"], 0) + 1
            summary["sequences"] = len(m["sequences"])
            summary["by_status"] = by_status
            summary["frames"] = sum(s["frames"] for s in m["sequences"])
            if by_status.get("pending") or by_status.get("failed"):
                log(f"error: the merged manifest still has {by_status.get('pending', 0)} pending "
                    f"and {by_status.get('failed', 0)} failed sequences")
                code = 1
            if a.verify:
                v = subprocess.run([weft, "data", "info", str(out), "--verify"],
                                   capture_output=True, text=True)
                summary["verified"] = v.returncode == 0
                if v.returncode != 0:
                    log(f"error: weft data info --verify failed: {v.stderr.strip()}")
                    code = 1
    summary["seconds"] = round(time.time() - started, 2)
    print_summary(summary)
    if a.summary_json:
        Path(a.summary_json).write_text(json.dumps(summary, indent=2) + "\n")
    return code


def retried(out: Path, n: int) -> int:
    return sum(1 for c in attempt_counts(out, n).values() if c > 1)


def attempt_counts(out: Path, n: int) -> dict:
    counts = {}
    try:
        for e in os.scandir(out / STATE_DIR):
            name = e.name
            if name.startswith("shard-") and ".attempt-" in name and not name.endswith(".log"):
                i = int(name[len("shard-"):name.index(".attempt-")])
                counts[i] = counts.get(i, 0) + 1
    except OSError:
        pass
    return counts


def print_summary(s: dict) -> None:
    if s.get("merged"):
        st = ", ".join(f"{v} {k}" for k, v in sorted(s["by_status"].items()))
        print(f"{s['out']}/manifest.json: {s['sequences']} sequences ({st}), {s['frames']} frames, "
              f"{s['workers']} shards in {s['seconds']:.1f} s"
              + ("; verified" if s.get("verified") else ""))
    else:
        print(f"{s['out']}: not merged; {s['workers']} shards in {s['seconds']:.1f} s")
    rows = s["shards"]
    show = rows if len(rows) <= 50 else [r for r in rows if r["status"] != "ok" or r["attempts"] > 1]
    if len(rows) > 50:
        slow = sorted(rows, key=lambda r: -r["seconds"])[:5]
        print(f"{sum(r['status'] == 'ok' for r in rows)} of {len(rows)} shards ok; slowest: "
              + ", ".join(f"{r['shard']} {r['seconds']:.0f} s" for r in slow))
    if show:
        print(f"{'shard':>10}  {'status':6}  {'attempts':>8}  {'seconds':>8}  last line")
        for r in show:
            last = r["error"] or r["last_line"] or ""
            print(f"{r['shard']:>10}  {r['status']:6}  {r['attempts']:>8}  {r['seconds']:>8.1f}  {last}")


if __name__ == "__main__":
    sys.exit(main())
