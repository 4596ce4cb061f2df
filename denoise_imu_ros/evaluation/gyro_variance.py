# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The corrected gyro's per-sample variance fitted by a proper scoring rule (``fit-variance``).

A VIO back-end pre-integrates the gyro between keyframes 0.1-2 s apart and weighs the
rotation increment by the covariance the messages' ``angular_velocity_covariance`` gives:
the sum of its samples' variances times dt^2, their errors taken as white. The model
(:class:`~denoise_imu_ros.core.schema.GyroVariance`, computed by
:mod:`~denoise_imu_ros.pipeline.covariance`) is fitted by the Gaussian negative
log-likelihood of the rotation increments' errors (the angle of dR_pose^T dR_gyro) over
WINDOWS_S windows, half-overlapping, of the training recordings' validation tails: what
the network did not train on. Each window's error also holds the poses' own noise at its
two ends, the same whatever the window's length where the gyro's grows with it: the fit
takes one such variance of the reference beside the model's (``reference_noise_deg``:
EuRoC's motion capture shows none at these lengths, TUM-VI's some 0.2 deg per axis), and
leaves it out of what ``imu/corrected`` publishes. The NEES of each window, that
noise counted (3 where the variance describes the error; 73.9 % of windows inside the
2-sigma ellipsoid then), says how well it does.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from scipy.optimize import minimize

from .filters import training_recordings
from .preintegration import window_starts
from ..core.metrics import block_errors, integrate
from ..core.modelfile import sample_rate
from ..core.records import Sequence
from ..core.schema import GyroVariance
from ..learn.checkpoint import load_model
from ..pipeline.covariance import features

__all__ = ['Fit', 'fit', 'fit_model', 'nees', 'Windows', 'WINDOWS_S']

WINDOWS_S = (0.1, 0.2, 0.5, 1.0, 2.0)  # the keyframe spacings a VIO pre-integrates over
START_LOG_VARIANCE = -9.0               # the fit's start: 0.011 rad/s, any axis
START_LOG_REFERENCE = -14.0             # and the reference's noise: 0.05 deg per axis
LOG_REFERENCE_BOUNDS = (-60.0, 0.0)     # from none at all to 1 rad per axis


