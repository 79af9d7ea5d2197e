#!/usr/bin/env bash
# An open-front top buttoned, and the same top unbuttoned mid-motion: `weft garment
# generate --open-front` cuts a long-sleeved top down the front and writes its button
# pairs, `weft simulate --buttons` holds them (top row) or lets them go at a frame
# (`--unbutton-at`, bottom row); frames 10, 19, 25, 40 and 59 over the posed body.
# With RUN set, a trained HOOD run rolls the top out instead (`weft animate RUN
# --buttons`, the same pairs and frame), with OPTIONS as extra `weft animate` flags
# (e.g. '--strain-limit 5 --push-out 2').
#
#   tools/tables/unbutton_pictures.sh OUT.png
#   RUN=R KIND=tshirt VERTICES=1000 MATERIAL=hood tools/tables/unbutton_pictures.sh OUT.png
#
# Environment: WEFT (default `weft`), RUN (none: simulate), KIND (longsleeve), VERTICES
# (2000), MOTION (raise-arms), SEED (2), MATERIAL (cotton), BUTTONS (6), UNBUTTON_AT (20),
# OPTIONS (none; with RUN only).
# Needs python3 with Pillow (tools/tables/contact_sheet.py).
set -euo pipefail

out=$1
weft=${WEFT:-weft}
kind=${KIND:-longsleeve} vertices=${VERTICES:-2000} motion=${MOTION:-raise-arms}
seed=${SEED:-2} material=${MATERIAL:-cotton} buttons=${BUTTONS:-6} at=${UNBUTTON_AT:-20}
read -ra options <<<"${OPTIONS:-}"
frames=(10 19 25 40 59)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$weft" garment generate --kind "$kind" --vertices "$vertices" --seed 1 \
    --open-front "$buttons" --buttons "$tmp/pairs.json" --out "$tmp/jacket.obj"
"$weft" motion generate --kind "$motion" --seed "$seed" --frames 60 --out "$tmp/motion.npz" >/dev/null
# roll OUT [FLAGS..]: the top on the motion, simulated or by RUN, as OUT/obj/frame_*.obj.
roll() {
    local dir=$1
    shift
    if [[ -n "${RUN:-}" ]]; then
        "$weft" animate "$RUN" --garment "$tmp/jacket.obj" --motion "$tmp/motion.npz" \
            --material "$material" --buttons "$tmp/pairs.json" "${options[@]}" "$@" \
            --format obj --out "$dir/obj"
    else
        "$weft" simulate --garment "$tmp/jacket.obj" --motion "$tmp/motion.npz" \
            --material "$material" --buttons "$tmp/pairs.json" "$@" --obj --out "$dir"
    fi
}
roll "$tmp/buttoned"
roll "$tmp/unbuttoned" --unbutton-at "$at"
row() {
    local dir=$1 name=$2 title=$3
    local files=($(ls "$dir"/obj/*.obj | sort))
    for t in "${frames[@]}"; do
        [[ -f "$tmp/body$t.obj" ]] ||
            "$weft" body pose --motion "$tmp/motion.npz" --frame "$t" --out "$tmp/body$t.obj" >/dev/null
        "$weft" render "${files[$t]}" --body "$tmp/body$t.obj" \
            --camera front --size 320 --title "$title, frame $t" --out "$tmp/$name-$t.png" >/dev/null
        echo "$tmp/$name-$t.png"
    done
}
top=$(row "$tmp/buttoned" buttoned buttoned)
bottom=$(row "$tmp/unbuttoned" unbuttoned "unbuttoned at $at")
python3 "$(dirname "$0")/contact_sheet.py" "$out" "$top" "$bottom"
echo "wrote $out"
