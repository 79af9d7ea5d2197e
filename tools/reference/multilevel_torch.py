"""The Multilevel model's two heaviest parts in PyTorch + PyTorch Geometric, for
`weft bench multilevel --preset paper` to be compared with on the same machine (issue 16,
docs/benchmarks.md).

    weft garment generate --kind skirt --vertices 4000 --seed 1 --out skirt.obj
    mkdir levels && weft mesh hierarchy skirt.obj --levels 3 --out levels --json > levels/hierarchy.json
    tools/reference/.venv/bin/python tools/reference/multilevel_torch.py levels --batch 1,16

`levels` holds weft's structure-preserving hierarchy of the skirt (`level_<l>.ply` and
which vertices each level keeps), so both sides run on the same graphs. Random weights
and inputs: only the time is compared.

- **M^mp** at the paper's widths (seed 000 §3.3, supplement §1), both submodules: the
  embedding GAT `F·S = 3072 → 4 × 32` of the motion-informed encoding `X ⊙ e_t`, two
  levels of pooling (keep rows) and GAT, two of unpooling (mean of the kept neighbours,
  a sparse product), skip and GAT, tanh after each, and the output GAT (3 channels,
  4 heads averaged). PyG's `GATConv` (self-loops, as weft's). `plain` builds `X ⊙ e_t`
  for every frame, as one writes it in PyTorch; `folded` multiplies `X` once by the
  frames' scaled weights laid side by side, weft's own arrangement (multilevel/mp.rs).
  The faster of the two is the reference.
- **E^t2**: `torch.nn.LSTM(1536, 3072, num_layers=2)` over the `m = 5` frames of each
  window.

Prints one JSON object per part and batch, milliseconds per frame, the median of
`--reps` runs after a warm-up, under `torch.inference_mode()` on `--threads` threads.
"""
import argparse
import json
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import torch
from torch_geometric.nn import GATConv

warnings.filterwarnings("ignore", message=".*[Ss]parse.*beta")
FUSED = 3072  # F·S = 128 · 24
HEADS, CHANNELS, OUT_HEADS = 4, 32, 4
SUBMODULES = 2
T2_INPUT, T2_HIDDEN, T2_LAYERS, HISTORY = 1536, 3072, 2, 5


def read_ply(path):
    """Vertex count and undirected edges of a weft level PLY (binary: triangles at level 0,
    an edge list at coarser levels)."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").split("\n")
    if "format binary_little_endian 1.0" not in header:
        sys.exit(f"{path}: expected a binary little-endian PLY from weft mesh hierarchy")
    counts = {l.split()[1]: int(l.split()[2]) for l in header if l.startswith("element")}
    vertex = np.dtype([("p", "<f8", 3), ("rgb", "u1", 3)])
    offset = end + counts["vertex"] * vertex.itemsize
    if "face" in counts:
        faces = np.frombuffer(data, np.dtype([("n", "u1"), ("v", "<u4", 3)]), counts["face"], offset)
        if (faces["n"] != 3).any():
            sys.exit(f"{path}: expected triangles")
        v = faces["v"].astype(np.int64)
        e = np.concatenate([v[:, [0, 1]], v[:, [1, 2]], v[:, [2, 0]]])
    else:
        e = np.frombuffer(data, np.dtype(("<u4", 2)), counts["edge"], offset).astype(np.int64)
    e = np.unique(np.sort(e, axis=1), axis=0)
    return counts["vertex"], e


class Level:
    """One level's graph, and how the next-finer level pools into it and unpools from it."""

    def __init__(self, n, edges):
        self.n = n
        e = torch.from_numpy(edges).t()
        self.edge_index = torch.cat([e, e.flip(0)], 1)  # both directions
        self.keep = None  # rows of the finer level kept here
        self.unpool = None  # finer × this, sparse: a removed vertex is the mean of its kept neighbours


def load_levels(directory):
    """The levels of `weft mesh hierarchy --json > hierarchy.json --out directory`."""
    info = json.loads((Path(directory) / "hierarchy.json").read_text())["levels"]
    levels = [Level(*read_ply(Path(directory) / f"level_{l}.ply")) for l in range(len(info))]
    for l in range(1, len(levels)):
        finer, kept = levels[l - 1], info[l]["kept"]
        if len(kept) != levels[l].n:
            sys.exit(f"hierarchy.json keeps {len(kept)} vertices of level {l - 1}, level_{l}.ply has {levels[l].n}")
        coarse_of = {v: c for c, v in enumerate(kept)}
        neighbours = [[] for _ in range(finer.n)]
        for a, b in finer.edge_index.t().tolist():
            neighbours[a].append(b)
        rows, cols, vals = [], [], []
        for v in range(finer.n):
            parents = [coarse_of[v]] if v in coarse_of else [coarse_of[u] for u in neighbours[v] if u in coarse_of]
            for c in parents:
                rows.append(v)
                cols.append(c)
                vals.append(1.0 / len(parents))
        levels[l].keep = torch.tensor(kept, dtype=torch.long)
        levels[l].unpool = torch.sparse_coo_tensor(
            torch.tensor([rows, cols]), torch.tensor(vals), (finer.n, levels[l].n)
        ).coalesce()
    return levels


