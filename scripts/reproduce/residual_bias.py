# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
How much of a model's error on a recording is one constant bias: an analysis, not a method.

Corrects the gyro with MODEL, fits one constant bias on the corrected gyro's 256-sample
increment errors against the recording's own poses (``metrics.fit_constant_bias``, as
check-data's supervision test) and prints the AOE before and after removing it, with
the bias. Fitting on the recording's poses uses its ground truth: the "after" column is
a bound on what a perfect per-recording constant would give, not something deployable.
Usage: .venv/bin/python scripts/reproduce/residual_bias.py MODEL DATA_DIR NAME [NAME ...]
"""

import dataclasses
from pathlib import Path
import sys

from denoise_imu_ros.data.check import supervision
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro

LENGTH = 256


def main(model: str, data: str, names: list[str]) -> None:
    """Print one line per recording."""
    net = load_model(model).model
    for name in names:
        seq = load_sequence(Path(data) / name)
        imu = seq.imu.copy()
        imu[:, :3] = correct_gyro(net, seq.imu)
        report = supervision(dataclasses.replace(seq, imu=imu), (LENGTH,))
        fit = report['fits'][LENGTH]
        print(f'{name}: AOE {report["aoe_plain_deg"]:.2f} -> {fit["aoe_deg"]:.2f} deg without '
              'the residual bias ' + ', '.join(f'{b:+.3f}' for b in fit['bias_deg_s'])
              + ' deg/s', flush=True)


if __name__ == '__main__':
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
