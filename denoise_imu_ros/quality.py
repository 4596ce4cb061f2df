# Copyright 2026 denoise_imu_ros authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Data quality before training (``denoise-imu check-data``): rates, holes, label noise.

The loss compares gyro increments with ground-truth increments over j samples. If the
ground truth jitters (mocap) or is interpolated between sparse poses (VIO at 10-20 Hz),
the short increments measure that noise rather than the gyro's error. The label-noise
profile integrates the gyro with one constant bias removed (fitted to the ground truth)
and reports the RMS increment residual per length j; divided by the increment's
duration it is the gyro error (deg/s) the noise alone would stand for. Above
NOISE_RATE_LIMIT_DEG_S, more than the corrections the method makes (at most ~1 deg/s,
the paper), an increment length is noise-dominated.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from .dataset import Sequence
from .metrics import integrate

LENGTHS = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512)  # increment lengths profiled (samples)
BIAS_FIT_LENGTH = 64      # increments the constant bias is fitted on (samples)
NOISE_RATE_LIMIT_DEG_S = 1.0


def increment_residuals(seq: Sequence, gyro: np.ndarray, length: int) -> np.ndarray:
    """(M, 3) rad: log(R_gt increment^T R_gyro increment) over trusted blocks of ``length``."""
    est = integrate(seq.gt_quat[0], gyro[:-1], seq.dt)
    gt = Rotation.from_quat(seq.gt_quat)
    idx = np.arange((len(seq) - 1) // length) * length
    ok = seq.gt_valid[idx] & seq.gt_valid[idx + length]
    idx = idx[ok]
    return ((gt[idx].inv() * gt[idx + length]).inv()
            * (est[idx].inv() * est[idx + length])).as_rotvec()


def label_noise(seq: Sequence) -> dict[str, Any]:
    """Constant gyro bias against the ground truth, and the increment residual per length."""
    gyro = seq.imu[:, :3]
    dt = float(np.mean(seq.dt))
    bias = increment_residuals(seq, gyro, BIAS_FIT_LENGTH).mean(0) / (BIAS_FIT_LENGTH * dt)
    profile = {}
    for j in LENGTHS:
        if (len(seq) - 1) // j < 2:
            break
        res = increment_residuals(seq, gyro - bias, j)
        if len(res) == 0:
            continue
        rms = float(np.sqrt(np.mean(res ** 2)))  # per axis
        profile[j] = {'residual_mrad': 1e3 * rms,
                      'noise_rate_deg_s': math.degrees(rms / (j * dt))}
    noisy = [j for j, p in profile.items() if p['noise_rate_deg_s'] > NOISE_RATE_LIMIT_DEG_S]
    return {'gyro_bias_deg_s': np.degrees(bias).tolist(), 'increments': profile,
            'noise_dominated_increments': noisy}


def check_sequence(seq: Sequence, gt_stamp_ns: np.ndarray) -> dict[str, Any]:
    """Rates, stamp jitter, ground-truth holes and label noise of one aligned recording."""
    imu_dt = np.diff(seq.stamp_ns) * 1e-9
    gt_dt = np.diff(gt_stamp_ns) * 1e-9
    holes = ~seq.gt_valid
    starts = np.flatnonzero(np.diff(np.r_[0, holes.astype(np.int8)]) == 1)
    ends = np.flatnonzero(np.diff(np.r_[holes.astype(np.int8), 0]) == -1)
    longest = float(max(((seq.stamp_ns[e] - seq.stamp_ns[max(s - 1, 0)]) * 1e-9
                         for s, e in zip(starts, ends)), default=0.0))
    report = {'name': seq.name, 'imu_rate_hz': seq.rate_hz,
              'imu_stamp_jitter_ms': 1e3 * float(imu_dt.std()),
              'pose_rate_hz': 1.0 / float(np.median(gt_dt)),
              'pose_holes': len(starts), 'pose_longest_hole_s': longest,
              'pose_hole_fraction': float(holes.mean()),
              'duration_s': float(imu_dt.sum())}
    report.update(label_noise(seq))
    noisy = report['noise_dominated_increments']
    clean = [j for j in report['increments'] if j >= 16 and j not in noisy]
    report['shortest_clean_increment'] = clean[0] if clean else None
    short = [j for j in (16, 32) if j in noisy]
    if not short:
        report['verdict'] = ('the 16- and 32-sample increments of the paper are not '
                             'dominated by ground-truth noise')
    else:
        report['verdict'] = (
            f'increments of {" and ".join(map(str, short))} samples are dominated by '
            'ground-truth noise' + (f'; from {clean[0]} samples on they are not'
                                    if clean else '; so are all up to 512 samples'))
    return report


def markdown(report: dict[str, Any]) -> str:
    """Human-readable report of :func:`check_sequence`."""
    lines = [f'{report["name"]}: {report["duration_s"]:.1f} s',
             f'  IMU {report["imu_rate_hz"]:.2f} Hz, stamp jitter '
             f'{report["imu_stamp_jitter_ms"]:.3f} ms',
             f'  poses {report["pose_rate_hz"]:.1f} Hz, {report["pose_holes"]} holes '
             f'(longest {report["pose_longest_hole_s"]:.2f} s, '
             f'{100 * report["pose_hole_fraction"]:.1f} % of IMU stamps)',
             '  gyro bias against the poses (deg/s): '
             + ', '.join(f'{b:+.3f}' for b in report['gyro_bias_deg_s']),
             '  increment residual after that bias (samples: mrad per axis, as deg/s):']
    lines += [f'    {j:4d}: {p["residual_mrad"]:7.3f}  {p["noise_rate_deg_s"]:7.3f}'
              for j, p in report['increments'].items()]
    lines.append(f'  verdict: {report["verdict"]}')
    return '\n'.join(lines) + '\n'
