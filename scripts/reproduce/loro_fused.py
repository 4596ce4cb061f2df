# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Open-loop and fused scores of cross-validation folds on the recordings they never saw.

For each fold that ``denoise-imu crossval --out DIR`` wrote (``DIR/fold<i>/network`` and
``calibrated``; with ``--seeds``, the ensemble of the fold's networks of every seed,
written to ``DIR/ensemble/fold<i>/``, and the first seed's calibration), the filters'
settings are chosen on that fold's own training
recordings' validation tails (``tune-fusion --attach``, never on the held-out one), then
``eval`` scores the held-out recordings. Prints one Markdown table: open loop (raw, the
classical pipeline with no model, calibrated, network) and fused (raw + VQF at its defaults
and as tuned, the classical pipeline, calibrated and network + VQF, calibrated + imufusion
and + Madgwick), AOE 3-D / tilt in degrees, per held-out recording and mean.
Run: .venv/bin/python scripts/reproduce/loro_fused.py CROSSVAL_DIR DATA_DIR
"""

import argparse
import json
from pathlib import Path
import subprocess
import sys

import numpy as np

OPEN = ('raw', 'tracker only', 'calibrated', 'network')
FUSED = ('raw + VQF defaults', 'raw + VQF', 'tracker only + VQF', 'calibrated + VQF',
         'calibrated + imufusion', 'calibrated + Madgwick', 'network + VQF')


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('crossval_dir', type=Path)
    parser.add_argument('data')
    args = parser.parse_args()
    report = json.loads((args.crossval_dir / 'crossval.json').read_text())
    cli = [sys.executable, '-m', 'denoise_imu_ros.cli']
    rows: dict[str, dict[str, tuple[float, float]]] = {}
    for i, held_out in enumerate(report['folds']):
        fold = args.crossval_dir / f'fold{i}'
        net, calib = fold / 'network.safetensors', fold / 'calibrated.safetensors'
        if 'seeds' in report:
            seeds = [args.crossval_dir / f'seed{s}' / f'fold{i}' for s in report['seeds']]
            fold = args.crossval_dir / 'ensemble' / f'fold{i}'
            net, calib = fold / 'network.safetensors', fold / 'calibrated.safetensors'
            if not net.exists():
                fold.mkdir(parents=True, exist_ok=True)
                calib.write_bytes((seeds[0] / 'calibrated.safetensors').read_bytes())
                if len(seeds) == 1:
                    net.write_bytes((seeds[0] / 'network.safetensors').read_bytes())
                else:
                    subprocess.run(cli + ['ensemble', '--out', str(net)] + [
                        str(d / 'network.safetensors') for d in seeds], check=True,
                        stdout=subprocess.DEVNULL)
        if not (fold / 'tuned').exists():
            subprocess.run(cli + ['tune-fusion', '--model', str(net), '--baseline', str(calib),
                                  '--data', args.data, '--attach', '--quiet'], check=True,
                           stdout=subprocess.DEVNULL)
            (fold / 'tuned').touch()
        out = fold / 'eval'
        if not (out / 'results.json').exists():
            subprocess.run(cli + ['eval', '--model', str(net), '--baseline', str(calib),
                                  '--data', args.data, '--sequences', *held_out, '--out',
                                  str(out), '--no-plots'], check=True, stdout=subprocess.DEVNULL)
        results = json.loads((out / 'results.json').read_text())
        for name in held_out:
            seq = results['sequences'][name]
            fused = results['fused'][name]
            rows[name] = {m: (seq[m]['aoe_deg'], seq[m]['tilt_deg']) for m in OPEN}
            rows[name].update({m: (fused[m]['aoe_deg'], fused[m]['tilt_deg']) for m in FUSED})
    names = list(rows)
    print('| gyro | ' + ' | '.join(names) + ' | mean |')
    print('|---' * (len(names) + 2) + '|')
    for m in OPEN + FUSED:
        cells = [f'{rows[n][m][0]:.2f}/{rows[n][m][1]:.2f}' for n in names]
        mean = np.mean([rows[n][m] for n in names], axis=0)
        print(f'| {m} | ' + ' | '.join(cells) + f' | **{mean[0]:.2f}/{mean[1]:.2f}** |')


if __name__ == '__main__':
    main()
