# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Ways of choosing the output bias tracking, each judged nested on a crossval's held-out recordings.

``crossval`` keeps the candidate of lowest mean figure over every held-out recording, and
scores each fold's recordings with the one the other folds' recordings chose. The same
nested scoring, from the per-recording figures a crossval report stores, for other rules:
the median over recordings, the mean over a candidate and its neighbours on the grid (a
flat minimum rather than a lone dip), the lowest worst recording, the lowest mean among
candidates that beat none on most recordings, and never tracking. Training recordings
only (a crossval's folds); the heading guard is left out, so a tilt-judged report's
lowest-mean figure may differ from its own.
Usage: .venv/bin/python scripts/experiments/tracking_rules.py REPORT...
(a crossval.json, or a model file carrying one)
"""

import json
from pathlib import Path
import sys
from typing import Callable

from denoise_imu_ros.core.modelfile import read_model_file
from denoise_imu_ros.evaluation.crossval import TRACKING_GRID, tracking_label
import numpy as np

Figures = dict[str, dict[str, float]]  # recording -> candidate label -> figure


def _neighbours() -> dict[str, list[str]]:
    """Each candidate and those one grid step from it (sigma or forgetting); none alone."""
    sigmas = sorted({t.sigma_motion_deg_s for t in TRACKING_GRID})
    times = sorted({t.forgetting_s for t in TRACKING_GRID})
    at = {tracking_label(t): (sigmas.index(t.sigma_motion_deg_s), times.index(t.forgetting_s))
          for t in TRACKING_GRID}
    near = {a: [b for b, q in at.items() if abs(p[0] - q[0]) + abs(p[1] - q[1]) <= 1]
            for a, p in at.items()}
    return {tracking_label(None): [tracking_label(None)], **near}


def _rules(fig: Figures, names: list[str]) -> dict[str, str]:
    """Return each rule's choice on the recordings ``names``."""
    labels = list(fig[names[0]])
    mean = {c: float(np.mean([fig[n][c] for n in names])) for c in labels}
    near = _neighbours()
    beat = [c for c in labels if c == 'none' or 2 * sum(
        fig[n][c] < fig[n]['none'] for n in names) > len(names)]

    def pick(figure: Callable[[str], float]) -> str:
        return min(labels, key=figure)

    return {'mean (crossval)': pick(mean.get),
            'median': pick(lambda c: np.median([fig[n][c] for n in names])),
            'grid neighbours': pick(lambda c: np.mean([mean[b] for b in near[c]])),
            'worst recording': pick(lambda c: max(fig[n][c] for n in names)),
            'beats none on most': min(beat, key=mean.get), 'never': 'none'}


def main(sources: list[str]) -> None:
    """Print, per report and row, each rule's nested mean figure and its choice on all."""
    for source in sources:
        report = (json.loads(Path(source).read_text()) if source.endswith('.json')
                  else read_model_file(source).meta.crossval.report)
        fold_of = {n: i for i, fold in enumerate(report['folds']) for n in fold}
        recordings = report['tracking']['recordings']
        for row in ('calibrated', 'network'):
            fig = {n: recordings[n][row] for n in recordings}
            nested: dict[str, list[float]] = {}
            for name in fig:
                others = [n for n in fig if fold_of[n] != fold_of[name]]
                for rule, choice in _rules(fig, others).items():
                    nested.setdefault(rule, []).append(fig[name][choice])
            print(f'{source} {row}: ' + ', '.join(
                f'{rule} {np.mean(v):.2f}' for rule, v in nested.items()))
            print('  chosen on every recording: ' + '; '.join(
                f'{rule}: {c}' for rule, c in _rules(fig, list(fig)).items()))


if __name__ == '__main__':
    if len(sys.argv) < 2:
        sys.exit(__doc__.strip().splitlines()[-2])
    main(sys.argv[1:])
