# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
A model taught without its poses' heading, with and without its correction about the vertical.

The choice :mod:`denoise_imu_ros.data.vertical` makes for a model trained with
``heading_weight: 0`` and fed the gyro less its turn-on bias, measured: the model's gyro
as every path ends it (tracked, guarded, its correction about the vertical dropped)
against the same with that correction kept, and the gyro less its turn-on bias. Open loop
AOE 3-D / yaw / tilt and VQF's (defaults) AOE 3-D / tilt, degrees, per recording and
their mean, from ``--start`` on (the training recordings' validation tails: ``tail``, the
model's ``training_span``; a test sequence: 0, the default), against the recordings' own
poses or, with ``--poses``, a VIO's or a SLAM's trajectory files (aligned as the model's
recipe aligns them).
Usage: .venv/bin/python scripts/experiments/vertical_projection.py MODEL DATA REC...
[--start N|tail] [--poses DIR]
"""

import argparse
from pathlib import Path

from denoise_imu_ros.core.metrics import score
from denoise_imu_ros.core.modelfile import sample_rate
from denoise_imu_ros.data import envelope, rest_bias
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.evaluation import filters
from denoise_imu_ros.learn.checkpoint import load_model
import numpy as np


def main() -> None:
    """Print one line per recording and gyro, then the means."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument('model')
    ap.add_argument('data')
    ap.add_argument('recordings', nargs='+')
    ap.add_argument('--start', default='0')
    ap.add_argument('--poses', default=None)
    args = ap.parse_args()
    loaded = load_model(args.model)
    rate, vqf = sample_rate(loaded), filters.Filter('vqf')
    field = loaded.model.receptive_field
    start = loaded.meta.training_span if args.start == 'tail' else int(args.start)
    figures: dict[str, list[tuple[float, ...]]] = {}
    for name in args.recordings:
        align = loaded.meta.recipe('align', 'auto') if args.poses else 'none'
        seq = load_sequence(Path(args.data) / name, min_samples=field, rate_hz=rate,
                            poses=args.poses, align_poses=align)
        fed = rest_bias.model_input(loaded, seq.stream)
        output = loaded.untracked(seq.stream)
        rows = {'rest bias': seq.on_poses(rest_bias.baseline_gyro(loaded, seq.stream))}
        for label, drop in (('vertical kept', False), ('as shipped', True)):
            rows[label] = seq.on_poses(envelope.finish(
                output, fed, rate, rest_bias.tracking(loaded.meta, 'model'),
                loaded.meta.input_envelope, field, drop))
        tail = seq.tail(start)
        for method, gyro in rows.items():
            open_loop = score(tail, gyro[start:])
            fused = filters.score(tail, filters.run(vqf, gyro[start:], tail.imu[:, 3:],
                                                    rate, tail.stamp_ns))
            figures.setdefault(method, []).append((
                open_loop['aoe_deg'], open_loop['aoe_yaw_deg'], open_loop['tilt_deg'],
                fused.aoe, fused.tilt))
            print(name, method, ' '.join(f'{v:.2f}' for v in figures[method][-1]), flush=True)
    for method, rows_ in figures.items():
        print('mean', method, ' '.join(f'{v:.2f}' for v in np.mean(rows_, axis=0)))


if __name__ == '__main__':
    main()
