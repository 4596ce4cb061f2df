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
Training speed of the EuRoC recipe (6 sequences x 16,000 samples per step).

Runs the real trainer twice per variant, for a few and for more steps, and reports the
difference per step, which leaves out loading and validation. Variants, side by side in
the same run so that ratios are meaningful on a shared machine:
  - one process with 2 threads;
  - 2 data-parallel worker processes with 1 thread each (the recipe's setting).
Prints seconds per step and the projected time of the full recipe.
Run: .venv/bin/python bench/train_speed.py [--steps N]
"""

import argparse
from pathlib import Path
import time

from denoise_imu_ros.train import load_config, train

ROOT = Path(__file__).resolve().parents[1]


def seconds_per_step(workers: int, steps: int) -> float:
    """Time of `steps` more training steps, by difference of two runs."""
    times = []
    for n in (steps // 4, steps + steps // 4):
        cfg = load_config(ROOT / 'config' / 'train_euroc.yaml',
                          data=str(ROOT.parent / 'shared' / 'data' / 'euroc'),
                          steps=n, val_every=10 * n, swa_start=0, select='final',
                          workers=workers)
        t = time.perf_counter()
        train(cfg, progress=False)
        times.append(time.perf_counter() - t)
    return (times[1] - times[0]) / steps


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('--steps', type=int, default=40, help='steps timed per variant')
    args = parser.parse_args()
    full = load_config(ROOT / 'config' / 'train_euroc.yaml').steps
    rows = [('1 process, 2 threads', seconds_per_step(1, args.steps)),
            ('2 worker processes, 1 thread each', seconds_per_step(2, args.steps))]
    base = rows[0][1]
    print(f'{"variant":36s} {"s/step":>8s} {f"{full} steps":>11s} {"ratio":>6s}')
    for name, t in rows:
        print(f'{name:36s} {t:8.3f} {t * full / 60:7.1f} min {t / base:6.2f}')


if __name__ == '__main__':
    main()
