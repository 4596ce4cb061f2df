# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Each incoming sample checked, then through the stage table: the node's and process-bag's pipeline.

:class:`OnlineDenoiser` takes one IMU sample at a time (stamp, gyro, accel) and either
returns the corrected gyro with the integrated (open-loop) attitude and, with fusion
settings, the gravity-aided orientation, or a counted drop. The ROS node and the bag
processor both drive it, so they publish identical numbers. What happens to an accepted
sample, in which order, and what each event resets, is the table of
:mod:`denoise_imu_ros.pipeline.stages`; this module decides the drops and the events.

Policies (each counted in :attr:`OnlineDenoiser.counts`):
- a non-finite field, a value beyond the physical range (:mod:`denoise_imu_ros.core.limits`),
  a zero stamp, a duplicate or out-of-order stamp: sample dropped; so is a sample whose
  correction is not finite (a model file that passed its checks and still overflows);
- a stamp more than ``time_jump_s`` behind the last one (bag loop, clock reset): a time
  jump, everything reset, the sample is the first of a new recording;
- a gap longer than ``max_gap_factor`` nominal periods: the network history restarts
  (as at start-up), the attitude is held across the gap, which cannot be integrated, and
  the gravity-aided orientation goes on (gravity corrects its tilt; its yaw is held);
- a stamp more than FORWARD_JUMP_S ahead (a second publisher on another clock, a clock
  set): a time jump as for a backward one, and no periods counted as skipped;
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
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any, NamedTuple

import numpy as np

from . import envelope, rest_bias
from .blend import Blender
from .fusion import FusionSettings, GravityFilter
from .stages import (Attitude, BiasTrackingStage, ClassicalMix, correction, EnvelopeCheck,
                     Event, Flow, Network, Orientation, Pipeline, TurnOnBias, VerticalDrop)
from .streaming import StreamingCorrector
from .vertical import Vertical
from ..core.limits import in_range, MAX_GAP_FACTOR, RATE_TOLERANCE
from ..core.modelfile import ModelFile, sample_rate
from ..core.msgs import finite_covariance, imu_fields, UNKNOWN_COVARIANCE


class Drop(str, Enum):
    """Why a sample was dropped (the value is its counter's name)."""

    NON_FINITE = 'non_finite'
    OUT_OF_RANGE = 'out_of_range'
    ZERO_STAMP = 'zero_stamp'
    DUPLICATE_STAMP = 'duplicate_stamp'
    OUT_OF_ORDER = 'out_of_order'
    NON_FINITE_OUTPUT = 'non_finite_output'  # the model's correction: a broken model file


DROP_CAUSES = tuple(d.value for d in Drop)
FORWARD_JUMP_S = 60.0  # a stamp this far ahead is another clock, not a dropout
RATE_RUN = 10          # consecutive off-period intervals that make a stream suspect
INPUT_WINDOW = 32      # intervals whose median is the stream's own period


class Output(NamedTuple):
    """What one accepted sample yields."""

    stamp_ns: int           # the sample's own stamp
    gyro: np.ndarray        # (3,) corrected angular velocity, rad/s
    accel: np.ndarray       # (3,) the accelerometer imu/corrected carries, m/s^2
    attitude: np.ndarray    # (4,) xyzw, IMU frame to the fixed frame (open loop)
    event: Event | None     # set when the state was reset at this sample
    orientation: np.ndarray | None = None  # (4,) xyzw, gravity-aided (with a filter)
    rate_suspect: bool = False  # the stream is off the model's period (see rate_suspect)
    accel_cov: np.ndarray | None = None  # the input's, finite (from process_imu)
    gyro_var: float | None = None  # the output rate's variance, (rad/s)^2, if the model has one
    accel_var: float | None = None  # the accelerometer's, (m/s^2)^2, if the model has one


