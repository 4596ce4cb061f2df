# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Learning curve: how a recipe's figures on held-out recordings move with its training set.

A fold of ``crossval`` trains on fewer recordings than the model shipped from the whole
recipe; this trains the recipe on growing subsets and scores each on the same held-out
recordings, with the README's commands: per subset, ``train --calibration-only`` (seed 0)
and ``train`` per seed, ``ensemble`` of the seeds (two or more), the output bias tracking
of ``--tracking-from`` (a model file whose ``crossval --attach`` chose it; none without)
written into each of them and the calibration, then ``eval`` of each against the
calibration, reading the poses as the recipe does (``align``, ``poses``, topics). Prints
one Markdown row per subset: the held-out means (open loop AOE 3-D, then ``imu/data``'s)
of the rest bias, the calibration, each seed's network and their mean ± std, the ensemble
(one seed: that network again) and its ratio to the calibration.

Usage: .venv/bin/python scripts/reproduce/learning_curve.py --recipe RECIPE --out DIR
       --held REC [REC ...] --subset REC,REC [--subset ...] [--seeds 0 1 2]
       [--tracking-from MODEL] [--data DIR]
(docs/results.md, BROAD: config/train_broad.yaml, subsets of one session, the other
session held out, --tracking-from a fold model of ``crossval --sessions``.)
"""

import argparse
import json
from pathlib import Path
import subprocess
import sys

from denoise_imu_ros.core.modelfile import add_metadata, read_model_file
from denoise_imu_ros.learn.config import TrainConfig
import numpy as np
import yaml

CLI = [sys.executable, '-m', 'denoise_imu_ros.cli']


def run(*args: str) -> None:
    """Run one ``denoise-imu`` command; stop on its failure."""
    subprocess.run([*CLI, *args], check=True, stdout=subprocess.DEVNULL)


def means(folder: Path) -> tuple[dict[str, float], dict[str, float]]:
    """Return an eval folder's mean AOE 3-D per row, open loop and through VQF."""
    report = json.loads((folder / 'results.json').read_text())
    rows = ('rest bias', 'calibrated', 'network')
    opened = {r: float(np.mean([s[r]['aoe_deg'] for s in report['sequences'].values()]))
              for r in rows}
    fused = {r: float(np.mean([s[f'{r} + VQF']['aoe_deg'] for s in report['fused'].values()]))
             for r in rows}
    return opened, fused


def main() -> None:
    """Train and score every subset, then print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--recipe', required=True)
    parser.add_argument('--out', required=True, type=Path)
    parser.add_argument('--held', required=True, nargs='+')
    parser.add_argument('--subset', required=True, action='append')
    parser.add_argument('--seeds', nargs='+', type=int, default=[0, 1, 2])
    parser.add_argument('--tracking-from')
    parser.add_argument('--data')
    args = parser.parse_args()
    recipe = yaml.safe_load(Path(args.recipe).read_text())
    data = args.data or recipe.get('data') or TrainConfig.data
    align = recipe.get('align') or 'none'
    if not isinstance(align, str):
        parser.error('the recipe gives its alignment as numbers: eval takes check, auto or '
                     'none; run eval by hand')
    reading = [*(['--poses', recipe['poses']] if recipe.get('poses') else []),
               *(['--imu-topic', recipe['imu_topic']] if recipe.get('imu_topic') else []),
               *(['--pose-topic', recipe['pose_topic']] if recipe.get('pose_topic') else [])]
    tracking = (read_model_file(args.tracking_from).meta.bias_tracking
                if args.tracking_from else None)
    print('| recordings | rest bias | calibration | network, each seed | network | ensemble '
          '| ensemble / calibration | rest bias + VQF | calibration + VQF | network + VQF '
          '| ensemble + VQF |')
    print('|---' * 11 + '|')
    for subset in args.subset:
        names = subset.split(',')
        folder = args.out / f'{len(names)}_{names[0]}'
        folder.mkdir(parents=True, exist_ok=True)
        config = folder / 'recipe.yaml'
        config.write_text(yaml.safe_dump({**recipe, 'sequences': names, 'data': data},
                                         sort_keys=False))
        calibration = folder / 'calibrated.safetensors'
        run('train', '--recipe', str(config), '--calibration-only', '--seed', '0',
            '--out', str(calibration), '--overwrite', '--quiet')
        models = [folder / f'seed{s}.safetensors' for s in args.seeds]
        for seed, model in zip(args.seeds, models):
            run('train', '--recipe', str(config), '--seed', str(seed), '--out', str(model),
                '--overwrite', '--quiet')
        ensemble = models[0]
        if len(models) > 1:
            ensemble = folder / 'ensemble.safetensors'
            run('ensemble', *map(str, models), '--out', str(ensemble), '--overwrite')
        if tracking is not None:
            for path in dict.fromkeys((calibration, *models, ensemble)):
                add_metadata(path, bias_tracking=tracking.as_dict())
        scored = []
        for model in dict.fromkeys((*models, ensemble)):
            run('eval', '--model', str(model), '--baseline', str(calibration), '--data', data,
                '--sequences', *args.held, '--align', align, *reading,
                '--out', str(folder / f'eval_{model.stem}'), '--no-plots')
            scored.append(means(folder / f'eval_{model.stem}'))
        if len(models) == 1:  # the ensemble is that network
            scored.append(scored[0])
        (opened, fused), seeds = scored[-1], scored[:-1]
        net = [o['network'] for o, _ in seeds]
        fnet = [f['network'] for _, f in seeds]
        spread = f' ± {np.std(net, ddof=1):.2f}' if len(net) > 1 else ''
        fspread = f' ± {np.std(fnet, ddof=1):.2f}' if len(fnet) > 1 else ''
        print(f'| {len(names)} ({", ".join(names)}) | {opened["rest bias"]:.2f} '
              f'| {opened["calibrated"]:.2f} | {" / ".join(f"{v:.2f}" for v in net)} '
              f'| {np.mean(net):.2f}{spread} | {opened["network"]:.2f} '
              f'| {opened["network"] / opened["calibrated"]:.2f} | {fused["rest bias"]:.2f} '
              f'| {fused["calibrated"]:.2f} '
              f'| {np.mean(fnet):.2f}{fspread} | {fused["network"]:.2f} |', flush=True)


if __name__ == '__main__':
    main()
