"""HOOD's `paper` network in PyTorch, for `weft bench hood --preset paper` to be compared
with on the same machine (the public HOOD code is PyTorch; issue 12 quotes 710 ms per
step for it at 4 000 vertices and 2 threads, on another host).

    weft garment generate --kind skirt --vertices 4000 --seed 1 --out skirt.obj
    mkdir levels && weft mesh hierarchy skirt.obj --levels 3 --out levels --json > levels/hierarchy.json
    tools/reference/.venv/bin/python tools/reference/hood_torch.py levels --batch 1,16
    weft bench hood --preset paper --vertices 4000 --batch 1,16 --json

The network is weft's (crates/weft-models/src/hood/{model,config}.rs, weft-nn's
graph_net.rs and mlp.rs), layer for layer, 5 110 915 parameters as `weft bench hood`
reports: every MLP is Linear-ReLU-Linear-ReLU-Linear of width 128, then LayerNorm (the
decoder has none); a node encoder (17 inputs), one edge encoder per mesh level (12), a
body-edge encoder (9); one block per step of the schedule `0,1 x3 | 1,2 x3 | 2 x3 |
1,2 x3 | 0,1 x3`, each step also reading the body edges; per edge set read,
`e' = e + f_k([x_receiver, x_sender, e])` and the sum of `e'` at the receivers; then
`x' = x + f_node([x, a_1, ..., a_K])`; the sets a step does not read keep their latents;
the decoder (3 outputs) on the garment rows. Random weights and inputs: only the time is
compared.

The graph is `weft bench hood`'s at 4 000 vertices: the skirt's 3 944 garment nodes and
the mesh edges of the three levels in `levels` (coarse edges mapped through `kept` to
the mesh's numbering, both directions: 23 200, 14 894, 9 958 directed edges), plus
3 308 body edges (`--body-edges`). weft's bench takes these at frame 3 of a walk (each
garment vertex within 3 cm of the posed body joined to its nearest body vertex, hands
omitted, both directions; every body vertex so reached is a node). Posing the body is
not reproduced here: the 1 654 garment vertices nearest the body in its rest pose
(assets/body/weft_body.npz, which the skirt is fitted to; 1 639 lie within 3 cm there)
are joined to their nearest body vertex, which gives 303 body nodes. Edge counts and
network are the same; only which body vertices are reached may differ, and with them
the body-node rows: 300 more or fewer change the node MLPs' rows by 7 %, and the node
MLPs are under a fifth of the work (the edge MLPs run on 3 to 10 times more rows), so
about 1 % of the time.

Two arrangements of the same parameters, both printed; the faster is the reference:
`plain` gathers `[x_receiver, x_sender, e]` per edge and runs the edge MLP on it, as
HOOD's and MeshGraphNets' code do; `split` is weft's (graph_net.rs `message`): the first
layer's weight split by input block, node rows multiplied once per endpoint node of the
set and then gathered. The sum at the receivers is `index_add_` (`--aggregate scatter`:
PyG's `scatter`); on the CPU both end in the same `scatter_add_` kernel (the profiler
shows it under `index_add_`), about 1 ms at 23 200 edges of width 128 on this machine
against tens of ms for an edge MLP, so neither is faster in a way that shows.

Times the forward pass only, on tensors already built; weft's `network_ms` also builds
its input tensors (its `inputs_ms`, about 2 ms). `--batch B` runs B disjoint copies of
the graph in one pass, as weft's batch does. Prints one JSON object per arrangement and
batch: `network_ms` for the batch's pass and `ms_per_garment`, the median of `--reps`
runs after a warm-up, under `torch.inference_mode()` on `--threads` threads.
"""
import argparse
import json
import sys
from pathlib import Path

import numpy as np
import torch
from torch import nn
from torch_geometric.utils import scatter

sys.path.insert(0, str(Path(__file__).resolve().parent))
from multilevel_torch import median_ms, read_ply  # noqa: E402

