# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The gyro's turn-on bias, estimated causally from the stillness a run starts with.

A consumer MEMS gyro's bias changes at every power-on and holds within one: a model
file cannot carry it, the recording itself must measure it. VQF's rest detection
(Laidig & Seel 2023, the ``vqf`` package) says when the IMU is still (gyro and
accelerometer within thresholds of their low-passed values for ``rest_min_s``), and its
rest bias estimator (a Kalman filter on the low-passed gyro while still; its motion bias
estimation is off) gives the bias and its standard deviation at every sample, from that
sample and the ones before it only. Later still periods refine it. Before the first
stillness the estimate is the ``prior``: the mean rest bias of the model's training
recordings (0 without a model). VQF is fed the gyro less the prior, so that its clip
(``bias_clip_deg_s``) bounds the distance from the prior: a steady turn about gravity
looks still to the accelerometer, and only a gyro level no power-on's bias would have
tells it from rest; a level within the clip is ambiguous (:attr:`RestBias.offset_deg_s`).

Every path uses it identically: the model's input gyro is the raw gyro minus the
estimate at that sample (:func:`remove_rest_bias` over arrays for training, ``eval``,
``correct``; :class:`RestBias` per sample for the node and ``process-bag``; both run
VQF's one C++ update, equal bit for bit). A model trained that way records its settings
under the ``rest_bias`` metadata key (:class:`~denoise_imu_ros.core.schema.RestBiasSettings`).

What the turn-on bias at rest does not catch, the bias of the model's output in motion,
is tracked after the model where its file says so (``bias_tracking``,
:class:`~denoise_imu_ros.core.schema.BiasTracking`): a second VQF, its rest and motion
bias estimators on, fed the model's output from a bias of 0; its estimate is removed
from the output (:func:`track_bias` over arrays, :class:`BiasTracker` per sample; its
estimate restored after motion faster than the model was trained on: the stage table,
:mod:`denoise_imu_ros.pipeline.stages`), and after rotation faster than its settings'
``hold_above_deg_s`` (:class:`FastRotation`): there VQF's own attitude takes the gyro's
scale error, which its motion estimate reads as a bias.
"""

from __future__ import annotations

from dataclasses import replace
import math
from pathlib import Path
from typing import Any, Iterable, NamedTuple

import numpy as np
from vqf import VQF

from ..core.architecture import ModelConfig
from ..core.errors import ModelFileError
from ..core.modelfile import code_version, Described, ModelFile, sample_rate, write_model_file
from ..core.schema import (BiasTracking, ModelMeta, REST_ONLY, RestBiasSettings, TRACKER_ONLY,
                           tracking_from_dict)

__all__ = ['baseline_gyro', 'baseline_settings', 'BiasTracker', 'CHOICES',
           'classical_tracking', 'estimator', 'fast_rotation', 'FastRotation',
           'HOLD_ABOVE_DEG_S', 'Nominal', 'nominal_bias', 'remove_rest_bias', 'resolve',
           'RestBias', 'rest_bias_batch', 'RestBiasSettings', 'track_bias', 'tracked_bias',
           'tracker', 'tracker_only_gyro', 'tracking', 'write_rest_only_model']

CHOICES = ('model', 'on', 'off')  # the node's rest_bias parameter, process-bag's option
WIDE_CLIP_DEG_S = 10.0  # a clip that finds a turn-on bias of any MEMS gyro's size
AMBIGUOUS_CLIP_FRACTION = 0.5  # a rest bias this far out in its clip may be a slow turn
# the tracker-only row's settings where neither crossval nor the model chose any: the
# sigma and forgetting BROAD's sessions choose (docs/results.md), started at that sigma and
# never held; the start and the hold are what crossval chooses per recipe
CLASSICAL_TRACKING = BiasTracking(0.05, 30.0, 0.05)
FAST_WINDOW_S = 0.1  # the gyro's mean norm over this is compared with a hold bound
# the bound crossval offers each tracking candidate (found on BROAD's fast trials, run 45
# of docs/experiments.md: beyond it VQF's own attitude takes the gyro's scale error)
HOLD_ABOVE_DEG_S = 400.0


def estimator(settings: RestBiasSettings, rate_hz: float) -> VQF:
    """Return a VQF that estimates the rest bias less the prior, alone, started at 0."""
    vqf = VQF(1.0 / rate_hz, motionBiasEstEnabled=False, restBiasEstEnabled=True,
              restMinT=settings.rest_min_s, restFilterTau=settings.filter_tau_s,
              restThGyr=settings.gyro_threshold_deg_s,
              restThAcc=settings.accel_threshold_m_s2, biasClip=settings.bias_clip_deg_s)
    vqf.setBiasEstimate(np.zeros(3), settings.prior_sigma_rad_s)
    return vqf


def _checked(choice: str) -> str:
    """Return the node's rest_bias choice, or raise ValueError naming the three."""
    if choice not in CHOICES:
        raise ValueError(f'rest_bias {choice!r}: must be one of {", ".join(CHOICES)}')
    return choice


def resolve(meta: ModelMeta, choice: str) -> RestBiasSettings | None:
    """
    Return the settings to run with, given ``model``, ``on`` or ``off``.

    ``model``: the model file's (None for a model trained on the raw gyro); ``on``: the
    model file's, or the defaults with a prior of 0 for a model that has none; ``off``:
    None, the raw gyro into the model whatever it was trained on.
    """
    stored = meta.rest_bias
    if _checked(choice) == 'off' or (choice == 'model' and stored is None):
        return None
    return stored or RestBiasSettings()


def tracker(settings: BiasTracking, rate_hz: float) -> VQF:
    """Return a VQF that tracks a model output's bias at rest and in motion, from 0."""
    return VQF(1.0 / rate_hz, motionBiasEstEnabled=True, restBiasEstEnabled=True,
               biasSigmaMotion=settings.sigma_motion_deg_s,
               biasForgettingTime=settings.forgetting_s,
               biasSigmaInit=settings.sigma_init_deg_s)


def tracking(meta: ModelMeta, choice: str) -> BiasTracking | None:
    """Return the model file's bias tracking, unless ``choice`` (as :func:`resolve`) is off."""
    return None if _checked(choice) == 'off' else meta.bias_tracking


def _fast_window(rate_hz: float) -> int:
    """Return the samples in FAST_WINDOW_S (one at least), per sample and over arrays alike."""
    return max(1, round(FAST_WINDOW_S * rate_hz))


class FastRotation:
    """
    Whether a gyro's mean norm over the last FAST_WINDOW_S reaches a bound, sample by sample.

    The running sum takes each new norm less the one leaving the window, in the order
    :func:`fast_rotation` sums them over arrays, so that the two agree bit for bit.
    """

    def __init__(self, bound_deg_s: float, rate_hz: float) -> None:
        self._n = _fast_window(rate_hz)
        self._bound = math.radians(bound_deg_s)
        self.reset()

    def reset(self) -> None:
        """Forget the rates seen (a new run)."""
        self._norms = [0.0] * self._n  # a list: its floats cost less per sample than numpy's
        self._seen = 0
        self._sum = 0.0

    def update(self, gyro: np.ndarray) -> bool:
        """Take one sample (rad/s); return whether the window up to it turns that fast."""
        x, y, z = float(gyro[0]), float(gyro[1]), float(gyro[2])
        norm = math.sqrt(x * x + y * y + z * z)
        i = self._seen % self._n
        self._sum += norm - self._norms[i]
        self._norms[i] = norm
        self._seen += 1
        return bool(self._sum >= self._bound * min(self._seen, self._n))


def fast_rotation(gyro: np.ndarray, rate_hz: float, bound_deg_s: float) -> np.ndarray:
    """Return :class:`FastRotation` (N,) of a gyro (N, 3) rad/s over a whole run."""
    n = _fast_window(rate_hz)
    norm = np.sqrt(gyro[:, 0] * gyro[:, 0] + gyro[:, 1] * gyro[:, 1] + gyro[:, 2] * gyro[:, 2])
    leaving = np.concatenate([np.zeros(min(n, len(norm))), norm[:max(len(norm) - n, 0)]])
    count = np.minimum(np.arange(1, len(norm) + 1), n)
    return np.cumsum(norm - leaving) >= math.radians(bound_deg_s) * count


class BiasTracker:
    """The tracked bias of a model's output (fed that output), one sample at a time."""

    _start = staticmethod(tracker)  # the VQF as a run starts: from a bias of 0

    def __init__(self, settings: BiasTracking | RestBiasSettings, rate_hz: float) -> None:
        self.settings = settings
        self._rate_hz = rate_hz
        self._gyro = np.zeros(3)
        self._accel = np.zeros(3)
        bound = settings.hold_above_deg_s if isinstance(settings, BiasTracking) else None
        self._fast = None if bound is None else FastRotation(bound, rate_hz)
        self.reset()

    def reset(self) -> None:
        """Start again (a new run: another power-on, a bag loop)."""
        self._vqf = self._start(self.settings, self._rate_hz)
        self._held: tuple[np.ndarray, np.ndarray] | None = None
        if self._fast is not None:
            self._fast.reset()

    def update(self, gyro: np.ndarray, accel: np.ndarray, hold: bool = False) -> np.ndarray:
        """
        Take one sample (rad/s, m/s^2); return the bias to remove at it (3,).

        That is the estimate after it, or, with ``hold`` (this sample is within a held
        stretch) or where it turns faster than the settings' hold bound, the estimate
        from before the stretch, to which the estimate and its covariance are restored at
        the first sample after it (:func:`tracked_bias`).
        """
        self._gyro[:] = gyro
        if self._fast is not None:
            hold = self._fast.update(self._gyro) or hold
        if hold != (self._held is not None):
            self._held = _hold(self._vqf, self._held)
        self._accel[:] = accel
        self._vqf.update(self._gyro, self._accel)
        return self._vqf.getBiasEstimate()[0] if self._held is None else self._held[0]

    def estimate(self) -> tuple[np.ndarray, float]:
        """Return the current bias (3,) and its standard deviation, both rad/s."""
        bias, sigma = self._vqf.getBiasEstimate()
        return bias, float(sigma)

    @property
    def held(self) -> bool:
        """Whether the last sample was within a held stretch (its estimate from before)."""
        return self._held is not None


class RestBias(BiasTracker):
    """The turn-on bias one sample at a time (the node, process-bag), and the rest seen."""

    _start = staticmethod(estimator)  # from the prior (an offset of 0), at rest only

    def __init__(self, settings: RestBiasSettings, rate_hz: float) -> None:
        self._prior = np.array(settings.prior_rad_s, dtype=float)
        super().__init__(settings, rate_hz)
        self.still_samples = 0  # samples detected still since the last reset

    def reset(self) -> None:
        """Start again from the prior (a new run: another power-on)."""
        super().reset()
        self.still_samples = 0

    def restart(self) -> None:
        """
        Look for stillness afresh (its filters restarted), from the estimate found so far.

        Its certainty is that of a start: where the jump was a new power-on after all (a
        driver restarted), the next stillness moves it as fast as it moves the prior.
        """
        found, _ = _hold(self._vqf, None)
        super().reset()
        _, fresh = _hold(self._vqf, None)
        _hold(self._vqf, (found, fresh))

    def update(self, gyro: np.ndarray, accel: np.ndarray) -> np.ndarray:
        """Take one sample (rad/s, m/s^2); return the bias estimate after it (3,)."""
        np.subtract(gyro, self._prior, out=self._gyro)
        self._accel[:] = accel
        self._vqf.update(self._gyro, self._accel)
        self.still_samples += bool(self._vqf.getRestDetected())
        return self._vqf.getBiasEstimate()[0] + self._prior

    def estimate(self) -> tuple[np.ndarray, float]:
        """Return the current bias (3,) and its standard deviation, both rad/s."""
        offset, sigma = self._vqf.getBiasEstimate()
        return offset + self._prior, float(sigma)

    @property
    def offset_deg_s(self) -> float:
        """Return the estimate's largest distance from the prior on any axis, deg/s."""
        return float(np.degrees(np.abs(self._vqf.getBiasEstimate()[0]).max()))

    @property
    def ambiguous(self) -> bool:
        """
        Whether the stillness found may have been a steady turn: over half the clip away.

        Within the clip a still IMU with that bias and a turn about gravity at that rate
        look alike to VQF's rest detection; near the prior the two differ by little.
        """
        return bool(self.still_samples) and (
            self.offset_deg_s > AMBIGUOUS_CLIP_FRACTION * self.settings.bias_clip_deg_s)

    @property
    def seconds_still(self) -> float:
        """Seconds of detected stillness since the last reset."""
        return self.still_samples / self._rate_hz


def _hold(vqf: VQF, held: tuple[np.ndarray, np.ndarray] | None
          ) -> tuple[np.ndarray, np.ndarray] | None:
    """Begin a hold (None: return the estimate and covariance) or end one (restore them)."""
    state = vqf.state
    if held is None:
        return state['bias'].copy(), state['biasP'].copy()
    state['bias'], state['biasP'] = held
    vqf.state = state
    return None


def tracked_bias(gyro: np.ndarray, accel: np.ndarray, rate_hz: float,
                 settings: BiasTracking, hold: np.ndarray | None = None) -> np.ndarray:
    """
    Return the tracked bias (N, 3) to remove from a model's output (N, 3) at each sample.

    ``hold`` (N,): held stretches, and where the gyro turns faster than the settings'
    hold bound (:func:`fast_rotation`). The tracker runs through them (its orientation
    goes on), and at the first sample after each its bias estimate and covariance are
    restored to those from before it: what it learnt there is forgotten (not what it
    learns after, from an orientation the stretch may have moved); through a stretch the
    bias removed is the one from before it.
    """
    vqf = tracker(settings, rate_hz)
    gyro, accel = (np.ascontiguousarray(a, dtype=float) for a in (gyro, accel))
    hold = np.zeros(len(gyro), bool) if hold is None else hold
    if settings.hold_above_deg_s is not None:
        hold = hold | fast_rotation(gyro, rate_hz, settings.hold_above_deg_s)
    ends = np.append(np.flatnonzero(np.diff(hold)) + 1, len(gyro)) if len(gyro) else []
    bias, held, start = np.empty_like(gyro), None, 0
    for end in ends:
        if hold[start] != (held is not None):
            held = _hold(vqf, held)
        estimate = vqf.updateBatch(gyro[start:end], accel[start:end])['bias']
        bias[start:end] = estimate if held is None else held[0]
        start = end
    return bias


def track_bias(gyro: np.ndarray, accel: np.ndarray, rate_hz: float,
               settings: BiasTracking | None, hold: np.ndarray | None = None) -> np.ndarray:
    """Return a model's output (N, 3) less its :func:`tracked_bias` (None: as is)."""
    if settings is None or not len(gyro):
        return gyro
    return gyro - tracked_bias(gyro, accel, rate_hz, settings, hold)


def rest_bias_batch(imu: np.ndarray, rate_hz: float, settings: RestBiasSettings
                    ) -> dict[str, np.ndarray]:
    """
    Run the estimator over a recording (N, 6): ``bias`` (N, 3), ``sigma`` (N,), ``rest``.

    Equal to :meth:`RestBias.update` sample by sample (one C++ update, the same order).
    """
    prior = np.array(settings.prior_rad_s, dtype=float)
    out = estimator(settings, rate_hz).updateBatch(
        np.ascontiguousarray(np.asarray(imu[:, :3], dtype=float) - prior),
        np.ascontiguousarray(imu[:, 3:], dtype=float))
    return {'bias': out['bias'] + prior, 'sigma': out['biasSigma'],
            'rest': out['restDetected'].astype(bool)}


def remove_rest_bias(imu: np.ndarray, rate_hz: float, settings: RestBiasSettings | None
                     ) -> np.ndarray:
    """Return ``imu`` with each gyro sample less the estimate at it (a copy; None: as is)."""
    if settings is None:
        return imu
    out = np.array(imu, dtype=np.float64)
    out[:, :3] -= rest_bias_batch(imu, rate_hz, settings)['bias']
    return out


def baseline_settings(meta: ModelMeta) -> RestBiasSettings:
    """
    Return the estimator of the "rest bias" baseline rows of ``eval`` and ``crossval``.

    The model's own settings and prior where it was trained with them; else the defaults
    with a prior of 0 and the wide clip, so that an IMU whose turn-on bias exceeds VQF's
    2 deg/s (EuRoC's ADIS16448: 4.6 deg/s about z) is still measured at rest: a baseline
    as strong as averaging the still start, not the node's cautious ``rest_bias:=on``.
    """
    return meta.rest_bias or RestBiasSettings(bias_clip_deg_s=WIDE_CLIP_DEG_S)


def baseline_gyro(loaded: Described, imu: np.ndarray) -> np.ndarray:
    """Return the "rest bias" row's gyro (N, 3): the raw gyro less its turn-on bias."""
    return remove_rest_bias(imu, sample_rate(loaded), baseline_settings(loaded.meta))[:, :3]


def classical_tracking(meta: ModelMeta) -> BiasTracking | None:
    """
    Return the tracking of the "tracker only" rows: the classical pipeline, no model.

    What ``crossval`` chose for that row (stored with its verdict; None: none), else the
    classical pipeline the network is blended with, else the model's own output tracking
    (the same tracker, no model before it), else CLASSICAL_TRACKING.
    """
    chosen = ((meta.crossval.report.get('tracking') or {}).get('chosen') or {}
              if meta.crossval is not None else {})
    if TRACKER_ONLY in chosen:
        stored = chosen[TRACKER_ONLY]
        try:
            return None if stored is None else tracking_from_dict(stored)
        except (AttributeError, ValueError) as err:
            raise ModelFileError(f'inconsistent crossval.tracking.chosen.{TRACKER_ONLY} '
                                 f'({err})') from err
    if meta.blend is not None:
        return meta.blend.tracking
    return meta.bias_tracking or CLASSICAL_TRACKING


def tracker_only_gyro(loaded: Described, imu: np.ndarray) -> np.ndarray:
    """Return the "tracker only" row's gyro (N, 3): the rest-bias row's, its bias tracked."""
    return track_bias(baseline_gyro(loaded, imu), imu[:, 3:], sample_rate(loaded),
                      classical_tracking(loaded.meta))


class Nominal(NamedTuple):
    """The training recordings' turn-on biases: their mean, how many, their spread."""

    prior_rad_s: tuple[float, float, float] | None  # None: no recording was still
    still: int            # recordings still at some point
    spread_rad_s: float   # the largest per-axis standard deviation among them (0: < 2)


def nominal_bias(imus: Iterable[np.ndarray], rate_hz: float,
                 settings: RestBiasSettings) -> Nominal:
    """
    Return the mean rest bias of recordings, how many were still, and their spread.

    Each recording's figure is the estimate at its last still sample (prior-free: VQF's
    own start of 0); recordings never still give none.
    """
    start = replace(settings, prior_rad_s=(0.0, 0.0, 0.0),
                    prior_sigma_rad_s=RestBiasSettings.prior_sigma_rad_s)
    found = []
    for imu in imus:
        est = rest_bias_batch(imu, rate_hz, start)
        if est['rest'].any():
            found.append(est['bias'][np.flatnonzero(est['rest'])[-1]])
    if not found:
        return Nominal(None, 0, 0.0)
    mean = np.mean(found, axis=0)
    return Nominal((float(mean[0]), float(mean[1]), float(mean[2])), len(found),
                   float(np.std(found, axis=0).max()) if len(found) > 1 else 0.0)


def write_rest_only_model(like: ModelFile, path: str | Path,
                          tracking: BiasTracking | None = None,
                          fusion: dict[str, Any] | None = None) -> None:
    """
    Write a model file that removes the turn-on bias and corrects nothing else.

    What ``crossval`` recommends where no learnt correction beats the raw gyro less its
    turn-on bias (``deploy: rest bias``): the identity (a calibration with Δ = 0 and no
    bias) fed the gyro less the estimate, with ``like``'s rate, estimator settings and
    prior, recordings, recipe and cross-recording report, so that every tool runs it as
    any model (the node, ``process-bag``, ``eval``, ``tune-fusion``). With ``tracking``,
    the classical pipeline (``deploy: tracker only``): the bias left tracked after it;
    ``fusion``, its ``imu/data`` filter (a model file's ``fusion`` entry).
    """
    settings = like.meta.rest_bias
    if settings is None:
        raise ModelFileError(f'{like.path}: not trained with rest_bias: it has no turn-on '
                             'bias estimator (settings and prior) to run alone')
    config = ModelConfig(gyro_std=like.config.gyro_std, calibration_only=True)
    arrays = {'input_mean': np.zeros(6, np.float32), 'input_std': np.ones(6, np.float32),
              'gyro_std': np.array(config.gyro_std, np.float32),
              'delta': np.zeros((3, 3), np.float32), 'bias': np.zeros(3, np.float32)}
    keep = ('dataset', 'sample_rate_hz', 'train_sequences', 'train_config', 'crossval')
    meta = {k: like.meta.raw[k] for k in keep if k in like.meta.raw}
    meta.update(kind=REST_ONLY if tracking is None else TRACKER_ONLY,
                rest_bias=settings.to_dict(), made_from=like.path.name,
                code_version=code_version())
    if tracking is not None:
        meta['bias_tracking'] = tracking.as_dict()
    if fusion is not None:
        meta['fusion'] = fusion
    write_model_file(path, config, arrays, meta)
