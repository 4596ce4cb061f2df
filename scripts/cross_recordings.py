# Copyright 2026 denoise_imu_ros authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Validation on unseen recordings, without the test sequences: two folds of the recipe.

The validation tails come from the training recordings, so they cannot tell how a model
does on a new recording (a new gyro bias). Here each fold trains on half of the recipe's
training recordings and scores whole held-out ones: the network's candidates (best
validation checkpoint, final weights, weight average) and a calibrated-IMU baseline fitted
on the same half. Folds: even- and odd-numbered recordings of the recipe's list.
Usage: .venv/bin/python scripts/cross_recordings.py OUT_DIR [--config RECIPE] [--seed N]
Takes about 2 x 10 minutes on 2 cores; prints a Markdown table of AOE 3-D / yaw (degrees).
"""

import argparse
from pathlib import Path
import sys

from denoise_imu_ros.evaluate import evaluate
from denoise_imu_ros.modelfile import save_model
from denoise_imu_ros.train import load_config, train
import numpy as np

CANDIDATES = ('best_checkpoint', 'final', 'swa')


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('out', type=Path)
    parser.add_argument('--config', default='config/train_euroc.yaml')
    parser.add_argument('--seed', type=int, default=0)
    args = parser.parse_args()
    recipe = load_config(args.config, seed=args.seed)
    rows: dict[str, list[float]] = {}
    for fold in (0, 1):
        train_on = recipe.sequences[fold::2]
        held_out = recipe.sequences[1 - fold::2]
        out = args.out / f'fold{fold}'
        cfg = load_config(args.config, seed=args.seed, sequences=train_on)
        model, meta = train(cfg, progress=False, candidates_dir=out / 'candidates')
        calib, calib_meta = train(load_config(args.config, seed=args.seed, sequences=train_on,
                                              calibration_only=True), progress=False)
        save_model(out / 'calibrated.safetensors', calib, calib_meta)
        for name in CANDIDATES:
            report = evaluate(str(out / 'candidates' / f'{name}.safetensors'), cfg.data,
                              held_out, str(out / f'{name}.eval'),
                              baseline=str(out / 'calibrated.safetensors'), plots=False)
            rows.setdefault(f'network, {name}', []).append(report['average']['network'])
        rows.setdefault('calibrated IMU', []).append(report['average']['calibrated'])
        print(f'fold {fold}: trained on {train_on}, scored on {held_out}', file=sys.stderr)
    print('| method | fold 0 | fold 1 | mean |\n|---|---|---|---|')
    for method, folds in rows.items():
        cells = [f'{f["aoe_deg"]:.2f}/{f["aoe_yaw_deg"]:.2f}' for f in folds]
        mean = [np.mean([f[k] for f in folds]) for k in ('aoe_deg', 'aoe_yaw_deg')]
        print(f'| {method} | ' + ' | '.join(cells) + f' | {mean[0]:.2f}/{mean[1]:.2f} |')


if __name__ == '__main__':
    main()
