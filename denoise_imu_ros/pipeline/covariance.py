# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The corrected IMU's variance per sample: what a VIO back-end weighs ``imu/corrected`` by.

A model file's :class:`~denoise_imu_ros.core.schema.SampleVariance` gives each sample's
gyro variance, the same on each axis, as exp(theta . phi): phi is 1 and three causal means
over the last ``mean_s`` seconds (since the last reset) of the output rate's norm, of the
accelerometer norm's distance from gravity and of the output rate's change per second,
each log1p-scaled; its accelerometer variance, where it has one, the same features with a
theta of its own. The error of a corrected IMU grows with how fast and how hard it
moves; one constant would be too large at rest and too small in fast motion. The means
restart with the network's history (a start, a gap, a clock jump).

Every path computes it alike: :func:`variances` over a recording's arrays (``eval``,
``tune-fusion``, the benches; the pipeline's batch form takes :func:`features` once for
both sensors, then :func:`from_features`), :class:`Variance` one sample at a time (node,
``process-bag``); equal to rounding (running sums against cumulative ones).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.limits import GRAVITY_M_S2
from ..core.schema import SampleVariance

__all__ = ['features', 'from_features', 'MAX_LOG_VARIANCE', 'Variance', 'variances']

MAX_LOG_VARIANCE = 50.0  # exp(theta . phi) capped here: glitched input gives a huge, finite one


def features(gyro: np.ndarray, accel: np.ndarray, rate_hz: float, spec: SampleVariance,
             restarts: np.ndarray | None = None) -> np.ndarray:
    """
    Return phi (N, 4) of every sample of one or more runs.

    ``gyro`` the output rate (N, 3), ``accel`` the accelerometer (N, 3); ``restarts``
    (N,) True where a run starts again (the first sample always does).
    """
    n = len(gyro)
    starts = np.zeros(n, bool) if restarts is None else np.asarray(restarts, bool).copy()
    starts[:1] = True
    change = np.zeros(n)
    change[1:] = np.linalg.norm(np.diff(gyro, axis=0), axis=1) * rate_hz
    change[starts] = 0.0  # no rate before a run's first sample
    raw = np.stack([np.linalg.norm(gyro, axis=1),
                    np.abs(np.linalg.norm(accel, axis=1) - GRAVITY_M_S2), change], axis=1)
    width = _width(spec, rate_hz)
    run_start = np.maximum.accumulate(np.where(starts, np.arange(n), 0))
    first = np.maximum(np.arange(n) + 1 - width, run_start)  # the mean's first sample
    total = np.vstack([np.zeros((1, 3)), np.cumsum(raw, axis=0)])
    mean = (total[1:] - total[first]) / (np.arange(n) + 1 - first)[:, None]
    return np.hstack([np.ones((n, 1)), np.log1p(mean / np.array(spec.scales))])


def variances(gyro: np.ndarray, accel: np.ndarray, rate_hz: float, spec: SampleVariance,
              restarts: np.ndarray | None = None) -> np.ndarray:
    """Return each sample's variance (N,), (rad/s)^2 or (m/s^2)^2, over the runs as given."""
    return from_features(features(gyro, accel, rate_hz, spec, restarts), spec)


def from_features(phi: np.ndarray, spec: SampleVariance) -> np.ndarray:
    """Return exp(theta . phi) of features (N, 4), capped at MAX_LOG_VARIANCE."""
    return np.exp(np.minimum(phi @ np.array(spec.theta), MAX_LOG_VARIANCE))


def _width(spec: SampleVariance, rate_hz: float) -> int:
    """Return the samples of the means' window."""
    return max(1, int(round(spec.mean_s * rate_hz)))


class Variance:
    """
    :func:`variances` one sample at a time: running sums over a ring of samples.

    The gyro's, and the accelerometer's where ``accel`` is given (on the same features:
    its ``mean_s`` and ``scales`` are the gyro's). On plain floats: numpy's calls on three
    numbers cost several times this work.
    """

    def __init__(self, spec: SampleVariance, rate_hz: float,
                 accel: SampleVariance | None = None) -> None:
        if accel is not None and (accel.mean_s, accel.scales) != (spec.mean_s, spec.scales):
            raise ValueError("the accelerometer's variance model is not on the gyro's features")
        self.spec, self.rate_hz = spec, rate_hz
        self._width = _width(spec, rate_hz)
        self._thetas = (tuple(spec.theta),) + (() if accel is None else (tuple(accel.theta),))
        self._scales = tuple(spec.scales)
        self.reset()

    def reset(self) -> None:
        """Start the means again: the next sample is a run's first."""
        self._ring = [(0.0, 0.0, 0.0)] * self._width
        self._sums = [0.0, 0.0, 0.0]
        self._count = self._next = 0
        self._last: tuple[float, float, float] | None = None

    def update(self, gyro: np.ndarray, accel: np.ndarray) -> tuple[float, float | None]:
        """
        Take one output rate and its accelerometer; return the sample's variances.

        The gyro's, then the accelerometer's (None without its model).
        """
        gx, gy, gz = (float(v) for v in gyro)
        ax, ay, az = (float(v) for v in accel)
        if self._last is None:
            change = 0.0
        else:
            lx, ly, lz = self._last
            change = math.sqrt((gx - lx) ** 2 + (gy - ly) ** 2 + (gz - lz) ** 2) * self.rate_hz
        self._last = (gx, gy, gz)
        raw = (math.sqrt(gx * gx + gy * gy + gz * gz),
               abs(math.sqrt(ax * ax + ay * ay + az * az) - GRAVITY_M_S2), change)
        old = self._ring[self._next]
        sums = self._sums
        for i in range(3):
            sums[i] += raw[i] - old[i]
        self._ring[self._next] = raw
        self._next = (self._next + 1) % self._width
        self._count = min(self._count + 1, self._width)
        count = self._count
        phi = [math.log1p(m / count / c) for m, c in zip(sums, self._scales)]
        found = [math.exp(min(theta[0] + sum(t * f for t, f in zip(theta[1:], phi)),
                              MAX_LOG_VARIANCE)) for theta in self._thetas]
        return found[0], found[1] if len(found) > 1 else None
