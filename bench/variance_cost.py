# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What the per-message variances add to the online pipeline's per-sample cost, side by side.

Runs one model over the same real samples through ``OnlineDenoiser.process`` (the node's
and process-bag's per-sample work, without ROS, ``imu/data``'s filter included, as the
node runs by default) three ways: without the file's variance models, with the gyro's
alone, and with the gyro's and the accelerometer's (what the file has); their order
rotated every round so that a change in the machine's speed hits all alike. Prints the
median per-sample time of each and the ratios to the first two.
Run: .venv/bin/python bench/variance_cost.py [--model euroc]
     [--data ../shared/data/euroc] [--recording V1_03_difficult] [--samples 20000]
     [--rounds 6]
"""

import argparse
import dataclasses
import gc
from pathlib import Path
import time

from denoise_imu_ros.core.modelfile import read_model_file
from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.pipeline.online import OnlineDenoiser
import numpy as np

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'euroc'


def per_sample_s(den: OnlineDenoiser, stamps: np.ndarray, imu: np.ndarray) -> float:
    """Return the mean time of ``den.process`` over the samples, seconds."""
    rows = [(int(t), r[:3].copy(), r[3:].copy()) for t, r in zip(stamps, imu)]
    gc.collect()  # the last round's garbage is not this one's cost
    start = time.perf_counter()
    for t, g, a in rows:
        den.process(t, g, a)
    return (time.perf_counter() - start) / len(rows)


def main() -> None:
    """Print the per-sample cost without variances, with the gyro's, with both."""
    parser = argparse.ArgumentParser()
    parser.add_argument('--model', default='euroc')
    parser.add_argument('--data', type=Path, default=DATA)
    parser.add_argument('--recording', default='V1_03_difficult')
    parser.add_argument('--samples', type=int, default=20000)
    parser.add_argument('--rounds', type=int, default=6)
    args = parser.parse_args()
    model = read_model_file(args.model)
    if model.meta.gyro_variance is None or model.meta.accel_variance is None:
        raise SystemExit(f'{args.model}: no gyro and accelerometer variance models to time '
                         '(fit-variance --attach)')
    meta = model.meta
    variants = {
        'no variances': model._replace(meta=dataclasses.replace(
            meta, gyro_variance=None, accel_variance=None)),
        "the gyro's": model._replace(meta=dataclasses.replace(meta, accel_variance=None)),
        "the gyro's and the accelerometer's": model}
    rec = load_imu(args.data / args.recording)
    stamps, imu = rec.imu_stamp_ns[:args.samples], rec.imu[:args.samples]
    times: dict[str, list[float]] = {name: [] for name in variants}
    names = list(variants)
    for k in range(args.rounds):
        for name in names[k % 3:] + names[:k % 3]:  # rotated each round
            den = OnlineDenoiser.from_model_file(variants[name], meta.fusion.chosen)
            times[name].append(per_sample_s(den, stamps, imu))
    median = {k: float(np.median(v)) for k, v in times.items()}
    print(f'{model.path.name}, {len(stamps)} samples of {args.recording}, {args.rounds} rounds '
          'rotated, median per sample (imu/data included):')
    for name, value in median.items():
        print(f'  {name}: {value * 1e6:.1f} us')
    both = median[names[2]]
    print(f"  both / the gyro's: {both / median[names[1]]:.3f}")
    print(f'  both / no variances: {both / median[names[0]]:.3f}')


if __name__ == '__main__':
    main()
