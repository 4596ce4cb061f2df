# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
How selection criteria on training recordings rank models (TUM-VI: rooms 1/3/5 only).

For each model, on the validation tail of every training recording (the samples after
the training window, the network seeing the whole past): the AOE of one integral over
the tail (what training reports), and the mean AOE over fixed-length segments, each
integrated from the ground truth at its start (mocap holes skipped, a segment with too
few trusted samples left out). Short segments weigh every stretch of the tail alike;
one integral over a tail is dominated by whatever error happened first. Plain
integration of the IMU ("raw") is printed as the reference every model must beat.
Run: .venv/bin/python scripts/experiments/selection_criteria.py --data DIR
         --sequences S... --start 16032 --segments 10 30 --models NAME=FILE ...
"""

import argparse
from pathlib import Path

from denoise_imu_ros.core.metrics import sequence_errors
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
import numpy as np

MIN_TRUSTED = 0.8  # a segment scores only if this share of its stamps has trusted poses


def segment_aoe(seq, gyro: np.ndarray, start: int, length: int) -> float:
    """Mean AOE (deg) of the integrals over consecutive ``length``-sample segments."""
    scores = []
    for a in range(start, len(seq) - length + 1, length):
        part = seq.tail(a, length)
        if part.gt_valid.mean() < MIN_TRUSTED or not part.gt_valid[0]:
            continue
        scores.append(sequence_errors(part, gyro[a:a + length], distances=())[1].aoe)
    return float(np.mean(scores)) if scores else float('nan')


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('--data', required=True)
    parser.add_argument('--sequences', nargs='+', required=True)
    parser.add_argument('--start', type=int, required=True, help='first tail sample')
    parser.add_argument('--segments', type=float, nargs='+', default=[10.0, 30.0],
                        help='segment lengths, s')
    parser.add_argument('--models', nargs='+', required=True, metavar='NAME=FILE')
    args = parser.parse_args()
    seqs = [load_sequence(Path(args.data) / s, min_samples=args.start + 1)
            for s in args.sequences]
    models = dict(m.split('=', 1) for m in args.models)
    print('| model | tail AOE | ' + ' | '.join(f'{s:g} s segments' for s in args.segments)
          + ' |')
    print('|---' * (2 + len(args.segments)) + '|')
    for name, spec in [('raw', None), *models.items()]:
        model = None if spec is None else load_model(spec).model
        tail, segs = [], {s: [] for s in args.segments}
        for seq in seqs:
            gyro = seq.imu[:, :3] if model is None else correct_gyro(model, seq.imu)
            tail.append(sequence_errors(seq.tail(args.start), gyro[args.start:],
                                        distances=())[1].aoe)
            for s in args.segments:
                segs[s].append(segment_aoe(seq, gyro, args.start, int(round(s * seq.rate_hz))))
        print(f'| {name} | {np.mean(tail):.3f} | '
              + ' | '.join(f'{np.nanmean(segs[s]):.3f}' for s in args.segments) + ' |')


if __name__ == '__main__':
    main()
