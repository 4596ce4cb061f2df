# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The network's output blended with the classical pipeline's, on a session crossval's folds.

For each held-out trial of ``crossval --sessions ... [--motions ...] --seeds ...`` (its
models in OUT), each seed's and the ensemble's guarded, tracked output N (as the product
computes it where it blends: its tracker held where too fast or beyond the sustained bound)
and the classical pipeline's gyro T (the gyro less its turn-on bias, its bias tracked as the
fold's tracker-only row) are combined per sample:
- ``blend W``: T + W (N - T), with T alone where the fallback rule flags the sample
  (``sustained``: a sample of the receptive field whose causal 1 s mean of ||a| - g| is
  above the largest any training trial reached, the model file's; ``envelope``: that or
  the model's own envelope, as the product's classical mix; ``held``: as ``envelope``,
  but there T's tracker held through the stretches faster than the envelope as the
  network's is (its estimate from before each restored after it); ``held everywhere``:
  that T blended everywhere; ``none``); ``--release S`` keeps the sustained flag S s
  after its last;
- ``gravity``: N or T, whichever kept the accelerometer's direction steadier in its own
  open-loop world frame over the last WIN s (low-passed over LP s), or the blend W unless
  its turn exceeds T's by more than ``--margins``: a causal selector;
- ``spread``: the blend W where the seeds' outputs agree, T where their spread (the RMS
  over the axes of their standard deviation, its causal mean over SPREAD_S) exceeds a
  bound (``--spreads``, deg/s): the ensemble's own doubt, beyond what its members saw;
- ``highpass``: T + W HP(N - T), the difference's causal first-order high-pass at TAU s
  (``--highpass``): the network gives what changes within seconds, the classical tracker
  the slow rest (the bias a new power-on moves);
- ``rates``: the blend W where the gyro's causal RATE_S mean norm is at least a bound
  (``--rates``, deg/s), T below it: the network in fast motion only, where a bias tracker
  cannot follow scale and misalignment, the classical pipeline in slow motion.
Prints, per fold and setting, the mean against tracker only, the mean per-trial ratio and
the worst, for the ensemble and each seed. Run: .venv/bin/python
scripts/reproduce/blend_fallback.py OUT ../shared/data/broad --weights 1 0.7 0.5 0.3
--fallback sustained [--gravity LP WIN]
"""

import argparse
import json
from pathlib import Path

from denoise_imu_ros.core.metrics import integrate, score
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.evaluation.crossval import CANDIDATES
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
from denoise_imu_ros.pipeline import envelope, stages
from denoise_imu_ros.pipeline.rest_bias import track_bias
import numpy as np
from scipy.signal import lfilter

SPREAD_S = 1.0  # s, the causal mean of the seeds' spread
RATE_S = 1.0    # s, the causal mean of the gyro's norm (--rates)


def trials(out: Path, data: Path, release_s: float = 0.0) -> dict[str, dict]:
    """
    Return, per held-out trial: its fold, sequence, T, each N and their flags.

    ``release_s``: the sustained flag kept that long after the receptive field's last.
    """
    report = json.loads((out / 'crossval.json').read_text())
    found = {}
    for i, held_out in enumerate(report['folds']):
        chosen = report['tracking']['per_fold'][str(i)]
        nets = [load_model(out / f'seed{s}' / f'fold{i}' / 'network.safetensors')
                for s in report['seeds']]
        bounds = [m.meta.input_envelope for m in nets]
        bounds.append(envelope.combine(bounds))  # the ensemble's
        field, rate = nets[0].model.receptive_field, nets[0].meta.sample_rate_hz
        tracking = CANDIDATES[chosen['network']]
        classical_tracking = CANDIDATES[chosen['tracker only']]
        for name in held_out:
            seq = load_sequence(data / name, min_samples=field, align_poses='auto')
            fed = stages.model_input(nets[0], seq.stream)
            gyros = [correct_gyro(m.model, fed) for m in nets]
            gyros.append(np.mean(gyros, axis=0))
            outputs, untrusted, flags, steady = [], [], [], []
            for g, env in zip(gyros, bounds):
                guard = envelope.Guard(env, field, rate, hold_beyond=True)  # as blended
                outputs.append(stages.Pipeline(
                    ([] if tracking is None else [stages.BiasTrackingStage(tracking, rate)])
                    + [stages.EnvelopeCheck(guard, rate), stages.EnvelopeApply(guard)]
                ).run(stages.Flow(fed, out=g)).out)
                untrusted.append(envelope.untrusted(fed, env, field))
                hold = envelope.too_fast(fed, env, field) | envelope.beyond(fed, env, field, rate)
                steady.append(track_bias(fed[:, :3], fed[:, 3:], rate, classical_tracking,
                                         hold))
                flags.append(envelope.beyond(fed, env, field + round(release_s * rate), rate))
            found[name] = {
                'fold': i, 'seq': seq, 'accel': fed[:, 3:], 'rate': rate,
                'classical': track_bias(fed[:, :3], fed[:, 3:], rate, classical_tracking),
                'nets': outputs, 'untrusted': untrusted, 'sustained': flags,
                'steady': steady, 'speed': causal_mean(np.linalg.norm(fed[:, :3], axis=1),
                                                       max(1, int(RATE_S * rate)))}
    return found


def causal_mean(values: np.ndarray, n: int) -> np.ndarray:
    """Return each sample's mean of ``values`` (N,) over the last n samples (fewer at first)."""
    total = np.concatenate([[0.0], np.cumsum(values)])
    k = np.arange(len(values))
    start = np.maximum(k + 1 - n, 0)
    return (total[k + 1] - total[start]) / (k + 1 - start)


