# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
A training recipe for your own recordings (``denoise-imu init-recipe``), from the data.

Every choice follows a documented rule from what ``check-data`` measures on each
recording; everything else is the reference recipe (``TrainConfig`` defaults):
- rate: the recordings' IMU rate (they must agree within the rate tolerance); the
  network, window and increments are in samples, so the model is for that rate only;
- increments: the paper's 0.08 and 0.16 s (16 and 32 samples at 200 Hz; in samples,
  the nearest powers of two: 8/16 at 100 Hz, 64/128 at 1 kHz) where they are not
  dominated by ground-truth noise on any recording, else the shortest clean length and
  its double;
- window: 80 s (the paper's), shortened to leave a third of the shortest recording as
  validation tail, in samples a multiple of the longest increment;
- sigma_g: per axis 1.2 times the largest constant gyro bias against the poses, at
  least 0.2 deg/s (the output scale the paper sets by hand: EuRoC [1, 2, 5], TUM-VI 0.2);
- align: ``auto`` when a recording's clock or frame is off, or its poses are read another
  way than written (check-data's ``read_as``: only alignment reads them so), else ``none``;
- rest_bias: off under motion capture; the reasons say how many recordings start still
  (VQF's rest detection within their first START_STILL_S). Turning it on removes each
  run's turn-on bias before the model; measured, it lost on EuRoC (one training): a
  choice to measure with ``crossval --sessions``, not to make by rule. recording_bias
  goes with it (each recording's constant learnt apart from the model; BROAD's other
  power-on, docs/results.md).
- under a VIO's or SLAM's estimate (trajectory files, ``poses``, or ``estimated``: a
  bag's odometry topic, say) with a recording that starts still: rest_bias and
  recording_bias on. The trajectory's drift over a recording is what a model learns as
  the gyro's bias from it (VINS-Mono on EuRoC); the bias is then measured from
  stillness, and what each recording's trajectory adds stays apart from the model
  (docs/results.md).
- heading_weight: 0 under an estimate whose heading disagrees with the gyro more
  than HEADING_RATIO times their tilt does (check-data's label noise at the first
  increment and over its drift horizons, 5-20 s, the largest, pooled over the
  recordings): a VIO's heading is not held by gravity, and a model taught it learns its
  drift (VINS-Mono on EuRoC: heading 2.1x tilt at 256 samples, 2.8x over 20 s; a model
  then learns from the tilt alone); else 1. Not under motion capture, whose heading can
  disagree as much where the gyro's own drift about the vertical is the larger (TUM-VI's
  rooms pooled: 1.67 over 10 s): no figure here tells an estimate from motion capture
  (their noise against the gyro overlaps too), so the user says which; a ratio above the
  limit is said with the question.
- increments_between_poses: on where the poses are too sparse for the motion on any
  recording (check-data's ``too_sparse``: interpolated between their stamps, they are off
  the gyro's scale by more than 1 %, e.g. a SLAM's keyframes), so that each increment
  runs between two poses' stamps, where the poses are right.
A recording the poses cannot supervise is left out of the recipe and named, and the
rules above apply to the others: one check-data finds not usable or cannot read (an error
only when no recording is left), one with no increment up to 512 samples free of
ground-truth noise (poses too noisy for its motion, e.g. a fast trial under slow motion
capture: an error only when every recording is so), and one whose poses do not lower its
own attitude error even with a constant bias fitted on them (check-data's
``supervision``), unless fewer than two recordings would remain: then they are kept and
named in the reasons, and such a recipe is not expected to beat plain integration,
whatever its other keys.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .config import TrainConfig
from ..core.atomic import write_text
from ..core.errors import DatasetError
from ..core.limits import common_rate
from ..data.check import (check, INTERPOLATION_LIMIT_PERCENT, interpolation_worst,
                          paper_increments)
from ..data.load import load_recording, no_such
from ..pipeline import rest_bias

WINDOW_S = 80.0
START_STILL_S = 5.0  # a recording still within this many seconds of its start starts still
MIN_GYRO_STD_DEG = 0.2
# heading residual over tilt residual above which the heading is left out of the loss
# (pooled; EuRoC at 1.28 s: motion capture 0.85, at most 1.28 on one recording, and 0.87
# at most over 5-20 s; VINS-Mono 2.1, 2.8 over 20 s; ORB-SLAM2 1.8 at 0.64 s)
HEADING_RATIO = 1.3
MIN_DRIFT_BLOCKS = 10  # a drift horizon's ratio from fewer increments, pooled, is not used


def init_recipe(data: str | Path, sequences: list[str], imu_topic: str | None = None,
                pose_topic: str | None = None, poses: str | Path | None = None,
                estimated: bool = False) -> tuple[dict[str, Any], list[str]]:
    """
    Return the recipe (a mapping of TrainConfig keys) and the reasons for each choice.

    ``estimated``: the recordings' own poses are a VIO's or SLAM's estimate, as trajectory
    files (``poses``) are.
    """
    estimated = estimated or poses is not None
    reports, still, unusable, asked = {}, [], {}, list(sequences)
    if poses is not None and not Path(poses).exists():  # said once, not per recording
        raise DatasetError(f'--poses {poses}: no such trajectory file or folder')
    if poses is not None and Path(poses).is_file() and len(sequences) > 1:
        raise DatasetError(f'--poses {poses}: one trajectory file for {len(sequences)} '
                           'recordings; give a folder of <recording>.txt')
    for name in sequences:
        if not (Path(data) / name).exists():  # a name mistyped: not a recording to leave out
            raise no_such(Path(data) / name)
        try:
            rec = load_recording(Path(data) / name, imu_topic, pose_topic, poses)
            report = check(rec)
        except DatasetError as err:  # unreadable, or poses of no clock or frame of its IMU
            unusable[name] = str(err)
            continue
        if report['usable'] == 'no':
            unusable[name] = (f'{Path(data) / name}: not usable for training: '
                              + '; '.join(report['reasons']))
            continue
        reports[name] = report
        if _starts_still(rec.imu, report['imu_rate_hz']):
            still.append(name)
    if not reports:
        raise DatasetError('; '.join(unusable.values()) if len(unusable) == 1 else
                           'no recording is usable for training: ' + '; '.join(
                               unusable.values()))
    sequences = [n for n in sequences if n in reports]
    rate = common_rate({n: r['imu_rate_hz'] for n, r in reports.items()}, data)
    noise = [n for n, r in reports.items() if r['shortest_clean_increment'] is None]
    if len(noise) == len(reports):
        raise DatasetError('no increment up to 512 samples is free of ground-truth noise '
                           'on any recording: the poses cannot supervise the loss')
    weak = [n for n, r in reports.items() if not r['supervision']['helps'] and n not in noise]
    if len(reports) - len(noise) - len(weak) < 2:
        weak = []  # kept, and named below: crossval needs two recordings
    left_out = noise + weak
    reports = {n: r for n, r in reports.items() if n not in left_out}
    sequences = [n for n in sequences if n not in left_out]
    noisy = set().union(*(r['noise_dominated_increments'] for r in reports.values()))
    paper = paper_increments(rate)
    absent = {j for r in reports.values() for j in paper if j not in r['increments']}
    if not set(paper) & (noisy | absent):
        increments = list(paper)
        why_inc = "the paper's 0.08/0.16 s, clean on every recording"
    else:
        first = max(r['shortest_clean_increment'] for r in reports.values())
        increments = [first, 2 * first]
        why_inc = (f"the paper's {paper[0]}/{paper[1]} are "
                   + ' or '.join((['noise-dominated'] if set(paper) & noisy else [])
                                 + (['without enough poses that far apart'] if absent else []))
                   + f' ({sorted(noisy | absent)}); {first} is clean on every recording')
    span = increments[-1]
    shortest = min(r['duration_s'] for r in reports.values()) * rate
    window = int(min(WINDOW_S * rate, shortest * 2 / 3) // span * span)
    if window < span:
        raise DatasetError(f'the shortest recording ({shortest / rate:.0f} s) leaves no '
                           f'training window of {span} samples')
    bias = np.max(np.abs([r['gyro_bias_vs_pose_deg_s'] for r in reports.values()]), axis=0)
    gyro_std = [max(MIN_GYRO_STD_DEG, round(1.2 * float(b), 2)) for b in bias]
    off = [n for n, r in reports.items() if r['usable'] == 'after alignment']
    # poses read another way than written are read so only where aligned (data.load)
    ways: dict[str, list[str]] = {}
    for n, r in reports.items():
        if r['read_as']:
            ways.setdefault(r['read_as'], []).append(n)
    moved = [f'{", ".join(off)} off in clock or frame'] if off else []
    moved += [f'{", ".join(names)} read {way}' for way, names in ways.items()]
    recipe = {k: v for k, v in asdict(TrainConfig()).items() if k != 'device'}
    recipe.update(
        # absolute: train, crossval and tune-fusion read them from any working directory
        dataset=Path(data).name, data=str(Path(data).resolve()), sequences=list(sequences),
        imu_topic=imu_topic, pose_topic=pose_topic,
        poses=None if poses is None else str(Path(poses).resolve()), increments=increments,
        increment_weights=[1.0, 0.5], window=window, gyro_std_deg=gyro_std,
        align='auto' if moved else 'none', swa_start=1200, select='swa',
        rest_bias=False, recording_bias=False, workers='auto', threads='auto')
    sparse = [n for n, r in reports.items() if r['too_sparse']]
    if sparse:
        recipe.update(increments_between_poses=True)
    estimate = estimated and bool(set(still) & set(sequences))
    if estimate:  # a trajectory's drift is not the gyro's bias: stillness measures that
        recipe.update(rest_bias=True, recording_bias=True)
    found = _heading_ratio(reports.values(), increments[0])
    heading, where = found if found else (None, '')
    if estimated and heading is not None and heading > HEADING_RATIO:
        recipe.update(heading_weight=0.0)
    why = [f'IMU rate {rate:.1f} Hz (the model is for this rate only; receptive field '
           f'511 samples = {511 / rate:.2f} s)',
           f'increments {increments} samples '
           f'({", ".join(f"{j / rate:.2f} s" for j in increments)}): ' + why_inc,
           f'window {window} samples ({window / rate:.0f} s)',
           f'gyro_std_deg {gyro_std}: 1.2 x the largest gyro bias per axis '
           f'({", ".join(f"{b:.3f}" for b in bias)} deg/s), at least {MIN_GYRO_STD_DEG}',
           f'align {recipe["align"]}: ' + ('; '.join(moved) or 'clocks and frames agree'),
           (f'rest_bias and recording_bias on: the poses are a trajectory estimate, whose '
            "drift over a recording a model would learn as the gyro's bias; the bias is "
            f'measured from stillness instead ({len(set(still) & set(sequences))} of '
            f'{len(sequences)} recordings are still within {START_STILL_S:g} s of their '
            'start; the others run from their mean until they stop), and what each '
            "recording's trajectory adds is learnt apart from the model (docs/method.md)"
            if estimate else
            f'rest_bias off: {len(set(still) & set(sequences))} of {len(sequences)} '
            f'recordings are still within {START_STILL_S:g} s of their start; whether '
            "removing each run's turn-on bias first helps is measured with crossval "
            '--sessions, not assumed; with it, set recording_bias too (docs/method.md)'
            + ('; the poses are a trajectory estimate, whose drift over a recording the '
               "model will learn as the gyro's bias: record a few still seconds at the "
               'start of each run, and stillness measures the bias instead'
               if estimated else ''))]
    measured = ('not measured (no increment of that length with trusted poses)'
                if heading is None else
                f"the poses' heading disagrees with the gyro {heading:.2f}x as much as "
                f'their tilt ({where})')
    if estimated:
        why.append(f"heading_weight {recipe['heading_weight']:g}: {measured}; " + (
            "a heading gravity does not hold would teach the model the trajectory's "
            'drift: learnt from the tilt alone' if recipe['heading_weight'] == 0 else
            f'not above {HEADING_RATIO:g}x: both taught'))
    elif heading is not None and heading > HEADING_RATIO:
        why.append('heading_weight 1: the poses are taken as motion capture (not said to be '
                   f"an estimate); {measured}, above {HEADING_RATIO:g}x, as a VIO's or "
                   "SLAM's drifting heading does (or a gyro drifting about the vertical): if "
                   'they are an estimate, give --estimated-poses')
    why += [f'left out: {said}' for said in unusable.values()]
    if noise:
        why.append(f'left out: {", ".join(noise)}: no increment up to 512 samples is free '
                   'of ground-truth noise there (poses too noisy for the motion), so '
                   + ('it cannot' if len(noise) == 1 else 'they cannot')
                   + ' supervise the loss; score with eval instead')
    if sparse:
        off_scale = ', '.join('{} {:+.1f} % about {}'.format(
            n, *interpolation_worst(reports[n])) for n in sparse)
        why.append('increments_between_poses: the poses are too sparse for the motion on '
                   f"{', '.join(sparse)} (the gyro's own attitude, known only at their stamps "
                   f"and interpolated between them, is off the gyro's scale: {off_scale}; "
                   f'limit {INTERPOLATION_LIMIT_PERCENT:g} %), which a model would learn as '
                   "the gyro's from increments of fixed length: each increment runs from a "
                   "pose's stamp to a later pose's instead")
    if weak:
        why.append(f'left out: {", ".join(weak)}: '
                   + ('its poses do not lower its own' if len(weak) == 1 else
                      'their poses do not lower their own')
                   + ' attitude error even with a constant bias fitted on them (check-data); '
                   'score with eval instead')
    weak = [n for n, r in reports.items() if not r['supervision']['helps']]
    why.append(f'supervision: the poses of {", ".join(weak)} do not lower their own '
               'attitude error even with a constant bias fitted on them (check-data): a '
               'network trained on them is not expected to beat plain integration; run '
               'denoise-imu crossval before deploying it' if weak else
               "supervision: a constant bias fitted on each recording's poses lowers its "
               'attitude error')
    if estimated:
        why.append("the poses are a VIO's or SLAM's estimate: train --calibration-only too "
                   'and let crossval (recordings held out whole) choose between the two; '
                   "a recording's own tail shares its trajectory's error and chose the "
                   'network where unseen recordings did not (EuRoC, docs/results.md)')
    if len(sequences) < 2:
        why.append('one recording: train works, crossval (whether the network beats plain '
                   'integration on a recording it never saw) needs at least two')
    if len(sequences) < len(asked):
        why.append(f'the recipe uses {len(sequences)} of the {len(asked)} recordings given '
                   f'(left out: {", ".join(n for n in asked if n not in sequences)}; above)')
    return recipe, why


def _heading_ratio(reports: Iterable[dict[str, Any]],
                   length: int) -> tuple[float, str] | None:
    """
    Heading residual over tilt residual of the poses, over all recordings, and where.

    The largest of the ratios at the first increment (a heading noisier than the tilt)
    and over check-data's drift horizons (a heading that drifts: noise as large in the
    tilt hides it at short lengths, and does not grow with the length as a drift does).
    """
    reports = list(reports)
    rate = reports[0]['imu_rate_hz'] if reports else 1.0
    horizons = sorted({j for r in reports for j in r['drift_increments'] or {}})
    ratios = []
    for key, j, label in ([('increments', length, f'{length}-sample increments')]
                          + [('drift_increments', j, f'{j / rate:.0f} s increments, a drift '
                              'horizon') for j in horizons]):
        profiles = [r[key][j] for r in reports if j in (r[key] or {})]
        if not profiles or (key == 'drift_increments'
                            and sum(p['blocks'] for p in profiles) < MIN_DRIFT_BLOCKS):
            continue
        heading = np.sqrt(np.mean([p['heading_mrad'] ** 2 for p in profiles]))
        tilt = np.sqrt(np.mean([p['tilt_mrad'] ** 2 for p in profiles]))
        if tilt > 0:
            ratios.append((float(heading / tilt), label))
    return max(ratios) if ratios else None


def _starts_still(imu: np.ndarray, rate_hz: float) -> bool:
    """Whether VQF's rest detection finds stillness in a recording's first seconds."""
    head = imu[:int(START_STILL_S * rate_hz)]
    wide = rest_bias.RestBiasSettings(bias_clip_deg_s=rest_bias.WIDE_CLIP_DEG_S)
    return bool(len(head)) and bool(rest_bias.rest_bias_batch(head, rate_hz, wide)['rest'].any())


def write_recipe(path: str | Path, recipe: dict[str, Any], why: list[str]) -> None:
    """Write the recipe as YAML, its reasons as comments on top."""
    text = ('# Written by denoise-imu init-recipe; see denoise_imu_ros/learn/config.py for '
            'every key.\n' + ''.join(f'# {line}\n' for line in why)
            + yaml.safe_dump(recipe, sort_keys=False))
    write_text(path, text)
