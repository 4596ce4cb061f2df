# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Can a trajectory's heading teach a gyro: its rotation about the vertical against the truth's.

For every window of each horizon (one every 100 samples, both ends on trusted poses) the
rotation over it from the trajectory files (aligned as ``align: auto`` does) and from a
model's "rest bias" gyro (the raw gyro less its turn-on bias, integrated) are compared
with the motion capture's: the component of each error about the world's vertical, RMS
over the recordings' windows, degrees. A trajectory whose figure is above the gyro's at
every horizon has nothing to teach the gyro about its heading.
Usage: .venv/bin/python scripts/reproduce/vio_heading.py MODEL DATA POSES REC...
"""

from pathlib import Path
import sys

from denoise_imu_ros.core.metrics import integrate
from denoise_imu_ros.core.modelfile import read_model_file
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.pipeline.rest_bias import baseline_gyro
import numpy as np
from scipy.spatial.transform import Rotation

HORIZONS = (256, 1024, 4096, 12000)  # samples
EVERY = 100


def about_vertical(truth: Rotation, other: Rotation, k: np.ndarray, h: int) -> np.ndarray:
    """Return the error of ``other``'s rotation from k to k + h about the vertical, rad."""
    true = truth[k].inv() * truth[k + h]
    error = (true.inv() * (other[k].inv() * other[k + h])).as_rotvec()
    return (error * truth[k + h].inv().apply([0.0, 0.0, 1.0])).sum(axis=1)


def main(model: str, data: str, poses: str, names: list[str]) -> None:
    """Print each horizon's RMS error about the vertical of the trajectory and the gyro."""
    loaded = read_model_file(model)
    errors: dict[int, dict[str, list[np.ndarray]]] = {
        h: {'poses': [], 'gyro': []} for h in HORIZONS}
    for name in names:
        mocap = load_sequence(Path(data) / name)
        vio = load_sequence(Path(data) / name, poses=poses, align_poses='auto')
        _, im, iv = np.intersect1d(mocap.stamp_ns, vio.stamp_ns, return_indices=True)
        quat = np.tile([0.0, 0.0, 0.0, 1.0], (len(mocap.stamp_ns), 1))
        quat[im] = vio.gt_quat[iv]
        valid = np.zeros(len(mocap.stamp_ns), bool)
        valid[im] = vio.gt_valid[iv]
        valid &= mocap.gt_valid
        gyro = mocap.on_poses(baseline_gyro(loaded, mocap.stream))
        rows = {'poses': Rotation.from_quat(quat),
                'gyro': integrate(mocap.gt_quat[0], gyro[:len(mocap.dt)], mocap.dt)}
        truth = Rotation.from_quat(mocap.gt_quat)
        for h in HORIZONS:
            k = np.arange(0, len(valid) - h, EVERY)
            k = k[valid[k] & valid[k + h]]
            for row, est in rows.items():
                errors[h][row].append(about_vertical(truth, est, k, h))
        print(name, 'done', flush=True)
    for h in HORIZONS:
        rms = {row: float(np.degrees(np.sqrt(np.mean(np.concatenate(e) ** 2))))
               for row, e in errors[h].items()}
        print(f'{h / loaded.meta.sample_rate_hz:5.1f} s: about the vertical, RMS: trajectory '
              f'{rms["poses"]:.2f} deg, gyro less its turn-on bias {rms["gyro"]:.2f} deg '
              f'({rms["poses"] / rms["gyro"]:.1f}x)')


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:])
