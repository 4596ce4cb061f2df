# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""What the node and process-bag warn of: a verdict against the model, a doubtful turn-on bias."""

from __future__ import annotations

from ..core.modelfile import ModelFile
from ..core.schema import JUDGED, NO_MODEL, REST_ONLY, RestBiasSettings, TRACKER_ONLY
from ..pipeline.rest_bias import resolve, RestBias

__all__ = ['ambiguous_rest', 'blend_warnings', 'deployment_warning', 'model_kind',
           'rest_warnings']

_ROWS = {'network': 'network', 'calibration': 'calibrated', REST_ONLY: 'rest bias',
         TRACKER_ONLY: 'tracker only', 'none': 'raw'}  # the report's row of each kind


def model_kind(loaded: ModelFile) -> str:
    """Return what the file corrects with: a network, a calibration, or no model (its kind)."""
    if loaded.meta.kind in NO_MODEL:
        return loaded.meta.kind
    return 'calibration' if loaded.config.calibration_only else 'network'


def deployment_warning(loaded: ModelFile) -> str | None:
    """
    Why this model should not be deployed, from its cross-recording validation, or None.

    The stored report names what did best on unseen recordings (the network, the
    calibration, the turn-on bias alone or no correction); a model of another kind still
    runs (benchmarks and comparisons need it) but says so. None when it is the kind
    recommended, or when the file has no report (``crossval --attach`` stores one).
    """
    verdict, kind = loaded.meta.crossval, model_kind(loaded)
    if verdict is None or verdict.deploy is None or verdict.deploy == kind:
        return None
    figures = [verdict.mean_deg.get(_ROWS[k]) for k in (kind, verdict.deploy)]
    label = {'none': 'no correction'}.get(verdict.deploy, verdict.deploy)
    said = (f' ({kind} {figures[0]:.2f}° against {label} {figures[1]:.2f}° in mean '
            f'{JUDGED[verdict.judged_on]} on unseen recordings)' if None not in figures else '')
    if kind in NO_MODEL:  # the verdict's own words are about the learnt rows
        return (f'{loaded.path.name} runs {kind} (no model), but the cross-recording '
                f'validation of its recipe recommends {label}{said}')
    return (f'{loaded.path.name} is a {kind} model, but the cross-recording validation of '
            f'its recipe says{said}: {verdict.verdict}')


def ambiguous_rest(rest: RestBias) -> str:
    """Say that the turn-on bias found at rest may be a slow steady turn (its figures)."""
    return (f'turn-on bias found at rest {rest.offset_deg_s:.2f} deg/s from the training '
            f'prior (clip {rest.settings.bias_clip_deg_s:g} deg/s): a still IMU with that '
            'bias and a steady turn about gravity at that rate look alike; if the robot was '
            'turning, the gyro is off by that much until the next stillness')


def blend_warnings(loaded: ModelFile, choice: str) -> list[str]:
    """
    Say that a run without the model's blend is not what its verdict judged (node, CLI alike).

    ``choice`` is the node's ``classical_blend`` (``model``, ``off``).
    """
    if choice != 'off' or loaded.meta.blend is None:
        return []
    verdict = loaded.meta.crossval
    figures = {} if verdict is None else verdict.mean_deg
    said = (f' (unseen recordings, mean {JUDGED[verdict.judged_on]}: '
            f'{figures["network unblended"]:.2f}° alone against {figures["network"]:.2f}° '
            'blended)' if verdict is not None and {'network', 'network unblended'} <= set(figures)
            else '')
    return [f'classical_blend off: the network alone, not the output its cross-recording '
            f'validation judged, blended with the classical pipeline at weight '
            f'{loaded.meta.blend.weight:g}{said}']


def rest_warnings(loaded: ModelFile, choice: str) -> list[str]:
    """
    Say what the turn-on bias settings of a run leave wrong or ambiguous (node, CLI alike).

    ``choice`` is the node's ``rest_bias`` (``model``, ``on``, ``off``).
    """
    stored, settings = loaded.meta.rest_bias, resolve(loaded.meta, choice)
    said = []
    if settings is None and stored is not None:
        said.append('rest_bias off: the model was trained on the gyro less its turn-on bias, '
                    'it now gets the raw gyro')
    if settings is not None and stored is None:
        said.append(f'rest_bias on: {loaded.path.name} was trained on the raw gyro and stores '
                    "no turn-on bias settings: VQF's defaults (a prior of 0, a "
                    f'{settings.bias_clip_deg_s:g} deg/s clip) find a bias under that only, '
                    'and the model now gets input it was not trained on')
    if settings is not None and settings.bias_clip_deg_s > RestBiasSettings.bias_clip_deg_s:
        said.append(f'turn-on bias clip {settings.bias_clip_deg_s:g} deg/s about the prior: a '
                    'steady turn about gravity slower than that is taken for stillness')
    return said
