# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The training loss's cost per step: increments on a fixed grid against between pose stamps.

One batch of the VINS-Mono recipe's shape (6 windows of 10,240 samples, increments of
256 and 512 samples), forward and backward, one thread, side by side in one run so
that the ratio is meaningful on a shared machine: the grid loss, then the loss between
poses with a pose every 20 samples (10 Hz) and every 40-200 (keyframes, 0.2-1.0 s).
Prints the median milliseconds of each and its ratio to the grid loss.
Run: .venv/bin/python bench/loss_cost.py [--repeats N]
"""

import argparse
import time

from denoise_imu_ros.learn.config import LossConfig
from denoise_imu_ros.learn.loss import increment_loss
from denoise_imu_ros.learn.so3 import prefix_product, quat_exp
import numpy as np
import torch

ROWS, WINDOW, INCREMENTS = 6, 10_240, (256, 512)


def median_ms(omega: torch.Tensor, inputs: tuple[torch.Tensor, ...], cfg: LossConfig,
              pose_at: torch.Tensor, repeats: int) -> float:
    """Return the median time of one loss, forward and backward, in ms."""
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        increment_loss(omega, *inputs, cfg, pose_at=pose_at).backward()
        times.append(time.perf_counter() - t)
    return 1e3 * float(np.median(times))


def main() -> None:
    """Time the three variants and print them."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--repeats', type=int, default=30)
    args = parser.parse_args()
    torch.set_num_threads(1)
    gen = torch.Generator().manual_seed(0)
    omega = (0.3 * torch.randn(ROWS, WINDOW, 3, generator=gen,
                               dtype=torch.float64)).requires_grad_()
    dt = torch.full((ROWS, WINDOW), 0.005, dtype=torch.float64)
    truth = prefix_product(quat_exp(1e-3 * torch.randn(ROWS, WINDOW, 3, generator=gen,
                                                       dtype=torch.float64)))
    valid = torch.ones(ROWS, WINDOW + 1, dtype=torch.bool)
    every10hz = torch.zeros_like(valid)
    every10hz[:, ::20] = True
    keyframes = torch.zeros_like(valid)
    stamps = np.cumsum(np.random.default_rng(0).integers(40, 201, (ROWS, WINDOW // 40)), 1)
    for row, s in enumerate(stamps):
        keyframes[row, s[s <= WINDOW]] = True
    grid = LossConfig(increments=INCREMENTS, weights=(1.0, 0.5))
    between = LossConfig(increments=INCREMENTS, weights=(1.0, 0.5), between_poses=True)
    inputs = (dt, truth, valid)
    base = median_ms(omega, inputs, grid, every10hz, args.repeats)
    print(f'grid increments:                      {base:6.1f} ms')
    for name, pose_at in (('10 Hz poses', every10hz), ('keyframes, 0.2-1.0 s', keyframes)):
        ms = median_ms(omega, inputs, between, pose_at, args.repeats)
        print(f'between pose stamps, {name:20s} {ms:6.1f} ms  ({ms / base:.1f}x the grid)')


if __name__ == '__main__':
    main()
