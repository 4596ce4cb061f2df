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
Prints seconds per step and the projected time of the full recipe, and a floor: the
recipe's convolution arithmetic (forward and backward) at the speed this machine
multiplies large float32 matrices, every core busy, nothing else counted. Then the
whole recipe once, timed end to end (loading, validation and weight average included),
with ``--full``.
Run: .venv/bin/python bench/train_speed.py [--steps N] [--full]
"""

import argparse
from pathlib import Path
import time

from denoise_imu_ros.core.architecture import ModelConfig
from denoise_imu_ros.learn.config import load_config, usable_cores
from denoise_imu_ros.learn.model import GyroNet
from denoise_imu_ros.learn.train import train
import torch

ROOT = Path(__file__).resolve().parents[1]


RECIPE = ROOT / 'config' / 'train_euroc.yaml'
DATA = str(ROOT.parent / 'shared' / 'data' / 'euroc')


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


def conv_macs_per_step(sequences: int, window: int) -> float:
    """Multiply-adds of the convolutions in one step: forward, input and weight gradients."""
    model = GyroNet(ModelConfig())
    convs = [m for m in model.net if isinstance(m, torch.nn.Conv1d)]
    length = window + model.receptive_field - 1  # the padded input of the first layer
    total = 0.0
    for i, conv in enumerate(convs):
        length -= conv.dilation[0] * (conv.kernel_size[0] - 1)
        forward = sequences * length * conv.in_channels * conv.out_channels * conv.kernel_size[0]
        total += forward * (2 if i == 0 else 3)  # no input gradient for the first layer
    return total


def gemm_macs_per_second(size: int = 2048, repeats: int = 5) -> float:
    """Float32 matrix-product speed of one thread (the best case for a convolution)."""
    torch.set_num_threads(1)
    a, b = torch.randn(size, size), torch.randn(size, size)
    torch.mm(a, b)
    t = time.perf_counter()
    for _ in range(repeats):
        torch.mm(a, b)
    return size ** 3 * repeats / (time.perf_counter() - t)


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
    macs = conv_macs_per_step(len(recipe.sequences), recipe.window)
    floor = macs / (usable_cores() * gemm_macs_per_second())
    base = rows[0][1]
    print(f'{"variant":52s} {"s/step":>8s} {f"{full} steps":>11s} {"ratio":>6s} '
          f'{"x floor":>8s}')
    for name, t in rows:
        print(f'{name:52s} {t:8.3f} {t * full / 60:7.1f} min {t / base:6.2f} '
              f'{t / floor:8.2f}')
    print(f'floor: {macs / 1e9:.1f} GMAC of convolutions per step at the float32 GEMM speed '
          f'of {usable_cores()} cores: {floor:.3f} s/step, {floor * full / 60:.1f} min')
    if args.full:
        t = time.perf_counter()
        train(load_config(RECIPE, data=DATA), progress=False)
        print(f'the whole recipe ({full} steps, validation and weight average included): '
              f'{(time.perf_counter() - t) / 60:.1f} min')


if __name__ == '__main__':
    main()
