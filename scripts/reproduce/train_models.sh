#!/usr/bin/env bash
# Train the shipped models and their seed repeats (the figures in the README), the EuRoC
# and TUM-VI ensembles of the seeds, the cross-recording reports of the recipes and the
# filter settings, and the BROAD models (broad, broad_network, broad_calibrated).
#   scripts/reproduce/train_models.sh OUT_DIR [SEEDS...]    (EuRoC seeds, default: 0 1 2 3 4)
#   TUMVI_SEEDS="0 1" scripts/reproduce/train_models.sh ... (TUM-VI seeds, default: 0 to 10)
#   TUMVI_CV_SEEDS="0 1" ...                                (its crossval seeds, default: 0 1 2)
#   DATA=DIR ...                                            (the data, default ../shared/data)
# Each run writes OUT_DIR/<name>.safetensors and OUT_DIR/<name>.log. Runs one after the
# other: a run uses both cores (or the GPU: train picks cuda when torch sees one).
set -euo pipefail
out=${1:?usage: scripts/reproduce/train_models.sh OUT_DIR [SEEDS...]}
shift
seeds=("${@:-0 1 2 3 4}")
mkdir -p "$out"
bin=$(dirname "$0")/../../.venv/bin
run() {  # name, args...
  local name=$1; shift
  [ -f "$out/$name.safetensors" ] && { echo "skip $name (exists)"; return; }
  echo "$(date -u +%H:%M:%S) training $name"
  "$bin/python" -u -m denoise_imu_ros.cli train "$@" --out "$out/$name.safetensors" --quiet \
    --candidates-dir "$out/$name.candidates" \
    > "$out/$name.log" 2>&1
  tail -n 1 "$out/$name.log"
}
run euroc_calibrated --recipe config/train_euroc.yaml --calibration-only
run tumvi_calibrated --recipe config/train_tumvi.yaml --calibration-only
first=${seeds[0]%% *}
run "euroc_s$first" --recipe config/train_euroc.yaml --seed "$first"
family=()
for seed in ${TUMVI_SEEDS:-0 1 2 3 4 5 6 7 8 9 10}; do
  run "tumvi_family_s$seed" --recipe config/train_tumvi_family.yaml --seed "$seed"
  family+=("$out/tumvi_family_s$seed.safetensors")
done
euroc=()
for seed in ${seeds[@]}; do
  run "euroc_s$seed" --recipe config/train_euroc.yaml --seed "$seed"
  euroc+=("$out/euroc_s$seed.safetensors")  # these seeds, not whatever else is in OUT_DIR
done
[ -f "$out/euroc_ensemble.safetensors" ] || "$bin/denoise-imu" ensemble "${euroc[@]}" \
  --out "$out/euroc_ensemble.safetensors"
[ -f "$out/tumvi_ensemble.safetensors" ] || "$bin/denoise-imu" ensemble "${family[@]}" \
  --out "$out/tumvi_ensemble.safetensors"  # two seeds at least
crossval() {  # name, recipe, folds, seeds ("" for the recipe's), models to attach to...
  local name=$1 recipe=$2 folds=$3 cv_seeds=$4; shift 4
  [ -f "$out/$name/crossval.json" ] && { echo "skip $name (exists)"; return; }
  echo "$(date -u +%H:%M:%S) $name"
  "$bin/denoise-imu" crossval --recipe "$recipe" --folds "$folds" --out "$out/$name" \
    ${cv_seeds:+--seeds $cv_seeds} --quiet --attach "$@" > "$out/$name.log" 2>&1
  tail -n 1 "$out/$name.log"
}
crossval crossval_euroc config/train_euroc.yaml 6 "" "$out/euroc_ensemble.safetensors" \
  "$out/euroc_calibrated.safetensors"
# tumvi_calibrated is the reference recipe's calibration: its report is that recipe's
crossval crossval_tumvi config/train_tumvi.yaml 3 "" "$out/tumvi_calibrated.safetensors"
crossval crossval_tumvi_family config/train_tumvi_family.yaml 3 "${TUMVI_CV_SEEDS:-0 1 2}" \
  "$out/tumvi_ensemble.safetensors"
for ds in euroc tumvi; do  # the filter settings, chosen on the training recordings' tails
  [ -f "$out/tune_$ds.log" ] && { echo "skip tune_$ds (exists)"; continue; }
  "$bin/denoise-imu" tune-fusion --model "$out/${ds}_ensemble.safetensors" \
    --baseline "$out/${ds}_calibrated.safetensors" --data "${DATA:-../shared/data}/$ds" \
    --attach --quiet > "$out/tune_$ds.log.part" 2>&1
  mv "$out/tune_$ds.log.part" "$out/tune_$ds.log"
done
# BROAD: three trainings of its recipe and its calibration on both power-on sessions,
# broad_network (their ensemble), the leave-one-session-out verdict with the output's
# tracking and its blend with the classical pipeline (the folds' ensembles of the three
# seeds), the filter settings, and broad: the tracker-only model the verdict recommends
broad_b=02_undisturbed_slow_rotation_B,05_undisturbed_slow_rotation_with_breaks_B,07_undisturbed_fast_rotation_B,11_undisturbed_slow_translation_B,14_undisturbed_slow_translation_with_breaks_B,16_undisturbed_fast_translation_B,21_undisturbed_fast_combined,29_disturbed_stationary_magnet_B
broad_c=03_undisturbed_slow_rotation_C,12_undisturbed_slow_translation_C,25_disturbed_tapping_B,27_disturbed_phone_vibration_B
broad=()
for seed in 0 1 2; do
  run "broad_s$seed" --recipe config/train_broad.yaml --seed "$seed"
  broad+=("$out/broad_s$seed.safetensors")
done
run broad_calibrated --recipe config/train_broad.yaml --calibration-only
[ -f "$out/broad_network.safetensors" ] || "$bin/denoise-imu" ensemble "${broad[@]}" \
  --out "$out/broad_network.safetensors"
[ -f "$out/tune_broad.log" ] || "$bin/denoise-imu" tune-fusion \
  --model "$out/broad_network.safetensors" --baseline "$out/broad_calibrated.safetensors" \
  --data "${DATA:-../shared/data}/broad" --attach --quiet > "$out/tune_broad.log" 2>&1
# after tune-fusion (the accelerometer bias and the other filters): the session folds
# choose imu/data's filter of each file, the tails sharing the training's power-on
[ -f "$out/crossval_broad/crossval.json" ] || "$bin/denoise-imu" crossval \
  --recipe config/train_broad.yaml --sessions "$broad_b" "$broad_c" --seeds 0 1 2 \
  --out "$out/crossval_broad" --quiet --attach "$out/broad_network.safetensors" \
  "$out/broad_calibrated.safetensors" > "$out/crossval_broad.log" 2>&1
[ -f "$out/broad.safetensors" ] || "$bin/denoise-imu" rest-model \
  --like "$out/broad_network.safetensors" --tracker-only --out "$out/broad.safetensors"
