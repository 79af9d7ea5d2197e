#!/usr/bin/env bash
# Seed 000's Table 1 on a weft dataset with several seeds per row (issue 15 item 2):
# every pooling kind trained with the `cpu` preset on the same data and budget (only
# `pooling` and the seed change), each run evaluated on the test split, then mean ± std
# over the seeds per row by table1.py.
#
#   tools/tables/table1.sh DATA OUT ["0 1 2"]      (WEFT=path/to/weft, default `weft`)
#
# Resumable: a run with an eval.json is skipped, a run with checkpoints continues from
# its latest one (`weft train --resume`).
set -euo pipefail
data=$1
out=$2
seeds=${3:-"0 1 2"}
weft=${WEFT:-weft}
mkdir -p "$out"
"$weft" config show --preset cpu > "$out/base.toml"
for pooling in structure none top_k sag asap; do
  for seed in $seeds; do
    run="$out/$pooling-s$seed"
    [ -f "$run/report/eval.json" ] && continue
    sed -e "s/^pooling = .*/pooling = \"$pooling\"/" -e "s/^seed = .*/seed = $seed/" \
      "$out/base.toml" > "$out/$pooling-s$seed.toml"
    if [ -f "$run/checkpoints/latest" ]; then
      "$weft" train --data "$data" --config "$out/$pooling-s$seed.toml" --out "$run" --resume --quiet
    else
      rm -rf "$run"
      "$weft" train --data "$data" --config "$out/$pooling-s$seed.toml" --out "$run" --quiet
    fi
    "$weft" eval "$run" --data "$data" --no-timing > "$run.eval.txt"
  done
done
python3 "$(dirname "$0")/table1.py" "$out" | tee "$out/table1.md"
