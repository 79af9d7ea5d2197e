#!/usr/bin/env bash
# Seed 001's Tables 3.2–3.4 and the translation test (Fig. 3.23) on the tiny character
# set, every row with the same data, seed and step budget:
#
#   tools/tables/characters.sh [OUT]      (default OUT: tables-characters)
#
# Environment: WEFT (the binary, default `weft`), STEPS (optimiser steps per run,
# default 1200), PRESET (default cpu). A killed script resumes: built characters are
# kept, a finished run is skipped, an unfinished one continues from its checkpoint.
# Writes OUT/table-3.2-3.3/, OUT/table-3.4/ and OUT/translated/ (characters.md, .json
# and the pictures of `weft eval`).
set -euo pipefail

out=${1:-tables-characters}
weft=${WEFT:-weft}
steps=${STEPS:-1200}
preset=${PRESET:-cpu}
mkdir -p "$out/configs"

"$weft" data characters --preset tiny --out "$out/chars"

# train NAME MODEL [TOML]: one row's run in OUT/NAME (the TOML is laid over the preset).
train() {
    local name=$1 model=$2 toml=${3:-}
    local run="$out/$name" config="$out/configs/$name.toml"
    printf '%s\n' "$toml" >"$config"
    if [[ -f "$run/finished" ]]; then
        echo "$name: finished, kept"
        return
    fi
    local resume=()
    [[ -f "$run/config.toml" ]] && resume=(--resume)
    echo "$name: training $model, $steps steps"
    "$weft" train --model "$model" --preset "$preset" --data "$out/chars" --out "$run" \
        --config "$config" --steps "$steps" --quiet "${resume[@]}"
    touch "$run/finished"
}

plain='[model]
dense = false
self_reinforced = 0.0'

# Table 3.3: DenseGATs and its ablations (the original GAT: 4 plain blocks, ELU, no
# batch normalisation; NeuroSkinning-style: 3 plain blocks, ELU).
train densegats densegats
train densegats-no-self densegats '[model]
self_reinforced = 0.0'
train densegats-no-dense densegats '[model]
dense = false'
train gat densegats "$plain
modules = 1
blocks = 4
batch_norm = false
activation = \"elu\""
train neuroskinning densegats "$plain
modules = 1
blocks = 3
activation = \"elu\""

# Table 3.4: MultiResGNet, its single-resolution ablation and fewer training
# characters (the thesis's 25 / 50 / 75 of 75, here 1 / 3 / 4 of the tiny set's 4).
train multiresgnet multiresgnet
train multiresgnet-single multiresgnet '[model]
global = false'
train multiresgnet-1-character multiresgnet '[train]
characters = 1'
train multiresgnet-3-characters multiresgnet '[train]
characters = 3'
# Table 3.4's MLP: the input and output transforms alone, blind to the graph.
train mlp densegats '[model]
modules = 0'

"$weft" eval "$out"/{densegats,densegats-no-self,densegats-no-dense,gat,neuroskinning} \
    --data "$out/chars" --out "$out/table-3.2-3.3"
"$weft" eval "$out"/{multiresgnet,multiresgnet-single,multiresgnet-1-character,multiresgnet-3-characters,mlp,neuroskinning,densegats} \
    --data "$out/chars" --out "$out/table-3.4"
"$weft" eval "$out"/{densegats,multiresgnet} --data "$out/chars" --translate 3,0,2 \
    --out "$out/translated"
echo "tables in $out/table-3.2-3.3, $out/table-3.4, $out/translated"
