# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Model files: one ``.safetensors`` per model, loadable without pickle.

The tensors are the model's state dict (weights, BatchNorm statistics, input
normalisation, gyro_std, Delta); the safetensors header metadata holds JSON strings
that make the file self-describing: architecture, sample rate, receptive field,
training recipe and sequences, validation figures and the code version.

Reading and writing need numpy only: the online runtime reads a model file with
:func:`read_model_file`; :mod:`denoise_imu_ros.learn.checkpoint` builds the torch module
on top, for training and batch evaluation.
"""

from __future__ import annotations

from dataclasses import asdict
import json
import math
import os
from pathlib import Path
import subprocess
from typing import Any, NamedTuple, Protocol

import numpy as np
from safetensors import safe_open, SafetensorError
from safetensors.numpy import load_file, save_file

from .architecture import ModelConfig
from .atomic import atomic_output
from .errors import ModelFileError, OutputError
from .limits import MAX_RATE_HZ
from .. import __version__

FORMAT = 'denoise_imu_ros.gyro_model'
FORMAT_VERSION = 1
SHIPPED_DIR = Path(__file__).parents[1] / 'models'
REST_ONLY = 'rest bias'  # the ``kind`` of a model file that removes the turn-on bias alone


class ModelFile(NamedTuple):
    """A model file's contents as numpy arrays: enough for the streaming engine."""

    config: ModelConfig
    arrays: dict[str, np.ndarray]  # the state dict
    meta: dict[str, Any]
    path: Path


class Described(Protocol):
    """Anything read from a model file: its metadata and where it came from."""

    meta: dict[str, Any]
    path: Path


def sample_rate(loaded: Described) -> float:
    """IMU rate (Hz) the model was trained at; online use needs it."""
    rate = loaded.meta.get('sample_rate_hz')
    if not isinstance(rate, (int, float)) or not rate > 0:
        raise ModelFileError(f'{loaded.path}: model file has no valid sample rate')
    return float(rate)


def gyro_covariance(loaded: Described, stddev: float = -1.0) -> list[float]:
    """
    Row-major 3x3 angular_velocity_covariance for corrected gyro messages.

    Diagonal, from ``stddev`` (rad/s) when >= 0, else from the per-axis residual std the
    model measured on its validation data (zero if the file has none).
    """
    std = (loaded.meta.get('validation') or {}).get('gyro_residual_std', [0.0] * 3)
    std = [stddev] * 3 if stddev >= 0 else [float(v) for v in std]
    return [std[i] ** 2 if i == j else 0.0 for i in range(3) for j in range(3)]


def deployment_warning(loaded: ModelFile) -> str | None:
    """
    Why this model should not be deployed, from its cross-recording validation, or None.

    The stored report names what did best on unseen recordings (the network, the
    calibration, the turn-on bias alone or no correction); a model of another kind still
    runs (benchmarks and comparisons need it) but says so. None when it is the kind
    recommended, or when the file has no report (``crossval --attach`` stores one).
    """
    report = loaded.meta.get('crossval')
    deploy = report.get('deploy') if isinstance(report, dict) else None
    kind = (REST_ONLY if loaded.meta.get('kind') == REST_ONLY else
            'calibration' if loaded.config.calibration_only else 'network')
    if deploy not in ('network', 'calibration', 'rest bias', 'none') or deploy == kind:
        return None
    rows = {'network': 'network', 'calibration': 'calibrated', REST_ONLY: 'rest bias',
            'none': 'raw'}
    mean = report.get('mean') if isinstance(report.get('mean'), dict) else {}
    own, best = (mean.get(rows[k]) for k in (kind, deploy))
    figures = [r.get('aoe_deg') if isinstance(r, dict) else None for r in (own, best)]
    label = {'none': 'no correction'}.get(deploy, deploy)
    said = (f' ({kind} {figures[0]:.2f}° against {label} {figures[1]:.2f}° in mean AOE on '
            'unseen recordings)' if all(isinstance(f, (int, float)) for f in figures) else '')
    return (f'{loaded.path.name} is a {kind} model, but the cross-recording validation of '
            f'its recipe says{said}: {report.get("verdict")}')


