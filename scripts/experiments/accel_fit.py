# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The accelerometer calibration the fused orientation needs: a bias, or a bias and a matrix.

On a model's training recordings, before their validation tails (as ``tune-fusion``):
the bias of each recording alone and pooled (``filters.fit_accel_bias``), the bias the
ground-truth file itself carries where it has one (EuRoC's 17-column files), and a full
affine fit (reading = A force + b, least squares); then the tails' fused errors of the
network's gyro through VQF (the model's stored time constant) with the accelerometer as
it came, without the bias, and through the inverse affine map.
Usage: .venv/bin/python scripts/experiments/accel_fit.py MODEL DATA_DIR
"""

from pathlib import Path
import sys

from denoise_imu_ros.core.modelfile import sample_rate
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.evaluation import filters
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
import numpy as np


def main(model: str, data: str) -> None:
    """Print the fits, then one line of tail errors per accelerometer model."""
    net = load_model(model)
    meta = net.meta
    names, start = meta.train_sequences, meta.training_span
    seqs = [load_sequence(f'{data}/{n}', meta.recipe('imu_topic'), meta.recipe('pose_topic'),
                          meta.recipe('max_gt_gap_s'), align_poses=meta.recipe('align', 'none'))
            for n in names]  # as tune-fusion reads them
    for name, seq in zip(names, seqs):
        fitted = filters.fit_accel_bias([seq], start)
        gt_file = Path(data) / name / 'mav0' / 'state_groundtruth_estimate0' / 'data.csv'
        cols = np.loadtxt(gt_file, delimiter=',', comments='#') if gt_file.exists() else None
        own = '' if cols is None or cols.shape[1] < 17 else \
            f', ground-truth file {np.round(cols[:, 14:17].mean(0), 3).tolist()}'
        print(f'{name}: {np.round(fitted[0], 3).tolist() if fitted else None}{own}')
    pooled = filters.fit_accel_bias(seqs, start)
    if pooled is None:
        sys.exit("no usable poses before the tails (or a fit out of any IMU's range)")
    bias, samples = pooled
    read, should = filters.specific_force(seqs, start)
    solved, *_ = np.linalg.lstsq(np.hstack([should, np.ones((len(should), 1))]), read,
                                 rcond=None)
    a, b = solved[:3].T, solved[3]
    print(f'pooled bias {np.round(bias, 4).tolist()} ({samples} samples), residual std '
          f'{np.round((read - should - bias).std(0), 3).tolist()}')
    print(f'affine: A {np.round(a, 3).tolist()}, b {np.round(b, 3).tolist()}, residual std '
          f'{np.round((read - should @ a.T - b).std(0), 3).tolist()}')
    settings = meta.fusion.chosen
    flt = filters.Filter('vqf', settings.tau_acc_s, settings.bias_estimation)
    tails = [s.tail(start) for s in seqs]
    gyros = [correct_gyro(net.model, s.imu)[start:] for s in seqs]
    inverse = np.linalg.inv(a)
    for label, accel in (('as it came', lambda x: x), ('bias removed', lambda x: x - bias),
                         ('affine inverted', lambda x: (x - b) @ inverse.T)):
        errs = [filters.score(t, filters.run(flt, g, accel(t.imu[:, 3:]), sample_rate(net)))
                for t, g in zip(tails, gyros)]
        print(f'{flt.label}, accelerometer {label}: 3-D {np.mean([e.aoe for e in errs]):.3f} '
              f'tilt {np.mean([e.tilt for e in errs]):.3f} yaw '
              f'{np.mean([e.aoe_yaw for e in errs]):.3f}')


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2])
