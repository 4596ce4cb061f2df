# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The model file's metadata as typed records, parsed and checked once when a file is read.

A model file is user input: every entry a tool computes with is checked here, with one
policy (a malformed entry is a :class:`~denoise_imu_ros.core.errors.ModelFileError` that
names the file and the entry; an absent one is ``None`` or the documented default), so
that no tool meets a string where it expects a rate. The stored JSON is kept whole in
:attr:`ModelMeta.raw`: writing a file again copies it along, entries this version does
not know included.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields
import math
from typing import Any, Callable

from .errors import ModelFileError
from .limits import MAX_RATE_HZ

__all__ = ['ACCEL_CHOICES', 'AS_IT_CAME', 'BiasTracking', 'Blend', 'Fusion', 'FusionSettings',
           'InputEnvelope', 'JUDGED', 'judged_on', 'MAX_ACCEL_BIAS_M_S2', 'ModelMeta', 'NO_MODEL',
           'parse_meta', 'REST_ONLY', 'RestBiasSettings', 'SampleVariance', 'TRACKER_ONLY',
           'tracking_from_dict', 'Validation', 'VARIANCE_KEYS', 'Verdict',
           'VQF_BIAS_SIGMA_INIT_DEG_S']

REST_ONLY = 'rest bias'  # the ``kind`` of a model file that removes the turn-on bias alone
# the ``kind`` of a model file that runs the classical pipeline, no model: the turn-on bias
# removed, then the remaining bias tracked at rest and in motion (its ``bias_tracking``)
TRACKER_ONLY = 'tracker only'
NO_MODEL = (REST_ONLY, TRACKER_ONLY)  # kinds whose file corrects nothing itself
MAX_ACCEL_BIAS_M_S2 = 2.0  # a larger "bias" is a wrong fit or a wrong unit, not an IMU's
DEPLOY_CHOICES = ('network', 'calibration', TRACKER_ONLY, REST_ONLY, 'none')
# the accelerometer imu/corrected carries: less the bias fitted on the training poses, or
# as it came where that bias did not carry to unseen recordings (crossval's verdict)
AS_IT_CAME = 'as it came'
ACCEL_CHOICES = ('bias removed', AS_IT_CAME)
JUDGED = {'aoe_deg': 'AOE', 'tilt_deg': 'tilt error'}  # figures a verdict compares, named
CROSSVAL_CHOICE = 'crossval: '  # how a choice's ``chosen_on`` starts where crossval made it


def judged_on(heading_weight: float, who: str = 'the verdict') -> tuple[str, str | None]:
    """
    Return the figure ``who`` compares (a key of JUDGED) and, if not the AOE, why.

    A recipe that leaves the poses' heading out of its loss or lowers its weight
    (``heading_weight`` below 1; ``init-recipe`` writes 0 for a VIO's) does not trust
    their rotation about the vertical: over a whole held-out recording the AOE against
    them is then mostly their own heading drift, which a model that learnt less of it
    cannot share. Their tilt, which gravity holds, still judges.
    """
    if heading_weight >= 1:
        return 'aoe_deg', None
    return 'tilt_deg', (f"the recipe does not trust the poses' heading (heading_weight "
                        f'{heading_weight:g}), so neither does {who}: the heading is '
                        'not judged')


