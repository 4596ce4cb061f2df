# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
A model taught without its poses' heading: its correction about the vertical dropped.

With ``heading_weight: 0`` (a VIO's or a SLAM's poses, whose heading disagrees with the
gyro more than their tilt) the loss sees only the tilt of each error, so nothing taught
the component of the correction about the world's vertical; what the model outputs there
is unchecked, and on EuRoC it is worse than nothing (docs/results.md). Such a model's
output keeps only the part of its correction (output less input gyro: the learnt
correction and the tracked bias) orthogonal to the vertical, the vertical in the body
frame from VQF (its defaults, no bias estimation) run on the model's output up to the
sample before: causal, the tilt any 6-D filter gives. About the vertical the output is
the model's input, the gyro less its turn-on bias (:func:`drops_vertical`: only a model
fed that).

The poses' heading could not have taught it either: on EuRoC's training recordings
VINS-Mono's yaw increments are 3 to 8 times further from the motion capture's than those
of the gyro less its turn-on bias, at every horizon from 1.3 s to 60 s (docs/results.md).

Every path applies it alike: :func:`drop_vertical` over arrays (``eval``, ``correct``,
``crossval``, ``tune-fusion``), :class:`Vertical` one sample at a time (node,
``process-bag``); equal bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from vqf import VQF

from .rest_bias import resolve
from ..core.schema import ModelMeta, NO_MODEL

__all__ = ['drops', 'drops_vertical', 'drop_vertical', 'up_in_body', 'Vertical']

TAU_ACC_S = 3.0  # VQF's own default accelerometer time constant


def drops(heading_weight: float, turn_on_bias_removed: bool) -> bool:
    """
    Whether a model's correction about the vertical is dropped: the one rule.

    Where its recipe left the heading out (``heading_weight: 0``) and it is fed the gyro
    less its turn-on bias: only then is what it leaves about the vertical the
    practitioner's baseline. Fed the raw gyro, the output would keep the whole turn-on
    bias about the vertical, so the model's own correction is kept.
    """
    return heading_weight == 0 and turn_on_bias_removed


def drops_vertical(meta: ModelMeta, rest: str = 'model') -> bool:
    """
    :func:`drops` for a model file fed as ``rest`` says.

    ``rest`` as :func:`~denoise_imu_ros.pipeline.rest_bias.resolve`; a rest-only or
    tracker-only model corrects nothing to drop.
    """
    return (meta.kind not in NO_MODEL
            and drops(meta.heading_weight, resolve(meta, rest) is not None))


def _filter(rate_hz: float) -> VQF:
    return VQF(1.0 / rate_hz, tauAcc=TAU_ACC_S, motionBiasEstEnabled=False,
               restBiasEstEnabled=False, magDistRejectionEnabled=False)


def up_in_body(w: Any, x: Any, y: Any, z: Any) -> tuple[Any, Any, Any]:
    """Return the world's z axis in the body frame of body-to-world quaternions (or one)."""
    return 2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)


def _less_along(output: Any, fed: Any, up: tuple[Any, Any, Any]) -> tuple[Any, Any, Any]:
    """Return ``output`` less the component of ``output - fed`` along ``up`` (unit)."""
    along = ((output[0] - fed[0]) * up[0] + (output[1] - fed[1]) * up[1]
             + (output[2] - fed[2]) * up[2])
    return output[0] - along * up[0], output[1] - along * up[1], output[2] - along * up[2]


def drop_vertical(output: np.ndarray, fed: np.ndarray, rate_hz: float) -> np.ndarray:
    """
    Return a model's ``output`` (N, 3) less its correction's component about the vertical.

    ``fed`` (N, 6): the model's input (its gyro is what the output is a correction of).
    One run from the first sample; sample k - 1's output drives the filter to sample k.
    """
    output = np.asarray(output, dtype=np.float64)
    if not len(output):
        return output
    shifted = np.zeros((len(output), 3))
    shifted[1:] = output[:-1]
    wxyz = _filter(rate_hz).updateBatch(
        shifted, np.ascontiguousarray(fed[:, 3:], dtype=np.float64))['quat6D']
    return np.stack(_less_along(output.T, fed.T, up_in_body(*wxyz.T)), axis=1)


class Vertical:
    """:func:`drop_vertical` one sample at a time (node, process-bag)."""

    def __init__(self, rate_hz: float) -> None:
        self._rate_hz = rate_hz
        self._last = np.zeros(3)  # the last output, which drives the next step
        self._accel = np.empty(3)
        self.reset()

    def reset(self) -> None:
        """Start again (a new run: a bag loop, a clock jump)."""
        self._vqf = _filter(self._rate_hz)
        self._last[:] = 0.0

    def apply(self, output: np.ndarray, fed: np.ndarray) -> np.ndarray:
        """Return one output (3,) less its correction about the vertical; ``fed`` (6,)."""
        self._accel[:] = fed[3:]
        self._vqf.update(self._last, self._accel)
        self._last[:] = output
        up = up_in_body(*self._vqf.getQuat6D().tolist())
        return np.array(_less_along(output.tolist(), fed.tolist(), up))
