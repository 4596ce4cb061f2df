# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The envelope guard's variants on a session crossval's fold models, with no retraining.

For each held-out trial of ``crossval --sessions ... --seeds ...`` (its models in OUT):
each seed's and the ensemble's open-loop AOE with the shipped guard, with the guard also
where the training power-on's sustained accelerometer excursion is exceeded (the causal
mean of ||a| - g| over W samples above the largest any training trial reached), and each
of those with the classical pipeline's output (the tracker-only gyro) as the fallback
instead of the input plus the envelope's constant less the network-fed tracker's bias.
The tracker-only row uses the fold's chosen tracking, and each seed its own envelope (the
ensemble their union), as crossval's; a recipe with its heading (no vertical drop, as
BROAD's). Prints the per-trial
figures and, per fold, the mean against tracker only, the mean per-trial ratio and the
worst. Run: scripts/reproduce/guard_variants.py OUT ../shared/data/broad [--window 286]
"""

import argparse
import json
from pathlib import Path

from denoise_imu_ros.core.metrics import score
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.evaluation.crossval import CANDIDATES
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
from denoise_imu_ros.pipeline import envelope, stages
from denoise_imu_ros.pipeline.envelope import sustained, within_field
from denoise_imu_ros.pipeline.rest_bias import track_bias, tracked_bias
from denoise_imu_ros.pipeline.vertical import drops_vertical
import numpy as np

VARIANTS = ('guard', 'guard + sustained', 'classical fallback',
            'classical fallback + sustained')


def main() -> None:
    """Score every variant on every held-out trial of every fold."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('out', type=Path, help="crossval's --out (crossval.json, seedS/foldF)")
    parser.add_argument('data', type=Path, help='the folder of the trials')
    parser.add_argument('--window', type=int, default=286, help='samples (286: 1 s at BROAD)')
    args = parser.parse_args()
    report = json.loads((args.out / 'crossval.json').read_text())
    seqs = {}
    for i, held in enumerate(report['folds']):
        train = [n for j, f in enumerate(report['folds']) if j != i for n in f]
        chosen = report['tracking']['per_fold'][str(i)]
        nets = [load_model(args.out / f'seed{s}' / f'fold{i}' / 'network.safetensors')
                for s in report['seeds']]
        bounds = [m.meta.input_envelope for m in nets]  # each seed's, as crossval's
        bounds.append(envelope.combine(bounds))  # the ensemble's
        field, rate = nets[0].model.receptive_field, nets[0].meta.sample_rate_hz
        tracking = CANDIDATES[chosen['network']]
        if drops_vertical(nets[0].meta):
            raise SystemExit('a recipe without its heading: its vertical drop is not scored here')
        for name in {*train, *held} - set(seqs):
            seqs[name] = load_sequence(args.data / name, min_samples=field, align_poses='auto')
        bar = max(sustained(seqs[n].stream, args.window).max() for n in train)
        print(f'fold {i}: sustained bound {bar:.2f} m/s^2 over {args.window} samples')
        figures = {v: {} for v in VARIANTS}  # trial -> (AOE per seed and ensemble, bar)
        for name in held:
            seq = seqs[name]
            fed = stages.model_input(nets[0], seq.stream)
            gyros = [correct_gyro(m.model, fed) for m in nets]
            gyros.append(np.mean(gyros, axis=0))
            classical = track_bias(fed[:, :3], fed[:, 3:], rate,
                                   CANDIDATES[chosen['tracker only']])
            tracker = score(seq, seq.on_poses(classical))['aoe_deg']
            over = within_field(sustained(fed, args.window) > bar, field)
            aoe = {v: [] for v in VARIANTS}
            for g, env in zip(gyros, bounds):
                hold = envelope.too_fast(fed, env, field)
                bias = (np.zeros_like(g) if tracking is None
                        else tracked_bias(g, fed[:, 3:], rate, tracking, hold))
                own = fed[:, :3] + np.array(env.fallback_rad_s) - bias
                base = envelope.untrusted(fed, env, field)
                for variant, mask, fallback in zip(
                        VARIANTS, (base, base | over, base, base | over),
                        (own, own, classical, classical)):
                    aoe[variant].append(score(seq, seq.on_poses(
                        np.where(mask[:, None], fallback, g - bias)))['aoe_deg'])
            for variant in VARIANTS:
                figures[variant][name] = (np.array(aoe[variant]), tracker)
            print(f'| {name} | {tracker:.2f} | ' + ' | '.join(
                '/'.join(f'{a:.2f}' for a in aoe[v]) for v in VARIANTS) + ' |')
        for variant, per in figures.items():
            aoe = np.array([a for a, _ in per.values()])  # trials x (seeds..., ensemble)
            bar_aoe = np.array([b for _, b in per.values()])
            ratio = aoe / bar_aoe[:, None]
            print(f'  {variant}: ensemble {aoe[:, -1].mean():.2f} against tracker only '
                  f'{bar_aoe.mean():.2f} ({aoe[:, -1].mean() / bar_aoe.mean():.2f}x), mean '
                  f'per-trial ratio {ratio[:, -1].mean():.2f}, worst {ratio[:, -1].max():.2f}; '
                  'each seed ' + ', '.join(f'{x:.2f}x' for x in aoe[:, :-1].mean(0)
                                           / bar_aoe.mean())
                  + f', worst {ratio[:, :-1].max():.2f}')


if __name__ == '__main__':
    main()
