# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Training speed of the EuRoC recipe (6 sequences x 16,000 samples per step).

Runs the real trainer twice per variant, for a few and for more steps, and reports the
difference per step, which leaves out loading and validation. Variants, side by side in
the same run so that ratios are meaningful on a shared machine, each with PyTorch's
BatchNorm, GELU and dropout layers one by one (``fused: false``) and with the fused block
(learn/fused.py, the default):
  - one process with 2 threads;
  - the recipe as shipped (``workers: auto``, ``threads: auto``: what this machine has).
Prints seconds per step and the projected time of the full recipe, and a floor: each
convolution layer of one core's share of the step (forward, input and weight gradients)
at the faster of two forms, the three matrix products of its gathered taps and oneDNN's
convolution, each the best of several timings of those very shapes, every core busy,
nothing else counted; the floor's spread over repeats; per layer both forms' speed beside
a large square GEMM's; and how much of the step is not convolution at all. Then the whole
recipe once, timed end to end (loading, validation and weight average included), with
``--full``.
Run: .venv/bin/python bench/train_speed.py [--steps N] [--full]
"""

import argparse
from pathlib import Path
import statistics
import time

from conv_layers import best_of, layer  # bench/, beside this script
from denoise_imu_ros.core.architecture import ModelConfig
from denoise_imu_ros.learn.config import load_config, usable_cores
from denoise_imu_ros.learn.train import train
import torch

ROOT = Path(__file__).resolve().parents[1]


RECIPE = ROOT / 'config' / 'train_euroc.yaml'
DATA = str(ROOT.parent / 'shared' / 'data' / 'euroc')
FLOOR_REPEATS = 5  # timings of the floor, whose spread is printed


def seconds_per_step(steps: int, **variant: object) -> float:
    """Time of `steps` more training steps, by difference of two runs."""
    times = []
    for n in (steps // 4, steps + steps // 4):
        cfg = load_config(RECIPE, data=DATA, steps=n, val_every=10 * n, swa_start=0,
                          select='final', **variant)
        t = time.perf_counter()
        train(cfg, progress=False)
        times.append(time.perf_counter() - t)
    return (times[1] - times[0]) / steps


def layer_shapes(windows: int, window: int) -> list[tuple[int, int, int, int, int]]:
    """(c_in, c_out, kernel, dilation, input length) of each convolution the step trains."""
    cfg = ModelConfig()
    length, shapes = window + cfg.receptive_field - 1, []  # the padded input of the first
    for c_in, c_out, k, d, groups in cfg.convolutions():
        if groups == 1:  # an ensemble's grouped layers are left out
            shapes.append((c_in, c_out, k, d, length))
        length -= d * (k - 1)
    return shapes


def layer_seconds(windows: int, shapes: list) -> dict[str, tuple[float, float, float]]:
    """
    Per layer: its matrix products' best time, its oneDNN convolution's, its multiply-adds.

    The products of the gathered taps (one core): forward W (c_out, c_in k) @ taps
    (c_in k, windows out), input gradient W^T @ grad, weight gradient grad @ taps^T; the
    first layer needs no input gradient, in either form.
    """
    out: dict[str, tuple[float, float, float]] = {}
    for i, (c_in, c_out, k, d, length) in enumerate(shapes):
        n = windows * (length - d * (k - 1))
        w, taps, grad = (torch.randn(c_out, c_in * k), torch.randn(c_in * k, n),
                         torch.randn(c_out, n))
        products = [lambda: torch.mm(w, taps), lambda: torch.mm(grad, taps.T)]
        if i:
            products.append(lambda: torch.mm(w.T, grad))
        out[f'{c_in}->{c_out} d={d}'] = (
            sum(best_of(p) for p in products),
            layer(c_in, c_out, k, d, length, torch.float32, False, windows, i > 0),
            float(len(products) * n * c_in * c_out * k))
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('--steps', type=int, default=40, help='steps timed per variant')
    parser.add_argument('--full', action='store_true',
                        help='then train the whole shipped recipe once, timed end to end')
    args = parser.parse_args()
    recipe = load_config(RECIPE)
    full = recipe.steps
    shipped = f'recipe: {recipe.workers} workers, {recipe.threads} threads'
    rows = [(f'{name}, {layers}', seconds_per_step(args.steps, fused=fused, **variant))
            for name, variant in (('1 process, 2 threads', {'workers': 1, 'threads': 2}),
                                  (shipped, {}))
            for layers, fused in (('PyTorch layers', False), ('fused', True))]
    torch.set_num_threads(1)
    cores = usable_cores()
    windows = -(-len(recipe.sequences) // cores)  # one core's share of the step's windows
    shapes = layer_shapes(windows, recipe.window)
    repeats = [layer_seconds(windows, shapes) for _ in range(FLOOR_REPEATS)]
    floors = [sum(min(gemm, conv) for gemm, conv, _ in r.values()) for r in repeats]
    floor = min(floors)
    base = rows[0][1]
    print(f'{"variant":52s} {"s/step":>8s} {f"{full} steps":>11s} {"ratio":>6s} '
          f'{"x floor":>8s}')
    for name, t in rows:
        print(f'{name:52s} {t:8.3f} {t * full / 60:7.1f} min {t / base:6.2f} '
              f'{t / floor:8.2f}')
    print(f'floor: the convolutions of {windows} windows per core ({cores} cores), each the '
          'faster of its matrix products and its oneDNN convolution at those shapes: '
          f'{floor:.3f} s/step (best of {FLOOR_REPEATS} timings; spread {min(floors):.3f}-'
          f'{max(floors):.3f}, median {statistics.median(floors):.3f}), '
          f'{floor * full / 60:.1f} min')
    a, b = torch.randn(2048, 2048), torch.randn(2048, 2048)
    peak = 2048 ** 3 / best_of(lambda: torch.mm(a, b))
    print(f'{"layer":>16s} {"GMAC":>6s} {"products ms":>12s} {"GMAC/s":>7s} {"oneDNN ms":>10s} '
          f'{"GMAC/s":>7s}   (a 2048x2048 float32 GEMM: {peak / 1e9:.1f} GMAC/s)')
    best = {name: [min(r[name][i] for r in repeats) for i in range(3)] for name in repeats[0]}
    for name, (gemm, conv, macs) in best.items():
        print(f'{name:>16s} {macs / 1e9:6.2f} {1e3 * gemm:12.1f} {macs / gemm / 1e9:7.1f} '
              f'{1e3 * conv:10.1f} {macs / conv / 1e9:7.1f}')
    conv_total = sum(conv for _, conv, _ in best.values())
    fastest = min(t for _, t in rows)
    print(f"the convolutions the step runs: {conv_total:.3f} s of the fastest variant's "
          f'{fastest:.3f} s/step; the rest ({max(fastest - conv_total, 0.0):.3f} s: '
          'normalisation, activations, loss, optimiser, data-parallel averaging) has no floor')
    if args.full:
        t = time.perf_counter()
        train(load_config(RECIPE, data=DATA), progress=False)
        print(f'the whole recipe ({full} steps, validation and weight average included): '
              f'{(time.perf_counter() - t) / 60:.1f} min')


if __name__ == '__main__':
    main()
