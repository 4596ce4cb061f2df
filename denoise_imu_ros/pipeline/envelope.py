# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Where a model's correction is trusted: within the motion its training recordings had.

A network extrapolates beyond the motion it was trained on (BROAD: networks of a slow
power-on session, at most 325 deg/s, add 1-20° on another session's trials at 600-1450
deg/s). Training stores the envelope of its input (:func:`measure`; the model file's
``input_envelope``: the largest gyro norm and the largest distance of the accelerometer
norm from gravity). Wherever a sample of the receptive field since the last reset lies
outside it, the output is the model's input gyro plus a constant (the model's mean
correction over its training recordings, or nothing where the turn-on bias is removed
before the model: its input is then the gyro less that bias), less the tracked bias where
the output's bias is tracked: what the classical pipeline gives, not the model's guess.
It comes after the output's bias tracking (and before the drop of a heading-less model's
correction about the vertical), whose tracker is fed the model's output throughout; the
bias removed through a stretch where the receptive field turned faster than the
envelope is the one from before it, and after it the tracker's estimate and covariance
are restored to those from before it: a network's output beyond the rates it was trained
on is off by more than a bias, and a tracker that kept what it learnt there carried the
error on (BROAD's fast trials 07 and 29). Where the classical pipeline's output is given
beyond the sustained bound (the blend's fallback, ``hold_beyond``), the same hold there:
where a sample of the receptive field has a mean | |accel| - g | over SUSTAINED_S above
the model file's bound (:func:`beyond`: acceleration longer and harder than any training
recording's), the network's tracker otherwise learns a bias that the stretches between
the bursts carry (another session's fast translation, run 36); where the output there is
the model's own, its tracker follows it. Accelerometer excursions alone (tapping) do not
hold it. Measured worse (docs/experiments.md): holding the last correction (a
correction taken in motion carries that motion's scale terms into faster motion),
guarding before the tracking (its estimate then follows the fallback through fast
motion), holding the estimate wherever the guard is (what it learns through tapping is
then discarded), and feeding the tracker the fallback through the held stretches.
Every path uses it identically (:func:`too_fast`, :func:`beyond` and :func:`guard_batch`
over arrays for ``eval``, ``correct`` and ``crossval``; :class:`Guard` per sample for the
node and ``process-bag``; equal bit for bit), in the order of
:data:`~denoise_imu_ros.pipeline.stages.STAGES`. The node's ``envelope_guard``
parameter (``correct``'s and ``process-bag``'s option) turns it off, and the envelope's
hold with it: the model's output everywhere, tracked throughout but where it turns faster
than the tracking's own ``hold_above_deg_s`` (:func:`resolve`).
"""

from __future__ import annotations

import math
from typing import Any, Iterable

import numpy as np

from ..core.limits import GRAVITY_M_S2
from ..core.schema import InputEnvelope

__all__ = ['beyond', 'CHOICES', 'combine', 'excursion', 'Guard', 'guard_batch', 'measure',
           'outside', 'resolve', 'Sustained', 'sustained', 'sustained_bound', 'SUSTAINED_S',
           'too_fast', 'untrusted', 'within_field']

CHOICES = ('model', 'off')  # the node's envelope_guard parameter, the offline tools' option
SUSTAINED_S = 1.0  # the accelerometer's excursion from gravity averaged over this long


def excursion(imu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return per sample of (N, 6) the gyro norm (rad/s) and |accelerometer norm - g| (m/s^2).

    Summed in the order :meth:`Guard.check` sums one sample's, so both agree bit for bit.
    """
    x, y, z, ax, ay, az = imu.T
    return (np.sqrt(x * x + y * y + z * z),
            np.abs(np.sqrt(ax * ax + ay * ay + az * az) - GRAVITY_M_S2))


def sustained(imu: np.ndarray, window: int) -> np.ndarray:
    """
    Return per sample of (N, 6) the causal mean of |accelerometer norm - g| over ``window``.

    Over the samples since the first where fewer; summed as :class:`Sustained` sums them,
    so both agree bit for bit.
    """
    total = np.concatenate([[0.0], np.cumsum(excursion(imu)[1])])
    n = np.arange(len(imu))
    start = np.maximum(n + 1 - window, 0)
    return (total[n + 1] - total[start]) / (n + 1 - start)


def _window(rate_hz: float) -> int:
    """Return SUSTAINED_S in samples at ``rate_hz``."""
    return max(1, round(SUSTAINED_S * rate_hz))


class Sustained:
    """:func:`sustained` one sample at a time."""

    def __init__(self, window: int) -> None:
        self.window = window
        self.reset()

    def reset(self) -> None:
        """Forget the past: another run."""
        self._totals = [0.0] * self.window  # the running sum at the last window samples
        self._total, self._n = 0.0, 0

    def update(self, accel: np.ndarray) -> float:
        """Take one accelerometer sample (3,); return the mean excursion up to it."""
        ax, ay, az = accel.tolist()
        before = self._totals[self._n % self.window] if self._n >= self.window else 0.0
        self._total += abs(math.sqrt(ax * ax + ay * ay + az * az) - GRAVITY_M_S2)
        self._totals[self._n % self.window] = self._total
        self._n += 1
        return (self._total - before) / min(self._n, self.window)


def sustained_bound(imus: Iterable[np.ndarray], rate_hz: float) -> float:
    """
    Return the largest :func:`sustained` excursion (over SUSTAINED_S) of whole recordings.

    Beyond it a recording accelerates for longer than any training recording did (BROAD:
    another session's fast translation), where a network's output lost to the classical
    pipeline's (docs/experiments.md, runs 24 and 26).
    """
    return float(max(sustained(imu, _window(rate_hz)).max() for imu in imus))


def measure(imus: Iterable[np.ndarray], corrections: Iterable[np.ndarray] | None = None,
            sustained_m_s2: float | None = None) -> InputEnvelope:
    """
    Return the envelope of every sample of ``imus`` (each (N, 6), as the model is fed).

    ``corrections``: the model's output less its input gyro on the same samples, whose
    mean is the fallback; None: no fallback correction (a turn-on bias removed first).
    ``sustained_m_s2``: the recordings' :func:`sustained_bound`, stored with the bounds.
    """
    gyro, accel = zip(*(excursion(imu) for imu in imus))
    fallback = (0.0, 0.0, 0.0) if corrections is None else tuple(
        float(v) for v in np.concatenate(list(corrections)).mean(0))
    return InputEnvelope(float(np.max(np.concatenate(gyro))),
                         float(np.max(np.concatenate(accel))), fallback, sustained_m_s2)


def combine(envelopes: list[InputEnvelope | None]) -> InputEnvelope | None:
    """
    Return the envelope of an ensemble of these models (None if one has none).

    The widest bounds, and the mean fallback: the members' mean corrections averaged, as
    their outputs are (no sustained bound where a member has none).
    """
    if not envelopes or any(e is None for e in envelopes):
        return None
    held = [e.sustained_accel_m_s2 for e in envelopes]
    return InputEnvelope(max(e.gyro_rad_s for e in envelopes),
                         max(e.accel_offset_m_s2 for e in envelopes),
                         tuple(np.mean([e.fallback_rad_s for e in envelopes], axis=0)),
                         None if None in held else max(held))


def outside(imu: np.ndarray, envelope: InputEnvelope) -> np.ndarray:
    """Whether each sample of (N, 6) lies outside ``envelope`` (N,)."""
    gyro, accel = excursion(imu)
    return (gyro > envelope.gyro_rad_s) | (accel > envelope.accel_offset_m_s2)


def within_field(bad: np.ndarray, field: int) -> np.ndarray:
    """Whether any of samples n - field + 1 ... n is ``bad`` (N,), for each n (N,)."""
    count = np.concatenate([[0], np.cumsum(bad)])
    n = np.arange(len(bad))
    return count[n + 1] > count[np.maximum(n + 1 - field, 0)]


def untrusted(fed: np.ndarray, envelope: InputEnvelope, field: int) -> np.ndarray:
    """Whether any of samples n - field + 1 ... n of (N, 6) is outside, for each n (N,)."""
    return within_field(outside(fed, envelope), field)


def too_fast(fed: np.ndarray, envelope: InputEnvelope, field: int) -> np.ndarray:
    """Whether any of samples n - field + 1 ... n of (N, 6) turns faster, for each n (N,)."""
    return within_field(excursion(fed)[0] > envelope.gyro_rad_s, field)


def beyond(fed: np.ndarray, envelope: InputEnvelope, field: int, rate_hz: float
           ) -> np.ndarray:
    """
    Whether a sample of n - field + 1 ... n of (N, 6) accelerates beyond the sustained bound.

    All False where the envelope has none.
    """
    if envelope.sustained_accel_m_s2 is None:
        return np.zeros(len(fed), bool)
    return within_field(sustained(fed, _window(rate_hz)) > envelope.sustained_accel_m_s2, field)


def guard_batch(output: np.ndarray, fed: np.ndarray, envelope: InputEnvelope | None,
                field: int, bias: np.ndarray | None = None) -> np.ndarray:
    """
    Return a model's ``output`` (N, 3) guarded for its input ``fed`` (N, 6), one run.

    An :func:`untrusted` sample gets its input gyro plus the envelope's fallback
    correction, less the tracked ``bias`` (N, 3) where the output's is tracked: what the
    tracker gives, not the model's guess.
    """
    if envelope is None:
        return output
    mask = untrusted(fed, envelope, field)
    if not mask.any():
        return output
    fallback = fed[:, :3] + np.array(envelope.fallback_rad_s)
    return np.where(mask[:, None], fallback if bias is None else fallback - bias, output)


def resolve(meta: Any, choice: str) -> InputEnvelope | None:
    """Return the envelope to guard with: the model file's for ``model``, None for ``off``."""
    if choice not in CHOICES:
        raise ValueError(f'envelope guard {choice!r}: one of {", ".join(CHOICES)}')
    return meta.input_envelope if choice == 'model' else None


class Guard:
    """
    :func:`guard_batch`, :func:`too_fast`, :func:`beyond` per sample (node, process-bag).

    :meth:`check` each input first (the tracker reads :attr:`hold` before the output is
    guarded), then :meth:`apply` to the output.
    """

    def __init__(self, envelope: InputEnvelope, field: int, rate_hz: float,
                 hold_beyond: bool = False) -> None:
        self.envelope, self.field, self.hold_beyond = envelope, field, hold_beyond
        self._fallback = np.array(envelope.fallback_rad_s)
        self._bound = envelope.sustained_accel_m_s2
        self.sustained = Sustained(_window(rate_hz))
        self.reset()
        self.guarded = 0  # samples guarded since start, for diagnostics

    def reset(self) -> None:
        """Forget the past: a new stream, or the network's history restarted."""
        self._since_outside = self._since_fast = self._since_beyond = self.field
        self.trusted, self.too_fast, self.beyond = True, False, False
        self.sustained.reset()

    @property
    def hold(self) -> bool:
        """Whether the output's tracker holds here: too fast, or beyond where that holds it."""
        return self.too_fast or (self.hold_beyond and self.beyond)

    def check(self, fed: np.ndarray) -> None:
        """Take the model's input ``fed`` (6,): set :attr:`trusted`, ``too_fast``, ``beyond``."""
        x, y, z, ax, ay, az = fed.tolist()
        fast = math.sqrt(x * x + y * y + z * z) > self.envelope.gyro_rad_s
        self._since_fast = 0 if fast else self._since_fast + 1
        if fast or (abs(math.sqrt(ax * ax + ay * ay + az * az) - GRAVITY_M_S2)
                    > self.envelope.accel_offset_m_s2):
            self._since_outside = 0
        else:
            self._since_outside += 1
        self.trusted = self._since_outside >= self.field
        self.too_fast = self._since_fast < self.field
        if self._bound is not None:
            over = self.sustained.update(fed[3:]) > self._bound
            self._since_beyond = 0 if over else self._since_beyond + 1
            self.beyond = self._since_beyond < self.field

    def apply(self, output: np.ndarray, fed: np.ndarray,
              bias: np.ndarray | None = None) -> np.ndarray:
        """Return the model's ``output`` (3,) guarded, for the input :meth:`check` took."""
        if self.trusted:
            return output
        self.guarded += 1
        return fed[:3] + self._fallback if bias is None else fed[:3] + self._fallback - bias
