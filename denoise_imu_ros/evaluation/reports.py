# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The Markdown tables of ``eval`` and ``crossval``: AOE per recording and method."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ..core.metrics import ROE_DISTANCES_M
from ..core.schema import JUDGED, ModelMeta

CROSSVAL_METHODS = ('raw', 'rest bias', 'tracker only', 'calibrated', 'network unblended',
                    'network')


def scored_on_training_samples(meta: ModelMeta, names: list[str],
                               start_sample: int) -> list[str]:
    """
    Which of ``names`` are training recordings of this model scored on its training span.

    Figures there measure the fit, not what a robot will see: a report says so.
    """
    trained = {Path(n).name for n in meta.train_sequences}
    span = meta.training_span
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


def eval_table(results: dict[str, Any], average: dict[str, Any]) -> str:
    """AOE 3-D / yaw (deg) per sequence and method, plus median ROE at 7/21/35 m."""
    methods = list(average)
    head = '| method | ' + ' | '.join(results) + ' | average |\n'
    lines = [head, '|---' * (len(results) + 2) + '|\n']
    for m in methods:
        cells = [f'{results[s][m]["aoe_deg"]:.2f}/{results[s][m]["aoe_yaw_deg"]:.2f}'
                 for s in results]
        avg = f'**{average[m]["aoe_deg"]:.2f}/{average[m]["aoe_yaw_deg"]:.2f}**'
        lines.append(f'| {m} | ' + ' | '.join(cells) + f' | {avg} |\n')
    lines.append('\nAOE 3-D / yaw in degrees. Median ROE (deg) at '
                 + '/'.join(f'{d:g}' for d in ROE_DISTANCES_M) + ' m (–: the recording '
                 'never travels that far):\n\n')
    for m in methods:
        cells = ['/'.join('–' if v is None or math.isnan(v) else f'{v:.2f}'
                          for v in results[s][m]['roe_median_deg'].values())
                 for s in results]
        lines.append(f'- {m}: ' + ', '.join(f'{s} {c}' for s, c in zip(results, cells)) + '\n')
    return ''.join(lines)


def crossval_table(report: dict[str, Any]) -> str:
    """AOE 3-D / yaw / tilt (deg) of each method per held-out recording, the mean, the verdict."""
    names = list(report['recordings'])
    rows = [m for m in CROSSVAL_METHODS if m in report['mean']]  # older: no rest bias
    keys = ['aoe_deg', 'aoe_yaw_deg'] + (['tilt_deg'] if all(  # older: no tilt
        'tilt_deg' in report['mean'][m] for m in rows) else [])
    lines = ['| method | ' + ' | '.join(names) + ' | mean |\n',
             '|---' * (len(names) + 2) + '|\n']
    for m in rows:
        cells = ['/'.join(f'{report["recordings"][s][m][k]:.2f}' for k in keys) for s in names]
        avg = '/'.join(f'{report["mean"][m][k]:.2f}' for k in keys)
        lines.append(f'| {m} | ' + ' | '.join(cells) + f' | **{avg}** |\n')
    kind = report.get('fold_kind', 'leave recordings out')
    said = ' / tilt' if 'tilt_deg' in keys else ''
    lines.append(f'\nUnseen recordings (folds: {kind}), AOE 3-D / yaw{said} in degrees. '
                 f'Verdict: {report["verdict"]}.\n')
    if 'judged_on_why' in report:
        lines.append(f'\nJudged on the tilt error alone: {report["judged_on_why"]}.\n')
    if 'fold_training' in report:
        lines.append(f'\nNote: {report["fold_training"]}.\n')
    if 'tracking' in report:
        tracking = report['tracking']
        said = [f'{m} {(c or {}).get("label", "none")}' for m, c in tracking['chosen'].items()]
        folds = [f'fold {f}: ' + ', '.join(f'{m} {c}' for m, c in chosen.items())
                 for f, chosen in tracking['per_fold'].items()]
        lines.append('\nOutput bias tracking (VQF at rest and in motion, after the model), '
                     f'chosen on {tracking["chosen_on"]}: {"; ".join(said)} (for the '
                     f'models this verdict is attached to); the figures above: '
                     f'{"; ".join(folds)}.\n')
    if 'blend' in report:
        blend = report['blend']
        folds = ', '.join(f'fold {f} {w:g}' for f, w in blend['per_fold'].items())
        lines.append("\nThe network rows blend the network's output with the classical "
                     "pipeline's (the tracker-only gyro), that alone where the acceleration "
                     'stays longer off gravity than in training; the weight of the network, '
                     f'chosen on {blend["chosen_on"]}: {blend["chosen"]["weight"]:g} (for the '
                     f'models this verdict is attached to); the figures above: {folds}.\n')
    if 'per_seed' in report:
        key = report.get('judged_on', 'aoe_deg')
        alone = [f'seed {s} {r["mean"]["network"][key]:.2f}'
                 for s, r in report['per_seed'].items()]
        lines.append(f'\nThe network rows average the corrected gyros of seeds '
                     f'{", ".join(map(str, report["seeds"]))} (the ensemble); each seed '
                     f'alone, mean {JUDGED[key]}: {", ".join(alone)}.\n')
    if 'accelerometer' in report:
        lines.append("\nThe accelerometer (imu/corrected's): the bias fitted on each fold's "
                     f"training poses against none, {report['accelerometer']['verdict']}.\n")
    if 'fusion' in report:
        lines.append(fusion_table(report['fusion'], names))
    return ''.join(lines)


