# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The constant vertical gyro bias each recording's poses would want after a model (oracle).

What is left about the vertical after a model whose correction there is dropped (a
VIO-trained one) is the gyro less its turn-on bias. For each recording, the constant
bias along its mean "up" (the accelerometer's mean direction over the stream) that
lowers the model's open-loop AOE 3-D against POSES most, and the figures with it: what a
perfect constant about the vertical would give, and whether a trajectory could teach it
(its constants against those of the motion capture).
Usage: .venv/bin/python scripts/reproduce/vertical_constant.py MODEL DATA POSES|- NAME...
"""

import argparse
from pathlib import Path

from denoise_imu_ros.core.metrics import score
from denoise_imu_ros.core.modelfile import sample_rate
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.learn.checkpoint import load_model
import numpy as np
from scipy.optimize import minimize_scalar

BOUND_DEG_S = 0.5  # searched within: 10x the largest constant motion capture asks for


def main() -> None:
    """Print each recording's figures before and with its best constant, and the constant."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument('model')
    ap.add_argument('data', type=Path)
    ap.add_argument('poses', help="a folder of trajectory files, or - for the recording's own")
    ap.add_argument('names', nargs='+')
    args = ap.parse_args()
    loaded = load_model(args.model)
    for name in args.names:
        seq = load_sequence(args.data / name, min_samples=loaded.model.receptive_field,
                            rate_hz=sample_rate(loaded), align_poses='auto',
                            poses=None if args.poses == '-' else args.poses)
        gyro = seq.on_poses(loaded.correct(seq.stream))
        up = seq.stream[:, 3:].mean(axis=0)
        up /= np.linalg.norm(up)

        def aoe(deg_s: float) -> float:
            """Open-loop AOE 3-D with ``deg_s`` more bias about the vertical."""
            return score(seq, gyro + np.radians(deg_s) * up)['aoe_deg']
        best = minimize_scalar(aoe, bounds=(-BOUND_DEG_S, BOUND_DEG_S), method='bounded',
                               options={'xatol': 1e-4}).x
        before, after = score(seq, gyro), score(seq, gyro + np.radians(best) * up)
        print(f'{name}: AOE / yaw {before["aoe_deg"]:.2f} / {before["aoe_yaw_deg"]:.2f} -> '
              f'{after["aoe_deg"]:.2f} / {after["aoe_yaw_deg"]:.2f} deg with '
              f'{best:+.4f} deg/s about the vertical'
              + (' (at the bound)' if abs(best) > 0.99 * BOUND_DEG_S else ''), flush=True)


if __name__ == '__main__':
    main()
