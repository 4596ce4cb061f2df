# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Would re-estimating the residual bias whenever the IMU stands still help? An experiment.

Most of the network's error on an unseen recording is one constant bias
(``scripts/experiments/residual_bias.py``). A robot that stops gives the gyro a known rate,
zero, so the corrected gyro's mean over a still stretch is a causal, IMU-only estimate of that
bias. This applies it: a trailing window of WINDOW_S is still when the raw gyro's and
the accelerometer's standard deviations (norm over the axes) are below the thresholds;
over a still run the bias is the corrected gyro's mean since the run's first window
(kept if under MAX_BIAS), subtracted from every later sample. It prints, per recording,
the AOE of the corrected gyro without and with it, the still samples, the last bias
estimate and, for comparison, the residual bias the recording's own poses give (the
bound of ``residual_bias.py``).
Usage: .venv/bin/python scripts/experiments/still_bias.py MODEL DATA_DIR NAME [NAME ...]
"""

import dataclasses
from pathlib import Path
import sys

from denoise_imu_ros.core.metrics import score
from denoise_imu_ros.core.records import Sequence
from denoise_imu_ros.data.check import supervision
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
import numpy as np

WINDOW_S = 1.0
GYRO_STD = 0.012     # rad/s: ADIS16448 at rest ~0.005, with propellers running > 0.08
ACCEL_STD = 0.2      # m/s^2: at rest ~0.08, in flight > 0.3
MAX_BIAS = np.radians(1.0)


def trailing_std(x: np.ndarray, w: int) -> np.ndarray:
    """Norm over the axes of the std of the w samples ending at each index (inf before)."""
    c1 = np.cumsum(np.vstack([np.zeros((1, x.shape[1])), x]), axis=0)
    c2 = np.cumsum(np.vstack([np.zeros((1, x.shape[1])), x * x]), axis=0)
    mean = (c1[w:] - c1[:-w]) / w
    var = np.maximum((c2[w:] - c2[:-w]) / w - mean ** 2, 0.0)
    out = np.full(len(x), np.inf)
    out[w - 1:] = np.sqrt(var.sum(axis=1))
    return out


def remove_still_bias(seq: Sequence, gyro: np.ndarray) -> tuple[np.ndarray, int, np.ndarray]:
    """Return the gyro with the still-run bias removed, the still samples, the last bias."""
    w = int(round(WINDOW_S / float(np.median(seq.dt))))
    still = ((trailing_std(seq.imu[:, :3], w) < GYRO_STD)
             & (trailing_std(seq.imu[:, 3:], w) < ACCEL_STD))
    csum = np.vstack([np.zeros((1, 3)), np.cumsum(gyro, axis=0)])
    out, bias, start = gyro.copy(), np.zeros(3), -1
    for t in range(len(gyro)):
        out[t] = gyro[t] - bias        # the estimate from samples before t only
        if not still[t]:
            start = -1
            continue
        start = t - w + 1 if start < 0 else start
        mean = (csum[t + 1] - csum[start]) / (t + 1 - start)
        if np.linalg.norm(mean) < MAX_BIAS:
            bias = mean
    return out, int(still.sum()), bias


def main(model: str, data: str, names: list[str]) -> None:
    """Print one line per recording and the mean AOE without and with the still bias."""
    net = load_model(model).model
    before, after = [], []
    for name in names:
        seq = load_sequence(Path(data) / name)
        gyro = correct_gyro(net, seq.imu)
        fixed, n_still, bias = remove_still_bias(seq, gyro)
        imu = seq.imu.copy()
        imu[:, :3] = gyro
        oracle = supervision(dataclasses.replace(seq, imu=imu), (256,))['fits'][256]
        before.append(score(seq, gyro)['aoe_deg'])
        after.append(score(seq, fixed)['aoe_deg'])
        print(f'{name}: AOE {before[-1]:.2f} -> {after[-1]:.2f} deg, {n_still} still '
              'samples, still bias ' + ', '.join(f'{b:+.3f}' for b in np.degrees(bias))
              + ' deg/s (poses say ' + ', '.join(f'{b:+.3f}' for b in oracle['bias_deg_s'])
              + ')', flush=True)
    print(f'mean AOE {np.mean(before):.2f} -> {np.mean(after):.2f} deg')


if __name__ == '__main__':
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
