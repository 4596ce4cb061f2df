# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The per-sample variance fit of ``fit-variance`` for the gyro and for the accelerometer, its NEES.

What a VIO back-end weighs ``imu/corrected`` by: each sample's variance, the same on every
axis, exp(theta . phi) (``pipeline/covariance.py``), theta fitted by the Gaussian negative
log-likelihood (a proper scoring rule) of the increments' errors over 0.1-2 s windows of the
training recordings' validation tails (``evaluation/variance.py``): the gyro's on
rotation increments (what ``fit-variance`` stores), the accelerometer's the same way on
velocity increments (the accelerometer less the model's fitted bias; the velocity the ground
truth's state estimate's). Beside each, the same fit of a constant and, for the gyro, the
model file's published constant. Scored on the test sequences with the increments'
covariance propagated in full (evaluation.preintegration, both sensors' variances): mean
NEES (3 where the covariance describes the error) and the share inside the 2-sigma ellipsoid
(73.9 % then). The poses' own noise is not taken out of the errors.
Run: .venv/bin/python scripts/reproduce/learned_covariance.py [--model euroc]
[--data ../shared/data/euroc]
"""

import argparse
from pathlib import Path

from denoise_imu_ros.core.modelfile import gyro_covariance, read_model_file
from denoise_imu_ros.core.schema import SampleVariance
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.evaluation.correct import corrected_gyro
from denoise_imu_ros.evaluation.preintegration import (
    errors, ground_truth_velocity, preintegrate, reference, window_starts)
from denoise_imu_ros.evaluation.variance import fit, Windows, WINDOWS_S
from denoise_imu_ros.pipeline.covariance import features
import numpy as np

TRAIN = ['MH_01_easy', 'MH_03_medium', 'MH_05_difficult', 'V1_02_medium', 'V2_01_easy',
         'V2_03_difficult']
TEST = ['MH_02_easy', 'MH_04_difficult', 'V1_01_easy', 'V1_03_difficult', 'V2_02_medium']
SHAPE = SampleVariance((0.0, 0.0, 0.0, 0.0))  # the features' means and scales


class Scored:
    """One recording's corrected IMU, features and ground truth, and its windows' errors."""

    def __init__(self, folder: Path, mf, start: int) -> None:
        seq = load_sequence(folder)
        stream = np.vstack([seq.lead_in, seq.imu])  # as the node runs it, from the first sample
        full = corrected_gyro(mf, stream)
        self.seq, self.gyro = seq, seq.on_poses(full)
        self.accel = seq.imu[:, 3:] - np.array(mf.meta.fusion.chosen.accel_bias_m_s2)
        self.phi = seq.on_poses(features(full, stream[:, 3:], seq.rate_hz, SHAPE))
        self.stamp_s = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
        self.vel = ground_truth_velocity(folder, seq.stamp_ns, seq.gt_pos, self.stamp_s)[0]
        self.rotation = Windows.of(seq, self.gyro, self.phi, start)
        self.velocity = Windows(self.rotation.phi, self.rotation.dt2, [
            (window_s, starts, length, np.sum((preintegrate(
                self.gyro, self.accel, self.stamp_s, starts, length).velocity - reference(
                seq.gt_quat, seq.gt_pos, self.vel, self.stamp_s, starts, length).velocity) ** 2,
                axis=1)) for window_s, starts, length, _ in self.rotation.found])

    def scored(self, gyro_var: np.ndarray, accel_var: np.ndarray) -> dict[float, dict]:
        """Return per window length the NEES of rotation and velocity, back-to-back windows."""
        found = {}
        for window_s in WINDOWS_S:
            length = max(1, int(round(window_s * self.seq.rate_hz)))
            starts = window_starts(self.seq.gt_valid, length)
            est = preintegrate(self.gyro, self.accel, self.stamp_s, starts, length, gyro_var,
                               accel_var)
            ref = reference(self.seq.gt_quat, self.seq.gt_pos, self.vel, self.stamp_s, starts,
                            length)
            e = errors(est, ref)
            found[window_s] = {k: e[k] for k in ('nees_rotation', 'nees_velocity')}
        return found


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('--model', default='euroc')
    parser.add_argument('--data', default=str(Path(__file__).resolve().parents[3] / 'shared'
                                              / 'data' / 'euroc'))
    args = parser.parse_args()
    mf = read_model_file(args.model)
    start = mf.meta.training_span
    recs = {part: [Scored(Path(args.data) / name, mf, start if part == 'train' else 0)
                   for name in names] for part, names in (('train', TRAIN), ('test', TEST))}
    published = np.diag(np.reshape(gyro_covariance(mf), (3, 3)))
    fitted = {}
    for sensor in ('rotation', 'velocity'):
        windows = [getattr(r, sensor) for r in recs['train']]
        learnt = fit(windows, reference_noise=False, lengths_alike=False).variance
        constant = fit([Windows(np.ones((len(w.phi), 1)) * [[1, 0, 0, 0]], w.dt2, w.found)
                        for w in windows], reference_noise=False, lengths_alike=False).variance
        fitted[sensor] = {'constant': constant, 'learnt': learnt}
        print(f'{sensor}: learnt theta {np.round(learnt.theta, 3).tolist()}, constant '
              f'{np.round(constant.theta, 3).tolist()}')

    def per_sample(spec: SampleVariance):
        return lambda r: np.repeat(np.exp(r.phi @ np.array(spec.theta))[:, None], 3, axis=1)
    rows = {
        "the file's gyro constant": (lambda r: np.broadcast_to(published, (len(r.phi), 3)),
                                     per_sample(fitted['velocity']['constant'])),
        'constants fitted': (per_sample(fitted['rotation']['constant']),
                             per_sample(fitted['velocity']['constant'])),
        'learnt': (per_sample(fitted['rotation']['learnt']),
                   per_sample(fitted['velocity']['learnt']))}
    print('\n| covariance | window | NEES rotation (in 2 sigma) | NEES velocity (in 2 sigma) |')
    print('|---|---|---|---|')
    for label, (gv, av) in rows.items():
        found: dict[float, dict[str, list]] = {}
        for r in recs['test']:
            for window_s, nees in r.scored(gv(r), av(r)).items():
                for key, v in nees.items():
                    found.setdefault(window_s, {}).setdefault(key, []).append(v)
        for window_s, by in found.items():
            cells = [f'{np.concatenate(v).mean():.2f} ({(np.concatenate(v) < 4).mean():.0%})'
                     for v in by.values()]
            print(f'| {label} | {window_s:g} s | {" | ".join(cells)} |')
    sigma = np.concatenate([np.sqrt(per_sample(fitted['rotation']['learnt'])(r)[:, 0])
                            for r in recs['test']])
    print(f'\nlearnt gyro sigma on the test sequences: 5/50/95 % '
          f'{np.percentile(sigma, [5, 50, 95]).round(4).tolist()} rad/s')


if __name__ == '__main__':
    main()
