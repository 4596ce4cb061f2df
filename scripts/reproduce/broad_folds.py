# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""BROAD's next-power-on tables from a crossval's folds, against the classical pipeline."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
import shutil
from typing import Any

import numpy as np

KEY = 'aoe_deg'
BAR = 'tracker only'


def ratios(recordings: dict[str, Any], names: list[str], row: str) -> dict[str, float]:
    """Return a row's mean, the bar's, their ratio, the mean and worst per-recording ratios."""
    got = np.array([recordings[n][row][KEY] for n in names])
    bar = np.array([recordings[n][BAR][KEY] for n in names])
    return {'mean': float(got.mean()), 'bar': float(bar.mean()),
            'ratio': float(got.mean() / bar.mean()), 'mean_ratio': float((got / bar).mean()),
            'worst_ratio': float((got / bar).max())}


def open_loop(report: dict[str, Any]) -> list[str]:
    """Markdown lines: each fold's held-out recordings, every row, each seed and the targets."""
    seeds = report.get('seeds', [])
    rows = [m for m in ('raw', 'rest bias', BAR, 'calibrated', 'network unblended', 'network')
            if m in report['mean']]
    lines = []
    for i, held in enumerate(report['folds']):
        per_seed = {s: report['per_seed'][str(s)]['recordings'] for s in seeds}
        lines += [f'\nFold {i}: held out {", ".join(held)}; open loop AOE 3-D (deg)\n',
                  '| trial | ' + ' | '.join(rows) + ''.join(f' | network seed {s}' for s in seeds)
                  + ' |', '|---' * (len(rows) + len(seeds) + 1) + '|']
        for n in held:
            r = report['recordings'][n]
            lines.append(f'| {n} | ' + ' | '.join(f'{r[m][KEY]:.2f}' for m in rows)
                         + ''.join(f' | {per_seed[s][n]["network"][KEY]:.2f}' for s in seeds)
                         + ' |')
        for label, recs in [('ensemble', report['recordings'])] + [
                (f'seed {s}', per_seed[s]) for s in seeds]:
            for row in ('network', 'network unblended', 'calibrated'):
                if row not in recs[held[0]]:
                    continue
                t = ratios(recs, held, row)
                lines.append(f'- {label}, {row}: mean {t["mean"]:.2f} against {t["bar"]:.2f} '
                             f'({t["ratio"]:.2f}x), mean per-trial ratio {t["mean_ratio"]:.2f}, '
                             f'worst {t["worst_ratio"]:.2f}')
    return lines


