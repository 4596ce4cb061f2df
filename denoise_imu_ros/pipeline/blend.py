# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The network's output blended with the classical pipeline's; the classical alone beyond training.

On a power-on it never saw, a network's output and the classical pipeline's (the gyro
less its turn-on bias, its bias tracked: the "tracker only" row, no model) err in part
independently: their weighted mean T + W (N - T) loses less often to T than N does, and
keeps part of N's gain where T's tracker diverges (BROAD's other session, run 26 of
docs/experiments.md). Where a sample of the receptive field has a mean | |accel| - g |
over the last SUSTAINED_S above the largest any training recording reached (the model
file's ``input_envelope.sustained_accel_m_s2``), the network is fed motion longer and
harder than it learnt (another session's fast translation) and the output is T alone.
``crossval`` chooses W on held-out recordings; the model file's ``blend`` stores it with
T's tracking. It comes after the envelope's guard (N is the guarded, tracked output),
reset with every run. :func:`blend_batch` over arrays and :class:`Blender` per sample
agree bit for bit.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from . import envelope, rest_bias
from ..core.limits import GRAVITY_M_S2
from ..core.schema import Blend, InputEnvelope

__all__ = ['blend_batch', 'Blender', 'CHOICES', 'resolve', 'Sustained']

CHOICES = ('model', 'off')  # the node's blend parameter, the offline tools' option


def resolve(meta: Any, choice: str) -> Blend | None:
    """Return the blend to run: the model file's for ``model``, None for ``off``."""
    if choice not in CHOICES:
        raise ValueError(f'blend {choice!r}: one of {", ".join(CHOICES)}')
    return meta.blend if choice == 'model' else None


def _window(rate_hz: float) -> int:
    return max(1, round(envelope.SUSTAINED_S * rate_hz))


def blend_batch(output: np.ndarray, fed: np.ndarray, rate_hz: float, blend: Blend,
                bounds: InputEnvelope | None, field: int) -> np.ndarray:
    """
    Return a network's finished ``output`` (N, 3) blended for its input ``fed`` (N, 6), one run.

    ``bounds``: the envelope whose sustained bound sends a sample to the classical
    pipeline alone (None, or none stored: the blend everywhere).
    """
    classical = rest_bias.track_bias(fed[:, :3], fed[:, 3:], rate_hz, blend.tracking)
    weight = np.full(len(output), blend.weight)
    held = None if bounds is None else bounds.sustained_accel_m_s2
    if held is not None:
        beyond = envelope.sustained(fed, _window(rate_hz)) > held
        weight[envelope.within_field(beyond, field)] = 0.0
    return classical + weight[:, None] * (output - classical)


class Sustained:
    """:func:`~denoise_imu_ros.pipeline.envelope.sustained` one sample at a time."""

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


class Blender:
    """:func:`blend_batch` one sample at a time (node, process-bag)."""

    def __init__(self, blend: Blend, rate_hz: float, bounds: InputEnvelope | None,
                 field: int) -> None:
        self.blend, self.rate_hz, self.bounds, self.field = blend, rate_hz, bounds, field
        self.held = None if bounds is None else bounds.sustained_accel_m_s2
        self.tracker = (None if blend.tracking is None
                        else rest_bias.BiasTracker(blend.tracking, rate_hz))
        self.sustained = Sustained(_window(rate_hz))
        self.classical_only = 0  # samples given the classical pipeline's alone, for diagnostics
        self.reset()

    def reset(self) -> None:
        """Start again: another run."""
        if self.tracker is not None:
            self.tracker.reset()
        self.sustained.reset()
        self._since_beyond = self.field  # none within the field

    def apply(self, output: np.ndarray, fed: np.ndarray) -> np.ndarray:
        """Return the finished ``output`` (3,) blended, for the model's input ``fed`` (6,)."""
        classical = fed[:3] if self.tracker is None else (
            fed[:3] - self.tracker.update(fed[:3], fed[3:]))
        weight = self.blend.weight
        if self.held is not None:
            beyond = self.sustained.update(fed[3:]) > self.held
            self._since_beyond = 0 if beyond else self._since_beyond + 1
            if self._since_beyond < self.field:
                weight = 0.0
                self.classical_only += 1
        return classical + weight * (output - classical)
