# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Streaming engine vs recomputing the window, side by side, on a real EuRoC test sequence.

Prints, for the same model and samples: the median and p99 per-sample cost of the
streaming engine's two steps (the compiled one, ``_step.c``, and numpy's), of the batch
torch network recomputing the last 511 samples for every new sample, the speed-up, the
largest difference between each step's output over the whole sequence and the batch
output, and the engine's floor: the same matrix-vector products alone (numpy's BLAS,
back to back on preallocated vectors), with each step's cost over it. With --members K,
the same for an ensemble of K networks (the model's weights K times over: the cost does
not depend on the weights), timed in the same run; an ensemble file (the shipped
``euroc``, ``tumvi``) is timed as it is.
Run: .venv/bin/python bench/streaming.py [--model euroc] [--sequence V1_01_easy]
     or, for one network and an ensemble of it: --model <one training's file> --members 5
"""

import argparse
from pathlib import Path
import time

from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
from denoise_imu_ros.learn.model import merge
from denoise_imu_ros.pipeline.streaming import StreamingCorrector
import numpy as np
import torch

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'euroc'


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--model', default='euroc')
    parser.add_argument('--sequence', default='V1_01_easy')
    parser.add_argument('--window-samples', type=int, default=2000,
                        help='samples timed for the window recompute (it is slow)')
    parser.add_argument('--members', type=int, default=1,
                        help='also time an ensemble of this many networks')
    args = parser.parse_args()
    torch.set_num_threads(1)
    torch.set_flush_denormal(True)  # as the denoise-imu command does
    model = load_model(args.model).model
    given = model.config.members
    if args.members > 1 and given > 1:
        parser.error(f'--members: {args.model} is an ensemble already; pass one network')
    imu = load_imu(DATA / args.sequence).imu
    print(f'sequence {args.sequence}: {len(imu)} samples, model {args.model}')
    rf = model.receptive_field
    u = torch.tensor(imu, dtype=torch.float32)
    window_costs = []
    with torch.no_grad():
        for n in range(rf, rf + args.window_samples):
            t = time.perf_counter()
            model(u[None, n - rf + 1:n + 1])[0, -1]
            window_costs.append(time.perf_counter() - t)
    print(f'window recompute : median {np.median(window_costs) * 1e6:7.1f} us  '
          f'p99 {np.percentile(window_costs, 99) * 1e6:7.1f} us per sample (torch, 1 thread)')
    nets = [('one network' if given == 1 else f'the model ({given} networks)', model)]
    if args.members > 1:
        nets.append((f'ensemble of {args.members}', merge([model] * args.members)))
    for name, net in nets:
        batch = correct_gyro(net, imu)
        base = np.median(floor(net))
        print(f'{name}: floor (the products alone) median {base * 1e6:6.1f} us')
        for compiled in (True, False):
            costs, out = stream(net, imu, compiled)
            med = np.median(costs)
            print(f'  {"compiled" if compiled else "numpy":8s} step: median {med * 1e6:6.1f} us  '
                  f'p99 {np.percentile(costs, 99) * 1e6:6.1f} us per sample; '
                  f'{med / base:.2f}x the floor; {np.median(window_costs) / med:.0f}x faster '
                  f'than the window; max |streaming - batch| {np.abs(out - batch).max():.1e}')


def floor(model, repeats: int = 5000) -> np.ndarray:
    """Per-sample cost (s) of the engine's matrix-vector products alone, back to back."""
    engine = StreamingCorrector.from_module(model, compiled=False)
    products = [(buf.weight[0], buf.col[0, :, 0], buf.out) if buf.layer.groups == 1 else
                (buf.weight, buf.col, buf.out.reshape(buf.layer.groups, -1, 1))
                for buf in engine._hidden]
    products.append((engine._out, engine._out_in, np.empty(3, np.float32)))
    costs = np.empty(repeats)
    for n in range(repeats):
        t = time.perf_counter()
        for w, x, y in products:
            (np.dot if w.ndim == 2 else np.matmul)(w, x, out=y)
        costs[n] = time.perf_counter() - t
    return costs


def stream(model, imu, compiled):
    """Per-sample cost (s) and output of the streaming engine over ``imu``."""
    engine = StreamingCorrector.from_module(model, compiled)
    costs = np.empty(len(imu))
    out = np.empty((len(imu), 3))
    for n, row in enumerate(imu):
        t = time.perf_counter()
        out[n] = engine.step(row)
        costs[n] = time.perf_counter() - t
    return costs, out


if __name__ == '__main__':
    main()