def training_span(meta: dict[str, Any]) -> int | None:
    """
    Return how many samples of each training recording the network was fitted on, or None.

    The recipe draws its windows from the first ``window + max_offset`` samples of every
    training recording; what follows is its validation tail. None when the file does not
    say (an older or hand-made file), or when it drew windows from whole recordings
    (``whole_sequences``: no sample of them is unseen).
    """
    cfg = meta.get('train_config')
    if not isinstance(cfg, dict) or 'window' not in cfg or cfg.get('whole_sequences'):
        return None
    return int(cfg['window']) + int(cfg.get('max_offset', 0))


def scored_on_training_samples(meta: dict[str, Any], names: list[str],
                               start_sample: int) -> list[str]:
    """
    Which of ``names`` are training recordings of this model scored on its training span.

    Figures there measure the fit, not what a robot will see: a report says so.
    """
    trained = {Path(str(n)).name for n in meta.get('train_sequences') or []}
    span = training_span(meta)
    return [n for n in names if Path(n).name in trained
            and (span is None or start_sample < span)]


def fitting_note(names: list[str], span: int | None) -> str:
    """Say that figures on a model's own training samples measure its fit."""
    which = ', '.join(Path(n).name for n in names)
    verb = 'was' if len(names) == 1 else 'were'
    if span is None:
        return (f'{which} {verb} used to train this model: these figures include that fit, '
                'not only what unseen recordings will show')
    return (f'{which} {verb} used to train this model (samples 0-{span - 1}): these '
            'whole-recording figures include that fit; --start-sample '
            f'{span} scores only the unseen tail')


def shipped_models() -> list[str]:
    """Names accepted by ``--model`` besides paths."""
    return sorted(p.stem for p in SHIPPED_DIR.glob('*.safetensors'))


def code_version(package: Path = Path(__file__).resolve().parents[1]) -> str:
    """
    Package version, plus the git commit when the package runs from its own checkout.

    The commit is recorded only when git tracks this package's own files there: an
    installed copy (a colcon workspace's install/ inside another repository) records the
    version alone, not the commit of whatever repository holds it; ``.dirty`` marks
    changes to the package not committed.
    """
    def git(*args: str) -> str:
        return subprocess.run(['git', *args], cwd=package, capture_output=True, text=True,
                              timeout=5, check=True).stdout.strip()
    try:
        git('ls-files', '--error-unmatch', '__init__.py')
        rev = git('rev-parse', '--short', 'HEAD')
        dirty = git('status', '--porcelain', '--untracked-files=no', '--', '.')
    except (OSError, subprocess.SubprocessError):
        return __version__
    return f'{__version__}+g{rev}' + ('.dirty' if dirty else '')


def write_model_file(path: str | Path, config: ModelConfig, arrays: dict[str, np.ndarray],
                     meta: dict[str, Any]) -> None:
    """Write a model file, under a temporary name renamed on success (never half-written)."""
    header = {'format': FORMAT, 'format_version': str(FORMAT_VERSION),
              'model_config': json.dumps(asdict(config)),
              'receptive_field': str(config.receptive_field)}
    # the architecture written is the model's own, whatever metadata was copied along
    header.update({k: json.dumps(v) for k, v in meta.items() if k not in header})
    try:
        with atomic_output(path, overwrite=True) as tmp:
            save_file({k: np.asarray(v, order='C') for k, v in arrays.items()}, str(tmp),
                      metadata=header)
            tmp.chmod(0o644)  # a shared artefact, not a secret
    except SafetensorError as err:  # its own I/O error: a full disk, a read-only folder
        raise OutputError(f'{path}: cannot write the model file ({err})') from err


def check_attachable(spec: str | Path, option: str = '--attach') -> Path:
    """
    Return the model file ``spec`` names if figures may be stored in it, else refuse.

    A shipped model is the installed package's, shared by every user of the install: it
    is never rewritten (copy it and attach to the copy). Checked before the work that
    produces the figures, so that none is lost.
    """
    path = resolve(spec)
    if path.resolve().parent == SHIPPED_DIR.resolve():
        raise ModelFileError(f'{option} {spec}: a shipped model, shared by every user of '
                             'this install, is never rewritten: copy it and attach to the copy')
    if not (os.access(path, os.W_OK) and os.access(path.parent, os.W_OK)):
        raise ModelFileError(f'{option} {spec}: not writable here (the file or its folder)')
    return path