@dataclass
class OnlineDenoiser:
    """Input checks and events, then the stage table, one sample at a time."""

    pipeline: Pipeline
    rate_hz: float                      # the model's sample rate
    max_gap_factor: float = MAX_GAP_FACTOR  # gap threshold, in nominal sample periods
    time_jump_s: float = 1.0            # backward stamp jump that resets everything
    rate_tolerance: float = RATE_TOLERANCE  # relative interval error of an off-rate stream
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(
        (*DROP_CAUSES, 'accepted', 'gap_resets', 'time_jump_resets', 'skipped_periods',
         'skipped_input_periods', 'non_finite_covariance'), 0))
    _last_ns: int | None = None
    _pending_reset: bool = False
    _off_rate_run: int = 0
    _intervals: list[int] = field(default_factory=list)  # recent ones, ns
    _input_period_ns: float = 0.0  # their median, refreshed every INPUT_WINDOW samples
    _window_off: bool = False      # that median's rate is off the model's
    # the accelerometer bias removed from Output.accel (imu/corrected's), m/s^2
    corrected_accel_bias: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @classmethod
    def of_engine(cls, engine: StreamingCorrector, rate_hz: float,
                  accel_bias: tuple[float, float, float] = (0.0, 0.0, 0.0),
                  **options: Any) -> OnlineDenoiser:
        """Build a pipeline of a network alone and its open-loop attitude."""
        return cls(Pipeline([Network(engine), Attitude(accel_bias)]), rate_hz,
                   corrected_accel_bias=np.array(accel_bias), **options)

    @classmethod
    def from_model_file(cls, model: ModelFile, fusion: FusionSettings | None = None,
                        rest_choice: str = 'model', guard_choice: str = 'model',
                        blend_choice: str = 'model',
                        accel_bias: tuple[float, float, float] | None = None,
                        corrected_accel_bias: tuple[float, float, float] | None = None,
                        **options: Any) -> OnlineDenoiser:
        """
        Build the pipeline of a model file (node and process-bag): numpy only, no torch.

        Its correcting stages (:func:`~denoise_imu_ros.pipeline.stages.correction`, with
        ``rest_choice``, ``guard_choice`` and ``blend_choice`` as the node's
        ``rest_bias``, ``envelope_guard`` and ``classical_blend``), the open-loop attitude
        and, with ``fusion`` settings, the gravity-aided orientation; the accelerometer
        bias they remove is removed from the attitude's initial tilt as well (unless
        ``accel_bias`` is given), and from the accelerometer of every output (unless
        ``corrected_accel_bias`` is given).
        """
        rate = sample_rate(model)
        if accel_bias is None:
            accel_bias = (0.0, 0.0, 0.0) if fusion is None else fusion.accel_bias_m_s2
        stages = [*correction(model, rest_choice, guard_choice, mix=blend_choice),
                  Attitude(accel_bias)]
        if fusion is not None:
            stages.append(Orientation(rate, fusion))
        published = accel_bias if corrected_accel_bias is None else corrected_accel_bias
        return cls(Pipeline(stages), rate, corrected_accel_bias=np.array(published), **options)

    @property
    def engine(self) -> StreamingCorrector:
        """Return the network's per-sample engine."""
        return self.pipeline.get(Network).engine

    @property
    def rest(self) -> rest_bias.RestBias | None:
        """Return the turn-on bias estimator (None: the raw gyro is fed)."""
        stage = self.pipeline.get(TurnOnBias)
        return None if stage is None else stage.estimator

    @property
    def track(self) -> rest_bias.BiasTracker | None:
        """Return the output's bias tracker (None: not tracked)."""
        stage = self.pipeline.get(BiasTrackingStage)
        return None if stage is None else stage.tracker

    @property
    def guard(self) -> envelope.Guard | None:
        """Return what guards the input envelope (None: nothing does)."""
        stage = self.pipeline.get(EnvelopeCheck)
        return None if stage is None else stage.guard

    @property
    def blender(self) -> Blender | None:
        """Return what blends the output with the classical pipeline's (None: nothing does)."""
        stage = self.pipeline.get(ClassicalMix)
        return None if stage is None else stage.blender

    @property
    def vertical(self) -> Vertical | None:
        """Return what drops the correction about the vertical; None where it is kept."""
        stage = self.pipeline.get(VerticalDrop)
        return None if stage is None else stage.vertical

    @property
    def fusion(self) -> GravityFilter | None:
        """Return the gravity-aided orientation's filter (None: not computed)."""
        stage = self.pipeline.get(Orientation)
        return None if stage is None else stage.filter

    @property
    def accel_bias(self) -> tuple[float, float, float]:
        """Return the accelerometer bias removed before the attitude's initial tilt."""
        return self.pipeline.get(Attitude).accel_bias

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

        events = frozenset() if event is None else frozenset({event})
        if self._pending_reset:
            events |= {Event.REQUESTED}
            self._pending_reset = False
        flow = Flow(np.concatenate([gyro, accel], dtype=np.float64), event,
                    (stamp_ns - self._last_ns) * 1e-9 if event is None else 0.0,
                    periods if event is None else 0.0, raw=gyro)  # a gap: yaw held
        if not self.pipeline.step(flow, events):  # never published: dropped as if lost
            return self._drop(Drop.NON_FINITE_OUTPUT)
        if event in (Event.START, Event.TIME_JUMP):  # another stream: its rate is new too
            self._off_rate_run, self._input_period_ns, self._window_off = 0, 0.0, False
            self._intervals.clear()
        self._last_ns = stamp_ns
        self.counts['accepted'] += 1
        return Output(stamp_ns=stamp_ns, gyro=flow.out, accel=accel - self.corrected_accel_bias,
                      attitude=flow.attitude, event=event,
                      orientation=flow.orientation, rate_suspect=self.rate_suspect,
                      accel_cov=accel_cov, gyro_var=flow.variance,
                      accel_var=flow.accel_variance)
