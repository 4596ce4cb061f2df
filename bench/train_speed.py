# Copyright 2026 denoise_imu_ros authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Training-step timing on the EuRoC recipe's batch (6 sequences x 16,000 samples).

Prints the median time of a full step (batch, forward, loss, backward, Adam) for the
shipped trainer and, side by side in the same run, for variants, so that ratios are
meaningful on a shared machine:
  - torch.nn.Dropout instead of the model's cheaper-mask Dropout;
  - one thread on half the batch (what each worker of a 2-process split would do).
Run: .venv/bin/python bench/train_speed.py [--steps N]
"""

import argparse
from pathlib import Path
import statistics
import time

from denoise_imu_ros.dataset import load_sequence
from denoise_imu_ros.loss import increment_loss, LossConfig
from denoise_imu_ros.model import GyroNet, ModelConfig
from denoise_imu_ros.train import batch, load_config, training_split
import torch

ROOT = Path(__file__).resolve().parents[1]


def time_steps(model, split, cfg, steps, threads):
    torch.set_num_threads(threads)
    torch.set_flush_denormal(True)  # as the trainer does
    opt = torch.optim.Adam(model.parameters(), lr=1e-3, weight_decay=0.1)
    gen = torch.Generator().manual_seed(0)
    times = []
    for _ in range(steps + 2):
        t = time.perf_counter()
        u, dt, quat, valid = batch(split, cfg, gen)
        loss = increment_loss(model(u), dt, quat, valid, LossConfig())
        opt.zero_grad()
        loss.backward()
        opt.step()
        times.append(time.perf_counter() - t)
    return statistics.median(times[2:])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--steps', type=int, default=10)
    args = parser.parse_args()
    cfg = load_config(ROOT / 'config' / 'train_euroc.yaml',
                      data=str(ROOT.parent / 'shared' / 'data' / 'euroc'))
    seqs = [load_sequence(Path(cfg.data) / s) for s in cfg.sequences]
    split = training_split(seqs, cfg)
    half = training_split(seqs[:3], cfg)
    torch.manual_seed(0)
    ours = GyroNet(ModelConfig())
    plain = GyroNet(ModelConfig())
    for i, m in enumerate(plain.net):
        if m.__class__.__name__ == 'Dropout':
            plain.net[i] = torch.nn.Dropout(0.1)
    rows = [
        ('shipped trainer, 2 threads, 6 sequences', time_steps(ours, split, cfg, args.steps, 2)),
        ('torch.nn.Dropout, 2 threads, 6 sequences', time_steps(plain, split, cfg, args.steps, 2)),
        ('shipped trainer, 1 thread, 3 sequences', time_steps(ours, half, cfg, args.steps, 1)),
    ]
    base = rows[0][1]
    print(f'{"variant":45s} {"s/step":>8s} {"1800 steps":>11s} {"ratio":>6s}')
    for name, t in rows:
        print(f'{name:45s} {t:8.3f} {t * 1800 / 60:9.1f} min {t / base:6.2f}')


if __name__ == '__main__':
    main()
