# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The online correction pipeline without ROS: input checks, streaming network, attitude.

:class:`OnlineDenoiser` takes one IMU sample at a time (stamp, gyro, accel) and either
returns the corrected gyro with the integrated (open-loop) attitude and, with a
:class:`~denoise_imu_ros.runtime.fusion.GravityFilter`, the gravity-aided orientation,
or a counted drop. The ROS node and the bag processor both drive it, so they publish
identical numbers.

Policies (each counted in :attr:`OnlineDenoiser.counts`):
- a non-finite field, a value beyond the physical range (:mod:`denoise_imu_ros.core.limits`),
  a zero stamp, a duplicate or out-of-order stamp: sample dropped; so is a sample whose
  correction is not finite (a model file that passed its checks and still overflows);
- a stamp more than ``time_jump_s`` behind the last one (bag loop, clock reset): full
  reset (network history and attitude), the sample is the first of a new recording;
- a gap longer than ``max_gap_factor`` nominal periods: the network history restarts
  (as at start-up) and the attitude is held across the gap, which cannot be integrated;
  the gravity-aided orientation goes on (gravity corrects its tilt; its yaw is held);
- a stamp more than FORWARD_JUMP_S ahead (a second publisher on another clock, a clock
  set): full reset as for a backward jump, and no periods counted as skipped;
- every nominal period without a sample is counted (``skipped_periods``): samples lost
  upstream or in a subscription queue show there, not only as a lower rate; so is every
  period of the stream's own rate (``skipped_input_periods``, the median of its recent
  intervals), which counts losses of a stream faster than the model too;
- the one rate verdict, :attr:`rate_suspect`: RATE_RUN consecutive stamp intervals more
  than ``rate_tolerance`` off the model's period (gaps included: a stream slower than the
  gap limit is all gaps), until an interval is on time again, or the stream's own rate
  (:attr:`input_rate_hz`, the median of its last INPUT_WINDOW intervals) that far off the
  model's, until a window is on rate again. The node withholds its corrections, attitudes
  and orientations while it holds, and says so in ``/diagnostics``; process-bag does not
  write them.

