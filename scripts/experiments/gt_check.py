# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
How the raw gyro relates to the ground truth, per recording: a data check, not a model.

Over non-overlapping 0.1 s blocks, fits  phi_gt = C phi_gyro + b T  by least squares
(phi: rotation vector of the block's increment, T: its duration) and prints the rotation
between the gyro and ground-truth body frames (polar part of C), the scale factors, the
bias b, and the bias over successive 20 s stretches (raw gyro minus ground-truth rate).
A frame rotation well above the others' flags ground truth in a different body frame;
bias differences between recordings are what a model trained on other recordings
cannot know.
Usage: .venv/bin/python scripts/experiments/gt_check.py SEQUENCE_DIR_OR_BAG [...]
"""

import sys

from denoise_imu_ros.data.load import load_sequence
import numpy as np
from scipy.linalg import polar
from scipy.spatial.transform import Rotation

BLOCK = 20      # samples per block (0.1 s at 200 Hz)
STRETCH = 4000  # samples per bias stretch (20 s at 200 Hz)


def check(path: str) -> None:
    """Print the fit for one recording."""
    s = load_sequence(path)
    n = (len(s) - 1) // BLOCK * BLOCK
    start = np.arange(0, n, BLOCK)
    gyro = Rotation.identity(len(start))
    for j in range(BLOCK):
        gyro = gyro * Rotation.from_rotvec(s.imu[start + j, :3] * s.dt[start + j, None])
    gt = Rotation.from_quat(s.gt_quat)
    phi_gt = (gt[start].inv() * gt[start + BLOCK]).as_rotvec()
    ok = s.gt_valid[start] & s.gt_valid[start + BLOCK]
    duration = (s.stamp_ns[start + BLOCK] - s.stamp_ns[start]) * 1e-9
    a = np.hstack([gyro.as_rotvec(), duration[:, None]])[ok]
    x = np.linalg.lstsq(a, phi_gt[ok], rcond=None)[0]
    frame, stretch = polar(x[:3].T)
    angle = np.degrees(Rotation.from_matrix(frame).magnitude())
    print(f'{s.name}: frame rotation {angle:.2f} deg, scale {np.diag(stretch).round(4)}, '
          f'bias {np.degrees(-x[3]).round(3)} deg/s')
    error = s.imu[:-1, :3] - (gt[:-1].inv() * gt[1:]).as_rotvec() / s.dt[:, None]
    error[~(s.gt_valid[:-1] & s.gt_valid[1:])] = np.nan  # ground-truth holes
    stretches = [np.degrees(np.nanmean(error[i:i + STRETCH], axis=0))
                 for i in range(0, len(error) - STRETCH + 1, STRETCH)]
    print('  bias per 20 s (deg/s): ' + ' '.join(str(b.round(3)) for b in stretches))


if __name__ == '__main__':
    for arg in sys.argv[1:]:
        check(arg)
