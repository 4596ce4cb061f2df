# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The torch side of model files: save a trained network, rebuild one, average several.

The file format and its checks are numpy-only (:mod:`denoise_imu_ros.core.modelfile`);
this module turns a file's arrays into an eval-mode :class:`GyroNet` and back.
"""

from __future__ import annotations

from pathlib import Path
import time
from typing import Any, NamedTuple

import numpy as np
import torch

from .model import correct_gyro, GyroNet, merge
from ..core.architecture import ModelConfig
from ..core.errors import ModelFileError
from ..core.modelfile import code_version, read_model_file, sample_rate, write_model_file
from ..core.schema import ModelMeta
from ..pipeline import envelope, stages


# imu/data's filter settings (tune-fusion), the cross-recording verdict and the output
# bias tracking it chose (crossval --seeds): kept by an ensemble when every member
# carries the same
SHARED_BY_MEMBERS = ('fusion', 'crossval', 'bias_tracking')


class LoadedModel(NamedTuple):
    """A torch model in eval mode plus the metadata it was saved with."""

    model: GyroNet
    meta: ModelMeta
    path: Path

    @property
    def config(self) -> ModelConfig:
        """Return the network's architecture."""
        return self.model.config

    def correct(self, imu: np.ndarray) -> np.ndarray:
        """Corrected gyro (N, 3) of a recording's raw samples (N, 6), as online."""
        return stages.corrected(self, imu, batch=lambda fed: correct_gyro(self.model, fed))

    def untracked(self, imu: np.ndarray) -> np.ndarray:
        """Return the model's output (N, 3) before its tracking, envelope and vertical drop."""
        return correct_gyro(self.model, stages.model_input(self, imu))


def save_model(path: str | Path, model: GyroNet, meta: dict[str, Any]) -> None:
    """Write a torch model's weights and metadata (JSON-serialisable values)."""
    write_model_file(path, model.config, {k: v.detach().cpu().numpy()
                                          for k, v in model.state_dict().items()}, meta)


def _recipe(meta: ModelMeta) -> dict[str, Any]:
    """Return a member's dataset and recipe, less what trainings of one recipe differ in."""
    cfg = {k: v for k, v in meta.train_config.items() if k not in ('seed', 'sequences')}
    return cfg | ({'dataset': meta.dataset} if meta.dataset else {})


def save_ensemble(path: str | Path, specs: list[str]) -> LoadedModel:
    """
    Write one model file averaging the outputs of trained model files (see model.merge).

    The metadata keeps each member's seed and validation figures; the residual std the
    node publishes as covariance is the members' mean (the ensemble's own is lower). The
    filter settings and the verdict are kept where every member has the same, else
    dropped (``tune-fusion --attach`` and ``crossval --attach`` store the ensemble's).
    """
    members = [load_model(spec) for spec in specs]
    if len(members) < 2:
        raise ModelFileError('an ensemble needs at least two model files')
    rates = [m.meta.sample_rate_hz for m in members]
    rate = sample_rate(members[0])
    if any(r is None or abs(r / rate - 1) > 1e-3 for r in rates):
        shown = ', '.join(f'{r:.2f} Hz' if isinstance(r, (int, float)) else repr(r)
                          for r in rates)
        raise ModelFileError(f'ensemble members were trained at different rates: {shown}')
    try:
        model = merge([m.model for m in members])
    except ValueError as err:
        raise ModelFileError(f'cannot average {", ".join(map(str, specs))}: {err}') from err
    first = members[0].meta
    recipe = _recipe(first)
    for m in members[1:]:  # the file describes every member with the first one's recipe
        other = _recipe(m.meta)
        differ = sorted(k for k in set(recipe) & set(other) if recipe[k] != other[k])
        if differ:
            raise ModelFileError(f'ensemble members {members[0].path} and {m.path} are not '
                                 f'trainings of one recipe (they differ in {", ".join(differ)})')
    rests = [m.meta.rest_bias for m in members]
    for m, rest in zip(members[1:], rests[1:]):  # one input for all: each was trained on its own
        if rest != rests[0]:
            raise ModelFileError(f'ensemble members {members[0].path} and {m.path} remove '
                                 'different turn-on biases (rest_bias settings, or priors of '
                                 'other training recordings)')
    stds = [m.meta.validation.gyro_residual_std for m in members]
    residual = (np.mean(stds, axis=0).tolist() if all(v is not None for v in stds)
                else None)  # a member that measured none: no figure, not a zero in the mean
    meta = {
        'dataset': first.dataset, 'sample_rate_hz': rate,
        # every member's (fold models trained on different ones): what eval warns about
        'train_sequences': list(dict.fromkeys(
            s for m in members for s in m.meta.train_sequences)) or None,
        'train_config': first.raw.get('train_config'),
        'rest_bias': None if rests[0] is None else rests[0].to_dict(),
        'validation': {} if residual is None else {'gyro_residual_std': residual},
        'members': [{'file': str(m.path), 'seed': m.meta.recipe('seed'),
                     'validation': m.meta.raw.get('validation'),
                     'code_version': m.meta.code_version} for m in members],
        'code_version': code_version(),
        'created': time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime()),
    }
    bounds = envelope.combine([m.meta.input_envelope for m in members])
    if bounds is not None:
        meta['input_envelope'] = bounds.as_dict()
    for key in SHARED_BY_MEMBERS:  # what every member says alike describes the ensemble
        values = [m.meta.raw.get(key) for m in members]
        if values[0] is not None and all(v == values[0] for v in values):
            meta[key] = values[0]
    save_model(path, model, meta)
    return load_model(path)


def load_model(spec: str | Path) -> LoadedModel:
    """Rebuild the torch model of a file, in eval mode (training, batch evaluation)."""
    mf = read_model_file(spec)
    model = GyroNet(mf.config)
    model.load_state_dict({k: torch.from_numpy(v.copy()) for k, v in mf.arrays.items()})
    model.eval()
    return LoadedModel(model=model, meta=mf.meta, path=mf.path)
