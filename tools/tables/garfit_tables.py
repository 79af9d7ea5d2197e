#!/usr/bin/env python3
"""Seed 001's Tables 4.1 and 4.2 and the Fig. 4.12 ablations as numbers, from the
eval.json of `weft eval` runs on a GarFitNet fit dataset (`weft data generate --preset
garfit-tiny`).

    garfit_tables.py DATA RUN [RUN ...] > tables.md

Table 4.1 groups the test sequences of walking clips by body shape (sorted by the
weight component β[3]: thin, regular, fat), Table 4.2 those of jumping clips by garment
length (the manifest's `length`: mini, knee, maxi as short, regular, long); each cell is the mean
over the group's sequences of their mean per-vertex error, cm. Every RUN's methods are
listed once (a method's name, with the run for GarFitNet's rows).
"""
import json
import sys
from pathlib import Path


LENGTHS = {"mini": "short", "knee": "regular", "maxi": "long"}


def main():
    data = Path(sys.argv[1])
    runs = [Path(r) for r in sys.argv[2:]]
    manifest = json.loads((data / "manifest.json").read_text())
    lengths = {g["id"]: g.get("length") for g in manifest["garments"]}
    rows = {}  # method label -> {sequence id -> error cm}
    scores = None
    for run in runs:
        report = json.loads((run / "report" / "eval.json").read_text())
        names = [m["name"] for m in report["methods"]]
        if not report.get("per_sequence"):
            sys.exit(f"{run}/report/eval.json has no per-sequence scores: evaluate again")
        scores = report["per_sequence"]
        for k, name in enumerate(names):
            label = f"{name} ({run.name})" if name.startswith("GarFitNet") else name
            rows.setdefault(label, {})
            for s in scores:
                rows[label][s["id"]] = s["e_verts_mm"][k] / 10.0
    # Body shapes by weight, garments by height.
    bodies = sorted({(s["betas"][3] if len(s["betas"]) > 3 else 0.0, s["body"]) for s in scores})
    order = list(LENGTHS)
    garments = sorted({(order.index(lengths[s["garment"]]) if lengths.get(s["garment"]) in order else 9, s["garment"]) for s in scores})
    body_names = dict(zip([b for _, b in bodies], ["thin", "regular", "fat"] if len(bodies) == 3 else [b for _, b in bodies]))
    garment_names = {g: LENGTHS.get(lengths.get(g), g) for _, g in garments}

    def table(title, key, names, motion):
        groups = list(names.values())
        out = [f"**{title}** (mean per-vertex error, cm; test sequences of `{motion}` clips)", ""]
        out.append("| method | " + " | ".join(groups) + " | all |")
        out.append("|---|" + "---|" * (len(groups) + 1))
        chosen = [s for s in scores if motion in s["motion"]]
        for label, errs in rows.items():
            cells = []
            for g in groups:
                vals = [errs[s["id"]] for s in chosen if names[s[key]] == g]
                cells.append(f"{sum(vals) / len(vals):.3f}" if vals else "–")
            vals = [errs[s["id"]] for s in chosen]
            cells.append(f"{sum(vals) / len(vals):.3f}" if vals else "–")
            out.append(f"| {label} | " + " | ".join(cells) + " |")
        return "\n".join(out)

    print(table("Table 4.1, by body shape", "body", body_names, "walk"))
    print()
    print(table("Table 4.2, by garment length", "garment", garment_names, "jump"))
    print()
    out = ["**Every test sequence** (mean per-vertex error, cm)", ""]
    out.append("| method | mean |")
    out.append("|---|---|")
    for label, errs in rows.items():
        out.append(f"| {label} | {sum(errs.values()) / len(errs):.3f} |")
    print("\n".join(out))


if __name__ == "__main__":
    main()
