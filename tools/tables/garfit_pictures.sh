#!/usr/bin/env bash
# A test garment of a fit dataset (made for β = 0) on the thin, regular and fat test
# bodies at one frame of the test walk (seed 001 Fig. 4.10): the simulated truth on top,
# GarFitNet's output (the pattern fitted onto each body with `weft animate --made-for`)
# below, each over its posed body.
#
#   tools/tables/garfit_pictures.sh RUN DATA GARMENT_ID OUT.png [FRAME]
#
# The walk is the test clip's (m006 of garfit-tiny: seed 1441, 1.4 m/s, 40 frames), so
# the two rows show the same pose. Environment: WEFT (default `weft`), MOTION (the
# clip's motion id, default m006-walk), SEED (1441), SPEED (1.4). Needs python3 with
# Pillow.
set -euo pipefail

run=$1 data=$2 garment=$3 out=$4 frame=${5:-20}
weft=${WEFT:-weft}
motion=${MOTION:-m006-walk} seed=${SEED:-1441} speed=${SPEED:-1.4}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
top=() bottom=()
for seq in $(ls "$data/shards" | grep "^test-$garment-b[0-9]*-$motion" | sort); do
    shard="$data/shards/$seq"
    id=${seq%.safetensors}
    # The body's β and the truth frame, read from the shard (safetensors: a JSON header,
    # then little-endian f32 data).
    betas=$(python3 - "$shard" "$frame" "$tmp/$id.truth.obj" <<'PY'
import json, struct, sys
path, frame, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
b = open(path, "rb").read()
n = struct.unpack("<Q", b[:8])[0]
h = json.loads(b[8:8 + n])
def tensor(name, fmt):
    lo, hi = h[name]["data_offsets"]
    raw = b[8 + n + lo:8 + n + hi]
    return struct.unpack("<%d%s" % (len(raw) // 4, fmt), raw)
frames, verts, _ = h["positions"]["shape"]
pos = tensor("positions", "f")[frame * verts * 3:(frame + 1) * verts * 3]
faces = tensor("faces", "I")
with open(out, "w") as f:
    for i in range(verts):
        f.write("v %f %f %f\n" % pos[3 * i:3 * i + 3])
    for i in range(0, len(faces), 3):
        f.write("f %d %d %d\n" % (faces[i] + 1, faces[i + 1] + 1, faces[i + 2] + 1))
print(",".join("%g" % x for x in tensor("betas", "f")))
PY
)
    w=$(cut -d, -f4 <<<"$betas")
    "$weft" motion generate --kind walk --seed "$seed" --speed "$speed" --frames 40 \
        --betas="$betas" --out "$tmp/$id.npz" >/dev/null
    "$weft" body pose --betas="$betas" --motion "$tmp/$id.npz" --frame "$frame" \
        --out "$tmp/$id.body.obj" >/dev/null
    "$weft" animate "$run" --garment "$data/garments/$garment.obj" --made-for 0 \
        --betas="$betas" --motion "$tmp/$id.npz" --format obj --out "$tmp/$id.pred" >/dev/null
    pred=$(ls "$tmp/$id.pred" | sort | sed -n "$((frame + 1))p")
    "$weft" render "$tmp/$id.truth.obj" --body "$tmp/$id.body.obj" --camera front --size 560 \
        --title "simulated, beta[3] = $w" --out "$tmp/$id.truth.png" >/dev/null
    "$weft" render "$tmp/$id.pred/$pred" --body "$tmp/$id.body.obj" --camera front --size 560 \
        --title "GarFitNet, beta[3] = $w" --out "$tmp/$id.pred.png" >/dev/null
    top+=("$tmp/$id.truth.png")
    bottom+=("$tmp/$id.pred.png")
done
[[ ${#top[@]} -gt 0 ]] || { echo "no test sequence of $garment with $motion in $data" >&2; exit 1; }
# Two rows of equal panels, one PNG.
python3 - "$out" "${#top[@]}" "${top[@]}" "${bottom[@]}" <<'PY'
import sys
from PIL import Image
out, n, paths = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
panels = [Image.open(p).convert("RGB") for p in paths]
w, h = max(p.width for p in panels), max(p.height for p in panels)
sheet = Image.new("RGB", (w * n, h * 2), "white")
for k, p in enumerate(panels):
    sheet.paste(p, ((k % n) * w, (k // n) * h))
sheet.save(out)
PY
echo "wrote $out"