def seed_spread(nets: list[np.ndarray], rate: float) -> np.ndarray:
    """Return the causal SPREAD_S mean of the seeds' outputs' spread (rad/s) per sample."""
    spread = np.sqrt(np.mean(np.var(np.stack(nets), axis=0), axis=1))
    return causal_mean(spread, max(1, int(SPREAD_S * rate)))


def high_pass(diff: np.ndarray, rate: float, tau_s: float) -> np.ndarray:
    """Return diff less its causal exponential mean over tau_s (started at zero)."""
    alpha = 1.0 / max(1.0, tau_s * rate)
    return diff - lfilter([alpha], [1.0, alpha - 1.0], diff, axis=0)


def gravity_drift(gyro: np.ndarray, accel: np.ndarray, rate: float, lp_s: float,
                  win_s: float) -> np.ndarray:
    """Return the angle (rad) the low-passed world accelerometer turned over the last win_s."""
    world = integrate(np.array([0.0, 0.0, 0.0, 1.0]), gyro[:-1],
                      np.full(len(gyro) - 1, 1.0 / rate)).apply(accel)
    n = max(1, int(lp_s * rate))
    total = np.concatenate([np.zeros((1, 3)), np.cumsum(world, axis=0)])
    k = np.arange(len(world))
    start = np.maximum(k + 1 - n, 0)
    low = (total[k + 1] - total[start]) / (k + 1 - start)[:, None]
    w = min(max(1, int(win_s * rate)), len(low))
    past = np.vstack([np.repeat(low[:1], w, axis=0), low[:len(low) - w]])
    norms = np.linalg.norm(low, axis=1) * np.linalg.norm(past, axis=1)
    cos = np.einsum('ij,ij->i', low, past) / norms
    return np.arccos(np.clip(cos, -1.0, 1.0))


