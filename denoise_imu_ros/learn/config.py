# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The training recipe without torch: ``TrainConfig``, its YAML file and every check of it.

``init-recipe`` writes recipes from these defaults and ``train`` reads them; neither
needs torch to know what a recipe may hold. Whether a device exists is checked where
the training starts (:func:`denoise_imu_ros.learn.train.resolve_device`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields
import math
import os
from pathlib import Path
import re
from typing import Any, Callable

import yaml

from ..core.architecture import ModelConfig
from ..core.errors import TrainingError

RUN_KEYS = ('data', 'threads', 'workers', 'device', 'fused')  # how it runs, not what it learns
OPTIONS = ('seed', 'data', 'steps', 'workers', 'device')  # keys train's options override
DEVICE = re.compile(r'cpu|cuda(:\d+)?')             # the devices training supports
AUTO = 'auto'                                         # workers and threads: from the machine


class _RecipeLoader(yaml.SafeLoader):
    """PyYAML's safe loader, reading ``1e-3`` as YAML 1.2 does: a float (1.1: a string)."""


_RecipeLoader.add_implicit_resolver(
    'tag:yaml.org,2002:float', re.compile(r'^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$'),
    list('-+0123456789.'))


@dataclass(frozen=True)
class LossConfig:
    """Reference values: Huber 0.005 rad, scale 1e6, L16 + 0.5 * L32, skip 5 blocks."""

    huber_delta: float = 0.005   # rad, Huber threshold per log component
    scale: float = 1e6           # keeps losses O(1) for the optimiser
    increments: tuple[int, ...] = (16, 32)  # samples per increment, powers of two, rising
    weights: tuple[float, ...] = (1.0, 0.5)  # per increment length (the reference code's)
    skip_blocks: int = 5         # first blocks of a window are warm-up (padded input)
    heading_weight: float = 1.0  # scales each error's component about the poses' vertical
    between_poses: bool = False  # increments from pose stamp to pose stamp (sparse poses)

    def __post_init__(self) -> None:
        """Check the increments and their weights (user input through the training recipe)."""
        j = self.increments
        if (len(self.weights) != len(j) or not j
                or any(n < 1 or n & (n - 1) for n in j) or sorted(set(j)) != list(j)):
            raise ValueError('increments must be rising powers of two, one weight each')
        if not all(math.isfinite(w) and w > 0 for w in self.weights):
            # a negative weight rewards error, a zero one learns nothing from its length
            raise ValueError(f'increment_weights must be positive, not {list(self.weights)}')

    @property
    def span(self) -> int:
        """Return the longest increment (samples): windows must be a multiple of it."""
        return self.increments[-1]


@dataclass
class TrainConfig:
    """
    Everything a training run depends on.

    The recipe (all but RUN_KEYS) is stored in the model file; the run environment (the
    local data folder, threads, workers, device, fused layers) is stored apart, as how it
    was made.
    """

    dataset: str = 'euroc'             # name of the data family (picks eval baselines)
    data: str = '../shared/data/euroc'  # folder holding the sequences (or bags)
    sequences: list[str] = field(default_factory=list)  # ASL folders or bags in `data`
    imu_topic: str | None = None       # bags only; None = the only Imu topic
    pose_topic: str | None = None      # bags only; None = the only pose topic
    # a folder of trajectories, <recording>.txt (.tum, .csv), as VIO/SLAM tools write them
    # (data.trajectory), whose poses replace the recordings' own; None: the recordings' poses
    poses: str | None = None
    # ground-truth holes longer than this (s) are masked; None: 2.5 of its own periods
    max_gt_gap_s: float | None = None
    # poses onto the IMU clock and frame: none, auto (estimated per recording, as
    # check-data does) or {time_offset_s: s, imu_from_pose_rotation_xyzw: [x, y, z, w]}
    align: str | dict = 'none'
    gyro_std_deg: list[float] = field(default_factory=lambda: [1.0, 2.0, 5.0])  # sigma_g
    dropout: float = 0.1
    calibration_only: bool = False     # the 12-parameter "calibrated IMU" baseline
    # True: the model's input gyro is each recording's own gyro less its turn-on bias,
    # estimated causally from stillness (pipeline/rest_bias.py), in training and wherever
    # the model runs; what is learnt then holds across power-ons
    rest_bias: bool = False
    # True (with rest_bias): each training recording has its own constant gyro bias, learnt
    # beside the model and not stored in it, and the model's constant terms are held at 0:
    # what stays constant within a recording but differs between them (the turn-on bias
    # estimate's error in motion, a VIO's drift) is not learnt as the gyro's
    recording_bias: bool = False
    # False: the network sees the gyro only (the accelerometer's channels normalised to 0),
    # so what it learns depends on the rotation rate alone (scale, misalignment,
    # non-linearity), never on gravity or on how hard the IMU accelerates
    accel_input: bool = True
    steps: int = 1800                  # one step = one batch of every sequence
    lr: float = 0.01                   # Adam
    weight_decay: float = 0.1          # L2 added to the gradient (not AdamW)
    lr_min: float = 1e-3               # cosine annealing floor
    restart_period: int = 600          # first cosine cycle (steps)
    restart_mult: int = 2              # each cycle this many times longer
    window: int = 16000                # training samples per sequence (80 s at 200 Hz)
    max_offset: int = 32               # window start drawn in [0, max_offset)
    # True: draw each window anywhere in its whole sequence instead (more data, but the
    # validation tails are then training data and validation figures are in-sample).
    whole_sequences: bool = False
    gyro_noise: float = 8e-5           # rad/s, white noise added to the gyro input
    accel_noise: float = 1e-3          # m/s^2
    gyro_bias: float = 1e-3            # rad/s, uniform +- per sequence and step
    accel_bias: float = 1e-3           # m/s^2
    # True: the gyro bias drawn above stays in what the loss compares with the poses, so the
    # network learns to pass a constant offset through to the output's bias tracker rather
    # than guess from a window a constant that no window shows (the next power-on's)
    gyro_bias_kept: bool = False
    huber_delta: float = 0.005         # rad
    increments: list[int] = field(default_factory=lambda: [16, 32])  # loss increments
    increment_weights: list[float] = field(default_factory=lambda: [1.0, 0.5])
    skip_blocks: int = 5               # warm-up blocks left out of the training loss
    # below 1: each increment's error about the poses' vertical (their world's z, gravity)
    # counts less than its tilt: for poses whose heading drifts (a VIO's yaw is not
    # observable) while their tilt is held by gravity
    heading_weight: float = 1.0
    # True: each increment runs from a pose's stamp to a later pose's (the nearest IMU
    # samples), not on a fixed grid with the poses interpolated: for poses too sparse for
    # the motion (check-data's too_sparse: a SLAM's keyframes)
    increments_between_poses: bool = False
    val_every: int = 100               # steps between validations (and at the end)
    swa_start: int = 0                 # > 0: average weights from this step on (SWA)
    select: str = 'best_validation'    # kept: best_validation (of all candidates), final, swa
    seed: int = 0
    threads: int = 2                   # torch intra-op threads, shared by the workers
    workers: int = 1                   # data-parallel processes (parallel.py), CPU only
    device: str | None = None          # cpu or cuda[:N]; None: cuda when available
    # True: each hidden block's BatchNorm, GELU and dropout in one compiled call on the CPU
    # (learn/fused.py; the same function); False: PyTorch's layers one by one
    fused: bool = True

    def model_config(self) -> ModelConfig:
        """Return the network this recipe trains."""
        return ModelConfig(gyro_std=tuple(math.radians(d) for d in self.gyro_std_deg),
                           dropout=self.dropout, calibration_only=self.calibration_only)

    def loss_config(self) -> LossConfig:
        """Return the loss constants of this recipe."""
        return LossConfig(huber_delta=self.huber_delta, increments=tuple(self.increments),
                          weights=tuple(self.increment_weights), skip_blocks=self.skip_blocks,
                          heading_weight=self.heading_weight,
                          between_poses=self.increments_between_poses)

    def recipe(self) -> dict[str, Any]:
        """Return what the model learns from: every key but the run environment."""
        return {k: v for k, v in asdict(self).items() if k not in RUN_KEYS}

    def run_environment(self) -> dict[str, Any]:
        """Return where and how this run was made (data folder, threads, workers, ...)."""
        return {k: getattr(self, k) for k in RUN_KEYS}


# Allowed range of each numeric recipe key: (lowest, highest, whether lowest is allowed).
RANGES = {
    'steps': (1, None, True), 'lr': (0, None, False), 'weight_decay': (0, None, True),
    'lr_min': (0, None, True), 'restart_period': (1, None, True),
    'restart_mult': (1, None, True), 'window': (1, None, True), 'max_offset': (1, None, True),
    'gyro_noise': (0, None, True), 'accel_noise': (0, None, True),
    'gyro_bias': (0, None, True), 'accel_bias': (0, None, True),
    'huber_delta': (0, None, False), 'skip_blocks': (0, None, True),
    'heading_weight': (0, None, True),
    'val_every': (1, None, True), 'swa_start': (0, None, True), 'threads': (1, None, True),
    'workers': (1, None, True), 'dropout': (0, 1, True), 'max_gt_gap_s': (0, None, False),
    'seed': (0, 2 ** 32, True),  # numpy's seeds, and torch's
}


def _is(value: Any, kind: str) -> bool:
    """Whether a YAML value fits a TrainConfig annotation (bool is not a number here)."""
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    checks = {
        'str': isinstance(value, str), 'bool': isinstance(value, bool),
        'int': isinstance(value, int) and not isinstance(value, bool),
        'float': number and math.isfinite(value),
        'list[str]': isinstance(value, list) and all(isinstance(v, str) for v in value),
        'list[int]': isinstance(value, list) and all(_is(v, 'int') for v in value),
        'list[float]': isinstance(value, list) and all(_is(v, 'float') for v in value),
        'dict': isinstance(value, dict),
    }
    return any(value is None if k == 'None' else checks[k] for k in kind.split(' | '))


def _alignment(value: Any) -> bool:
    """
    Whether a recipe's ``align`` mapping is one offset and frame for every recording.

    Within a minute: poses on another clock each have their own offset (``align: auto``).
    """
    if not isinstance(value, dict) or set(value) != {'time_offset_s',
                                                     'imu_from_pose_rotation_xyzw'}:
        return False
    offset, quat = value['time_offset_s'], value['imu_from_pose_rotation_xyzw']
    return (_is(offset, 'float') and abs(offset) <= 60.0 and isinstance(quat, list)
            and len(quat) == 4 and all(_is(q, 'float') for q in quat)
            and abs(math.hypot(*quat) - 1.0) < 1e-3)


def usable_cores() -> int:
    """CPU cores this process may run on (its affinity, which containers narrow)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def machine_share(recordings: int, cores: int) -> tuple[int, int]:
    """
    Data-parallel workers and torch threads in all (``workers: auto``, ``threads: auto``).

    A worker holds whole recordings, so a step lasts as long as the busiest worker's
    share: the fewest workers that give it the fewest recordings (six recordings on four
    cores: three workers of two, not four of two, two, one and one), every core a thread.
    """
    recordings, cores = max(1, recordings), max(1, cores)
    busiest = -(-recordings // min(cores, recordings))
    workers = -(-recordings // busiest)
    return workers, max(workers, cores)


def load_config(path: str | Path, **overrides: Any) -> TrainConfig:
    """
    Read a YAML recipe and check every value's type and range.

    Unknown keys are errors (a typo must not train silently), and so are values of the
    wrong type (``steps: 3.7``, ``calibration_only: "no"``) or out of range.
    """
    raw = _read(path)
    given = {k: v for k, v in overrides.items() if v is not None}
    raw.update(given)
    if AUTO in (raw.get('workers'), raw.get('threads')):
        recordings = raw.get('sequences')
        share = machine_share(len(recordings) if isinstance(recordings, list) else 1,
                              usable_cores())
        for key, value in zip(('workers', 'threads'), share):
            if raw.get(key) == AUTO:
                raw[key] = value

    def source(key: str) -> str:
        """Where a value came from: the command line's option, or the file."""
        return f'--{key.replace("_", "-")}' if key in given and key in OPTIONS else str(path)
    _check_values(raw, source)
    if 'gyro_std_deg' in raw and (len(raw['gyro_std_deg']) != 3
                                  or min(raw['gyro_std_deg']) <= 0):
        raise TrainingError(f'{path}: gyro_std_deg must be three positive values (deg/s)')
    cfg = TrainConfig(**raw)
    _check_recipe(cfg, path, source)
    cfg.workers = min(cfg.workers, len(cfg.sequences))  # each worker needs a sequence
    if cfg.swa_start > cfg.steps and 'steps' in given and 'swa_start' not in given:
        raise TrainingError(f"--steps {cfg.steps}: ends before the recipe's swa_start "
                            f'{cfg.swa_start} (its weight average starts there): give more '
                            'steps, or train a copy of the recipe with a lower swa_start')
    if cfg.swa_start > cfg.steps:
        raise TrainingError(f'{path}: swa_start {cfg.swa_start} is after the last step '
                            f'{cfg.steps}')
    return cfg


def _read(path: str | Path) -> dict[str, Any]:
    """Return a recipe file's mapping; unreadable YAML, a non-mapping, unknown keys refused."""
    try:
        raw = yaml.load(Path(path).read_text(encoding='utf-8'), Loader=_RecipeLoader)
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as err:
        raise TrainingError(f'{path}: cannot read training config '
                            f'({" ".join(str(err).split())})') from err
    raw = {} if raw is None else raw
    if not isinstance(raw, dict):
        raise TrainingError(f'{path}: a training config is a mapping of keys, '
                            f'not {type(raw).__name__}')
    unknown = sorted(set(map(str, raw)) - {f.name for f in fields(TrainConfig)})
    if unknown:
        raise TrainingError(f'{path}: unknown keys {unknown}')
    return raw


def _check_values(raw: dict[str, Any], source: Callable[[str], str]) -> None:
    """Refuse a value of the wrong type or out of its range, naming where it came from."""
    types = {f.name: f.type for f in fields(TrainConfig)}
    for key, value in raw.items():
        if not _is(value, types[key]):
            raise TrainingError(f'{source(key)}: {key} must be {types[key]}, not {value!r}')
        if key in RANGES and value is not None:
            low, high, closed = RANGES[key]
            if value < low or (value == low and not closed) or (
                    high is not None and value >= high):
                bound = ('at least' if closed else 'above') + f' {low}'
                bound += f' and below {high}' if high is not None else ''
                raise TrainingError(f'{source(key)}: {key} must be {bound}, not {value!r}')


def _check_recipe(cfg: TrainConfig, path: str | Path, source: Callable[[str], str]) -> None:
    """Refuse values that are each valid but do not go together (a recipe that cannot run)."""
    try:
        span = cfg.loss_config().span
    except ValueError as err:
        raise TrainingError(f'{path}: {err}') from err
    if cfg.window % span:
        raise TrainingError(f'{path}: window must be a multiple of {span}')
    longest = max(cfg.increments)
    if cfg.skip_blocks >= cfg.window // longest:  # the loss would drop every such block
        raise TrainingError(f'{path}: skip_blocks {cfg.skip_blocks} leaves no '
                            f'{longest}-sample increment of a {cfg.window}-sample window '
                            f'(at most {cfg.window // longest - 1})')
    if not cfg.sequences:
        raise TrainingError(f'{path}: no training sequences')
    repeated = sorted({s for s in cfg.sequences if cfg.sequences.count(s) > 1})
    if repeated:  # it would weigh that recording twice, and fold it against itself
        raise TrainingError(f'{path}: sequences listed more than once: {repeated}')
    if cfg.lr_min > cfg.lr:  # the cosine schedule would raise the rate above lr
        raise TrainingError(f'{source("lr_min")}: lr_min {cfg.lr_min:g} is above lr '
                            f'{cfg.lr:g}')
    if not (cfg.align in ('none', 'auto') or _alignment(cfg.align)):
        raise TrainingError(f'{path}: align must be none, auto or a mapping with '
                            'time_offset_s (seconds, at most 60 either way) and '
                            'imu_from_pose_rotation_xyzw (a unit quaternion)')
    if cfg.recording_bias and not cfg.rest_bias:
        raise TrainingError(f'{path}: recording_bias needs rest_bias: without it nothing '
                            "would remove the gyro's constant bias where the model runs")
    if cfg.device is not None and not DEVICE.fullmatch(cfg.device):
        raise TrainingError(f'device {cfg.device!r}: not a torch device (use cpu or cuda)')
    if cfg.select not in ('best_validation', 'final', 'swa') or (
            cfg.select == 'swa' and cfg.swa_start <= 0):
        raise TrainingError(f'{path}: select must be best_validation, final or swa '
                            '(swa needs swa_start > 0)')
