# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Gravity-aided orientation: the corrected gyro and the accelerometer through VQF.

VQF (Laidig & Seel 2023, the ``vqf`` package, C++ core) is a standard 6-D filter: the
gyro carries the orientation, the low-passed accelerometer pulls its tilt back towards
gravity with the time constant ``tau_acc_s``. Its own gyro-bias estimators are off by
default: the network has already removed the bias it can see, and a second estimator
chasing the same error makes the result worse (docs/results.md). The accelerometer's own
constant bias, fitted on the training recordings' poses (``tune-fusion``), is removed
before the filter sees it: a bias b tilts the estimated vertical by about |b| / g, which
the filter cannot average away (0.7 deg for EuRoC's ADIS16448).

With ``classical_tilt`` a second VQF runs at its defaults (its own bias estimation on) on
the raw gyro and accelerometer, what a user runs with no model, and the orientation takes
its roll and pitch with this filter's heading (:func:`~denoise_imu_ros.core.rotation.
with_tilt_of`): where the corrected gyro's filter tilts worse than the classical one on
recordings of another power-on (``crossval --sessions`` chooses it), the tilt is that one's.

Time convention, as imu_tools' (imu_filter_madgwick, VQF, every filter a user would
swap in): the orientation published at stamp k includes sample k's rate. At sample k the
filter integrates the interval from stamp k - 1 to stamp k at the mean of samples k - 1
and k (:func:`interval_rates`: a sample is the rate at its stamp, the midpoint rule of
VIO pre-integrators), then corrects with sample k's accelerometer. Measured against
sample k alone over that interval, on poses moved onto the IMU's clock: lower tilt error
on EuRoC's, TUM-VI's and BROAD's training recordings (docs/results.md). The paper's
open-loop AOE keeps its own convention, sample k driving stamp k to k + 1
(:mod:`denoise_imu_ros.core.metrics`).

VQF steps by one nominal period; the gyro is scaled by the real interval in periods, so
that a lost message does not take its rotation out of the yaw (as the open-loop attitude,
which integrates the real interval). Across a gap (the network restarts) and at the
first sample after a reset there is no gyro step: the yaw is held, as the attitude is,
and gravity keeps correcting the tilt.
:func:`fuse` (offline, one compiled batch) equals :meth:`GravityFilter.update` (online,
per sample) bit for bit.

Quaternions are xyzw, body (IMU) to an earth frame whose z axis points up. VQF's own
earth frame starts at a heading of its choosing (the shortest rotation onto the first
accelerometer reading); the output is turned about z so that the first orientation has
yaw 0 as ``imu/attitude``'s (Rz(0) Ry(pitch) Rx(roll)): both topics start in one frame.
"""

from __future__ import annotations

import numpy as np
from vqf import VQF

from ..core.limits import MAX_GAP_FACTOR
from ..core.rotation import hamilton, level_heading, Quat, with_tilt_of
from ..core.schema import FusionSettings, ModelMeta


VQF_OWN_DEFAULTS = FusionSettings(3.0, True)  # the vqf package's: tau 3 s, bias estimation on


def _vqf(rate_hz: float, settings: FusionSettings) -> VQF:
    return VQF(1.0 / rate_hz, tauAcc=float(settings.tau_acc_s),
               motionBiasEstEnabled=settings.bias_estimation,
               restBiasEstEnabled=settings.bias_estimation, magDistRejectionEnabled=False)


_XYZW = np.array([1, 2, 3, 0])  # VQF's wxyz to the package's xyzw


def _xyzw(wxyz: np.ndarray) -> np.ndarray:
    return wxyz.take(_XYZW, axis=-1)


class GravityFilter:
    """One sample at a time (the node, process-bag); see the module docstring."""

    def __init__(self, rate_hz: float, settings: FusionSettings = FusionSettings()) -> None:
        self.settings = settings
        self._vqf = _vqf(rate_hz, settings)
        self._accel_bias = np.array(settings.accel_bias_m_s2)
        # preallocated: this runs on every IMU message
        self._step, self._accel, self._last = np.empty(3), np.empty(3), np.zeros(3)
        self._heading: Quat | None = None  # the turn to yaw 0, set by the first sample
        self._classical = _vqf(rate_hz, VQF_OWN_DEFAULTS) if settings.classical_tilt else None
        self._raw_step, self._raw_last = np.empty(3), np.zeros(3)

    def reset(self) -> None:
        """Start again: the next sample's accelerometer sets the tilt, yaw 0."""
        self._vqf.resetState()
        if self._classical is not None:
            self._classical.resetState()
        self._heading = None

    def update(self, gyro: np.ndarray, accel: np.ndarray, periods: float = 1.0,
               raw: np.ndarray | None = None) -> np.ndarray:
        """
        Orientation (4,) xyzw at this sample's stamp, this sample's ``gyro`` included.

        ``periods``: the interval since the last sample, in nominal periods (no step at
        the first sample since a reset). ``raw``: the gyro as received (the classical
        tilt's; ``accel`` is as received).
        """
        scale = 0.5 * periods if self._heading is not None else 0.0
        np.subtract(accel, self._accel_bias, out=self._accel)
        np.add(self._last, gyro, out=self._step)  # the interval's rate: its two ends' mean
        self._step *= scale
        self._last[:] = gyro
        self._vqf.update(self._step, self._accel)
        w, x, y, z = self._vqf.getQuat6D().tolist()  # floats: numpy on four costs more
        q = (x, y, z, w)
        if self._classical is not None:
            if raw is None:
                raise ValueError('the classical tilt needs the raw gyro')
            np.add(self._raw_last, raw, out=self._raw_step)
            self._raw_step *= scale
            self._raw_last[:] = raw
            self._classical.update(self._raw_step, np.asarray(accel, dtype=np.float64))
            cw, cx, cy, cz = self._classical.getQuat6D().tolist()
            q = with_tilt_of(q, (cx, cy, cz, cw))
        if self._heading is None:
            self._heading = level_heading(q)
        return np.array(hamilton(self._heading, q))


def interval_rates(gyro: np.ndarray) -> np.ndarray:
    """Return each interval's rate (N, 3) to a stamp: its two samples' mean; 0 to the first."""
    rates = np.zeros((len(gyro), 3))
    np.add(gyro[:-1], gyro[1:], out=rates[1:])
    rates[1:] *= 0.5
    return rates


def step_periods(stamp_ns: np.ndarray, rate_hz: float,
                 max_gap_factor: float = MAX_GAP_FACTOR) -> np.ndarray:
    """
    Each interval to a stamp in nominal periods, as the online pipeline passes them.

    0 across a gap (more than ``max_gap_factor`` periods: no gyro step) and for the first
    stamp (nothing before it).
    """
    periods = np.zeros(len(stamp_ns))
    periods[1:] = np.diff(np.asarray(stamp_ns, dtype=np.int64)) * 1e-9 * rate_hz
    periods[periods > max_gap_factor] = 0.0
    return periods


def fuse(gyro: np.ndarray, accel: np.ndarray, rate_hz: float,
         settings: FusionSettings = FusionSettings(),
         periods: np.ndarray | None = None, raw: np.ndarray | None = None) -> np.ndarray:
    """
    Orientation (N, 4) xyzw at every stamp of (N, 3) gyro and accelerometer samples.

    ``periods`` (N,): each interval to a stamp in nominal periods (:func:`step_periods`);
    None: every interval one period. ``raw`` (N, 3): the gyro as received, for the
    classical tilt (``accel`` as received).
    """
    def batch(rates: np.ndarray, flt: FusionSettings) -> np.ndarray:
        step = interval_rates(np.asarray(rates, dtype=np.float64))
        if periods is not None:
            step *= np.asarray(periods, dtype=np.float64)[:, None]
        return _xyzw(_vqf(rate_hz, flt).updateBatch(
            np.ascontiguousarray(step),
            np.asarray(accel, dtype=np.float64) - np.array(flt.accel_bias_m_s2))['quat6D'])
    out = batch(gyro, settings)
    if settings.classical_tilt:
        if raw is None:
            raise ValueError('the classical tilt needs the raw gyro')
        tilts = batch(raw, VQF_OWN_DEFAULTS)  # composed as update's, sample by sample
        out = np.array([with_tilt_of(tuple(h), tuple(t))
                        for h, t in zip(out.tolist(), tilts.tolist())]).reshape(-1, 4)
    if not len(out):
        return out
    return np.stack(hamilton(level_heading(out[0]), out.T), axis=-1)  # as update's, on arrays


DEFAULT_ORIENTATION_STD_RAD = 0.05  # used when a model file stores no fused-error figures


def orientation_covariance(meta: ModelMeta, stddev: float = -1.0) -> list[float]:
    """
    Row-major 3x3 orientation_covariance of the fused orientation (``imu/data``).

    Diagonal, from ``stddev`` (rad) when >= 0, else from the per-axis RMS errors of the
    fused orientation the model file stores (measured where its settings were chosen),
    else DEFAULT_ORIENTATION_STD_RAD.
    """
    std = meta.fusion.orientation_std_rad
    if stddev >= 0 or std is None:
        std = [stddev if stddev >= 0 else DEFAULT_ORIENTATION_STD_RAD] * 3
    return [float(std[i]) ** 2 if i == j else 0.0 for i in range(3) for j in range(3)]