LATENT, HIDDEN, LEVELS = 128, 2, 3
SCHEDULE = "0,1 x3 | 1,2 x3 | 2 x3 | 1,2 x3 | 0,1 x3"
NODE_WIDTH = 11 + LEVELS + 3  # velocity, normal, type, dt, log mass; level one-hot; material
MESH_WIDTH = 9 + 3  # relative position and length, now and at rest; dt; material
BODY_WIDTH = 9  # garment minus body at t and t + 1 with lengths; dt
HAND_JOINTS = [20, 21, 22, 23]  # SMPL's wrists and hands: no body edges (HoodConfig::omit_hands)
BODY = Path(__file__).resolve().parents[2] / "assets" / "body" / "weft_body.npz"


def parse_schedule(text):
    steps = []
    for step in text.split("|"):
        levels, *repeat = step.split()
        steps += [[int(l) for l in levels.split(",")]] * (int(repeat[0][1:]) if repeat else 1)
    return steps


def load_levels(directory):
    """Garment positions and each level's directed edges (both directions, in the mesh's
    numbering, as weft's `nested_levels`), from `weft mesh hierarchy`'s output."""
    directory = Path(directory)
    info = json.loads((directory / "hierarchy.json").read_text())["levels"]
    data = (directory / "level_0.ply").read_bytes()
    n, _ = read_ply(directory / "level_0.ply")
    start = data.index(b"end_header\n") + len(b"end_header\n")
    positions = np.frombuffer(data, np.dtype([("p", "<f8", 3), ("rgb", "u1", 3)]), n, start)["p"].copy()
    to_mesh, levels = np.arange(n), []
    for l in range(LEVELS):
        built = min(l, len(info) - 1)  # a hierarchy of fewer levels repeats its coarsest, as weft
        if 0 < l == built:
            to_mesh = to_mesh[np.asarray(info[l]["kept"])]  # `kept`: rows of the level above
        e = to_mesh[read_ply(directory / f"level_{built}.ply")[1]]
        levels.append(np.stack([e, e[:, ::-1]], 1).reshape(-1, 2))
    return positions, levels


