# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""What a model's own cross-recording verdict says against running it: the node's warning."""

from __future__ import annotations

from ..core.modelfile import ModelFile
from ..core.schema import JUDGED, NO_MODEL, REST_ONLY, TRACKER_ONLY

__all__ = ['deployment_warning', 'model_kind']

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
    return (f'{loaded.path.name} is a {kind} model, but the cross-recording validation of '
            f'its recipe says{said}: {verdict.verdict}')
