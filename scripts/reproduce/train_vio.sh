#!/usr/bin/env bash
# Train on a VIO's or SLAM's trajectories instead of motion capture, then score on the five
# EuRoC test sequences against their real ground truth (docs/results.md, "EuRoC without
# motion capture").
#   scripts/reproduce/train_vio.sh OUT_DIR [SOURCE] [SEEDS...]
#     SOURCE: a folder of ../shared/data/euroc_vio (default vins_mono); SEEDS default 0 1 2
#   DATA=DIR ...   (the data, default ../shared/data)
# Writes OUT_DIR/recipe.yaml (init-recipe's, unchanged), OUT_DIR/seed<s>.safetensors and
# OUT_DIR/eval<s>/; logs beside them.
set -euo pipefail
out=${1:?usage: scripts/reproduce/train_vio.sh OUT_DIR [SOURCE] [SEEDS...]}
source=${2:-vins_mono}
shift $(( $# > 1 ? 2 : 1 ))
seeds=("${@:-0 1 2}")
data=${DATA:-../shared/data}
bin=$(dirname "$0")/../../.venv/bin
train=(MH_01_easy MH_03_medium MH_05_difficult V1_02_medium V2_01_easy V2_03_difficult)
test=(MH_02_easy MH_04_difficult V1_01_easy V1_03_difficult V2_02_medium)
mkdir -p "$out"
"$bin/denoise-imu" init-recipe --data "$data/euroc" --sequences "${train[@]}" \
    --poses "$data/euroc_vio/$source" --out "$out/recipe.yaml" --overwrite \
    > "$out/init.log" 2>&1
for seed in ${seeds[@]}; do
  "$bin/denoise-imu" train --recipe "$out/recipe.yaml" --seed "$seed" \
      --out "$out/seed$seed.safetensors" --overwrite --quiet > "$out/train$seed.log" 2>&1
  "$bin/denoise-imu" eval --model "$out/seed$seed.safetensors" --data "$data/euroc" \
      --sequences "${test[@]}" --out "$out/eval$seed" > "$out/eval$seed.log" 2>&1
  echo "$(date -u +%H:%M:%S) seed $seed: $(grep '^| network |' "$out/eval$seed.log" | head -1)"
done
