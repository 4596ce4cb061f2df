# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""How three ways of choosing the output bias tracking do on a crossval's held-out recordings."""

import argparse
from pathlib import Path

from denoise_imu_ros.core.metrics import score
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.data.rest_bias import track_bias
from denoise_imu_ros.evaluation.crossval import CANDIDATES
from denoise_imu_ros.learn.checkpoint import load_model
import numpy as np


def main(data: Path, held_out: list[str], models: list[str]) -> None:
    """Print one line per model: its mean AOE on the held-out recordings it never saw."""
    seqs = {p.name: load_sequence(p, align_poses='auto') for p in sorted(data.iterdir())
            if p.is_dir()}
    for path in models:
        model = load_model(path)
        start, trained = model.meta.training_span, model.meta.train_sequences
        figures = {}  # candidate -> recording -> (whole, tail)
        for name, seq in seqs.items():
            gyro = model.untracked(seq.imu)
            for label, t in CANDIDATES.items():
                tracked = track_bias(gyro, seq.imu[:, 3:], seq.rate_hz, t)
                figures.setdefault(label, {})[name] = (
                    score(seq, tracked)['aoe_deg'],
                    score(seq.tail(start), tracked[start:])['aoe_deg'] if name in trained
                    else None)
        held = [n for n in held_out if n not in trained]

        def mean(label: str, names: list[str], which: int) -> float:
            return float(np.mean([figures[label][n][which] for n in names]))
        tails = min(figures, key=lambda c: mean(c, list(trained), 1))
        whole = min(figures, key=lambda c: mean(c, list(trained), 0))
        best = min(figures, key=lambda c: mean(c, held, 0))
        print(f'{path}: held out, none {mean("none", held, 0):.2f}; tails choose {tails}: '
              f'{mean(tails, held, 0):.2f}; whole recordings choose {whole}: '
              f'{mean(whole, held, 0):.2f}; best on them {best}: {mean(best, held, 0):.2f}',
              flush=True)


if __name__ == '__main__':
    parser = argparse.ArgumentParser(description=(
        'For each fold model (trained on some recordings of DATA_DIR, align: auto): the '
        'mean AOE on the --held-out recordings it never saw, with the tracking candidate '
        'its training tails choose, with the one its whole training recordings choose, '
        'and with the best one on the held-out recordings (a bound, chosen on them).'))
    parser.add_argument('data', type=Path, metavar='DATA_DIR')
    parser.add_argument('--held-out', nargs='+', required=True, metavar='RECORDING')
    parser.add_argument('--models', nargs='+', required=True, metavar='MODEL')
    args = parser.parse_args()
    main(args.data, args.held_out, args.models)
