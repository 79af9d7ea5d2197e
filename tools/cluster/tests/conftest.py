"""Shared fixtures: the weft binary under test ($WEFT_BIN, set by
crates/weft-cli/tests/cluster_cli.rs) and the small test config."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
TOOLS = HERE.parent
CONFIG = HERE / "small.toml"
SEQUENCES = 8  # what small.toml plans

sys.path.insert(0, str(TOOLS))


@pytest.fixture(scope="session")
def weft():
    path = os.environ.get("WEFT_BIN")
    if not path or not Path(path).is_file():
        pytest.skip("WEFT_BIN is not set to the weft binary (cargo test -p weft-cli --test cluster_cli sets it)")
    return path


def run(cmd, timeout=240, **kw):
    """Runs a command, echoing its output so a failing test shows it."""
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=timeout, **kw)
    sys.stdout.write(f"$ {' '.join(str(c) for c in cmd)}\n{r.stdout}")
    sys.stderr.write(r.stderr)
    return r


def manifest(path: Path) -> dict:
    return json.loads(path.read_text())


def check_dataset(weft: str, out: Path) -> dict:
    """The merged manifest lists every planned sequence, each done with its shard on
    disk, and `weft data info --verify` passes. Returns the manifest."""
    m = manifest(out / "manifest.json")
    assert "job" not in m, "manifest.json is still a partial manifest"
    assert len(m["sequences"]) == SEQUENCES
    assert [s["index"] for s in m["sequences"]] == list(range(SEQUENCES))
    assert {s["status"] for s in m["sequences"]} == {"done"}
    for s in m["sequences"]:
        assert (out / s["shard"]).is_file(), s["shard"]
        assert s["frames"] == 6 and len(s["sha256"]) == 64
    v = run([weft, "data", "info", out, "--verify"])
    assert v.returncode == 0, v.stderr
    assert f"verified: {SEQUENCES} shards" in v.stdout
    return m
