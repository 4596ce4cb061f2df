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
Node start-up cost: import time, resident memory, whether torch was loaded.

Each run is a fresh process that imports denoise_imu_ros.runtime.node and starts the node with
a shipped model. With --other PATH (another checkout, e.g. an older commit made with
``git worktree add``), the same is measured for that code in the same run, alternating.
Run: .venv/bin/python bench/node_import.py [--model euroc] [--runs 5] [--other PATH]
"""

import argparse
import json
import os
from pathlib import Path
import subprocess
import sys

import numpy as np

PROBE = """
import json, resource, sys, time
t = time.perf_counter()
import denoise_imu_ros.runtime.node as node_module
imported = time.perf_counter() - t
import rclpy
from rclpy.parameter import Parameter
rclpy.init()
node = node_module.GyroDenoiser(parameter_overrides=[Parameter('model', value=sys.argv[1])])
started = time.perf_counter() - t
node.destroy_node()
rclpy.shutdown()
print(json.dumps({'import_s': imported, 'start_s': started, 'torch': 'torch' in sys.modules,
                  'rss_mb': resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def probe(code: Path, model: str) -> dict:
    """One fresh process importing the node from ``code`` and starting it."""
    env = dict(os.environ, PYTHONPATH=str(code))
    out = subprocess.run([sys.executable, '-c', PROBE, model], env=env, check=True,
                         capture_output=True, text=True, cwd='/').stdout
    return json.loads(out.splitlines()[-1])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--model', default='euroc')
    parser.add_argument('--runs', type=int, default=5)
    parser.add_argument('--other', type=Path, help='another checkout to compare with')
    args = parser.parse_args()
    codes = {'this checkout': Path(__file__).resolve().parents[1]}
    if args.other:
        codes['other'] = args.other.resolve()
    runs = {name: [] for name in codes}
    for _ in range(args.runs):
        for name, code in codes.items():
            runs[name].append(probe(code, args.model))
    for name, rs in runs.items():
        med = {k: float(np.median([r[k] for r in rs])) for k in ('import_s', 'start_s', 'rss_mb')}
        print(f'{name:14s}: import {med["import_s"]:.2f} s, import + start '
              f'{med["start_s"]:.2f} s, max RSS {med["rss_mb"]:.0f} MB, torch loaded: '
              f'{any(r["torch"] for r in rs)} (median of {len(rs)})')


if __name__ == '__main__':
    main()
