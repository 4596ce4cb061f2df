# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
A model taught without the poses' heading, its correction about the vertical dropped.

With ``heading_weight: 0`` the loss never sees the component of the correction about
the world's vertical, so nothing but the turn-on bias vouches for it. Here the network's
correction (its gyro less the rest-bias gyro) loses that component: the vertical in the
body frame taken from VQF run on the network's gyro (what a node has online), or from the
ground truth (the bound). Open loop AOE 3-D / yaw / tilt and VQF's (defaults) AOE 3-D /
tilt, degrees, per recording and their mean, from ``START`` on (the training recordings'
validation tails: ``training_span``; a test sequence: 0), against the recordings' own poses.
Usage: .venv/bin/python scripts/experiments/vertical_projection.py MODEL DATA_DIR START REC...
"""

from pathlib import Path
import sys

from denoise_imu_ros.core.metrics import score
from denoise_imu_ros.core.modelfile import sample_rate
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.evaluation import filters
from denoise_imu_ros.evaluation.evaluate import gyros_of
from denoise_imu_ros.learn.checkpoint import load_model
import numpy as np
from scipy.spatial.transform import Rotation


def without_vertical(gyro: np.ndarray, base: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Return ``base`` plus the part of ``gyro - base`` orthogonal to ``up`` (unit, body)."""
    d = gyro - base
    return base + d - (d * up).sum(1, keepdims=True) * up


def main(model: str, data: str, start: int, names: list[str]) -> None:
    """Print one line per recording and gyro, then the means."""
    loaded = load_model(model)
    rate, vqf = sample_rate(loaded), filters.Filter('vqf')
    figures: dict[str, list[tuple[float, ...]]] = {}
    for name in names:
        seq = load_sequence(Path(data) / name, min_samples=loaded.model.receptive_field,
                            rate_hz=rate)
        g = gyros_of(seq, {'network': loaded})
        online = filters.run(vqf, g['network'], seq.imu[:, 3:], rate, seq.stamp_ns)
        ups = {'filter': Rotation.from_quat(online).inv().apply([0.0, 0.0, 1.0]),
               'truth': Rotation.from_quat(seq.gt_quat).inv().apply([0.0, 0.0, 1.0])}
        rows = {'rest bias': g['rest bias'], 'network': g['network']}
        rows.update({f'network less its vertical ({k})': without_vertical(
            g['network'], g['rest bias'], up) for k, up in ups.items()})
        tail = seq.tail(start)
        for method, gyro in rows.items():
            open_loop = score(tail, gyro[start:])
            fused = filters.score(tail, filters.run(vqf, gyro[start:], tail.imu[:, 3:], rate,
                                                    tail.stamp_ns))
            figures.setdefault(method, []).append((
                open_loop['aoe_deg'], open_loop['aoe_yaw_deg'], open_loop['tilt_deg'],
                fused.aoe, fused.tilt))
            print(name, method, ' '.join(f'{v:.2f}' for v in figures[method][-1]), flush=True)
    for method, rows_ in figures.items():
        print('mean', method, ' '.join(f'{v:.2f}' for v in np.mean(rows_, axis=0)))


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:])
