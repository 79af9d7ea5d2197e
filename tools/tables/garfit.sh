#!/usr/bin/env bash
# Seed 001's Tables 4.1 and 4.2 (coarse vs refined error per body shape and per garment
# length) and the two ablations of Fig. 4.12 as numbers, on the garfit-tiny fit dataset,
# every run with the same data, seed and step budget:
#
#   tools/tables/garfit.sh [OUT]      (default OUT: tables-garfit)
#
# Environment: WEFT (the binary, default `weft`), STEPS (optimiser steps per run, default
# 1500), PRESET (default cpu), MULTILEVEL_STEPS (a Multilevel run on the same data for
# comparison, default 0: none). A killed script resumes: finished sequences are kept, a
# finished run is skipped, an unfinished one continues from its checkpoint. Writes
# OUT/tables.md and each run's report (OUT/RUN/report/).
set -euo pipefail

out=${1:-tables-garfit}
weft=${WEFT:-weft}
steps=${STEPS:-1500}
preset=${PRESET:-cpu}
mkdir -p "$out/configs"
here=$(cd "$(dirname "$0")" && pwd)

"$weft" data generate --preset garfit-tiny --out "$out/data"

# train NAME MODEL STEPS [TOML]: one run in OUT/NAME (the TOML is laid over the preset).
train() {
    local name=$1 model=$2 n=$3 toml=${4:-}
    local run="$out/$name" config="$out/configs/$name.toml"
    printf '%s\n' "$toml" >"$config"
    if [[ ! -f "$run/finished" ]]; then
        local resume=()
        [[ -f "$run/config.toml" ]] && resume=(--resume)
        echo "$name: training $model, $n steps"
        "$weft" train --model "$model" --preset "$preset" --data "$out/data" --out "$run" \
            --config "$config" --steps "$n" --quiet "${resume[@]}"
        touch "$run/finished"
    fi
    [[ -f "$run/report/eval.json" ]] || "$weft" eval "$run" --data "$out/data" --no-timing >/dev/null
}

train garfitnet garfitnet "$steps"
# Fig. 4.12: without the GarFit parameter branch; without the output decomposition.
train garfitnet-no-garfit garfitnet "$steps" '[model.network]
garfit_branch = false'
train garfitnet-no-decomposition garfitnet "$steps" '[model.network]
decomposed = false'
runs=("$out"/garfitnet "$out"/garfitnet-no-garfit "$out"/garfitnet-no-decomposition)
if [[ ${MULTILEVEL_STEPS:-0} -gt 0 ]]; then
    train multilevel multilevel "$MULTILEVEL_STEPS"
    runs+=("$out"/multilevel)
fi
python3 "$here/garfit_tables.py" "$out/data" "${runs[@]}" >"$out/tables.md"
echo "tables in $out/tables.md"
