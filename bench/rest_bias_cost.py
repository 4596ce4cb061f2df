# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What the bias estimates add to the online pipeline's per-sample cost, side by side.

Runs the same model over the same real samples through ``OnlineDenoiser.process`` (the
node's and process-bag's per-sample work, without ROS) with ``rest_bias`` off and on
(the turn-on bias before the model, and its output's tracking where the file has one),
alternating rounds so that a change in the machine's speed hits both alike, and each
estimator alone (``RestBias.update``, ``BiasTracker.update``; the tracker with and without
its hold through fast rotation, ``hold_above_deg_s``), and the input envelope's
guard alone where the file has one (``Guard.check`` and ``Guard.apply``, which both
settings run), and the vertical's projection alone (``Vertical.apply``, which both run for
a model taught without its poses' heading). Where the file blends its output with the
classical pipeline's (its ``blend``), also rounds with ``rest_bias`` on and
``classical_blend`` off, and the blend alone (``Blender.apply``). And rounds with
``imu/data``'s filter (the file's settings), with and without the classical tilt (a
second VQF on the raw IMU), their order swapped every round, and each filter alone
(``GravityFilter.update``). Prints the median per-sample time of each, and the ratios
on/off, blend/no blend, held/unheld tracker and classical tilt/own tilt.
Run: .venv/bin/python bench/rest_bias_cost.py [--model broad_network]
     [--data ../shared/data/broad] [--recording 03_undisturbed_slow_rotation_C]
     [--samples 20000] [--rounds 5]
"""

import argparse
import dataclasses
import gc
from pathlib import Path
import time

from denoise_imu_ros.core.modelfile import read_model_file, sample_rate
from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.pipeline.blend import Blender
from denoise_imu_ros.pipeline.envelope import Guard
from denoise_imu_ros.pipeline.fusion import GravityFilter
from denoise_imu_ros.pipeline.online import OnlineDenoiser
from denoise_imu_ros.pipeline.rest_bias import BiasTracker, HOLD_ABOVE_DEG_S, resolve, RestBias
from denoise_imu_ros.pipeline.vertical import Vertical
import numpy as np

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'broad'


def per_sample_s(step, stamps: np.ndarray, imu: np.ndarray) -> float:
    """Return the mean time of ``step(stamp, gyro, accel)`` over the samples, seconds."""
    rows = [(int(t), r[:3].copy(), r[3:].copy()) for t, r in zip(stamps, imu)]
    gc.collect()  # the last round's garbage is not this one's cost
    start = time.perf_counter()
    for t, g, a in rows:
        step(t, g, a)
    return (time.perf_counter() - start) / len(rows)


def main() -> None:
    """Print the per-sample cost with rest_bias off and on, and of each estimator alone."""
    parser = argparse.ArgumentParser()
    parser.add_argument('--model', default='broad_network')
    parser.add_argument('--data', type=Path, default=DATA)
    parser.add_argument('--recording', default='03_undisturbed_slow_rotation_C')
    parser.add_argument('--samples', type=int, default=20000)
    parser.add_argument('--rounds', type=int, default=5)
    args = parser.parse_args()
    model = read_model_file(args.model)
    rec = load_imu(args.data / args.recording)
    stamps, imu = rec.imu_stamp_ns[:args.samples], rec.imu[:args.samples]
    blended = model.meta.blend is not None
    own = model.meta.fusion.chosen
    filters = {'on, imu/data': dataclasses.replace(own, classical_tilt=False),
               'on, imu/data, classical tilt': dataclasses.replace(own, classical_tilt=True)}
    times = {'off': [], 'on': [], 'on, no blend': [], **{name: [] for name in filters},
             **{f'{name} filter alone': [] for name in filters},
             'estimator alone': [],
             'tracker alone': [], 'held tracker alone': [], 'envelope guard alone': [],
             'blend alone': [],
             'vertical alone': []}
    for _ in range(args.rounds):
        for name, choice, mix in (('off', 'off', 'model'), ('on', 'on', 'model'),
                                  ('on, no blend', 'on', 'off')):
            if mix == 'off' and not blended:
                continue
            den = OnlineDenoiser.from_model_file(model, rest_choice=choice, blend_choice=mix)
            times[name].append(per_sample_s(den.process, stamps, imu))
        for name in sorted(filters, reverse=len(times['off']) % 2 == 0):  # order swapped
            den = OnlineDenoiser.from_model_file(model, filters[name], rest_choice='on')
            times[name].append(per_sample_s(den.process, stamps, imu))
            gravity = GravityFilter(sample_rate(model), filters[name])
            times[f'{name} filter alone'].append(
                per_sample_s(lambda t, g, a: gravity.update(g, a, 1.0, g), stamps, imu))
        rest = RestBias(resolve(model.meta, 'on'), sample_rate(model))
        times['estimator alone'].append(
            per_sample_s(lambda t, g, a: rest.update(g, a), stamps, imu))
        if model.meta.bias_tracking is not None:
            for name, bound in (('tracker alone', None), ('held tracker alone', HOLD_ABOVE_DEG_S)):
                settings = dataclasses.replace(model.meta.bias_tracking, hold_above_deg_s=bound)
                track = BiasTracker(settings, sample_rate(model))
                times[name].append(per_sample_s(lambda t, g, a: track.update(g, a), stamps, imu))
        if model.meta.input_envelope is not None:
            guard = Guard(model.meta.input_envelope, model.config.receptive_field,
                          sample_rate(model))

            def guarded(t: int, g: np.ndarray, a: np.ndarray) -> np.ndarray:
                fed = np.concatenate([g, a])  # fed as the pipeline feeds it
                guard.check(fed)
                return guard.apply(g, fed)

            times['envelope guard alone'].append(per_sample_s(guarded, stamps, imu))
        if blended:
            blender = Blender(model.meta.blend, sample_rate(model))

            def mixed(t: int, g: np.ndarray, a: np.ndarray) -> np.ndarray:
                return blender.apply(g, np.concatenate([g, a]))

            times['blend alone'].append(per_sample_s(mixed, stamps, imu))
        vertical = Vertical(sample_rate(model))

        def projected(t: int, g: np.ndarray, a: np.ndarray) -> np.ndarray:
            return vertical.apply(g, np.concatenate([g, a]))

        times['vertical alone'].append(per_sample_s(projected, stamps, imu))
    median = {k: float(np.median(v)) for k, v in times.items() if v}
    print(f'{model.path.name}, {len(stamps)} samples of {args.recording}, '
          f'{args.rounds} rounds alternating, median per sample:')
    for name, value in median.items():
        print(f'  the {name.replace(" alone", "").replace("on, ", "")} alone: '
              f'{value * 1e6:.1f} us' if name.endswith(' alone')
              else f'  rest_bias {name}: {value * 1e6:.1f} us')
    print(f'  on / off: {median["on"] / median["off"]:.3f}')
    if 'tracker alone' in median:
        print(f'  held / unheld tracker: '
              f'{median["held tracker alone"] / median["tracker alone"]:.3f}, the difference '
              f'{(median["held tracker alone"] - median["tracker alone"]) / median["on"]:.3f} '
              'of rest_bias on')
    if blended:
        print(f'  blend / no blend (rest_bias on): {median["on"] / median["on, no blend"]:.3f}')
    print(f'  imu/data / none (rest_bias on): {median["on, imu/data"] / median["on"]:.3f}')
    print('  classical tilt / own tilt (rest_bias on, imu/data): '
          f'{median["on, imu/data, classical tilt"] / median["on, imu/data"]:.3f}')


if __name__ == '__main__':
    main()