def body_edges(positions, count, body_path):
    """`count` body edges (both directions): the `count / 2` garment vertices nearest the
    rest-pose body, each to its nearest body vertex (hand vertices take none). Returns the
    edges, body vertices numbered after the garment's in order of first use, and how many
    body nodes there are."""
    body = np.load(body_path)
    hands = body["weights"][:, HAND_JOINTS].sum(1) > 0.5
    d, nearest = torch.cdist(torch.from_numpy(positions), torch.from_numpy(body["v_template"]).double()).min(1)
    d[torch.from_numpy(hands)[nearest]] = float("inf")
    garment = torch.sort(torch.argsort(d)[: count // 2]).values
    slot, g_side, b_side = {}, [], []
    for g in garment.tolist():
        b = slot.setdefault(int(nearest[g]), len(positions) + len(slot))
        g_side.append(g)
        b_side.append(b)
    forward = np.array([g_side, b_side]).T
    return np.concatenate([forward, forward[:, ::-1]]), len(slot)


class EdgeSet:
    """Directed edges (sender, receiver), and the same as positions among the set's
    endpoint nodes (weft's `Endpoints`: a coarse level touches a quarter of the nodes)."""

    def __init__(self, edges, n):
        e = torch.from_numpy(np.ascontiguousarray(edges)).long()
        self.senders, self.receivers, self.n = e[:, 0], e[:, 1], n
        nodes, local = torch.unique(e, return_inverse=True)
        self.nodes = None if len(nodes) == n else nodes  # every node an endpoint: local == e
        self.local_senders, self.local_receivers = local[:, 0], local[:, 1]


def mlp(inputs, outputs, layer_norm=True):
    layers, width = [], inputs
    for _ in range(HIDDEN):
        layers += [nn.Linear(width, LATENT), nn.ReLU()]
        width = LATENT
    layers.append(nn.Linear(width, outputs))
    return nn.Sequential(*layers, *([nn.LayerNorm(outputs)] if layer_norm else []))


class Block(nn.Module):
    def __init__(self, sets):
        super().__init__()
        self.edge_mlps = nn.ModuleList(mlp(3 * LATENT, LATENT) for _ in range(sets))
        self.node_mlp = mlp((1 + sets) * LATENT, LATENT)

    def forward(self, x, sets, latents, split, aggregate):
        node_input, new = [x], []
        for f, s, e in zip(self.edge_mlps, sets, latents):
            if split:  # [x_r, x_s, e] W + b = (x_U W_r + b)[receivers] + (x_U W_s)[senders] + e W_e
                w, xu = f[0].weight, (x if s.nodes is None else x[s.nodes])
                at_receiver = torch.addmm(f[0].bias, xu, w[:, :LATENT].t())
                at_sender = xu @ w[:, LATENT : 2 * LATENT].t()
                first = e @ w[:, 2 * LATENT :].t() + at_receiver[s.local_receivers] + at_sender[s.local_senders]
                e = e + f[1:](first)
            else:
                e = e + f(torch.cat([x[s.receivers], x[s.senders], e], 1))
            if aggregate == "scatter":
                node_input.append(scatter(e, s.receivers, 0, dim_size=s.n, reduce="sum"))
            else:
                node_input.append(x.new_zeros(s.n, LATENT).index_add_(0, s.receivers, e))
            new.append(e)
        return x + self.node_mlp(torch.cat(node_input, 1)), new


class Hood(nn.Module):
    def __init__(self, schedule):
        super().__init__()
        self.node_encoder = mlp(NODE_WIDTH, LATENT)
        self.mesh_encoders = nn.ModuleList(mlp(MESH_WIDTH, LATENT) for _ in range(LEVELS))
        self.body_encoder = mlp(BODY_WIDTH, LATENT)
        self.schedule = [levels + [LEVELS] for levels in schedule]  # every step reads the body edges
        self.blocks = nn.ModuleList(Block(len(step)) for step in self.schedule)
        self.decoder = mlp(LATENT, 3, layer_norm=False)

    def forward(self, nodes, edge_features, sets, garment_rows, split, aggregate):
        x = self.node_encoder(nodes)
        latents = [f(e) for f, e in zip([*self.mesh_encoders, self.body_encoder], edge_features)]
        for block, step in zip(self.blocks, self.schedule):
            x, new = block(x, [sets[k] for k in step], [latents[k] for k in step], split, aggregate)
            for k, e in zip(step, new):
                latents[k] = e
        return self.decoder(x[garment_rows])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("levels", help="directory of weft mesh hierarchy's level_<l>.ply and hierarchy.json")
    ap.add_argument("--batch", default="1", help="garments per forward pass, comma-separated")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--arrangement", default="plain,split", help="plain, split or both, comma-separated")
    ap.add_argument("--aggregate", choices=["index_add", "scatter"], default="index_add")
    ap.add_argument("--body-edges", type=int, default=3308, help="weft bench hood's body_edges (both directions)")
    ap.add_argument("--body", default=str(BODY), help="the body the skirt is fitted to (.npz)")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    positions, levels = load_levels(args.levels)
    body, body_nodes = body_edges(positions, args.body_edges, args.body)
    garment, nodes = len(positions), len(positions) + body_nodes
    model = Hood(parse_schedule(SCHEDULE)).eval()
    common = {"torch": torch.__version__, "threads": torch.get_num_threads(),
              "parameters": sum(p.numel() for p in model.parameters()), "aggregate": args.aggregate,
              "vertices": garment, "body_nodes": body_nodes, "nodes": nodes,
              "level_edges": [len(e) for e in levels], "body_edges": len(body)}
    with torch.inference_mode():
        for batch in map(int, args.batch.split(",")):
            copies = lambda e: np.concatenate([e + k * nodes for k in range(batch)])
            sets = [EdgeSet(copies(e), batch * nodes) for e in [*levels, body]]
            features = [torch.randn(len(s.senders), w) for s, w in zip(sets, [MESH_WIDTH] * LEVELS + [BODY_WIDTH])]
            x = torch.randn(batch * nodes, NODE_WIDTH)
            rows = torch.cat([torch.arange(garment) + k * nodes for k in range(batch)])
            for arrangement in args.arrangement.split(","):
                split = {"plain": False, "split": True}[arrangement]
                ms = median_ms(lambda: model(x, features, sets, rows, split, args.aggregate), args.reps)
                print(json.dumps({"bench": "hood", "preset": "paper", "arrangement": arrangement, "batch": batch,
                                  "network_ms": round(ms, 1), "ms_per_garment": round(ms / batch, 1), **common}),
                      flush=True)


if __name__ == "__main__":
    main()
