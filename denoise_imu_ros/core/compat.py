# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Whether two models, or a model and a recording, belong together: checked in one place.

Every command that takes a model and a recording (``correct``, ``eval``, ``noise``,
``train`` without a model) runs :func:`check_stream`; every command that takes a model
and its calibration baseline (``eval``, ``noise``, ``tune-fusion``) runs
:func:`check_baseline`. Each refusal is one line; a model file that lacks what a check
needs (its rate) is refused too.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import numpy as np

from .architecture import ModelConfig
from .errors import ModelFileError
from .limits import check_gaps, check_rate, check_units
from .modelfile import sample_rate
from .schema import ModelMeta, REST_ONLY, TRACKER_ONLY

__all__ = ['check_baseline', 'check_stream']


class Paired(Protocol):
    """A model as the checks see it: its metadata, architecture and file."""

    meta: ModelMeta
    path: Path

    @property
    def config(self) -> ModelConfig:
        """Return the model's architecture."""


def check_stream(stamps_ns: np.ndarray, imu: np.ndarray, source: object,
                 model_rate_hz: float | None = None, model_input_std: np.ndarray | None = None,
                 model_input_mean: np.ndarray | None = None) -> None:
    """
    Run the checks every offline tool runs on a recording before computing with it.

    Its rate against the model's (when there is a model), the units of its samples (and
    against the model's training data: scale and mounting), and its holes.
    """
    if model_rate_hz is not None:
        check_rate(stamps_ns, model_rate_hz, source)
    check_units(imu, source, model_input_std, model_input_mean)
    check_gaps(stamps_ns, model_rate_hz, source)


def check_baseline(model: Paired, baseline: Paired) -> None:
    """
    Refuse a calibration baseline that does not belong with ``model``: one line each.

    It must be a calibration (``train --calibration-only``), not a network nor a rest-only
    file, and of the model's IMU rate: the "calibrated" rows and the filter settings
    stored crosswise would otherwise be wrong without a word.
    """
    role = {REST_ONLY: 'a rest-only model', TRACKER_ONLY: 'a tracker-only model'}.get(
        baseline.meta.kind, None if baseline.config.calibration_only else 'a network')
    if role:
        raise ModelFileError(f'--baseline {baseline.path}: {role}, not a calibration (train '
                             '--calibration-only makes one)')
    rates = sample_rate(model), sample_rate(baseline)
    if abs(rates[1] / rates[0] - 1) > 1e-3:
        raise ModelFileError(f'--baseline {baseline.path}: a calibration of {rates[1]:.2f} Hz, '
                             f'the model {model.path.name} is of {rates[0]:.2f} Hz')
