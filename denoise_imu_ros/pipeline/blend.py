# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The network's output blended with the classical pipeline's; the classical alone beyond training.

On a power-on it never saw, a network's output and the classical pipeline's (the gyro
less its turn-on bias, its bias tracked: the "tracker only" row, no model) err in part
independently: their weighted mean T + W (N - T) loses less often to T than N does, and
keeps part of N's gain where T's tracker diverges (BROAD's other session, run 26 of
docs/experiments.md). Where the envelope finds a sample of the receptive field beyond its
sustained bound (:func:`~denoise_imu_ros.pipeline.envelope.beyond`: acceleration longer
and harder than any training recording's, as on another session's fast translation),
the output is T alone; N's tracker holds there. ``crossval`` chooses W on held-out
recordings; the model file's ``blend`` stores it with T's tracking. It comes after the
envelope's guard (N is the guarded, tracked output), reset with every run.
:func:`blend_batch` over arrays and :class:`Blender` per sample agree bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import rest_bias
from ..core.schema import Blend

__all__ = ['blend_batch', 'Blender', 'CHOICES', 'resolve']

CHOICES = ('model', 'off')  # the node's blend parameter, the offline tools' option


def resolve(meta: Any, choice: str) -> Blend | None:
    """Return the blend to run: the model file's for ``model``, None for ``off``."""
    if choice not in CHOICES:
        raise ValueError(f'blend {choice!r}: one of {", ".join(CHOICES)}')
    return meta.blend if choice == 'model' else None


def blend_batch(output: np.ndarray, fed: np.ndarray, rate_hz: float, blend: Blend,
                beyond: np.ndarray | None = None) -> np.ndarray:
    """
    Return a network's finished ``output`` (N, 3) blended for its input ``fed`` (N, 6), one run.

    ``beyond`` (N,): the samples given the classical pipeline alone (the envelope's
    :func:`~denoise_imu_ros.pipeline.envelope.beyond`; None: the blend everywhere).
    """
    classical = rest_bias.track_bias(fed[:, :3], fed[:, 3:], rate_hz, blend.tracking)
    weight = np.full(len(output), blend.weight)
    if beyond is not None:
        weight[beyond] = 0.0
    return classical + weight[:, None] * (output - classical)


class Blender:
    """:func:`blend_batch` one sample at a time (node, process-bag)."""

    def __init__(self, blend: Blend, rate_hz: float) -> None:
        self.blend, self.rate_hz = blend, rate_hz
        self.tracker = (None if blend.tracking is None
                        else rest_bias.BiasTracker(blend.tracking, rate_hz))
        self.classical_only = 0  # samples given the classical pipeline's alone, for diagnostics
        self.reset()

    def reset(self) -> None:
        """Start again: another run."""
        if self.tracker is not None:
            self.tracker.reset()

    def apply(self, output: np.ndarray, fed: np.ndarray, beyond: bool = False) -> np.ndarray:
        """
        Return the finished ``output`` (3,) blended, for the model's input ``fed`` (6,).

        ``beyond``: the envelope's :attr:`~denoise_imu_ros.pipeline.envelope.Guard.beyond`
        (the classical pipeline's alone).
        """
        classical = fed[:3] if self.tracker is None else (
            fed[:3] - self.tracker.update(fed[:3], fed[3:]))
        weight = self.blend.weight
        if beyond:
            weight = 0.0
            self.classical_only += 1
        return classical + weight * (output - classical)
