#!/usr/bin/env bash
# A HOOD rollout beside weft simulate's for the same input: an unseen skirt on the
# default body walking, frames 0, 10, 20, 30 and 39, each over its posed body (top row
# simulated, then HOOD), with each row's mean edge strain over all frames printed.
# With OPTIONS (extra `weft animate` flags, e.g. '--strain-limit 10 --push-out 2'), a
# third row rolls the same run out with them; sets separated by ';' add a row each.
#
#   tools/tables/hood_pictures.sh RUN OUT.png [GARMENT.obj]
#
# Environment: WEFT (default `weft`), KIND (skirt), VERTICES (1000), MOTION (walk),
# SEED (3), MATERIAL (hood), OPTIONS (none). Needs python3 with Pillow.
set -euo pipefail

run=$1 out=$2 garment=${3:-}
weft=${WEFT:-weft}
kind=${KIND:-skirt} vertices=${VERTICES:-1000} motion=${MOTION:-walk} seed=${SEED:-3}
material=${MATERIAL:-hood} options=${OPTIONS:-}
frames=(0 10 20 30 39)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [[ -z "$garment" ]]; then
    garment="$tmp/garment.obj"
    "$weft" garment generate --kind "$kind" --vertices "$vertices" --seed 101 --out "$garment" >/dev/null
fi
"$weft" motion generate --kind "$motion" --seed "$seed" --frames 40 --out "$tmp/motion.npz" >/dev/null
"$weft" simulate --garment "$garment" --motion "$tmp/motion.npz" --material "$material" \
    --obj --out "$tmp/sim" >/dev/null
"$weft" animate "$run" --garment "$garment" --motion "$tmp/motion.npz" --material "$material" \
    --format obj --out "$tmp/hood" >/dev/null || echo "HOOD's rollout stopped early (see above)" >&2
IFS=';' read -ra option_sets <<<"$options"
for i in "${!option_sets[@]}"; do
    # shellcheck disable=SC2086 # each set is a list of flags
    "$weft" animate "$run" --garment "$garment" --motion "$tmp/motion.npz" --material "$material" \
        --format obj --out "$tmp/corrected$i" ${option_sets[$i]} >/dev/null ||
        echo "HOOD's rollout with ${option_sets[$i]} stopped early (see above)" >&2
done
row() {
    local dir=$1 title=$2 name=$3
    local files=($(ls "$dir"/*.obj | sort))
    for t in "${frames[@]}"; do
        [[ $t -lt ${#files[@]} ]] || continue
        "$weft" body pose --motion "$tmp/motion.npz" --frame "$t" --out "$tmp/body$t.obj" >/dev/null
        "$weft" render "${files[$t]}" --body "$tmp/body$t.obj" --camera front --size 420 \
            --title "$title, frame $t" --out "$tmp/$name-$t.png" >/dev/null
        echo "$tmp/$name-$t.png"
    done
}
top=$(row "$tmp/sim/obj" simulated sim)
bottom=$(row "$tmp/hood" HOOD hood)
rows=("$top" "$bottom")
dirs=("$tmp/sim/obj" "$tmp/hood")
names=(simulated HOOD)
for i in "${!option_sets[@]}"; do
    set_name=$(echo ${option_sets[$i]})
    rows+=("$(row "$tmp/corrected$i" "HOOD $set_name" "corrected$i")")
    dirs+=("$tmp/corrected$i")
    names+=("HOOD $set_name")
done
python3 - "$out" "$garment" "${#dirs[@]}" "${dirs[@]}" "${names[@]}" <<PY
import math, os, sys
out, garment, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
dirs, names = sys.argv[4:4 + count], sys.argv[4 + count:]
def load(p):
    v, f = [], []
    for l in open(p):
        t = l.split()
        if t and t[0] == "v": v.append(tuple(map(float, t[1:4])))
        elif t and t[0] == "f": f.append(tuple(int(x.split("/")[0]) - 1 for x in t[1:4]))
    return v, f
rest, faces = load(garment)
edges = {tuple(sorted(e)) for f in faces for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
for name, d in zip(names, dirs):
    s = []
    for p in sorted(os.listdir(d)):
        v, _ = load(os.path.join(d, p))
        s += [abs(math.dist(v[a], v[b]) / math.dist(rest[a], rest[b]) - 1) for a, b in edges]
    print(f"{name}: {len(os.listdir(d))} frames, mean edge strain {100 * sum(s) / max(len(s), 1):.2f} %")
PY
python3 "$(dirname "$0")/contact_sheet.py" "$out" "${rows[@]}"
echo "wrote $out"