def _number(v: Any) -> bool:
    """Say whether ``v`` is a finite JSON number; a bool is not one."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _triple(v: Any, minimum: float = -math.inf) -> bool:
    return isinstance(v, (list, tuple)) and len(v) == 3 and all(
        _number(x) and x >= minimum for x in v)


@dataclass(frozen=True)
class RestBiasSettings:
    """
    The stillness detector and the estimate's start, as VQF's parameters name them.

    The time constants were chosen on BROAD's session-B trials (docs/method.md):
    0.5 s of stillness and a 0.25 s low-pass start the estimate earlier than VQF's
    defaults (1.5 s, 0.5 s), which lowered the open-loop error of the rest-bias gyro;
    the gyro and accelerometer thresholds are VQF's. ``bias_clip_deg_s`` bounds the
    estimate's distance from the prior, and so what counts as still: a gyro level further
    from the prior than that is a steady turn, never a bias. The accelerometer cannot tell
    a still IMU from a steady turn about gravity: the gyro's level against the prior is
    what can, and a turn within the clip of it stays ambiguous (said in ``/diagnostics``).
    """

    rest_min_s: float = 0.5               # stillness lasting this long is rest
    filter_tau_s: float = 0.25            # low-pass of the rest detector and estimate
    gyro_threshold_deg_s: float = 2.0     # gyro deviation from its low-pass
    accel_threshold_m_s2: float = 0.5     # accelerometer deviation from its low-pass
    bias_clip_deg_s: float = 2.0          # largest distance from the prior; beyond: motion
    prior_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0)  # the estimate before rest
    prior_sigma_rad_s: float = math.radians(0.5)  # its standard deviation (VQF's default)

    def to_dict(self) -> dict[str, Any]:
        """Return the settings as the model file stores them (JSON types)."""
        return dict(asdict(self), prior_rad_s=list(self.prior_rad_s))

    @classmethod
    def from_dict(cls, value: Any, where: str) -> RestBiasSettings:
        """Read stored settings; anything malformed is a ModelFileError naming ``where``."""
        names = {f.name for f in fields(cls)}
        if not isinstance(value, dict) or not set(value) <= names:
            raise ModelFileError(f'{where}: rest_bias {value!r} is not a mapping of '
                                 f'{", ".join(sorted(names))}')
        prior = value.get('prior_rad_s', [0.0] * 3)
        scalars = [v for k, v in value.items() if k != 'prior_rad_s']
        if not (_triple(prior) and all(_number(v) for v in scalars)):
            raise ModelFileError(f'{where}: rest_bias {value!r} holds a value that is not a '
                                 'finite number (prior_rad_s: three)')
        settings = cls(**dict(value, prior_rad_s=tuple(float(v) for v in prior)))
        if min(settings.rest_min_s, settings.filter_tau_s, settings.gyro_threshold_deg_s,
               settings.accel_threshold_m_s2, settings.bias_clip_deg_s,
               settings.prior_sigma_rad_s) <= 0:
            raise ModelFileError(f'{where}: rest_bias {value!r}: its thresholds, time '
                                 'constants and prior_sigma_rad_s must be positive')
        if settings.bias_clip_deg_s > MAX_BIAS_CLIP_DEG_S:
            raise ModelFileError(f'{where}: rest_bias.bias_clip_deg_s '
                                 f'{settings.bias_clip_deg_s:g} is beyond any MEMS gyro turn-on '
                                 f'bias (at most {MAX_BIAS_CLIP_DEG_S:g} deg/s)')
        if max(map(abs, settings.prior_rad_s)) > math.radians(MAX_BIAS_CLIP_DEG_S):
            raise ModelFileError(f'{where}: rest_bias.prior_rad_s {list(settings.prior_rad_s)} '
                                 f'is beyond any MEMS gyro turn-on bias (at most '
                                 f'{MAX_BIAS_CLIP_DEG_S:g} deg/s = '
                                 f'{math.radians(MAX_BIAS_CLIP_DEG_S):.4g} rad/s): '
                                 'written in deg/s?')
        return settings


# the largest turn-on bias (and clip about the prior) a model file may hold: consumer MEMS
# gyros are specified at a few to 20 deg/s of zero-rate offset
MAX_BIAS_CLIP_DEG_S = 60.0
VQF_BIAS_SIGMA_INIT_DEG_S = 0.5  # VQF's biasSigmaInit default, for a raw gyro


@dataclass(frozen=True)
class BiasTracking:
    """
    The bias left in the model's output, tracked at rest and in motion (VQF's estimators).

    What a turn-on bias removed at the start does not catch (a session's bias in motion
    off its bias at rest, a network's constant error on an unseen recording) VQF
    estimates from the accelerometer's tilt corrections while moving and from the gyro
    while still; ``crossval`` chooses its settings (VQF's two, and whether to hold through
    fast rotation) and its start, or none, on recordings its folds never trained on.
    """

    sigma_motion_deg_s: float  # VQF's biasSigmaMotion: smaller trusts motion updates more
    forgetting_s: float        # VQF's biasForgettingTime: how long an estimate is kept
    # VQF's biasSigmaInit, its certainty of the 0 it starts from; a file without the key
    # runs with VQF's default, as its tracking was chosen
    sigma_init_deg_s: float = VQF_BIAS_SIGMA_INIT_DEG_S
    # the estimate held where the gyro it tracks turns at least this fast (its mean norm
    # over the last 0.1 s): there VQF's own attitude takes the gyro's scale error, which its
    # motion estimate would read as a bias; None (a file without the key): never held
    hold_above_deg_s: float | None = None

    def __post_init__(self) -> None:
        """Refuse settings VQF cannot run with (model files are user input)."""
        for name in ('sigma_motion_deg_s', 'forgetting_s', 'sigma_init_deg_s',
                     'hold_above_deg_s'):
            value = getattr(self, name)
            if name == 'hold_above_deg_s' and value is None:
                continue
            if not (_number(value) and 0 < value < 1e6):
                raise ValueError(f'{name} must be a positive number, not {value!r}')

    def as_dict(self) -> dict[str, float]:
        """Return the settings as stored in a model file (never held: no key, as before it)."""
        stored = asdict(self)
        if self.hold_above_deg_s is None:
            del stored['hold_above_deg_s']
        return stored

    def describe(self) -> str:
        """Say the settings in words (reports, the node's log); the start where not sigma."""
        held = ('' if self.hold_above_deg_s is None
                else f', held above {self.hold_above_deg_s:g} deg/s')
        init = self.sigma_init_deg_s
        started = '' if init == self.sigma_motion_deg_s else f', started at {init:g} deg/s'
        return (f'sigma {self.sigma_motion_deg_s:g} deg/s, forgetting {self.forgetting_s:g} s'
                f'{held}{started}')


@dataclass(frozen=True)
class InputEnvelope:
    """
    How far the model's training input went, so that it is not trusted beyond.

    The largest gyro norm and the largest distance of the accelerometer norm from gravity
    over its training recordings. A network fed motion faster than any it was trained on
    extrapolates (BROAD: networks of a slow session fail on another session's fast
    trials); where a sample of its receptive field leaves the envelope, the output is
    its input gyro plus a constant correction instead (``pipeline/envelope.py``).
    """

    gyro_rad_s: float           # the largest |gyro| trained on
    accel_offset_m_s2: float    # the largest | |accel| - g | trained on
    # rad/s added to the input gyro outside: the model's mean correction over its
    # training recordings, 0 where the turn-on bias is removed before the model
    fallback_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    # the largest mean | |accel| - g | over any 1 s of its training recordings, whole
    # (pipeline/envelope.py: sustained_bound); None in a file without it
    sustained_accel_m_s2: float | None = None

    def __post_init__(self) -> None:
        """Refuse bounds that are not positive numbers (model files are user input)."""
        for name in ('gyro_rad_s', 'accel_offset_m_s2', 'sustained_accel_m_s2'):
            value = getattr(self, name)
            if name == 'sustained_accel_m_s2' and value is None:
                continue
            if not (_number(value) and 0 < value < 1e6):
                raise ValueError(f'{name} must be a positive number, not {value!r}')
        if not (_triple(self.fallback_rad_s) and max(map(abs, self.fallback_rad_s)) <= 1.0):
            raise ValueError(f'fallback_rad_s must be three numbers of at most 1 rad/s, not '
                             f'{self.fallback_rad_s!r}')
        object.__setattr__(self, 'fallback_rad_s', tuple(map(float, self.fallback_rad_s)))

    def as_dict(self) -> dict[str, Any]:
        """Return the bounds as stored in a model file."""
        return {**asdict(self), 'fallback_rad_s': list(self.fallback_rad_s)}


@dataclass(frozen=True)
class Blend:
    """
    The network's output N blended with the classical pipeline's T: T + weight (N - T).

    T is the model's input gyro (the raw gyro less its turn-on bias) less the bias
    ``tracking`` finds in it (None: untracked), as the "tracker only" row; ``crossval``
    chooses the weight on held-out recordings (``pipeline/blend.py``).
    """

    weight: float                   # 1: the network's output, 0: the classical pipeline's
    tracking: BiasTracking | None   # the classical pipeline's

    def __post_init__(self) -> None:
        """Refuse a weight outside 0 ... 1 (model files are user input)."""
        if not (_number(self.weight) and 0 <= self.weight <= 1):
            raise ValueError(f'weight must be a number from 0 to 1, not {self.weight!r}')
        object.__setattr__(self, 'weight', float(self.weight))

    def as_dict(self) -> dict[str, Any]:
        """Return the blend as stored in a model file."""
        return {'weight': self.weight,
                'tracking': None if self.tracking is None else self.tracking.as_dict()}


def _accel_bias(bias: Any) -> tuple[float, float, float]:
    """Return an accelerometer bias as floats, or refuse what no IMU's bias is."""
    if not (_triple(bias) and all(abs(b) <= MAX_ACCEL_BIAS_M_S2 for b in bias)):
        raise ValueError(f'accel_bias_m_s2 must be three numbers within '
                         f'±{MAX_ACCEL_BIAS_M_S2:g} m/s^2, not {bias!r}')
    return tuple(float(b) for b in bias)


@dataclass(frozen=True)
class SampleVariance:
    """
    A corrected sensor's variance per sample, the same on each axis: exp(theta . phi).

    phi: 1, then log1p(m / scale) of three causal means m over ``mean_s`` seconds: of the
    rate's norm (rad/s), of the accelerometer norm's distance from gravity (m/s^2) and of
    the rate's change per second (rad/s^2), each over its ``scales`` entry
    (``pipeline/covariance.py``). ``fit-variance`` fits the gyro's theta by the likelihood
    of the rotation increments' errors on the validation tails, the accelerometer's by
    that of the velocity increments' ((rad/s)^2 and (m/s^2)^2). The accelerometer's says
    which accelerometer it describes: the one less ``accel_bias_m_s2`` (None for the gyro).
    """

    theta: tuple[float, float, float, float]
    mean_s: float = 0.1
    scales: tuple[float, float, float] = (0.1, 0.5, 1.0)
    accel_bias_m_s2: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        """Refuse what no variance model is (model files are user input)."""
        theta = self.theta
        if not (isinstance(theta, (list, tuple)) and len(theta) == 4
                and all(_number(v) and abs(v) < 100 for v in theta)):
            raise ValueError(f'theta must be four numbers, not {theta!r}')
        if not (_number(self.mean_s) and 0 < self.mean_s <= 10):
            raise ValueError(f'mean_s must be a number of seconds from 0 to 10, not '
                             f'{self.mean_s!r}')
        if not (_triple(self.scales) and min(self.scales) > 0):
            raise ValueError(f'scales must be three positive numbers, not {self.scales!r}')
        object.__setattr__(self, 'theta', tuple(map(float, theta)))
        object.__setattr__(self, 'mean_s', float(self.mean_s))
        object.__setattr__(self, 'scales', tuple(map(float, self.scales)))
        if self.accel_bias_m_s2 is not None:
            object.__setattr__(self, 'accel_bias_m_s2', _accel_bias(self.accel_bias_m_s2))

    def as_dict(self) -> dict[str, Any]:
        """Return the variance model as stored in a model file."""
        found = {'theta': list(self.theta), 'mean_s': self.mean_s, 'scales': list(self.scales)}
        if self.accel_bias_m_s2 is not None:
            found['accel_bias_m_s2'] = list(self.accel_bias_m_s2)
        return found


@dataclass(frozen=True)
class FusionSettings:
    """The filter's choices; defaults are VQF's own time constant, no bias removed or estimated."""

    tau_acc_s: float = 3.0         # accelerometer time constant: longer trusts the gyro more
    bias_estimation: bool = False  # VQF's rest and motion gyro-bias estimators
    accel_bias_m_s2: tuple[float, float, float] = (0.0, 0.0, 0.0)  # removed before the filter
    classical_tilt: bool = False   # the tilt of VQF's defaults on the raw IMU, this one's heading

    def __post_init__(self) -> None:
        """Refuse settings the filter cannot run with (model files are user input)."""
        if not (_number(self.tau_acc_s) and 0 < self.tau_acc_s < 1e6):
            raise ValueError(f'tau_acc_s must be a positive number of seconds, '
                             f'not {self.tau_acc_s!r}')
        for name in ('bias_estimation', 'classical_tilt'):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f'{name} must be true or false, not {getattr(self, name)!r}')
        object.__setattr__(self, 'accel_bias_m_s2', _accel_bias(self.accel_bias_m_s2))

    def as_dict(self) -> dict[str, Any]:
        """Return the settings as stored in a model file."""
        return dict(asdict(self), accel_bias_m_s2=list(self.accel_bias_m_s2))


@dataclass(frozen=True)
class Validation:
    """Figures of the selected weights on the training recordings' validation tails."""

    step: int | None = None
    loss: float | None = None
    aoe_mean_deg: float | None = None
    gyro_residual_std: tuple[float, float, float] | None = None  # rad/s, per sample


@dataclass(frozen=True)
class Fusion:
    """What ``tune-fusion`` stored: ``imu/data``'s filter, its error, every filter's settings."""

    settings: FusionSettings | None = None                    # None: the filter's defaults
    orientation_std_rad: tuple[float, float, float] | None = None  # the fused error, per axis
    filters: dict[str, dict[str, Any]] = field(default_factory=dict)  # "<gyro> <filter>"
    by_crossval: bool = False  # chosen on another power-on's trials, not the validation tails

    @property
    def chosen(self) -> FusionSettings:
        """Return the settings ``imu/data`` runs with: the stored ones, else the defaults."""
        return self.settings or FusionSettings()


def fusion_metadata(report: dict[str, Any], row: str, meta: ModelMeta
                    ) -> dict[str, Any] | None:
    """
    Return the ``fusion`` entry of ``meta``'s file for ``row`` with a report's filter (None: none).

    Only where the folds leave a power-on out (``--sessions``): there the validation tails
    ``tune-fusion`` chooses on cannot see what a new power-on changes; elsewhere its choice
    stands. The file's own entry (as ``tune-fusion`` stored it: the other filters' settings)
    with the filter the folds chose for ``row``; where they chose the accelerometer less its
    training bias, that bias is the file's (fitted on its training poses).
    """
    try:
        chosen = (report.get('fusion') or {}).get('chosen', {}).get(row)
        if chosen is None or 'session' not in str(report.get('fold_kind', '')):
            return None
        bias = meta.fusion.chosen.accel_bias_m_s2
        settings = FusionSettings(chosen['tau_acc_s'], chosen['bias_estimation'],
                                  bias if chosen['accel_bias_removed'] else (0.0,) * 3,
                                  chosen.get('classical_tilt', False))
        std = chosen['orientation_std_rad']
        if not _triple(std, 0.0):
            raise ValueError(f'orientation_std_rad {std!r}')
        return dict(meta.raw.get('fusion') or {}, settings=settings.as_dict(),
                    orientation_std_rad=list(std),
                    chosen_on=CROSSVAL_CHOICE + report['fusion']['chosen_on'],
                    scored='held-out recordings whole; yaw aligned once 1.5 s in, tilt never')
    except (AttributeError, KeyError, TypeError, ValueError) as err:
        raise ModelFileError(f'inconsistent crossval.fusion.chosen.{row} ({err})') from err


@dataclass(frozen=True)
class Verdict:
    """The cross-recording report (``crossval --attach``): what to deploy and why."""

    deploy: str | None              # one of DEPLOY_CHOICES; None in a report that chose none
    verdict: str                    # its one sentence
    mean_deg: dict[str, float]      # row ("raw", "calibrated", ...) -> mean judged figure
    judged_on: str                  # that figure: "aoe_deg", or "tilt_deg" (heading untrusted)
    held_out: tuple[str, ...]       # every recording a fold held out
    steps: int | None               # how long the folds trained
    train_config: dict[str, Any]    # the folds' recipe
    report: dict[str, Any]          # the whole report, as stored
    # whether the accelerometer's bias fitted on training recordings carries to unseen ones
    # (ACCEL_CHOICES); None: not judged (a report before it)
    accel_deploy: str | None = None


@dataclass(frozen=True)
class ModelMeta:
    """A model file's metadata: typed entries the tools use, and everything as stored."""

    raw: dict[str, Any]
    sample_rate_hz: float | None = None
    dataset: str | None = None
    kind: str | None = None                     # REST_ONLY, else the architecture says
    train_sequences: tuple[str, ...] = ()
    train_config: dict[str, Any] = field(default_factory=dict)  # the recipe, as trained
    data: str | None = None                     # the folder it was trained from
    validation: Validation = Validation()
    fusion: Fusion = Fusion()
    crossval: Verdict | None = None
    rest_bias: RestBiasSettings | None = None   # None: the model is fed the raw gyro
    bias_tracking: BiasTracking | None = None   # None: the model's output as it is
    input_envelope: InputEnvelope | None = None  # None: the correction applies everywhere
    blend: Blend | None = None                  # None: the network's output unblended
    gyro_variance: SampleVariance | None = None   # None: one covariance for every message
    accel_variance: SampleVariance | None = None  # None: the input's covariance passed on
    code_version: str | None = None
    members: int = 0                            # an ensemble's trainings; 0 for one

    @property
    def training_span(self) -> int | None:
        """
        How many samples of each training recording the network was fitted on, or None.

        The recipe draws its windows from the first ``window + max_offset`` samples of
        every training recording; what follows is its validation tail. None when the file
        does not say, or when it drew windows from whole recordings (``whole_sequences``:
        no sample of them is unseen).
        """
        cfg = self.train_config
        if 'window' not in cfg or cfg.get('whole_sequences'):
            return None
        return int(cfg['window']) + int(cfg.get('max_offset', 0))

    def recipe(self, key: str, default: Any = None) -> Any:
        """Return one entry of the training recipe, ``default`` where it has none."""
        return self.train_config.get(key, default)

    @property
    def heading_weight(self) -> float:
        """Return the recipe's ``heading_weight``: 1 (the heading taught) where it has none."""
        weight = self.recipe('heading_weight', 1.0)
        return float(weight) if _number(weight) else 1.0


def _fail(where: str, key: str, value: Any, what: str) -> ModelFileError:
    return ModelFileError(f'{where}: inconsistent model file ({key} {value!r} is not {what})')


def _mapping(raw: dict[str, Any], key: str, where: str) -> dict[str, Any]:
    value = raw.get(key)
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise _fail(where, key, value, 'a mapping')
    return value


def _optional(raw: dict[str, Any], key: str, where: str, kind: type | tuple[type, ...],
              what: str) -> Any:
    value = raw.get(key)
    if value is not None and (not isinstance(value, kind) or isinstance(value, bool)):
        raise _fail(where, key, value, what)
    return value


def _validation(raw: dict[str, Any], where: str) -> Validation:
    value = _mapping(raw, 'validation', where)
    std = value.get('gyro_residual_std')
    if std is not None and not _triple(std, 0.0):
        raise _fail(where, 'validation.gyro_residual_std', std, 'three non-negative numbers')
    for key in ('step', 'loss', 'aoe_mean_deg'):
        if value.get(key) is not None and not _number(value[key]):
            raise _fail(where, f'validation.{key}', value[key], 'a number')
    return Validation(step=value.get('step'), loss=value.get('loss'),
                      aoe_mean_deg=value.get('aoe_mean_deg'),
                      gyro_residual_std=None if std is None else tuple(float(v) for v in std))


def _fusion(raw: dict[str, Any], where: str) -> Fusion:
    value = _mapping(raw, 'fusion', where)
    settings = value.get('settings')
    if settings is not None:
        if not isinstance(settings, dict):
            raise _fail(where, 'fusion.settings', settings, 'a mapping')
        try:
            settings = FusionSettings(**settings)
        except (TypeError, ValueError) as err:
            raise ModelFileError(f'{where}: inconsistent fusion settings ({err})') from err
    std = value.get('orientation_std_rad')
    if std is not None and not _triple(std, 0.0):
        raise _fail(where, 'fusion.orientation_std_rad', std, 'three non-negative numbers')
    filters = value.get('filters') or {}
    if not (isinstance(filters, dict) and all(isinstance(v, dict) for v in filters.values())):
        raise _fail(where, 'fusion.filters', filters, 'a mapping of filter settings')
    return Fusion(settings, None if std is None else tuple(float(v) for v in std), filters,
                  str(value.get('chosen_on', '')).startswith(CROSSVAL_CHOICE))


def _verdict(raw: dict[str, Any], where: str) -> Verdict | None:
    report = raw.get('crossval')
    if report is None:
        return None
    if not isinstance(report, dict):
        raise _fail(where, 'crossval', report, 'a mapping')
    deploy = report.get('deploy')
    if deploy is not None and deploy not in DEPLOY_CHOICES:
        raise _fail(where, 'crossval.deploy', deploy, f'one of {", ".join(DEPLOY_CHOICES)}')
    mean = report.get('mean') or {}
    if not isinstance(mean, dict):
        raise _fail(where, 'crossval.mean', mean, 'a mapping of rows')
    key = report.get('judged_on', 'aoe_deg')
    if not isinstance(key, str) or key not in JUDGED:
        raise _fail(where, 'crossval.judged_on', key, f'one of {", ".join(JUDGED)}')
    figures = {row: float(v[key]) for row, v in mean.items()
               if isinstance(v, dict) and _number(v.get(key))}
    folds = report.get('folds') or []
    if not (isinstance(folds, list) and all(isinstance(f, list) for f in folds)):
        raise _fail(where, 'crossval.folds', folds, 'a list of recording lists')
    steps = report.get('steps')
    if steps is not None and not _number(steps):
        raise _fail(where, 'crossval.steps', steps, 'a number')
    cfg = report.get('train_config') or {}
    if not isinstance(cfg, dict):
        raise _fail(where, 'crossval.train_config', cfg, 'a mapping')
    accel = report.get('accelerometer')
    if accel is not None and not (isinstance(accel, dict)
                                  and accel.get('deploy') in ACCEL_CHOICES):
        raise _fail(where, 'crossval.accelerometer', accel,
                    f'a mapping whose deploy is one of {", ".join(ACCEL_CHOICES)}')
    return Verdict(deploy, str(report.get('verdict', '')), figures, key,
                   tuple(str(n) for fold in folds for n in fold), steps, cfg, report,
                   None if accel is None else accel['deploy'])


def _settings(raw: dict[str, Any], key: str, where: str,
              build: Callable[[dict[str, Any]], Any], known: set[str]) -> Any:
    """
    Return ``build`` of a mapping entry (None where absent); its errors name the entry.

    A key outside ``known`` is refused: a misspelt setting would otherwise be ignored.
    """
    value = raw.get(key)
    if value is None:
        return None
    if not isinstance(value, dict):
        raise _fail(where, key, value, 'a mapping')
    unknown = sorted(set(value) - known, key=str)
    if unknown:
        raise ModelFileError(f'{where}: {key} has unknown entries {unknown} (known: '
                             f'{", ".join(sorted(known))})')
    try:
        return build(value)
    except ValueError as err:
        raise ModelFileError(f'{where}: inconsistent {key} ({err})') from err


def tracking_from_dict(v: dict[str, Any]) -> BiasTracking:
    """Return the tracking a model file stores (``as_dict``); ValueError where inconsistent."""
    return BiasTracking(v.get('sigma_motion_deg_s'), v.get('forgetting_s'),
                        v.get('sigma_init_deg_s', VQF_BIAS_SIGMA_INIT_DEG_S),
                        v.get('hold_above_deg_s'))


TRACKING_KEYS = {f.name for f in fields(BiasTracking)} | {'label', 'chosen_on'}


def _blend(v: dict[str, Any]) -> Blend:
    tracking = v.get('tracking')
    if tracking is not None and not (isinstance(tracking, dict)
                                     and set(tracking) <= TRACKING_KEYS):
        raise ValueError(f'tracking must be a mapping of {", ".join(sorted(TRACKING_KEYS))} '
                         f'or null, not {tracking!r}')
    return Blend(v.get('weight'), None if tracking is None else tracking_from_dict(tracking))


VARIANCE_KEYS = {'theta', 'mean_s', 'scales', 'accel_bias_m_s2', 'fitted_on',
                 'reference_noise_deg', 'reference_noise_m_s', 'nees', 'held_out'}


def _variance(v: dict[str, Any]) -> SampleVariance:
    return SampleVariance(v.get('theta'), v.get('mean_s', 0.1), v.get('scales', (0.1, 0.5, 1.0)),
                          v.get('accel_bias_m_s2'))


def _accel_variance(raw: dict[str, Any], where: str, gyro: SampleVariance | None
                    ) -> SampleVariance | None:
    """Return the accelerometer's variance model: on the gyro's features, so beside it."""
    accel = _settings(raw, 'accel_variance', where, _variance, VARIANCE_KEYS)
    if accel is not None and (gyro is None or (accel.mean_s, accel.scales)
                              != (gyro.mean_s, gyro.scales)):
        raise ModelFileError(f'{where}: accel_variance needs a gyro_variance of the same '
                             'mean_s and scales: both are computed from one set of features')
    if accel is not None and accel.accel_bias_m_s2 is None:
        raise ModelFileError(f'{where}: accel_variance needs its accel_bias_m_s2: which '
                             'accelerometer it was fitted on')
    return accel


def parse_meta(raw: dict[str, Any], where: str) -> ModelMeta:
    """Return the typed metadata of a model file's entries; ``where`` names it in errors."""
    rate = raw.get('sample_rate_hz')
    if rate is not None and not (_number(rate) and 0 < rate <= MAX_RATE_HZ):
        raise _fail(where, 'sample_rate_hz', rate, f'a rate from 0 to {MAX_RATE_HZ:g} Hz')
    names = raw.get('train_sequences') or []
    if not (isinstance(names, list) and all(isinstance(n, str) for n in names)):
        raise _fail(where, 'train_sequences', names, 'a list of recording names')
    kind = _optional(raw, 'kind', where, str, 'a model kind')
    rest = raw.get('rest_bias')
    recipe = _mapping(raw, 'train_config', where)
    for key in ('window', 'max_offset'):  # the training span every report uses
        if key in recipe and not (isinstance(recipe[key], int) and not isinstance(
                recipe[key], bool) and recipe[key] >= 0):
            raise _fail(where, f'train_config.{key}', recipe[key], 'a number of samples')
    members = raw.get('members') or []
    if not isinstance(members, list):
        raise _fail(where, 'members', members, 'a list')
    gyro_variance = _settings(raw, 'gyro_variance', where, _variance, VARIANCE_KEYS)
    return ModelMeta(
        raw=raw,
        sample_rate_hz=None if rate is None else float(rate),
        dataset=_optional(raw, 'dataset', where, str, 'a dataset name'),
        kind=kind,
        train_sequences=tuple(names),
        train_config=recipe,
        data=_optional(_mapping(raw, 'run', where), 'data', where, str, 'a folder'),
        validation=_validation(raw, where),
        fusion=_fusion(raw, where),
        crossval=_verdict(raw, where),
        rest_bias=None if rest is None else RestBiasSettings.from_dict(rest, where),
        bias_tracking=_settings(raw, 'bias_tracking', where, tracking_from_dict, TRACKING_KEYS),
        blend=_settings(raw, 'blend', where, _blend, {'weight', 'tracking', 'label',
                                                      'chosen_on'}),
        input_envelope=_settings(raw, 'input_envelope', where, lambda v: InputEnvelope(
            v.get('gyro_rad_s'), v.get('accel_offset_m_s2'),
            v.get('fallback_rad_s', (0.0, 0.0, 0.0)), v.get('sustained_accel_m_s2')),
            {f.name for f in fields(InputEnvelope)}),
        gyro_variance=gyro_variance,
        accel_variance=_accel_variance(raw, where, gyro_variance),
        code_version=_optional(raw, 'code_version', where, str, 'a version'),
        members=len(members))
