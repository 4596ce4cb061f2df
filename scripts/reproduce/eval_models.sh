#!/usr/bin/env bash
# Evaluate the models scripts/reproduce/train_models.sh wrote (and their candidates) on the EuRoC
# test sequences and on the TUM-VI validation tails, then print the seed summaries.
#   scripts/reproduce/eval_models.sh RUNS_DIR
set -euo pipefail
runs=${1:?usage: scripts/reproduce/eval_models.sh RUNS_DIR}
bin=$(dirname "$0")/../../.venv/bin
data=${DATA:-../shared/data}
euroc_test=(MH_02_easy MH_04_difficult V1_01_easy V1_03_difficult V2_02_medium)
tumvi_rooms=(dataset-room1_512_16 dataset-room3_512_16 dataset-room5_512_16)
ev() {  # model, out, dataset args...
  local model=$1 out=$2; shift 2
  [ -f "$out/results.json" ] || "$bin/denoise-imu" eval --model "$model" --out "$out" "$@" \
    > /dev/null
}
for m in "$runs"/euroc_s*.safetensors "$runs"/euroc_s*.candidates/*.safetensors; do
  [ -f "$m" ] || continue
  ev "$m" "${m%.safetensors}.eval" --baseline euroc_calibrated \
    --data "$data/euroc" --sequences "${euroc_test[@]}" --no-plots
done
for m in "$runs"/tumvi_family_s*.safetensors "$runs"/tumvi_family_s*.candidates/*.safetensors; do
  [ -f "$m" ] || continue
  ev "$m" "${m%.safetensors}.eval" --baseline tumvi_calibrated \
    --data "$data/tumvi" --sequences "${tumvi_rooms[@]}" --start-sample 16032 --no-plots
done
for ds in euroc tumvi_family; do
  for kind in "" ".candidates/best_checkpoint" ".candidates/swa"; do
    dirs=("$runs"/${ds}_s[0-9]${kind}.eval)
    [ -d "${dirs[0]}" ] || continue
    echo "## $ds${kind:+ ($kind)}"
    "$bin/python" "$(dirname "$0")/seed_table.py" "${dirs[@]}"
    echo
  done
done
