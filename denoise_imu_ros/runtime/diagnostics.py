# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What the node's ``/diagnostics`` says, as a pure function of the pipeline's state.

:func:`status` returns the level, the one-line message and the key/value pairs; the node
only wraps them in a ``DiagnosticArray`` (and logs the errors), so every case is tested
without DDS. The level is the first that applies: no input for STALL_S seconds, a rate
off the model's, nothing accepted (with what was dropped), then the warnings: no input
yet, warming up, a model its verdict does not recommend, a turn-on bias that may have been
a slow turn.
"""

from __future__ import annotations

from enum import IntEnum
from typing import Iterable, NamedTuple

import numpy as np

from .advice import ambiguous_rest
from ..pipeline.online import DROP_CAUSES, OnlineDenoiser

__all__ = ['Level', 'STALL_S', 'status', 'Status']

STALL_S = 2.0  # s without any input message after which diagnostics say the input stopped


class Level(IntEnum):
    """diagnostic_msgs/DiagnosticStatus's levels."""

    OK = 0
    WARN = 1
    ERROR = 2


class Status(NamedTuple):
    """One status: its level, its message and its values (all strings, as ROS carries them)."""

    level: Level
    message: str
    values: dict[str, str]


def status(den: OnlineDenoiser, withheld: dict[str, int], silent_s: float | None,
           input_topic: str, not_recommended: str = '',
           callback_s: Iterable[float] = ()) -> Status:
    """
    Return the node's status for its pipeline ``den`` and what its outputs ``withheld``.

    ``silent_s``: seconds since the last input message (None: none yet); ``callback_s``
    the recent callbacks' durations.
    """
    counts, engine = den.counts, den.engine
    rate = den.input_rate_hz
    fill = min(engine.samples, engine.receptive_field)
    level, message = Level.OK, 'ok'
    if silent_s is not None and silent_s > STALL_S:
        rate = 0.0  # its last stamps say nothing of its rate now
        level, message = Level.ERROR, f'no input for {silent_s:.1f} s on {input_topic}'
    elif den.rate_suspect:
        level, message = Level.ERROR, (
            f'input rate {rate:.1f} Hz differs from the model rate {den.rate_hz:.1f} Hz: '
            'corrections are not valid, imu/corrected, imu/attitude and imu/data not '
            'published')
    elif counts['accepted'] == 0 and any(counts[c] for c in DROP_CAUSES):
        level, message = Level.ERROR, 'no message accepted: dropped ' + ', '.join(
            f'{counts[c]} ({c.replace("_", " ")})' for c in DROP_CAUSES if counts[c])
    elif counts['accepted'] == 0:
        level, message = Level.WARN, 'no input yet'
    elif fill < engine.receptive_field:
        level, message = Level.WARN, 'warming up'
    elif not_recommended:
        level, message = Level.WARN, not_recommended
    elif den.rest is not None and den.rest.ambiguous:
        level, message = Level.WARN, ambiguous_rest(den.rest)
    callbacks = np.array(list(callback_s) or [0.0])
    values = {'input_rate_hz': f'{rate:.2f}', 'model_rate_hz': f'{den.rate_hz:.2f}',
              'seconds_since_input': '' if silent_s is None else f'{silent_s:.1f}',
              'buffer_fill': f'{fill}/{engine.receptive_field}',
              'callback_time_p50_us': f'{np.median(callbacks) * 1e6:.1f}',
              'callback_time_max_us': f'{callbacks.max() * 1e6:.1f}'}
    values.update({k: str(v) for k, v in counts.items()})
    values.update({k: str(withheld[k]) for k in
                   ('corrected_withheld', 'attitude_withheld', 'fused_withheld')})
    values.update(_bias_values(den))
    guard = den.guard
    values['envelope_guard_applied'] = str(guard is not None)
    if guard is not None:  # samples given the fallback (motion it was not trained on)
        values['envelope_guarded_samples'] = str(guard.guarded)
        values['envelope_trusted'] = str(guard.trusted)
    blender = den.blender
    values['classical_blend_applied'] = str(blender is not None)
    if blender is not None:  # the network's weight, and the samples given the classical alone
        values['classical_blend_weight'] = f'{blender.blend.weight:g}'
        values['classical_only_samples'] = str(blender.classical_only)
    return Status(level, message, values)


def _bias_values(den: OnlineDenoiser) -> dict[str, str]:
    """Return the bias estimates: applied, seconds still, values."""
    rest, track = den.rest, den.track
    values = {'rest_bias_applied': str(rest is not None),
              'tracked_bias_applied': str(track is not None),
              'vertical_correction_dropped': str(den.vertical is not None)}
    if rest is not None:
        bias, sigma = rest.estimate()
        values.update({'rest_bias_seconds_still': f'{rest.seconds_still:.1f}',
                       'rest_bias_source': 'stillness' if rest.still_samples else 'prior',
                       'rest_bias_from_prior_deg_s': f'{rest.offset_deg_s:.3f}',
                       'rest_bias_ambiguous': str(rest.ambiguous),
                       'rest_bias_rad_s': ' '.join(f'{v:.6f}' for v in bias),
                       'rest_bias_sigma_rad_s': f'{sigma:.6f}'})
    if track is not None:
        bias, sigma = track.estimate()
        # held through motion faster or longer than trained on, or faster than its bound
        values.update({'tracked_bias_rad_s': ' '.join(f'{v:.6f}' for v in bias),
                       'tracked_bias_sigma_rad_s': f'{sigma:.6f}',
                       'tracked_bias_held': str(track.held)})
    return values
