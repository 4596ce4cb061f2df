# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The correction pipeline as one table: the stages in order and the events that reset each.

Every stage has two forms: :meth:`Stage.step` takes one sample (the node and
process-bag, through :class:`~denoise_imu_ros.pipeline.online.OnlineDenoiser`, which
checks each sample and finds the events) and :meth:`Stage.run` a whole recording as one
run (``eval``, ``correct``, ``crossval``, ``tune-fusion``); the two agree bit for bit
except the network's batch form (torch's float32 batch network within 1e-6 rad/s of the
compiled step). :class:`Pipeline` runs the stages a model file has in the order of
:data:`STAGES` and resets each at its events, so no stage can reach one path only.

==============  =========================  =========================  ===================
stage           per sample                 over a recording           reset by
==============  =========================  =========================  ===================
turn-on bias    ``RestBias.update``        ``remove_rest_bias``       start, jump (kept)
envelope check  ``Guard.check``            ``too_fast``, ``beyond``   start, gap, jump
network         ``StreamingCorrector``     torch's ``GyroNet``        start, gap, jump
bias tracking   ``BiasTracker.update``     ``tracked_bias``           start, jump
envelope apply  ``Guard.apply``            ``guard_batch``            (the check's)
classical mix   ``Blender.apply``          ``blend_batch``            start, jump
vertical drop   ``Vertical.apply``         ``drop_vertical``          start, jump
variances       ``Variance.update``        ``variances``              start, gap, jump
attitude        :class:`Attitude`          the same step, in a loop   start, jump, request
orientation     ``GravityFilter.update``   ``fuse``                   start, jump, request
==============  =========================  =========================  ===================

A gap restarts the network's history (and the envelope's view of it) but not the
estimates of the same run; the open-loop attitude is held across it and the orientation
takes no gyro step (gravity corrects its tilt). A jump (a clock stepped back, a bag
replayed) restarts everything but the turn-on bias found, the power-on's, whose
stillness is looked for afresh. A request (the node's ``reset_attitude`` service)
restarts the attitude and the orientation from the next accelerometer only.
"""

from __future__ import annotations

from enum import Enum
from typing import Any, Callable, Iterable

import numpy as np

from . import envelope, rest_bias
from .blend import blend_batch, Blender, resolve as resolve_blend
from .covariance import features, from_features, Variance
from .fusion import fuse, FusionSettings, GravityFilter
from .streaming import StreamingCorrector
from .vertical import drop_vertical, drops_vertical, Vertical
from ..core import rotation
from ..core.limits import MAX_GAP_FACTOR
from ..core.modelfile import ModelFile, sample_rate
from ..core.schema import BiasTracking, Blend, InputEnvelope, RestBiasSettings, SampleVariance

__all__ = ['Attitude', 'BiasTrackingStage', 'ClassicalMix', 'correction', 'corrected',
           'EnvelopeApply', 'EnvelopeCheck', 'Event', 'finish', 'Flow', 'model_input', 'Network',
           'Orientation', 'Pipeline', 'Stage', 'STAGES', 'TurnOnBias', 'VarianceStage',
           'VerticalDrop']


class Event(str, Enum):
    """Why the pipeline's state is reset at an accepted sample (the value names it)."""

    START = 'start'          # first sample: network warm-up, attitude from gravity
    GAP = 'gap'              # stamps too far apart: network warm-up, attitude held
    TIME_JUMP = 'time_jump'  # stamps jumped back, or a minute ahead: a new run
    REQUESTED = 'reset_attitude'  # the node's service: attitude and orientation only


RUN = frozenset({Event.START, Event.TIME_JUMP})  # another run, perhaps another power-on
HISTORY = RUN | {Event.GAP}                      # the network's input history restarts
ATTITUDE = RUN | {Event.REQUESTED}               # integrated from gravity again


class Flow:
    """
    What the stages hand on: one sample's values, or a recording's arrays.

    ``fed`` is the model's input (the raw gyro less the turn-on bias, and the
    accelerometer), ``raw`` the gyro as received, ``out`` the gyro so far; the rest are
    set by the stages that have them (``bias`` the tracked bias removed, ``hold`` the
    envelope's hold of the tracker, ``beyond`` its samples beyond the sustained bound,
    ``variance`` the output's, ``accel_variance`` the accelerometer's).
    """

    __slots__ = ('fed', 'raw', 'out', 'bias', 'hold', 'beyond', 'event', 'dt_s', 'periods',
                 'attitude', 'orientation', 'variance', 'accel_variance')

    def __init__(self, fed: np.ndarray, event: Event | None = None, dt_s: Any = 0.0,
                 periods: Any = 0.0, out: np.ndarray | None = None,
                 raw: np.ndarray | None = None) -> None:
        self.fed, self.event, self.dt_s, self.periods = fed, event, dt_s, periods
        self.raw: Any = raw  # the orientation's classical tilt: no stage changes it
        self.out: Any = out
        self.bias: Any = None
        self.hold: Any = False
        self.beyond: Any = False
        self.attitude: Any = None
        self.orientation: Any = None
        self.variance: Any = None
        self.accel_variance: Any = None

    @classmethod
    def recording(cls, imu: np.ndarray, stamp_ns: np.ndarray | None = None,
                  rate_hz: float = 0.0, max_gap_factor: float = MAX_GAP_FACTOR) -> Flow:
        """
        Return a recording's raw samples (N, 6) as one run, with their stamps if given.

        ``periods`` as the online pipeline passes them (0 at the first stamp and across
        a gap of more than ``max_gap_factor`` periods), ``dt_s`` each interval's length.
        """
        if stamp_ns is None:
            return cls(imu, raw=imu[:, :3].copy())
        stamps = np.asarray(stamp_ns, dtype=np.int64)
        dt = np.zeros(len(stamps))
        dt[1:] = np.diff(stamps) * 1e-9
        periods = dt * rate_hz
        periods[periods > max_gap_factor] = 0.0
        return cls(imu, dt_s=dt, periods=periods, raw=imu[:, :3].copy())


class Stage:
    """One stage: :meth:`step` per sample, :meth:`run` over a recording, :meth:`reset`."""

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """Start again at one of the events :data:`STAGES` gives it."""

    def step(self, flow: Flow) -> bool | None:
        """Take one sample; False drops it (the stages after it do not see it)."""
        raise NotImplementedError

    def run(self, flow: Flow) -> None:
        """Take a whole recording, one run from its first sample."""
        raise NotImplementedError


class TurnOnBias(Stage):
    """The raw gyro less the turn-on bias estimated from stillness so far (the model's input)."""

    def __init__(self, settings: RestBiasSettings, rate_hz: float) -> None:
        self.settings, self.rate_hz = settings, rate_hz
        self.estimator = rest_bias.RestBias(settings, rate_hz)

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """
        Start from the prior again at a start; after a jump, from the estimate found.

        A clock stepped back (NTP) or a bag replayed in a loop is the same power-on: the
        estimate is kept till the next stillness, which moves it as it would the prior.
        """
        if Event.START in events:
            self.estimator.reset()
        else:
            self.estimator.restart()

    def step(self, flow: Flow) -> None:
        """Remove this sample's estimate from its gyro."""
        flow.fed[:3] -= self.estimator.update(flow.fed[:3], flow.fed[3:])

    def run(self, flow: Flow) -> None:
        """Remove each sample's estimate (a copy)."""
        flow.fed = rest_bias.remove_rest_bias(flow.fed, self.rate_hz, self.settings)


class EnvelopeCheck(Stage):
    """Whether the receptive field holds motion the model was not trained on."""

    def __init__(self, guard: envelope.Guard, rate_hz: float) -> None:
        self.guard, self.rate_hz = guard, rate_hz

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """Forget the inputs seen: the network's history restarted."""
        self.guard.reset()

    def step(self, flow: Flow) -> None:
        """Take the model's input; the tracker holds while too fast (or beyond, if blended)."""
        guard = self.guard
        guard.check(flow.fed)
        flow.hold, flow.beyond = guard.hold, guard.beyond

    def run(self, flow: Flow) -> None:
        """Mark the samples whose receptive field turns faster or accelerates beyond; the hold."""
        guard = self.guard
        flow.beyond = envelope.beyond(flow.fed, guard.envelope, guard.field, self.rate_hz)
        flow.hold = envelope.too_fast(flow.fed, guard.envelope, guard.field)
        if guard.hold_beyond:
            flow.hold = flow.hold | flow.beyond


class Network(Stage):
    """The model's correction: the compiled step per sample, ``batch`` (or it) over arrays."""

    def __init__(self, engine: StreamingCorrector | None,
                 batch: Callable[[np.ndarray], np.ndarray] | None = None) -> None:
        if engine is None and batch is None:
            raise ValueError('a network stage needs its per-sample engine or a batch form')
        self.engine, self.batch = engine, batch

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """Warm up again: the history is filled with the next input."""
        if self.engine is not None:
            self.engine.reset()

    def step(self, flow: Flow) -> bool:
        """Correct one sample; a correction that is not finite drops it."""
        flow.out = self.engine.step(flow.fed)
        return bool(np.isfinite(flow.out).all())

    def run(self, flow: Flow) -> None:
        """Correct every sample."""
        flow.out = (self.engine.process if self.batch is None else self.batch)(flow.fed)


class BiasTrackingStage(Stage):
    """The model's output less the bias it still has, tracked from gravity (VQF)."""

    def __init__(self, settings: BiasTracking, rate_hz: float) -> None:
        self.settings, self.rate_hz = settings, rate_hz
        self.tracker = rest_bias.BiasTracker(settings, rate_hz)

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """Start the estimate again: another run."""
        self.tracker.reset()

    def step(self, flow: Flow) -> None:
        """Remove the bias tracked up to this sample (held as the envelope or its bound says)."""
        flow.bias = self.tracker.update(flow.out, flow.fed[3:], flow.hold)
        flow.out = flow.out - flow.bias

    def run(self, flow: Flow) -> None:
        """Remove the bias tracked at each sample."""
        hold = flow.hold if isinstance(flow.hold, np.ndarray) else None
        flow.bias = rest_bias.tracked_bias(flow.out, flow.fed[:, 3:], self.rate_hz,
                                           self.settings, hold)
        flow.out = flow.out - flow.bias


class EnvelopeApply(Stage):
    """Outside the envelope, the input plus a constant, less the tracked bias."""

    def __init__(self, guard: envelope.Guard) -> None:
        self.guard = guard  # the check's, reset by it

    def step(self, flow: Flow) -> None:
        """Guard one output."""
        flow.out = self.guard.apply(flow.out, flow.fed, flow.bias)

    def run(self, flow: Flow) -> None:
        """Guard every output."""
        flow.out = envelope.guard_batch(flow.out, flow.fed, self.guard.envelope,
                                        self.guard.field, flow.bias)


class ClassicalMix(Stage):
    """The output blended with the classical pipeline's, which alone is given beyond training."""

    def __init__(self, blender: Blender) -> None:
        self.blender = blender

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """Start the classical pipeline's tracker and the acceleration's mean again."""
        self.blender.reset()

    def step(self, flow: Flow) -> None:
        """Blend one output."""
        flow.out = self.blender.apply(flow.out, flow.fed, flow.beyond)

    def run(self, flow: Flow) -> None:
        """Blend every output."""
        b = self.blender
        beyond = flow.beyond if isinstance(flow.beyond, np.ndarray) else None
        flow.out = blend_batch(flow.out, flow.fed, b.rate_hz, b.blend, beyond)


class VerticalDrop(Stage):
    """A heading-less model's output less its correction about the vertical."""

    def __init__(self, rate_hz: float) -> None:
        self.rate_hz = rate_hz
        self.vertical = Vertical(rate_hz)

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """Find the vertical again: another run."""
        self.vertical.reset()

    def step(self, flow: Flow) -> None:
        """Drop one output's correction about the vertical."""
        flow.out = self.vertical.apply(flow.out, flow.fed)

    def run(self, flow: Flow) -> None:
        """Drop every output's correction about the vertical."""
        flow.out = drop_vertical(flow.out, flow.fed, self.rate_hz)


class VarianceStage(Stage):
    """Each output's variance, the gyro's and the accelerometer's, from how the IMU moves."""

    def __init__(self, spec: SampleVariance, rate_hz: float,
                 accel: SampleVariance | None = None) -> None:
        self.spec, self.rate_hz, self.accel = spec, rate_hz, accel
        self.variance = Variance(spec, rate_hz, accel)

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """Start the motion's means again, with the network's history."""
        self.variance.reset()

    def step(self, flow: Flow) -> None:
        """Give this output its variances."""
        flow.variance, flow.accel_variance = self.variance.update(flow.out, flow.fed[3:])

    def run(self, flow: Flow) -> None:
        """Give every output its variances; the means restart at each gap (periods 0)."""
        restarts = (flow.periods == 0) if isinstance(flow.periods, np.ndarray) else None
        phi = features(flow.out, flow.fed[:, 3:], self.rate_hz, self.spec, restarts)
        flow.variance = from_features(phi, self.spec)
        if self.accel is not None:
            flow.accel_variance = from_features(phi, self.accel)


class Attitude(Stage):
    """
    The open-loop attitude (``imu/attitude``): the corrected gyro integrated, xyzw.

    From gravity at a reset (less the accelerometer's constant bias); then the interval
    from stamp k - 1 to k at samples k - 1's and k's mean rate, as ``imu/data``; held
    across a gap, which cannot be integrated.
    """

    def __init__(self, accel_bias: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
        self.accel_bias = accel_bias
        self._attitude: rotation.Quat | None = None
        self._last: np.ndarray | None = None

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """Take the next sample's accelerometer for the tilt, yaw 0."""
        self._attitude = None

    def step(self, flow: Flow) -> None:
        """Integrate to this sample's stamp."""
        if self._attitude is None:
            bx, by, bz = self.accel_bias
            accel = flow.fed[3:]
            self._attitude = rotation.from_gravity(float(accel[0]) - bx, float(accel[1]) - by,
                                                   float(accel[2]) - bz)
        elif flow.event is None:
            dt = flow.dt_s
            self._attitude = rotation.multiply(self._attitude, rotation.exp(
                *(0.5 * (float(a) + float(b)) * dt for a, b in zip(self._last, flow.out))))
        self._last = flow.out
        flow.attitude = np.array(self._attitude)

    def run(self, flow: Flow) -> None:
        """Integrate over the recording: the same step, each gap (periods 0) held."""
        self.reset()
        attitude = np.empty((len(flow.out), 4))
        for k, (fed, out, periods) in enumerate(zip(flow.fed, flow.out, flow.periods)):
            sample = Flow(fed, None if periods else Event.GAP, flow.dt_s[k], out=out)
            self.step(sample)
            attitude[k] = sample.attitude
        flow.attitude = attitude


class Orientation(Stage):
    """The gravity-aided orientation (``imu/data``): VQF on the corrected gyro."""

    def __init__(self, rate_hz: float, settings: FusionSettings) -> None:
        self.rate_hz, self.settings = rate_hz, settings
        self.filter = GravityFilter(rate_hz, settings)

    def reset(self, events: frozenset[Event] = RUN) -> None:
        """Take the next sample's accelerometer for the tilt, yaw 0."""
        self.filter.reset()

    def step(self, flow: Flow) -> None:
        """Update with this sample (no gyro step after an event: the yaw is held)."""
        flow.orientation = self.filter.update(flow.out, flow.fed[3:], flow.periods, flow.raw)

    def run(self, flow: Flow) -> None:
        """Filter the recording in one compiled batch."""
        flow.orientation = fuse(flow.out, flow.fed[:, 3:], self.rate_hz, self.settings,
                                flow.periods if isinstance(flow.periods, np.ndarray)
                                else None, flow.raw)


# The one table: the order of the stages and the events that reset each.
STAGES: tuple[tuple[type[Stage], frozenset[Event]], ...] = (
    (TurnOnBias, RUN),
    (EnvelopeCheck, HISTORY),
    (Network, HISTORY),
    (BiasTrackingStage, RUN),
    (EnvelopeApply, frozenset()),  # its guard is the check's, reset there
    (ClassicalMix, RUN),
    (VerticalDrop, RUN),
    (VarianceStage, HISTORY),
    (Attitude, ATTITUDE),
    (Orientation, ATTITUDE),
)
RESETS = dict(STAGES)


class Pipeline:
    """The stages a model file has, in the order of :data:`STAGES`, reset at its events."""

    def __init__(self, stages: Iterable[Stage]) -> None:
        stages = list(stages)
        given = {type(s): s for s in stages}
        if len(given) < len(stages):
            raise TypeError('two stages of one kind: a pipeline has each stage once')
        unknown = set(given) - set(RESETS)
        if unknown:
            raise TypeError(f'not a stage of the table: {sorted(k.__name__ for k in unknown)}')
        self.stages = tuple(given[kind] for kind, _ in STAGES if kind in given)
        self._resets = tuple((s, RESETS[type(s)]) for s in self.stages)

    def get(self, kind: type[Stage]) -> Any:
        """Return the stage of that kind, or None where this pipeline has none."""
        return next((s for s in self.stages if type(s) is kind), None)

    def step(self, flow: Flow, events: frozenset[Event] = frozenset()) -> bool:
        """Take one sample after resetting the stages ``events`` reset; False: dropped."""
        if events:
            for stage, resets in self._resets:
                if not resets.isdisjoint(events):
                    stage.reset(events)
        for stage in self.stages:
            if stage.step(flow) is False:
                return False
        return True

    def run(self, flow: Flow, before: type[Stage] | None = None) -> Flow:
        """Take a recording, one run, through every stage (or up to ``before``)."""
        for stage in self.stages:
            if type(stage) is before:
                break
            stage.run(flow)
        return flow


def correction(model: ModelFile, rest: str = 'model', guard: str = 'model',
               batch: Callable[[np.ndarray], np.ndarray] | None = None,
               mix: str = 'model') -> list[Stage]:
    """
    Return the correcting stages of a model file (numpy only, no torch).

    ``rest`` as the node's ``rest_bias`` (``model``, ``on``, ``off``): the turn-on bias
    removed first (:func:`~denoise_imu_ros.pipeline.rest_bias.resolve`), the output's
    bias tracked (:func:`~denoise_imu_ros.pipeline.rest_bias.tracking`) and the correction
    about the vertical dropped (:func:`~denoise_imu_ros.pipeline.vertical.drops_vertical`)
    where the model file says; ``guard`` as its ``envelope_guard`` (``model``, ``off``:
    :func:`~denoise_imu_ros.pipeline.envelope.resolve`); ``mix`` as its ``blend``
    (``model``, ``off``: :func:`~denoise_imu_ros.pipeline.blend.resolve`), the
    classical pipeline's alone beyond the envelope's sustained bound only where the
    envelope guards. ``batch``: the network over arrays (torch's, for a model loaded with
    torch) instead of the per-sample engine. Last, where the file has them, each output's
    variances (:mod:`~denoise_imu_ros.pipeline.covariance`).
    """
    rate = sample_rate(model)
    settings = rest_bias.resolve(model.meta, rest)
    tracking = rest_bias.tracking(model.meta, rest)
    bounds = envelope.resolve(model.meta, guard)
    blend = resolve_blend(model.meta, mix)
    stages: list[Stage] = [Network(
        StreamingCorrector(model.config, model.arrays) if batch is None else None, batch)]
    if settings is not None:
        stages.append(TurnOnBias(settings, rate))
    if tracking is not None:
        stages.append(BiasTrackingStage(tracking, rate))
    if bounds is not None:
        stages += _guarded(bounds, model.config.receptive_field, rate, blend is not None)
    if blend is not None:
        stages.append(ClassicalMix(Blender(blend, rate)))
    if drops_vertical(model.meta, rest):
        stages.append(VerticalDrop(rate))
    if model.meta.gyro_variance is not None:
        stages.append(VarianceStage(model.meta.gyro_variance, rate, model.meta.accel_variance))
    return stages


def _guarded(bounds: InputEnvelope, field: int, rate_hz: float, blended: bool
             ) -> list[Stage]:
    """Return the envelope's check and apply (the tracker held beyond the bound if blended)."""
    guard = envelope.Guard(bounds, field, rate_hz, hold_beyond=blended)
    return [EnvelopeCheck(guard, rate_hz), EnvelopeApply(guard)]


def corrected(model: ModelFile, imu: np.ndarray, rest: str = 'model', guard: str = 'model',
              batch: Callable[[np.ndarray], np.ndarray] | None = None, mix: str = 'model'
              ) -> np.ndarray:
    """
    Return the corrected gyro (N, 3) of a recording's raw samples (N, 6), one run.

    The stages up to the variances, which are not the gyro
    (:func:`~denoise_imu_ros.pipeline.covariance.variances`).
    """
    return Pipeline(correction(model, rest, guard, batch, mix)).run(
        Flow.recording(imu), before=VarianceStage).out


def model_input(model: Any, imu: np.ndarray, rest: str = 'model') -> np.ndarray:
    """Return what a model is fed for a recording's raw samples (N, 6): the stages before it."""
    settings = rest_bias.resolve(model.meta, rest)
    stages = [] if settings is None else [TurnOnBias(settings, sample_rate(model))]
    return Pipeline(stages).run(Flow.recording(imu)).fed


def finish(output: np.ndarray, fed: np.ndarray, rate_hz: float,
           tracking: BiasTracking | None, bounds: InputEnvelope | None, field: int,
           vertical: bool = False, blend: Blend | None = None) -> np.ndarray:
    """
    Return a network's ``output`` (N, 3) for its input ``fed`` (N, 6) through the stages after it.

    With these settings rather than a model file's: ``crossval`` tries several trackings
    and blends on one output, and on the mean of its folds' outputs.
    """
    stages: list[Stage] = [] if tracking is None else [BiasTrackingStage(tracking, rate_hz)]
    if bounds is not None:
        stages += _guarded(bounds, field, rate_hz, blend is not None)
    if blend is not None:
        stages.append(ClassicalMix(Blender(blend, rate_hz)))
    if vertical:
        stages.append(VerticalDrop(rate_hz))
    return Pipeline(stages).run(Flow(fed, out=output)).out