def main() -> None:
    """Score every setting on every held-out trial of every fold."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('out', type=Path, help="crossval's --out (crossval.json, seedS/foldF)")
    parser.add_argument('data', type=Path, help='the folder of the trials')
    parser.add_argument('--weights', type=float, nargs='+', default=[1.0, 0.7, 0.5, 0.3])
    parser.add_argument('--fallback', choices=('none', 'sustained', 'envelope', 'held',
                                               'held everywhere'), default='sustained')
    parser.add_argument('--gravity', type=float, nargs=2, metavar=('LP', 'WIN'),
                        help='also the gravity selector, low-pass LP s, window WIN s')
    parser.add_argument('--margins', type=float, nargs='+', default=[0.0], metavar='DEG',
                        help='the gravity selector keeps the blend unless its drift exceeds '
                             "T's by more than DEG (one setting per weight and margin)")
    parser.add_argument('--spreads', type=float, nargs='+', default=[], metavar='DEG_S',
                        help="also the blend where the seeds' spread stays within DEG_S deg/s "
                             '(T beyond it), one setting per weight and bound')
    parser.add_argument('--highpass', type=float, nargs='+', default=[], metavar='TAU',
                        help="also the blend of the difference's high-pass at TAU s (one "
                             'setting per weight and TAU)')
    parser.add_argument('--rates', type=float, nargs='+', default=[], metavar='DEG_S',
                        help='also the blend where the 1 s mean rate is at least DEG_S deg/s '
                             '(T below it), one setting per weight and bound')
    parser.add_argument('--release', type=float, default=0.0, metavar='S',
                        help='the sustained flag kept S s after its last sample')
    args = parser.parse_args()
    found = trials(args.out, args.data, args.release)
    settings = [(f'blend {w:g}', w, None, None, None, None) for w in args.weights]
    if args.gravity:
        settings += [(f'gravity {args.gravity[0]:g} s / {args.gravity[1]:g} s, blend {w:g}, '
                      f'margin {m:g} deg', w, np.radians(m), None, None, None)
                     for w in args.weights for m in args.margins]
    settings += [(f'spread within {b:g} deg/s, blend {w:g}', w, None, np.radians(b), None,
                  None) for w in args.weights for b in args.spreads]
    settings += [(f'high-pass {tau:g} s, blend {w:g}', w, None, None, tau, None)
                 for w in args.weights for tau in args.highpass]
    settings += [(f'from {r:g} deg/s, blend {w:g}', w, None, None, None, np.radians(r))
                 for w in args.weights for r in args.rates]
    for fold in sorted({t['fold'] for t in found.values()}):
        names = [n for n, t in found.items() if t['fold'] == fold]
        bar = np.array([score(found[n]['seq'], found[n]['seq'].on_poses(
            found[n]['classical']))['aoe_deg'] for n in names])
        print(f'fold {fold}: tracker only {bar.mean():.2f} over ' + ', '.join(names))
        turned = {}  # T's gravity drift per trial and network: the same for every setting
        spread = {n: seed_spread(found[n]['nets'][:-1], found[n]['rate']) for n in names}
        for label, weight, margin, bound, tau, fast in settings:
            aoe = []
            for n in names:
                t = found[n]
                row = []
                for k, (net, untrusted, held, steady) in enumerate(zip(
                        t['nets'], t['untrusted'], t['sustained'], t['steady'])):
                    flag = {'none': np.zeros(len(net), bool), 'sustained': held}.get(
                        args.fallback, held | untrusted)
                    classical = {'held': np.where(untrusted[:, None], steady, t['classical']),
                                 'held everywhere': steady}.get(args.fallback, t['classical'])
                    w = np.full(len(net), weight)
                    if margin is not None:
                        if (n, k) not in turned:
                            turned[n, k] = gravity_drift(classical, t['accel'], t['rate'],
                                                         *args.gravity)
                        blend = classical + weight * (net - classical)
                        w *= gravity_drift(blend, t['accel'], t['rate'], *args.gravity) <= \
                            turned[n, k] + margin
                    if bound is not None:
                        w *= spread[n] <= bound
                    if fast is not None:
                        w *= t['speed'] >= fast
                    w = np.where(flag, 0.0, w)[:, None]
                    diff = net - classical
                    if tau is not None:
                        diff = high_pass(diff, t['rate'], tau)
                    row.append(score(t['seq'], t['seq'].on_poses(
                        classical + w * diff))['aoe_deg'])
                aoe.append(row)
            aoe = np.array(aoe)  # trials x (seeds..., ensemble)
            ratio = aoe / bar[:, None]
            print(f'  {label}, fallback {args.fallback}: ensemble {aoe[:, -1].mean():.2f} '
                  f'({aoe[:, -1].mean() / bar.mean():.2f}x), per-trial {ratio[:, -1].mean():.2f}, '
                  f'worst {ratio[:, -1].max():.2f}; seeds '
                  + ', '.join(f'{x:.2f}x' for x in aoe[:, :-1].mean(0) / bar.mean())
                  + ', per-trial ' + ', '.join(f'{x:.2f}' for x in ratio[:, :-1].mean(0))
                  + f', worst {ratio[:, :-1].max():.2f}')
            print('    ' + ' '.join(f'{n[:2]} {a:.2f}/{b:.2f}' for n, a, b in
                                    zip(names, aoe[:, -1], bar)))


if __name__ == '__main__':
    main()
