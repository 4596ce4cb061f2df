# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The corrected IMU's per-sample variances fitted by a proper scoring rule (``fit-variance``).

A VIO back-end pre-integrates the IMU between keyframes 0.1-2 s apart and weighs the
increments by the covariance the messages' ``angular_velocity_covariance`` and
``linear_acceleration_covariance`` give: the rotation's is the sum of its samples' gyro
variances times dt^2, the velocity's that of their accelerometer variances, their errors
taken as white. Each model (:class:`~denoise_imu_ros.core.schema.SampleVariance`,
computed by :mod:`~denoise_imu_ros.pipeline.covariance`) is fitted by the Gaussian
negative log-likelihood of the increments' errors over WINDOWS_S windows, half-overlapping,
of the training recordings' validation tails (what the network did not train on), each
window length weighing alike: a VIO's keyframes may be any of them apart, and weighed per
window the short ones, twenty times as many, decide the fit (docs/experiments.md). The
gyro's on the rotation increments (the angle of dR_pose^T dR_gyro), the accelerometer's on
the velocity increments (pre-integrated from the poses' state, against their velocities:
a state estimate's where the recording has one and its poses are read as written, else the
positions' derivative), the accelerometer as ``imu/corrected`` carries it (and stored with
the bias it was less: the node publishes it on that accelerometer only). Each window's
error also holds the poses' own noise at its two ends, the same whatever the window's
length where the IMU's grows with it: the fit takes one such variance of the reference
beside the model's (``reference_noise_deg``: EuRoC's motion capture shows none at these
lengths, TUM-VI's some 0.2 deg per axis; ``reference_noise_m_s`` for the velocities), and
leaves it out of what ``imu/corrected`` publishes. The NEES of each window, that noise
counted (3 where the variance describes the error; 73.9 % of windows inside the 2-sigma
ellipsoid then), says how well it does. The velocity's error left by the gyro's (the
specific force turned by the rotation's error) is counted in the accelerometer's.
"""

from __future__ import annotations

from dataclasses import replace
import math
from pathlib import Path
from typing import Any, Callable, NamedTuple

import numpy as np
from scipy.optimize import minimize

from .filters import training_recordings
from .preintegration import (ground_truth_velocity, preintegrate, reference,
                             velocity_from_positions, window_starts)
from ..core.metrics import block_errors, integrate
from ..core.modelfile import sample_rate
from ..core.records import Sequence
from ..core.schema import SampleVariance
from ..learn.checkpoint import load_model
from ..pipeline.covariance import features, from_features
from ..runtime.settings import Settings

__all__ = ['Fit', 'fit', 'fit_model', 'nees', 'Windows', 'WINDOWS_S']

WINDOWS_S = (0.1, 0.2, 0.5, 1.0, 2.0)  # the keyframe spacings a VIO pre-integrates over
START_LOG_VARIANCE = -9.0               # the fit's start: 0.011 rad/s or m/s^2, any axis
START_LOG_REFERENCE = -14.0             # and the reference's noise: 0.05 deg (or 0.9 mm/s)
LOG_REFERENCE_BOUNDS = (-60.0, 0.0)     # from none at all to 1 rad (or 1 m/s) per axis


class Windows(NamedTuple):
    """One recording's windows: its samples' features and dt^2, the windows' errors."""

    phi: np.ndarray           # (N, 4) the samples' features
    dt2: np.ndarray           # (N,) each sample's interval, squared
    found: list[tuple[float, np.ndarray, int, np.ndarray]]  # window s, starts, length, err^2

    @classmethod
    def of(cls, seq: Sequence, gyro: np.ndarray, phi: np.ndarray, start: int = 0) -> Windows:
        """Return the rotation windows of ``seq`` from sample ``start`` on, poses trusted."""
        dt = np.diff((seq.stamp_ns - seq.stamp_ns[0]) * 1e-9)
        attitude = integrate(np.array([0.0, 0.0, 0.0, 1.0]), gyro[:-1], dt)
        found = [(window_s, starts, length,
                  np.sum(block_errors(seq.gt_quat, starts, starts + length, attitude) ** 2,
                         axis=1)) for window_s, starts, length in _spans(seq, start)]
        return cls(phi, np.r_[dt, 0.0] ** 2, found)

    @classmethod
    def velocity(cls, seq: Sequence, gyro: np.ndarray, accel: np.ndarray,
                 velocity: np.ndarray, phi: np.ndarray, start: int = 0) -> Windows:
        """Return the same windows' velocity increments' errors (``velocity``: the poses')."""
        stamp_s = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
        found = [(window_s, starts, length, np.sum((
            preintegrate(gyro, accel, stamp_s, starts, length).velocity
            - reference(seq.gt_quat, seq.gt_pos, velocity, stamp_s, starts, length).velocity
        ) ** 2, axis=1)) for window_s, starts, length in _spans(seq, start)]
        return cls(phi, np.r_[np.diff(stamp_s), 0.0] ** 2, found)


def _spans(seq: Sequence, start: int) -> list[tuple[float, np.ndarray, int]]:
    """Return per window length its half-overlapping starts from ``start`` on, poses trusted."""
    valid = seq.gt_valid.copy()
    valid[:start] = False
    found = []
    for window_s in WINDOWS_S:
        length = max(1, int(round(window_s * seq.rate_hz)))
        starts = window_starts(valid, length, max(1, length // 2))
        if len(starts):
            found.append((window_s, starts, length))
    return found


class Fit(NamedTuple):
    """The variance model, and the reference's own noise the same windows show."""

    variance: SampleVariance
    reference_var: float  # per axis (rad^2, (m/s)^2): the poses' noise in every window


def _nll(params: np.ndarray, windows: list[Windows], lengths_alike: bool = True
         ) -> tuple[float, np.ndarray]:
    """
    Return the windows' mean 3-D Gaussian negative log-likelihood and its gradient.

    ``params``: theta, then the log of the reference's variance per window (per axis).
    ``lengths_alike``: the mean of each window length's mean, else of every window (where
    the short windows, many more, outweigh the long ones).
    """
    theta, reference = params[:-1], float(np.exp(params[-1]))
    totals: dict[float, list[Any]] = {}
    for w in windows:
        v = np.exp(w.phi @ theta) * w.dt2
        sums = np.vstack([np.zeros((1, len(theta) + 1)),
                          np.cumsum(np.hstack([v[:, None], v[:, None] * w.phi]), axis=0)])
        for window_s, starts, length, err2 in w.found:
            inside = sums[starts + length] - sums[starts]
            s, ds = inside[:, 0] + reference, inside[:, 1:]
            slope = 1.5 / s - 0.5 * err2 / s ** 2
            grad = np.r_[(slope[:, None] * ds).sum(0), float(slope.sum()) * reference]
            found = totals.setdefault(window_s if lengths_alike else 0.0, [0.0, 0.0, 0])
            found[0] += float(np.sum(0.5 * err2 / s + 1.5 * np.log(s)))
            found[1] += grad
            found[2] += len(s)
    return (sum(t / n for t, _, n in totals.values()) / len(totals),
            sum(g / n for _, g, n in totals.values()) / len(totals))


def fit(windows: list[Windows], mean_s: float = 0.1,
        scales: tuple[float, float, float] = (0.1, 0.5, 1.0), reference_noise: bool = True,
        lengths_alike: bool = True) -> Fit:
    """
    Return the variance model of least negative log-likelihood over the windows.

    With ``reference_noise`` the reference's own variance per window is fitted beside it
    (else taken as none); with ``lengths_alike`` each window length weighs alike (else
    each window: :func:`_nll`).
    """
    if not any(len(starts) for w in windows for _, starts, _, _ in w.found):
        raise ValueError('no window of trusted poses to fit a variance on')
    start = np.array([START_LOG_VARIANCE, 0.0, 0.0, 0.0,
                      START_LOG_REFERENCE if reference_noise else LOG_REFERENCE_BOUNDS[0]])
    bounds = [(None, None)] * 4 + [LOG_REFERENCE_BOUNDS if reference_noise
                                   else (LOG_REFERENCE_BOUNDS[0],) * 2]
    found = minimize(_nll, start, args=(windows, lengths_alike), jac=True, method='L-BFGS-B',
                     bounds=bounds)
    reference = float(np.exp(found.x[-1])) if reference_noise else 0.0
    return Fit(SampleVariance(tuple(found.x[:-1]), mean_s, scales), reference)


def nees(spec: SampleVariance, windows: list[Windows], reference_var: float = 0.0
         ) -> dict[str, dict[str, float]]:
    """
    Return per window length the mean NEES and the share inside the 2-sigma ellipsoid.

    Each window's variance: the model's over it plus ``reference_var``, the reference's.
    """
    per: dict[float, list[np.ndarray]] = {}
    for w in windows:
        sums = np.r_[0.0, np.cumsum(from_features(w.phi, spec) * w.dt2)]  # as published
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
    context), its features over the same run; the accelerometer less the bias the node
    removes from ``imu/corrected``'s at its default settings. Beside the NEES of the
    tails fitted on, each recording's under the fit on the others' (``held_out``): the
    network saw every recording's head, the variances' fit not that tail. The
    accelerometer's only where every recording's poses have positions.
    """
    net = load_model(model_spec)
    names, start, seqs = training_recordings(net, data, 'fit a variance')
    folder = Path(data or net.meta.data)
    rate = sample_rate(net)
    shape = SampleVariance((0.0, 0.0, 0.0, 0.0), mean_s, scales)
    bias = np.array(Settings().corrected_accel_bias(net))
    rotation, velocity = [], []
    for name, seq in zip(names, seqs):
        stream = net.correct(seq.stream)
        phi = seq.on_poses(features(stream, seq.stream[:, 3:], rate, shape))
        gyro = seq.on_poses(stream)
        rotation.append(Windows.of(seq, gyro, phi, start))
        if np.ptp(seq.gt_pos, axis=0).max() > 0:  # orientation-only poses: no velocity
            stamp_s = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
            truth = (ground_truth_velocity(folder / name, seq.stamp_ns, seq.gt_pos, stamp_s)[0]
                     if seq.pose_alignment is None  # a file's velocities, as its poses
                     else velocity_from_positions(seq.gt_pos, stamp_s))
            velocity.append(Windows.velocity(seq, gyro, seq.on_poses(seq.stream[:, 3:]) - bias,
                                             truth, phi, start))
        if progress:
            print(f'tail of {name}: {sum(len(s) for _, s, _, _ in rotation[-1].found)} windows',
                  flush=True)
    windows_s = ', '.join(f'{w:g}' for w in WINDOWS_S)
    where = f'of the validation tails of {", ".join(names)} (from sample {start} on)'
    report = {'gyro_variance': _report(
        rotation, names, mean_s, scales, f'rotation increments over {windows_s} s {where}',
        'reference_noise_deg', math.degrees)}
    if len(velocity) == len(names):
        report['accel_variance'] = _report(
            velocity, names, mean_s, scales, f'velocity increments over {windows_s} s {where}',
            'reference_noise_m_s', float, tuple(map(float, bias)))
    return report


def _report(windows: list[Windows], names: list[str], mean_s: float,
            scales: tuple[float, float, float], fitted_on: str, noise_key: str,
            unit: Callable[[float], float],
            accel_bias: tuple[float, float, float] | None = None) -> dict[str, Any]:
    """Return one sensor's fit, its NEES and its held-out NEES, as a model file stores it."""
    found = fit(windows, mean_s, scales)
    variance = replace(found.variance, accel_bias_m_s2=accel_bias)
    return {**variance.as_dict(), 'fitted_on': fitted_on,
            noise_key: unit(math.sqrt(found.reference_var)),
            'nees': nees(found.variance, windows, found.reference_var),
            'held_out': _held_out(names, windows, mean_s, scales)}


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
