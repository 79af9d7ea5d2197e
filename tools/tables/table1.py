#!/usr/bin/env python3
"""Mean ± std over seeds of the runs table1.sh made: OUT/<pooling>-s<seed>/report/eval.json.

Prints a Markdown table: per pooling kind, E_verts per garment kind and overall, E_norm,
the share of vertices inside the body and the distance below LBS, each as mean ± sample
std over the seeds found (the LBS row is the same for every run: it is read once).
"""
import glob
import json
import os
import statistics
import sys

ROWS = [
    ("structure", "Multilevel (structure-preserving)"),
    ("none", "Single-level"),
    ("top_k", "TopKPool"),
    ("sag", "SAGPool"),
    ("asap", "ASAP"),
]


def pm(values, digits=1, scale=1.0):
    v = [x * scale for x in values]
    if len(v) == 1:
        return f"{v[0]:.{digits}f}"
    return f"{statistics.mean(v):.{digits}f} ± {statistics.stdev(v):.{digits}f}"


def main(out):
    lbs = None
    kinds = None
    lines = []
    for key, label in ROWS:
        runs = sorted(glob.glob(os.path.join(out, f"{key}-s*", "report", "eval.json")))
        if not runs:
            continue
        rows = []
        for path in runs:
            with open(path) as f:
                report = json.load(f)
            model, base = report["methods"][0], None
            for m in report["methods"]:
                if m["name"] == "LBS only":
                    base = m
            rows.append(model)
            if lbs is None and base is not None:
                lbs = base
            if kinds is None:
                kinds = sorted(model["per_kind"])
        seeds = len(rows)
        cells = [f"{label} ({seeds} seed{'s' if seeds > 1 else ''})"]
        for k in kinds:
            cells.append(pm([r["per_kind"][k]["e_verts_mm"]["mean"] for r in rows]))
        cells.append(pm([r["overall"]["e_verts_mm"]["mean"] for r in rows]))
        cells.append(pm([r["overall"]["e_norm_deg"]["mean"] for r in rows]))
        cells.append(pm([r["overall"]["collision_rate"] for r in rows], 2, 100.0) + " %")
        if lbs is not None:
            base = lbs["overall"]["e_verts_mm"]["mean"]
            below = [100.0 * (1.0 - r["overall"]["e_verts_mm"]["mean"] / base) for r in rows]
            cells.append(pm(below) + " %")
        else:
            cells.append("–")
        lines.append("| " + " | ".join(cells) + " |")
    if kinds is None:
        sys.exit(f"no runs with report/eval.json under {out}")
    head = ["method"] + [f"{k} E_verts (mm)" for k in kinds]
    head += ["all E_verts (mm)", "E_norm (°)", "inside the body", "below LBS"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for line in lines:
        print(line)
    if lbs is not None:
        cells = ["LBS only"]
        cells += [f"{lbs['per_kind'][k]['e_verts_mm']['mean']:.1f}" for k in kinds]
        cells += [
            f"{lbs['overall']['e_verts_mm']['mean']:.1f}",
            f"{lbs['overall']['e_norm_deg']['mean']:.1f}",
            f"{100.0 * lbs['overall']['collision_rate']:.2f} %",
            "–",
        ]
        print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: table1.py OUT")
    main(sys.argv[1])