With a :class:`~denoise_imu_ros.data.rest_bias.RestBias`, the gyro the model sees is the
raw gyro less the turn-on bias estimated from stillness up to that sample (the model's
training input); a full reset starts the estimate again from its prior (another run,
perhaps another power-on), a gap does not (the same run). With a
:class:`~denoise_imu_ros.data.rest_bias.BiasTracker` (the model file's ``bias_tracking``),
the model's output less its tracked bias is what every output carries, the open-loop
attitude and the gravity-aided orientation included; it restarts with the estimate.
With a :class:`~denoise_imu_ros.data.envelope.Guard` (the model file's
``input_envelope``), last, the output is the model's input plus a constant, less the
tracker's bias, while the receptive field holds motion the model was not trained on (what
the tracker gives, not the model's guess), and the tracker's estimate is held through
stretches where it turns faster than that (restored after each); it restarts
with the network's history, and a gap ends a held stretch. With a
:class:`~denoise_imu_ros.data.vertical.Vertical` (a model taught without its poses'
heading), last of all, the output keeps only the part of its correction orthogonal to
the vertical; it restarts with the turn-on bias's estimate.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any, NamedTuple

import numpy as np

from .fusion import FusionSettings, GravityFilter
from .streaming import StreamingCorrector
from ..core import rotation
from ..core.limits import in_range, MAX_GAP_FACTOR, RATE_TOLERANCE
from ..core.modelfile import ModelFile, sample_rate
from ..core.msgs import finite_covariance, imu_fields, UNKNOWN_COVARIANCE
from ..data import envelope, rest_bias
from ..data.vertical import drops_vertical, Vertical


class Drop(str, Enum):
    """Why a sample was dropped (the value is its counter's name)."""

    NON_FINITE = 'non_finite'
    OUT_OF_RANGE = 'out_of_range'
    ZERO_STAMP = 'zero_stamp'
    DUPLICATE_STAMP = 'duplicate_stamp'
    OUT_OF_ORDER = 'out_of_order'
    NON_FINITE_OUTPUT = 'non_finite_output'  # the model's correction: a broken model file


class Event(str, Enum):
    """A reset of the pipeline's state at an accepted sample."""

    START = 'start'          # first sample: network warm-up, attitude from gravity
    GAP = 'gap'              # stamps too far apart: network warm-up, attitude held
    TIME_JUMP = 'time_jump'  # stamps jumped back, or a minute ahead: everything reset


DROP_CAUSES = tuple(d.value for d in Drop)
FORWARD_JUMP_S = 60.0  # a stamp this far ahead is another clock, not a dropout
RATE_RUN = 10          # consecutive off-period intervals that make a stream suspect
INPUT_WINDOW = 32      # intervals whose median is the stream's own period


class Output(NamedTuple):
    """What one accepted sample yields."""

    stamp_ns: int           # the sample's own stamp
    gyro: np.ndarray        # (3,) corrected angular velocity, rad/s
    attitude: np.ndarray    # (4,) xyzw, IMU frame to the fixed frame (open loop)
    event: Event | None     # set when the state was reset at this sample
    orientation: np.ndarray | None = None  # (4,) xyzw, gravity-aided (with a filter)
    rate_suspect: bool = False  # the stream is off the model's period (see rate_suspect)
    accel_cov: np.ndarray | None = None  # the input's, finite (from process_imu)


@dataclass
class OnlineDenoiser:
    """Streaming gyro correction and attitude integration with input checks."""

    engine: StreamingCorrector
    rate_hz: float                      # the model's sample rate
    max_gap_factor: float = MAX_GAP_FACTOR  # gap threshold, in nominal sample periods
    time_jump_s: float = 1.0            # backward stamp jump that resets everything
    fusion: GravityFilter | None = None  # the gravity-aided orientation, if wanted
    rate_tolerance: float = RATE_TOLERANCE  # relative interval error of an off-rate stream
    # the accelerometer's constant bias (m/s^2), removed before the initial tilt is read
    accel_bias: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rest: rest_bias.RestBias | None = None  # the turn-on bias removed before the model
    track: rest_bias.BiasTracker | None = None  # the output's bias tracked after it
    guard: envelope.Guard | None = None  # the model not trusted beyond its input envelope
    vertical: Vertical | None = None  # its correction about the vertical dropped
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(
        (*DROP_CAUSES, 'accepted', 'gap_resets', 'time_jump_resets', 'skipped_periods',
         'skipped_input_periods', 'non_finite_covariance'), 0))
    _last_ns: int | None = None
    _attitude: rotation.Quat | None = None
    _last_gyro: np.ndarray | None = None
    _pending_reset: bool = False
    _off_rate_run: int = 0
    _intervals: list[int] = field(default_factory=list)  # recent ones, ns
    _input_period_ns: float = 0.0  # their median, refreshed every INPUT_WINDOW samples
    _window_off: bool = False      # that median's rate is off the model's

    @classmethod
    def from_model_file(cls, model: ModelFile, fusion: FusionSettings | None = None,
                        rest_choice: str = 'model', guard_choice: str = 'model',
                        **options: Any) -> OnlineDenoiser:
        """
        Build the pipeline of a model file (node and process-bag): numpy only, no torch.

        With ``fusion`` settings, the gravity-aided orientation is computed too, and the
        accelerometer bias they remove is removed from the open-loop attitude's initial
        tilt as well (unless ``accel_bias`` is given). ``rest_choice`` (``model``, ``on``,
        ``off``) says whether the turn-on bias is estimated and removed
        (:func:`denoise_imu_ros.data.rest_bias.resolve`) and the output's bias tracked
        (:func:`denoise_imu_ros.data.rest_bias.tracking`); ``guard_choice`` (``model``,
        ``off``) whether the output is guarded (:func:`denoise_imu_ros.data.envelope.resolve`).
        The correction about the vertical is dropped where the model file and
        ``rest_choice`` say so (:func:`denoise_imu_ros.data.vertical.drops_vertical`).
        """
        rate = sample_rate(model)
        if fusion is not None:
            options.setdefault('accel_bias', fusion.accel_bias_m_s2)
        settings = rest_bias.resolve(model.meta, rest_choice)
        track = rest_bias.tracking(model.meta, rest_choice)
        bounds = envelope.resolve(model.meta, guard_choice)
        return cls(StreamingCorrector(model.config, model.arrays), rate,
                   guard=None if bounds is None else envelope.Guard(
                       bounds, model.config.receptive_field),
                   fusion=None if fusion is None else GravityFilter(rate, fusion),
                   rest=None if settings is None else rest_bias.RestBias(settings, rate),
                   track=None if track is None else rest_bias.BiasTracker(track, rate),
                   vertical=Vertical(rate) if drops_vertical(model.meta, rest_choice) else None,
                   **options)

    def _count_input_periods(self, interval_ns: int) -> None:
        """Count the periods of the stream's own recent rate that went without a sample."""
        if self._input_period_ns > 0:
            missed = round(interval_ns / self._input_period_ns) - 1
            self.counts['skipped_input_periods'] += max(missed, 0)
        self._intervals.append(interval_ns)
        if len(self._intervals) == INPUT_WINDOW:
            self._input_period_ns = float(np.median(self._intervals))
            self._intervals.clear()
            self._window_off = abs(self.input_rate_hz / self.rate_hz - 1) > self.rate_tolerance

    @property
    def input_rate_hz(self) -> float:
        """Return the stream's own rate: its recent median interval's (0 until known)."""
        return 1e9 / self._input_period_ns if self._input_period_ns > 0 else 0.0

    @property
    def rate_suspect(self) -> bool:
        """Whether the stream is off the model's rate: a run of intervals, or its median."""
        return self._off_rate_run >= RATE_RUN or self._window_off

    def reset_attitude(self) -> None:
        """Re-initialise the attitude (and the orientation) from the next accelerometer."""
        self._pending_reset = True

    def _drop(self, cause: Drop) -> Drop:
        self.counts[cause.value] += 1
        return cause

    def process_imu(self, msg: Any) -> Output | Drop:
        """
        Correct one sensor_msgs/Imu (rclpy or rosbags message); see :meth:`process`.

        The output carries the accelerometer covariance to publish, checked once here: a
        non-finite one is replaced by zeros ('unknown') and counted
        (``non_finite_covariance``).
        """
        cov = finite_covariance(msg.linear_acceleration_covariance)
        if cov is UNKNOWN_COVARIANCE:
            self.counts['non_finite_covariance'] += 1
        return self.process(*imu_fields(msg), accel_cov=cov)

    def process(self, stamp_ns: int, gyro: np.ndarray, accel: np.ndarray,
                accel_cov: np.ndarray | None = None) -> Output | Drop:
        """Correct one sample; returns an :class:`Output` or the cause of a drop."""
        if not (np.isfinite(gyro).all() and np.isfinite(accel).all()):
            return self._drop(Drop.NON_FINITE)
        if not in_range(gyro, accel):
            return self._drop(Drop.OUT_OF_RANGE)
        if stamp_ns <= 0:
            return self._drop(Drop.ZERO_STAMP)
        event, periods = None, 1.0
        if self._last_ns is None:
            event = Event.START
        elif stamp_ns == self._last_ns:
            return self._drop(Drop.DUPLICATE_STAMP)
        elif stamp_ns < self._last_ns:
            if (self._last_ns - stamp_ns) * 1e-9 <= self.time_jump_s:
                return self._drop(Drop.OUT_OF_ORDER)
            event = Event.TIME_JUMP
            self.counts['time_jump_resets'] += 1
        elif (stamp_ns - self._last_ns) * 1e-9 > FORWARD_JUMP_S:
            event = Event.TIME_JUMP
            self.counts['time_jump_resets'] += 1
        else:
            periods = (stamp_ns - self._last_ns) * 1e-9 * self.rate_hz  # model periods
            # nominal periods with no sample: lost upstream or in a queue (or a slow stream)
            self.counts['skipped_periods'] += max(round(periods) - 1, 0)
            if periods > self.max_gap_factor:
                event = Event.GAP
                self.counts['gap_resets'] += 1
                self._off_rate_run += 1  # a stream slower than the gap limit: all gaps
            else:
                off = abs(periods - 1) > self.rate_tolerance
                self._off_rate_run = self._off_rate_run + 1 if off else 0
            self._count_input_periods(stamp_ns - self._last_ns)

        if event is not None:
            self.engine.reset()
        if self.rest is not None:
            if event in (Event.START, Event.TIME_JUMP):
                self.rest.reset()
            gyro = gyro - self.rest.update(gyro, accel)
        fed = np.concatenate([gyro, accel])
        corrected = self.engine.step(fed)
        if self.guard is not None:  # every input the engine's history holds
            if event is not None:  # that history restarted
                self.guard.reset()
            self.guard.check(fed)
        if not np.isfinite(corrected).all():  # never published: dropped as if lost
            return self._drop(Drop.NON_FINITE_OUTPUT)
        bias = None
        if self.track is not None:
            if event in (Event.START, Event.TIME_JUMP):
                self.track.reset()
            bias = self.track.update(corrected, accel,
                                     self.guard is not None and self.guard.too_fast)
            corrected = corrected - bias
        if self.guard is not None:
            corrected = self.guard.apply(corrected, fed, bias)
        if self.vertical is not None:
            if event in (Event.START, Event.TIME_JUMP):
                self.vertical.reset()
            corrected = self.vertical.apply(corrected, fed)
        if event in (Event.START, Event.TIME_JUMP):  # another stream: its rate is new too
            self._off_rate_run, self._input_period_ns, self._window_off = 0, 0.0, False
            self._intervals.clear()
        if event in (Event.START, Event.TIME_JUMP) or self._pending_reset:
            bx, by, bz = self.accel_bias
            self._attitude = rotation.from_gravity(float(accel[0]) - bx, float(accel[1]) - by,
                                                   float(accel[2]) - bz)
            if self.fusion is not None:
                self.fusion.reset()
            self._pending_reset = False
        elif event is None:  # stamp k-1 to k at samples k-1's and k's mean, as imu/data
            dt = (stamp_ns - self._last_ns) * 1e-9
            step = rotation.exp(*(0.5 * (float(a) + float(b)) * dt
                                  for a, b in zip(self._last_gyro, corrected)))
            self._attitude = rotation.multiply(self._attitude, step)
        self._last_ns, self._last_gyro = stamp_ns, corrected
        self.counts['accepted'] += 1
        orientation = None if self.fusion is None else self.fusion.update(
            corrected, accel, periods if event is None else 0.0)  # a gap: yaw held
        return Output(stamp_ns=stamp_ns, gyro=corrected, attitude=np.array(self._attitude),
                      event=event, orientation=orientation, rate_suspect=self.rate_suspect,
                      accel_cov=accel_cov)