def batched(levels, batch):
    """The levels of `batch` disjoint copies (PyG's batching of one graph per frame)."""
    out = []
    for l, lv in enumerate(levels):
        b = Level.__new__(Level)
        b.n = lv.n * batch
        e = lv.edge_index
        b.edge_index = torch.cat([e + k * lv.n for k in range(batch)], 1)
        b.keep = b.unpool = None
        if l > 0:
            finer = levels[l - 1].n
            b.keep = torch.cat([lv.keep + k * finer for k in range(batch)])
            u = lv.unpool
            idx = torch.cat([u.indices() + torch.tensor([[k * finer], [k * lv.n]]) for k in range(batch)], 1)
            b.unpool = torch.sparse_coo_tensor(idx, u.values().repeat(batch), (finer * batch, b.n)).to_sparse_csr()
        out.append(b)
    return out


class Submodule(torch.nn.Module):
    def __init__(self, levels, folded):
        super().__init__()
        width = HEADS * CHANNELS
        self.folded = folded
        self.embed = GATConv(FUSED, CHANNELS, heads=HEADS)
        if folded:
            self.embed.lin = torch.nn.Identity()
            self.weight = torch.nn.Parameter(torch.randn(FUSED, width) / FUSED**0.5)
        self.down = torch.nn.ModuleList(GATConv(width, CHANNELS, heads=HEADS) for _ in range(levels - 1))
        self.up = torch.nn.ModuleList(GATConv(width, CHANNELS, heads=HEADS) for _ in range(levels - 1))
        self.out = GATConv(width, 3, heads=OUT_HEADS, concat=False)

    def forward(self, x, e, levels):
        t, n = e.shape[0], x.shape[0]
        if self.folded:
            w = (e.unsqueeze(2) * self.weight.unsqueeze(0)).permute(1, 0, 2).reshape(FUSED, -1)
            h = (x @ w).reshape(n, t, -1).transpose(0, 1).reshape(t * n, -1)
        else:
            h = (x.unsqueeze(0) * e.unsqueeze(1)).reshape(t * n, FUSED)
        h = torch.tanh(self.embed(h, levels[0].edge_index))
        skips = []
        for l, conv in enumerate(self.down):
            skips.append(h)
            h = torch.tanh(conv(h[levels[l + 1].keep], levels[l + 1].edge_index))
        for l, conv in enumerate(self.up):
            coarse = len(self.up) - l
            h = levels[coarse].unpool @ h + skips.pop()
            h = torch.tanh(conv(h, levels[coarse - 1].edge_index))
        return self.out(h, levels[0].edge_index)


def median_ms(fn, reps):
    fn()
    times = []
    for _ in range(reps):
        start = time.perf_counter()
        fn()
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("levels", help="directory of weft mesh hierarchy's level_<l>.ply and hierarchy.json")
    ap.add_argument("--batch", default="1,16", help="frames per forward pass, comma-separated")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--parts", default="mp,t2", help="which of mp and t2 to time, comma-separated")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    parts = set(args.parts.split(","))
    torch.manual_seed(0)
    levels = load_levels(args.levels)
    n = levels[0].n
    x = torch.randn(n, FUSED)
    lstm = torch.nn.LSTM(T2_INPUT, T2_HIDDEN, num_layers=T2_LAYERS, batch_first=True)
    subs = {f: [Submodule(len(levels), f) for _ in range(SUBMODULES)] for f in (False, True)}
    common = {"torch": torch.__version__, "threads": torch.get_num_threads(), "vertices": n,
              "level_vertices": [lv.n for lv in levels],
              "directed_edges": [lv.edge_index.shape[1] for lv in levels]}
    with torch.inference_mode():
        for batch in map(int, args.batch.split(",")):
            e = torch.randn(batch, FUSED)
            lv = batched(levels, batch)
            for folded, mods in subs.items() if "mp" in parts else ():
                ms = median_ms(lambda: [m(x, e, lv) for m in mods], args.reps)
                print(json.dumps({"part": "mp", "arrangement": "folded" if folded else "plain",
                                  "batch": batch, "ms_per_frame": round(ms / batch, 2), **common}), flush=True)
            if "t2" not in parts:
                continue
            window = torch.randn(batch, HISTORY, T2_INPUT)
            ms = median_ms(lambda: lstm(window), args.reps)
            print(json.dumps({"part": "t2", "batch": batch, "ms_per_frame": round(ms / batch, 2), **common}), flush=True)


if __name__ == "__main__":
    main()