def add_metadata(path: str | Path, **meta: Any) -> None:
    """
    Add or replace metadata entries of an existing model file (weights untouched).

    Used to store figures measured after training (cross-recording validation). The file
    is rewritten under a temporary name and renamed, so a failure leaves it intact.
    Shipped models are refused (:func:`check_attachable`).
    """
    mf = read_model_file(check_attachable(path))
    write_model_file(mf.path, mf.config, mf.arrays, dict(mf.meta, **meta))


def resolve(spec: str | Path) -> Path:
    """Find a shipped model by name (``euroc``, ``tumvi``, ...) or a model file by path."""
    shipped = SHIPPED_DIR / f'{spec}.safetensors'
    if str(spec) in shipped_models():
        return shipped
    path = Path(spec)
    if not path.is_file():
        raise ModelFileError(f'{spec}: no such model file, and not a shipped model '
                             f'({", ".join(shipped_models()) or "none shipped"})')
    return path


def read_model_file(spec: str | Path) -> ModelFile:
    """Read and check a model file with numpy alone; every failure is ModelFileError."""
    path = resolve(spec)
    try:
        with open(path, 'rb') as f:
            head = f.read(8)
        if len(head) < 8:
            raise ModelFileError(f'{path}: not a model file (too short)')
        with safe_open(str(path), framework='np') as f:
            header = f.metadata() or {}
        arrays = load_file(str(path))
    except (SafetensorError, OSError, ValueError) as err:
        raise ModelFileError(f'{path}: corrupt or not a model file ({err})') from err
    if header.get('format') != FORMAT:
        raise ModelFileError(f'{path}: not a {FORMAT} file')
    if header.get('format_version') != str(FORMAT_VERSION):
        raise ModelFileError(f'{path}: model format version {header.get("format_version")}, '
                             f'this code reads version {FORMAT_VERSION}')
    try:
        cfg = json.loads(header['model_config'])
        config = ModelConfig(**{k: tuple(v) if isinstance(v, list) else v
                                for k, v in cfg.items()})
        meta = {k: json.loads(v) for k, v in header.items()
                if k not in ('format', 'format_version')}
    except (KeyError, TypeError, ValueError, AttributeError) as err:
        raise ModelFileError(f'{path}: inconsistent model file ({err})') from err
    shapes = {k: tuple(v.shape) for k, v in arrays.items()}
    if shapes != config.state_shapes():
        wrong = sorted(set(shapes.items()) ^ set(config.state_shapes().items()))
        raise ModelFileError(f'{path}: inconsistent model file (weights do not match its '
                             f'architecture: {wrong[0][0]})')
    if not all(np.isfinite(v).all() for v in arrays.values()):
        raise ModelFileError(f'{path}: model file holds non-finite weights')
    if not (arrays['input_std'] > 0).all():
        raise ModelFileError(f'{path}: model file has a non-positive input_std')
    if not all((v >= 0).all() for k, v in arrays.items() if k.endswith('.running_var')):
        raise ModelFileError(f'{path}: model file has a negative BatchNorm variance')
    _check_meta(meta, path)
    return ModelFile(config, arrays, meta, path)


def _check_meta(meta: dict[str, Any], path: Path) -> None:
    """Refuse metadata the tools would compute with: a rate, the residual std."""
    def number(v: Any) -> bool:
        return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)

    rate = meta.get('sample_rate_hz')
    if rate is not None and not (number(rate) and 0 < rate <= MAX_RATE_HZ):
        raise ModelFileError(f'{path}: inconsistent model file (sample_rate_hz {rate!r} is '
                             f'not a rate from 0 to {MAX_RATE_HZ:g} Hz)')
    for key in ('train_config', 'validation'):
        if meta.get(key) is not None and not isinstance(meta[key], dict):
            raise ModelFileError(f'{path}: inconsistent model file ({key} {meta[key]!r} is '
                                 'not a mapping)')
    validation = meta.get('validation') or {}
    std = validation.get('gyro_residual_std', [])
    if 'gyro_residual_std' in validation and not (
            isinstance(std, list) and len(std) == 3 and all(number(v) and v >= 0
                                                            for v in std)):
        raise ModelFileError(f'{path}: inconsistent model file (validation.gyro_residual_std '
                             f'{std!r} is not three non-negative numbers)')
