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
import hashlib
import json
import os
from pathlib import Path
from typing import Any, NamedTuple, Protocol

import numpy as np
from safetensors import safe_open, SafetensorError
from safetensors.numpy import load_file, save_file

from .architecture import ModelConfig
from .atomic import atomic_output
from .errors import ModelFileError, OutputError
from .schema import ModelMeta, parse_meta
from .. import __version__

FORMAT = 'denoise_imu_ros.gyro_model'
FORMAT_VERSION = 1
SHIPPED_DIR = Path(__file__).parents[1] / 'models'


class ModelFile(NamedTuple):
    """A model file's contents as numpy arrays: enough for the streaming engine."""

    config: ModelConfig
    arrays: dict[str, np.ndarray]  # the state dict
    meta: ModelMeta
    path: Path


class Described(Protocol):
    """Anything read from a model file: its metadata and where it came from."""

    meta: ModelMeta
    path: Path


def sample_rate(loaded: Described) -> float:
    """IMU rate (Hz) the model was trained at; online use needs it."""
    rate = loaded.meta.sample_rate_hz
    if rate is None:
        raise ModelFileError(f'{loaded.path}: model file has no valid sample rate')
    return rate


def gyro_covariance(loaded: Described, stddev: float = -1.0) -> list[float]:
    """
    Row-major 3x3 angular_velocity_covariance for corrected gyro messages.

    Diagonal, from ``stddev`` (rad/s) when >= 0, else from the per-axis residual std the
    model measured on its validation data (zero if the file has none).
    """
    std = loaded.meta.validation.gyro_residual_std or (0.0, 0.0, 0.0)
    std = [stddev] * 3 if stddev >= 0 else list(std)
    return [std[i] ** 2 if i == j else 0.0 for i in range(3) for j in range(3)]


def shipped_models() -> list[str]:
    """Names accepted by ``--model`` besides paths."""
    return sorted(p.stem for p in SHIPPED_DIR.glob('*.safetensors'))


MODEL_HELP = (f'shipped name ({", ".join(shipped_models())}) or the path of a .safetensors '
              'model file')


def code_version(package: Path = Path(__file__).resolve().parents[1]) -> str:
    """
    Package version plus a digest of its Python sources: which code wrote a file.

    Read from the files themselves, never from git at run time: an installed copy (a
    colcon workspace, a wheel) records the digest of the checkout it was built from, not
    that of whatever repository holds it, and a change not committed changes the digest.
    ``denoise-imu --version`` prints the running code's, to compare with a model's.
    """
    digest = hashlib.sha256()
    for path in sorted(package.rglob('*.py')):
        digest.update(path.relative_to(package).as_posix().encode() + b'\0')
        digest.update(path.read_bytes())
    return f'{__version__}+src.{digest.hexdigest()[:12]}'


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
    write_model_file(mf.path, mf.config, mf.arrays, dict(mf.meta.raw, **meta))


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
    return ModelFile(config, arrays, parse_meta(meta, str(path)), path)
