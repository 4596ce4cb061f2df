# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What one accepted sample publishes, and what it withholds: one policy, one message builder.

The node sends the messages to its publishers and ``process-bag`` writes them into a
bag: both only transport what :class:`Outputs` builds, so they publish the same numbers
by construction. The policy (:func:`withheld`):
- at a rate the model was not made for (the pipeline's one rate verdict,
  ``Output.rate_suspect``) the corrections are not valid: ``imu/corrected``,
  ``imu/data`` and ``imu/attitude`` are all withheld;
- the sample after a gap has an attitude held across it, not integrated: ``imu/attitude``
  (and the attitude embedded in ``imu/corrected``) is withheld, the corrected rate and the
  gravity-aided orientation are not.
Headers are the raw message's, never re-stamped; covariances are the model's (or the
node's overrides; the accelerometer's the input's where neither gives one), fixed when the
outputs are set up, except where the model gives each sample a variance
(``per_sample_gyro``, ``per_sample_accel``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any, Callable, NamedTuple

import numpy as np

from ..core import msgs
from ..pipeline.online import Event, Output

Send = Callable[[Any], None]


class Withheld(str, Enum):
    """Why an output of an accepted sample is not published (the value: its reason)."""

    OFF_RATE = "the input rate is off the model's: its corrections are not valid there"
    GAP = 'the attitude is held across a stamp gap, not integrated'


class Decision(NamedTuple):
    """Per output of one sample: None (publish) or why it is withheld."""

    corrected: Withheld | None
    fused: Withheld | None
    attitude: Withheld | None


def withheld(out: Output) -> Decision:
    """Return what to publish of ``out``, given the pipeline's one rate verdict."""
    if out.rate_suspect:
        return Decision(Withheld.OFF_RATE, Withheld.OFF_RATE, Withheld.OFF_RATE)
    return Decision(None, None, Withheld.GAP if out.event == Event.GAP else None)


@dataclass
class Outputs:
    """
    Builds and sends the messages of every accepted sample; counts what it withholds.

    ``send_fused`` None: ``imu/data`` is off (``publish_fused:=false``). Messages are
    built once and refilled for every sample (a send serialises at once): the fused
    message is the corrected one with its orientation replaced.
    """

    types: msgs.MsgTypes
    send_corrected: Send
    send_fused: Send | None
    send_attitude: Send
    fixed_frame: str
    gyro_cov: np.ndarray                # imu/corrected's angular_velocity_covariance
    fused_cov: np.ndarray               # imu/data's orientation_covariance
    embed_attitude: bool = False        # the attitude in imu/corrected too
    orientation_cov: np.ndarray = field(default_factory=lambda: np.diag([0.05 ** 2] * 3).ravel())
    per_sample_gyro: bool = False       # each sample's own variance instead of gyro_cov
    accel_cov: np.ndarray | None = None  # imu/corrected's linear_acceleration_covariance
    per_sample_accel: bool = False      # each sample's own variance instead of accel_cov
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(
        ('corrected_withheld', 'fused_withheld', 'attitude_withheld'), 0))
    _corrected: Any = None
    _attitude: Any = None
    _sample_cov: np.ndarray = field(default_factory=lambda: np.zeros(9))
    _accel_sample_cov: np.ndarray = field(default_factory=lambda: np.zeros(9))

    def send(self, raw: Any, out: Output) -> Decision:
        """Send what the policy publishes of one sample (``raw``: its input message)."""
        decision = withheld(out)
        embed = out.attitude if self.embed_attitude and decision.attitude is None else None
        gyro_cov = self.gyro_cov
        if self.per_sample_gyro and out.gyro_var is not None:
            gyro_cov = self._sample_cov
            gyro_cov[0] = gyro_cov[4] = gyro_cov[8] = out.gyro_var
        accel_cov = out.accel_cov if self.accel_cov is None else self.accel_cov
        if self.per_sample_accel and out.accel_var is not None:
            accel_cov = self._accel_sample_cov
            accel_cov[0] = accel_cov[4] = accel_cov[8] = out.accel_var
        self._corrected = msgs.corrected_imu(
            self.types, raw, out.gyro, gyro_cov, embed, self.orientation_cov,
            accel_cov, into=self._corrected, accel=out.accel)
        if decision.corrected is None:
            self.send_corrected(self._corrected)
        else:
            self.counts['corrected_withheld'] += 1
        if self.send_fused is not None and decision.fused is None:
            self.send_fused(msgs.reorient(self._corrected, out.orientation, self.fused_cov))
        elif self.send_fused is not None:
            self.counts['fused_withheld'] += 1
        if decision.attitude is None:
            self._attitude = msgs.attitude(self.types, raw, self.fixed_frame, out.attitude,
                                           into=self._attitude)
            self.send_attitude(self._attitude)
        else:
            self.counts['attitude_withheld'] += 1
        return decision