def fusion_table(fusion: dict[str, Any], names: list[str]) -> str:
    """``crossval``'s imu/data: AOE 3-D / tilt (deg) per held-out recording, the filters chosen."""
    rows = list(fusion['mean'])
    lines = ['\n`imu/data` on the unseen recordings, AOE 3-D / tilt in degrees:\n\n| method | '
             + ' | '.join(names) + ' | mean |\n', '|---' * (len(names) + 2) + '|\n']
    for row in rows:
        cells = [f'{fusion["recordings"][n][row]["aoe_deg"]:.2f}/'
                 f'{fusion["recordings"][n][row]["tilt_deg"]:.2f}' for n in names]
        mean = fusion['mean'][row]
        lines.append(f'| {row} | ' + ' | '.join(cells)
                     + f' | **{mean["aoe_deg"]:.2f}/{mean["tilt_deg"]:.2f}** |\n')
    said = '; '.join(f'{m}: {c["label"]}' for m, c in fusion['chosen'].items())
    folds = '; '.join(f'fold {f}: ' + ', '.join(f'{m} {c}' for m, c in chosen.items())
                      for f, chosen in fusion['per_fold'].items())
    lines.append(f"\nThe filters (VQF), chosen on {fusion['chosen_on']}: {said} (for the "
                 f'models this verdict is attached to); the figures above: {folds}.\n')
    return ''.join(lines)


def fused_table(fused: dict[str, Any], average: dict[str, Any]) -> str:
    """Gravity-aided rows: 3-D / tilt (deg) per sequence, and the tilt growth (deg/min)."""
    names = list(fused)
    lines = ['\nGravity-aided orientation (yaw aligned once 1.5 s in, tilt never), AOE 3-D / '
             'tilt in degrees:\n\n| method | ' + ' | '.join(names) + ' | average |\n',
             '|---' * (len(names) + 2) + '|\n']
    for m in average:
        cells = [f'{fused[s][m]["aoe_deg"]:.2f}/{fused[s][m]["tilt_deg"]:.2f}' for s in names]
        avg = f'**{average[m]["aoe_deg"]:.2f}/{average[m]["tilt_deg"]:.2f}**'
        lines.append(f'| {m} | ' + ' | '.join(cells) + f' | {avg} |\n')
    filters = [f'{m}: {fused[names[0]][m]["filter"]}' for m in average]
    lines.append('\nFilters: ' + '; '.join(filters) + '.\n')
    return ''.join(lines)


def growth_table(results: dict[str, Any], fused: dict[str, Any]) -> str:
    """Tilt error growth (deg/min) per sequence: open-loop rows, then gravity-aided ones."""
    names = list(results)
    methods = [(m, results) for m in results[names[0]] if m != 'pose_alignment']
    methods += [(m, fused) for m in fused[names[0]]]
    lines = ['\nTilt error growth, deg/min (slope of a least-squares line through the tilt '
             'error against time):\n\n| method | ' + ' | '.join(names) + ' |\n',
             '|---' * (len(names) + 1) + '|\n']
    for m, table in methods:
        cells = [f'{table[s][m]["tilt_growth_deg_min"]:+.2f}' for s in names]
        lines.append(f'| {m} | ' + ' | '.join(cells) + ' |\n')
    return ''.join(lines)