class Windows(NamedTuple):
    """One recording's windows: its samples' features and dt^2, the windows' errors."""

    phi: np.ndarray           # (N, 4) the samples' features
    dt2: np.ndarray           # (N,) each sample's interval, squared
    found: list[tuple[float, np.ndarray, int, np.ndarray]]  # window s, starts, length, err^2

    @classmethod
    def of(cls, seq: Sequence, gyro: np.ndarray, phi: np.ndarray, start: int = 0) -> Windows:
        """Return the windows of ``seq`` from sample ``start`` on whose poses are trusted."""
        dt = np.diff((seq.stamp_ns - seq.stamp_ns[0]) * 1e-9)
        attitude = integrate(np.array([0.0, 0.0, 0.0, 1.0]), gyro[:-1], dt)
        valid = seq.gt_valid.copy()
        valid[:start] = False
        found = []
        for window_s in WINDOWS_S:
            length = max(1, int(round(window_s * seq.rate_hz)))
            starts = window_starts(valid, length, max(1, length // 2))
            if not len(starts):
                continue
            error = block_errors(seq.gt_quat, starts, starts + length, attitude)
            found.append((window_s, starts, length, np.sum(error ** 2, axis=1)))
        return cls(phi, np.r_[dt, 0.0] ** 2, found)


class Fit(NamedTuple):
    """The variance model, and the reference's own noise the same windows show."""

    variance: GyroVariance
    reference_var: float  # rad^2 per axis: the poses' noise in every window, whatever long


def _nll(params: np.ndarray, windows: list[Windows]) -> tuple[float, np.ndarray]:
    """
    Return the windows' mean 3-D Gaussian negative log-likelihood and its gradient.

    ``params``: theta, then the log of the reference's variance per window (per axis).
    """
    theta, reference = params[:-1], float(np.exp(params[-1]))
    total, grad, count = 0.0, np.zeros_like(params), 0
    for w in windows:
        v = np.exp(w.phi @ theta) * w.dt2
        sums = np.vstack([np.zeros((1, len(theta) + 1)),
                          np.cumsum(np.hstack([v[:, None], v[:, None] * w.phi]), axis=0)])
        for _, starts, length, err2 in w.found:
            inside = sums[starts + length] - sums[starts]
            s, ds = inside[:, 0] + reference, inside[:, 1:]
            total += float(np.sum(0.5 * err2 / s + 1.5 * np.log(s)))
            slope = 1.5 / s - 0.5 * err2 / s ** 2
            grad[:-1] += (slope[:, None] * ds).sum(0)
            grad[-1] += float(slope.sum()) * reference
            count += len(s)
    return total / count, grad / count


def fit(windows: list[Windows], mean_s: float = 0.1,
        scales: tuple[float, float, float] = (0.1, 0.5, 1.0), reference_noise: bool = True
        ) -> Fit:
    """
    Return the variance model of least negative log-likelihood over the windows.

    With ``reference_noise`` the reference's own variance per window is fitted beside it
    (else taken as none).
    """
    if not any(len(starts) for w in windows for _, starts, _, _ in w.found):
        raise ValueError('no window of trusted poses to fit a variance on')
    start = np.array([START_LOG_VARIANCE, 0.0, 0.0, 0.0,
                      START_LOG_REFERENCE if reference_noise else LOG_REFERENCE_BOUNDS[0]])
    bounds = [(None, None)] * 4 + [LOG_REFERENCE_BOUNDS if reference_noise
                                   else (LOG_REFERENCE_BOUNDS[0],) * 2]
    found = minimize(_nll, start, args=(windows,), jac=True, method='L-BFGS-B', bounds=bounds)
    reference = float(np.exp(found.x[-1])) if reference_noise else 0.0
    return Fit(GyroVariance(tuple(found.x[:-1]), mean_s, scales), reference)


def nees(spec: GyroVariance, windows: list[Windows], reference_var: float = 0.0
         ) -> dict[str, dict[str, float]]:
    """
    Return per window length the mean NEES and the share inside the 2-sigma ellipsoid.

    Each window's variance: the model's over it plus ``reference_var``, the reference's.
    """
    per: dict[float, list[np.ndarray]] = {}
    for w in windows:
        sums = np.r_[0.0, np.cumsum(np.exp(w.phi @ np.array(spec.theta)) * w.dt2)]
        for window_s, starts, length, err2 in w.found:
            per.setdefault(window_s, []).append(
                err2 / (sums[starts + length] - sums[starts] + reference_var))
    return {f'{k:g} s': {'mean': float(np.concatenate(v).mean()),
                         'in_2_sigma': float((np.concatenate(v) < 4.0).mean()),
                         'windows': int(sum(map(len, v)))} for k, v in sorted(per.items())}


def fit_model(model_spec: str, data: str | None = None, progress: bool = True,
              mean_s: float = 0.1, scales: tuple[float, float, float] = (0.1, 0.5, 1.0)
              ) -> dict[str, Any]:
    """
    :func:`fit` on the validation tails of a model's training recordings; a report.

    The corrected gyro as the node computes it over each whole recording (the tail's
    context), its features over the same run. Beside the NEES of the tails fitted on,
    each recording's under the fit on the others' (``held_out``): the network saw every
    recording's head, the variance's fit not that tail.
    """
    net = load_model(model_spec)
    names, start, seqs = training_recordings(net, data, 'fit a variance')
    rate = sample_rate(net)
    shape = GyroVariance((0.0, 0.0, 0.0, 0.0), mean_s, scales)
    windows = []
    for name, seq in zip(names, seqs):
        stream = net.correct(seq.stream)
        phi = seq.on_poses(features(stream, seq.stream[:, 3:], rate, shape))
        windows.append(Windows.of(seq, seq.on_poses(stream), phi, start))
        if progress:
            print(f'tail of {name}: {sum(len(s) for _, s, _, _ in windows[-1].found)} windows',
                  flush=True)
    found = fit(windows, mean_s, scales)
    return {'gyro_variance': {
        **found.variance.as_dict(),
        'fitted_on': f'rotation increments over {", ".join(f"{w:g}" for w in WINDOWS_S)} s '
                     f'of the validation tails of {", ".join(names)} (from sample {start} on)',
        'reference_noise_deg': math.degrees(math.sqrt(found.reference_var)),
        'nees': nees(found.variance, windows, found.reference_var),
        'held_out': _held_out(names, windows, mean_s, scales)}}


def _held_out(names: list[str], windows: list[Windows], mean_s: float,
              scales: tuple[float, float, float]) -> dict[str, dict[str, dict[str, float]]]:
    """Return each recording's NEES under the fit on the other recordings' tails."""
    held = {}
    for k, name in enumerate(names):
        others = [w for j, w in enumerate(windows) if j != k]
        if not any(len(starts) for w in others for _, starts, _, _ in w.found):
            continue
        found = fit(others, mean_s, scales)
        held[name] = nees(found.variance, [windows[k]], found.reference_var)
    return held
