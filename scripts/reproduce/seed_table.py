# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Seed summary: mean and spread of AOE over several ``denoise-imu eval`` result folders.

Usage: .venv/bin/python scripts/reproduce/seed_table.py EVAL_DIR [EVAL_DIR ...]
Prints a Markdown table, one row per method, "mean ± std" of AOE 3-D / yaw (degrees) over
the folders, per sequence and averaged over sequences, then each folder's average.
"""

import json
from pathlib import Path
import sys

import numpy as np


def main(dirs):
    reports = [json.loads((Path(d) / 'results.json').read_text()) for d in dirs]
    seqs = list(reports[0]['sequences'])
    methods = list(reports[0]['sequences'][seqs[0]])
    print('| method | ' + ' | '.join(seqs) + ' | average |')
    print('|---' * (len(seqs) + 2) + '|')
    for m in methods:
        cells = []
        for s in seqs + ['average']:
            src = [r['average'][m] if s == 'average' else r['sequences'][s][m] for r in reports]
            a = np.array([x['aoe_deg'] for x in src])
            y = np.array([x['aoe_yaw_deg'] for x in src])
            cells.append(f'{a.mean():.2f}±{a.std():.2f} / {y.mean():.2f}±{y.std():.2f}')
        print(f'| {m} | ' + ' | '.join(cells) + ' |')
    print()
    for d, r in zip(dirs, reports):
        avg = r['average']['network']
        print(f'- {d}: network {avg["aoe_deg"]:.2f} / {avg["aoe_yaw_deg"]:.2f}')


if __name__ == '__main__':
    main(sys.argv[1:])
