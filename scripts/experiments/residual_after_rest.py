# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What is left of each recording's gyro bias once its turn-on bias is removed, against the poses.

Per recording: check-data's constant gyro bias against the poses (``gyro_bias_vs_pose``,
fitted with the clock offset and frame rotation) of the raw gyro, then of the raw gyro
less its causal turn-on bias estimate (``data/rest_bias.py``, default settings), and the
per-axis scale error. What remains is the error in motion a model could learn; where it
is a constant of each power-on session, one session cannot teach it for the next.
Usage: .venv/bin/python scripts/experiments/residual_after_rest.py DATA_DIR RECORDING...
"""

import dataclasses
from pathlib import Path
import sys

from denoise_imu_ros.core.limits import stream_rate_hz
from denoise_imu_ros.data.load import load_recording
from denoise_imu_ros.data.pose_alignment import estimate_pose_alignment
from denoise_imu_ros.data.rest_bias import remove_rest_bias, RestBiasSettings
import numpy as np


def main(data: str, names: list[str]) -> None:
    """Print, per recording: the raw bias, the bias left after the rest bias, the scale."""
    for name in names:
        rec = load_recording(Path(data) / name)
        rate = stream_rate_hz(rec.imu_stamp_ns)
        raw = estimate_pose_alignment(rec)['gyro_bias_vs_pose_deg_s']
        less = dataclasses.replace(rec, imu=remove_rest_bias(rec.imu, rate, RestBiasSettings()))
        left = estimate_pose_alignment(less)
        print(f'{name}: raw {np.round(raw, 3).tolist()} deg/s, less the turn-on bias '
              f'{np.round(left["gyro_bias_vs_pose_deg_s"], 4).tolist()} deg/s, scale error '
              f'{np.round(left["gyro_scale_error_percent"], 2).tolist()} %', flush=True)


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2:])
