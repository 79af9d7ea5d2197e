#!/usr/bin/env bash
# HOOD's run-time materials (issue 12 item 6): one unseen dress rolled out by a trained
# HOOD run in three materials, all LIGHT (silk), all HEAVY (denim), and a HEAVY bodice
# over a LIGHT skirt (`--material HEAVY,LIGHT --material-map MAP.npy`, the map
# splitting the dress at BODICE of its height from the top); frames 0, 10, 20, 30 and 39 over the posed body,
# a row each, with each HOOD row's strain and penetration printed. Above the HOOD LIGHT
# and HEAVY rows, `weft simulate` of the same dress in the same material (the simulator
# takes one material a garment, and starts after its warm-up frames where HOOD starts
# from the skinned dress). OPTIONS are extra `weft animate`
# flags for every HOOD row (e.g. '--refine 4').
#
#   tools/tables/material_pictures.sh RUN OUT.png
#
# Environment: WEFT (default `weft`), KIND (dress), VERTICES (1000), MOTION (twist),
# SEED (3), BODICE (0.35), LIGHT (silk), HEAVY (denim; each a preset name or a material
# TOML file), OPTIONS (none). Needs python3 with Pillow.
set -euo pipefail

run=$1 out=$2
weft=${WEFT:-weft}
kind=${KIND:-dress} vertices=${VERTICES:-1000} motion=${MOTION:-twist} seed=${SEED:-3}
bodice=${BODICE:-0.35} light=${LIGHT:-silk} heavy=${HEAVY:-denim}
read -ra options <<<"${OPTIONS:-}"
frames=(0 10 20 30 39)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
garment="$tmp/garment.obj"
"$weft" garment generate --kind "$kind" --vertices "$vertices" --seed 101 --out "$garment" >/dev/null
"$weft" motion generate --kind "$motion" --seed "$seed" --frames 40 --out "$tmp/motion.npz" >/dev/null
# The map: 0 (the first --material, HEAVY) above the split, 1 (LIGHT) below, as int64 .npy.
python3 - "$garment" "$bodice" "$tmp/map.npy" <<'PY'
import struct, sys
garment, bodice, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]
ys = [float(l.split()[2]) for l in open(garment) if l.startswith("v ")]
split = max(ys) - bodice * (max(ys) - min(ys))
header = "{'descr': '<i8', 'fortran_order': False, 'shape': (%d,), }" % len(ys)
header += " " * (63 - (10 + len(header)) % 64) + "\n"
with open(out, "wb") as f:
    f.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode())
    f.write(struct.pack("<%dq" % len(ys), *[0 if y > split else 1 for y in ys]))
PY
roll() {
    local dir=$1
    shift
    "$weft" animate "$run" --garment "$garment" --motion "$tmp/motion.npz" "$@" \
        "${options[@]}" --format obj --out "$dir" | tail -1
}
simulate() {
    "$weft" simulate --garment "$garment" --motion "$tmp/motion.npz" --frames 40 --material "$2" --obj --out "$tmp/sim" >/dev/null
    mv "$tmp/sim/obj" "$1"
    rm -rf "$tmp/sim"
}
l=$(basename "$light" .toml) h=$(basename "$heavy" .toml)
names=("simulated $l" "HOOD $l" "simulated $h" "HOOD $h" "HOOD $h bodice, $l skirt")
simulate "$tmp/r0" "$light"
roll "$tmp/r1" --material "$light"
simulate "$tmp/r2" "$heavy"
roll "$tmp/r3" --material "$heavy"
roll "$tmp/r4" --material "$heavy,$light" --material-map "$tmp/map.npy"
rows=()
for i in 0 1 2 3 4; do
    files=($(ls "$tmp/r$i"/*.obj | sort))
    row=""
    for t in "${frames[@]}"; do
        [[ -f "$tmp/body$t.obj" ]] ||
            "$weft" body pose --motion "$tmp/motion.npz" --frame "$t" --out "$tmp/body$t.obj" >/dev/null
        "$weft" render "${files[$t]}" --body "$tmp/body$t.obj" --camera front --size 360 \
            --title "${names[$i]}, frame $t" --out "$tmp/r$i-$t.png" >/dev/null
        row+="$tmp/r$i-$t.png "
    done
    rows+=("$row")
done
python3 "$(dirname "$0")/contact_sheet.py" "$out" "${rows[@]}"
echo "wrote $out"
