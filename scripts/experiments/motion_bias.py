# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Whether the gyro's bias in motion is its bias at rest: drift, g-sensitivity or neither.

Per recording: the raw gyro's mean over its first and over its last still stretch (VQF's
rest detection), and, over 2 s blocks in motion, the mean error of the gyro less its
causal turn-on bias against the poses (clock and frame aligned), with the mean
accelerometer in motion beside the one at rest. A bias in motion off the one at rest,
alike in translation trials held at the rest attitude, is neither drift (start and end
agree) nor g-sensitivity (the same gravity).
Usage: .venv/bin/python scripts/experiments/motion_bias.py DATA_DIR RECORDING...
"""

from pathlib import Path
import sys

from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.data.rest_bias import rest_bias_batch, RestBiasSettings
import numpy as np
from scipy.spatial.transform import Rotation

BLOCK_S = 2.0


def main(data: str, names: list[str]) -> None:
    """Print one line per recording (mdeg/s; m/s^2)."""
    for name in names:
        seq = load_sequence(Path(data) / name, align_poses='auto')
        est = rest_bias_batch(seq.imu, seq.rate_hz, RestBiasSettings())
        still = np.flatnonzero(est['rest'])
        first = still[still < len(seq) * 0.3]
        last = still[still > len(seq) * 0.7]
        gyro = seq.imu[:, :3] - est['bias']
        n = int(BLOCK_S * seq.rate_hz)
        errors, accel = [], []
        for s in range(0, len(seq) - n, n):
            if not seq.gt_valid[s:s + n + 1].all() or est['rest'][s:s + n].mean() > 0.5:
                continue
            turn = Rotation.identity()
            for w, dt in zip(gyro[s:s + n], seq.dt[s:s + n]):
                turn = turn * Rotation.from_rotvec(w * dt)
            truth = Rotation.from_quat(seq.gt_quat[s]).inv() * Rotation.from_quat(
                seq.gt_quat[s + n])
            errors.append((truth.inv() * turn).as_rotvec() / (n / seq.rate_hz))
            accel.append(seq.imu[s:s + n, 3:].mean(axis=0))

        def mdeg(v: np.ndarray) -> list[float]:
            return np.round(np.degrees(v) * 1e3, 1).tolist()
        print(f'{name}: rest bias at start {mdeg(seq.imu[first, :3].mean(0))}, at end '
              f'{mdeg(seq.imu[last, :3].mean(0))}; in motion less the turn-on bias '
              f'{mdeg(np.mean(errors, axis=0))} ({len(errors)} blocks); accelerometer at '
              f'rest {np.round(seq.imu[first, 3:].mean(0), 2).tolist()}, in motion '
              f'{np.round(np.mean(accel, axis=0), 2).tolist()}', flush=True)


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2:])