def fused(out: Path, dest: Path, data: str, report: dict[str, Any],
          tune: bool = False, vqf: tuple[float, bool, bool] | None = None) -> list[str]:
    """
    Markdown lines: ``imu/data`` of each fold's seeds and ensemble against VQF's defaults.

    Each fold's models with the tracking, and the network with the blend, that the other
    folds chose (the report's ``per_fold``), as its open-loop figures; with ``tune``, their
    filters chosen on their own training trials' validation tails (``tune-fusion
    --attach``, as the shipped file's); with ``vqf`` (tau_acc_s, bias estimation, the
    classical tilt), that VQF for the models' gyros and, without the classical tilt, for the
    raw gyro's rows (as ``tune-fusion --attach`` stores a choice); else at the defaults
    ``train`` stores.
    """
    from denoise_imu_ros.core.modelfile import add_metadata
    from denoise_imu_ros.core.schema import Blend
    from denoise_imu_ros.evaluation.crossval import CANDIDATES
    from denoise_imu_ros.evaluation.evaluate import evaluate
    from denoise_imu_ros.evaluation.filters import attach, Filter, tune_model
    from denoise_imu_ros.learn.checkpoint import save_ensemble
    seeds = report['seeds']
    names = [f'seed{s}' for s in seeds] + ['ensemble']
    lines = []
    for i, held in enumerate(report['folds']):
        choice = report['tracking']['per_fold'][str(i)]
        for name in names:
            folder = dest / f'fold{i}' / name
            folder.mkdir(parents=True, exist_ok=True)
            source = out / (f'seed{seeds[0]}' if name == 'ensemble' else name) / f'fold{i}'
            shutil.copy(source / 'calibrated.safetensors', folder / 'calibrated.safetensors')
            if name == 'ensemble':
                if not (folder / 'network.safetensors').exists():
                    save_ensemble(folder / 'network.safetensors', [
                        str(out / f'seed{s}' / f'fold{i}' / 'network.safetensors')
                        for s in seeds])
            else:
                shutil.copy(source / 'network.safetensors', folder / 'network.safetensors')
            for row in ('network', 'calibrated'):  # the fold's own tracking
                chosen = CANDIDATES[choice[row]]
                add_metadata(folder / f'{row}.safetensors',
                             bias_tracking=None if chosen is None else chosen.as_dict())
            if 'blend' in report:
                classical = CANDIDATES[choice['tracker only']]
                add_metadata(folder / 'network.safetensors', blend=Blend(
                    report['blend']['per_fold'][str(i)], classical).as_dict())
            if vqf is not None:
                chosen = Filter('vqf', vqf[0], vqf[1], classical_tilt=vqf[2])
                raw = Filter('vqf', vqf[0], vqf[1])  # the raw gyro's rows: its own tilt
                for row in ('network', 'calibrated'):
                    add_metadata(folder / f'{row}.safetensors', fusion={
                        'settings': chosen.settings.as_dict(),
                        'filters': {'raw vqf': raw.as_dict()}})
            if tune and not (folder / 'tuned').exists():
                nets = [str(folder / f'{row}.safetensors') for row in ('network', 'calibrated')]
                attach(*nets, tune_model(*nets, data, progress=False))
                (folder / 'tuned').touch()
            if not (folder / 'eval' / 'results.json').exists():
                evaluate(str(folder / 'network.safetensors'), data, held, str(folder / 'eval'),
                         baseline=str(folder / 'calibrated.safetensors'), plots=False,
                         align_poses='auto')
        got = {name: json.loads((dest / f'fold{i}' / name / 'eval' / 'results.json')
                                .read_text())['fused'] for name in names}
        classical = ('raw + VQF defaults', 'tracker only + VQF')
        lines += [f'\nFold {i}: `imu/data` AOE 3-D / tilt (deg)\n',
                  '| trial | ' + ' | '.join(classical) + ' | '
                  + ' | '.join(f'network {n}' for n in names) + ' |',
                  '|---' * (len(names) + 3) + '|']

        def cell(row: dict[str, float]) -> str:
            return f'{row["aoe_deg"]:.2f}/{row["tilt_deg"]:.2f}'
        for n in held:
            lines.append(f'| {n} | ' + ' | '.join(cell(got[names[0]][n][c]) for c in classical)
                         + ' | ' + ' | '.join(cell(got[m][n]['network + VQF']) for m in names)
                         + ' |')
        means = {c: np.array([[got[names[0]][n][c][k] for n in held]
                              for k in ('aoe_deg', 'tilt_deg')]).mean(1) for c in classical}
        lines.append('- ' + ', '.join(f'{c}: 3-D {v[0]:.2f}, tilt {v[1]:.2f}'
                                      for c, v in means.items()))
        base = means['raw + VQF defaults']
        for m in names:
            net = np.array([[got[m][n]['network + VQF'][k] for n in held]
                            for k in ('aoe_deg', 'tilt_deg')]).mean(1)
            lines.append(f'- network {m}: 3-D {net[0]:.2f} against {base[0]:.2f} '
                         f'({net[0] / base[0]:.2f}x), tilt {net[1]:.2f} against {base[1]:.2f}')
    return lines


def main() -> None:
    """Print the open-loop tables of OUT/crossval.json, and with --data the fused ones."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('out', type=Path, help='a crossval --seeds ... --out folder')
    parser.add_argument('--data', help='the recordings (../shared/data/broad): also imu/data')
    parser.add_argument('--dest', type=Path, help='where the fold models with their tracking '
                        'and their eval go, kept and reused (default: OUT/fused, OUT/tuned or '
                        'OUT/vqf_tau<TAU>_bias_<on|off>)')
    parser.add_argument('--tune', action='store_true', help="imu/data's filters chosen on "
                        "each fold model's training trials' tails, as the shipped file's")
    parser.add_argument('--classical-tilt', action='store_true', help='with --vqf: the '
                        "orientation's roll and pitch of VQF's defaults on the raw IMU")
    parser.add_argument('--vqf', nargs=2, metavar=('TAU_S', 'BIAS'), help="imu/data's filter "
                        'for every gyro: VQF with this tau and its bias estimation on or off')
    args = parser.parse_args()
    if args.tune and args.vqf:
        parser.error('--tune and --vqf choose the filter two ways: give one')
    if args.classical_tilt and not args.vqf:
        parser.error('--classical-tilt sets a tilt of --vqf: give it with --vqf')
    vqf = None
    if args.vqf:
        tau, bias = args.vqf
        if bias not in ('on', 'off'):
            parser.error(f'--vqf: bias estimation on or off, not {bias!r}')
        try:
            vqf = (float(tau), bias == 'on', args.classical_tilt)
        except ValueError:
            parser.error(f'--vqf: tau in seconds, not {tau!r}')
    report = json.loads((args.out / 'crossval.json').read_text())
    lines = [f'Verdict ({report["fold_kind"]}): {report["verdict"]}.',
             f'Tracking chosen: {json.dumps(report["tracking"]["per_fold"])}']
    if 'blend' in report:
        lines.append(f'Blend weights chosen: {json.dumps(report["blend"]["per_fold"])}')
    lines += open_loop(report)
    if args.data:
        kind = ('tuned' if args.tune else 'fused' if vqf is None
                else f'vqf_tau{vqf[0]:g}_bias_{args.vqf[1]}'
                + ('_classical_tilt' if args.classical_tilt else ''))
        lines += fused(args.out, args.dest or args.out / kind, args.data, report, args.tune,
                       vqf)
    print('\n'.join(lines))


if __name__ == '__main__':
    main()
