"""tools/cluster/ray_generate.py on a local Ray instance of 2 CPUs: a 2-shard dataset,
one shard's worker killed mid-run and retried, merged and verified; and a shard that
stays failed named in the exit."""

import json
import os
import re
import stat
import sys
import time

import pytest

from conftest import CONFIG, SEQUENCES, TOOLS, check_dataset, manifest, run

pytest.importorskip("ray", reason="ray is not installed in tools/cluster/.venv")

DRIVER = TOOLS / "ray_generate.py"


def drive(weft, out, *extra, env=None):
    return run(
        [sys.executable, DRIVER, "--weft", weft, "--config", CONFIG, "--out", out,
         "--workers", 2, "--num-cpus", 2, "--progress-interval", 0, *extra],
        env={**os.environ, **(env or {})},
    )


def test_a_killed_worker_is_retried_resumes_and_the_dataset_merges(weft, tmp_path):
    out, summary = tmp_path / "data", tmp_path / "summary.json"
    started = time.time()
    r = drive(weft, out, "--verify", "--summary-json", summary,
              env={"WEFT_RAY_TEST_KILL_SHARD": "1"})
    print(f"driver: {time.time() - started:.1f} s")
    assert r.returncode == 0, r.stderr

    s = json.loads(summary.read_text())
    assert s["merged"] and s["verified"]
    assert s["sequences"] == SEQUENCES and s["by_status"] == {"done": SEQUENCES}
    assert [(x["shard"], x["status"], x["attempts"]) for x in s["shards"]] == [
        ("0/2", "ok", 1),
        ("1/2", "ok", 2),
    ]
    # The first attempt of shard 1 was killed after one finished sequence; the retry
    # kept it and simulated only the rest.
    state = out / ".weft-ray"
    assert "test hook: weft killed" in (state / "shard-1.attempt-0.log").read_text()
    retry = (state / "shard-1.attempt-1.log").read_text()
    kept = re.search(r"4 sequences in this job, (\d+) kept from an earlier run, (\d+) simulated", retry)
    assert kept, retry
    assert int(kept.group(1)) >= 1 and int(kept.group(1)) + int(kept.group(2)) == 4
    assert "1 retried" in r.stderr and f"sequences {SEQUENCES}/{SEQUENCES} (100 %)" in r.stderr
    assert re.search(r"manifest.json: 8 sequences \(8 done\), 48 frames, 2 shards", r.stdout)

    merged = check_dataset(weft, out)
    # Byte for byte what one job writes, the killed-and-resumed shard included.
    single = tmp_path / "single"
    assert run([weft, "data", "generate", "--config", CONFIG, "--out", single]).returncode == 0
    assert (out / "manifest.json").read_bytes() == (single / "manifest.json").read_bytes()
    for seq in merged["sequences"]:
        assert (out / seq["shard"]).read_bytes() == (single / seq["shard"]).read_bytes()


def test_a_shard_that_stays_failed_is_named_and_nothing_is_merged(weft, tmp_path):
    # A weft that always fails for shard 0 (as a broken node would) and works for 1.
    fake = tmp_path / "weft"
    fake.write_text(
        "#!/bin/sh\n"
        'case "$*" in *"--shard 0/2"*) echo "simulated failure of shard 0" >&2; exit 3;; esac\n'
        f'exec "{weft}" "$@"\n'
    )
    fake.chmod(fake.stat().st_mode | stat.S_IXUSR)
    out = tmp_path / "data"
    r = drive(fake, out, "--retries", 1)
    assert r.returncode == 1
    assert "shard(s) 0/2 failed after 2 attempts" in r.stderr
    assert "simulated failure of shard 0" in r.stderr
    assert not (out / "manifest.json").exists()
    assert re.search(r"0/2\s+failed\s+2", r.stdout) and re.search(r"1/2\s+ok\s+1", r.stdout)
    # Shard 1 finished; a rerun with a working weft resumes it and does only shard 0.
    r = drive(weft, out)
    assert r.returncode == 0, r.stderr
    retry = (out / ".weft-ray" / "shard-1.attempt-0.log").read_text()
    assert "4 sequences in this job, 4 kept from an earlier run, 0 simulated" in retry
    check_dataset(weft, out)


def test_progress_line_has_an_eta(tmp_path):
    import ray_generate

    (tmp_path / "shards").mkdir()
    p = ray_generate.Progress(tmp_path, 2)
    part = {"sequences": [{"index": i, "status": "pending"} for i in range(4)]}
    (tmp_path / "manifest.part-1-of-2.json").write_text(json.dumps(part))
    (tmp_path / "shards" / "a.safetensors").write_bytes(b"")
    (tmp_path / "shards" / ".a.safetensors.1.2.tmp").write_bytes(b"")
    p.started -= 10.0
    assert p.line(0, 0, 1) == "10 s: shards 0/2 finished, 1 retried; sequences 1/4 (25 %), ETA 30 s"
    assert manifest(tmp_path / "manifest.part-1-of-2.json") == part
