# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Node start-up cost: import time, resident memory, whether torch was loaded.

Each run is a fresh process that imports denoise_imu_ros.runtime.node and starts the node with
a shipped model; beside it, in the same run and alternating, the floor: a process that
imports rclpy and the message packages the node uses and starts an empty node. With
--other PATH (another checkout, e.g. an older commit made with ``git worktree add``),
its node is measured too.
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


BARE = """
import json, resource, sys, time
t = time.perf_counter()
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import QuaternionStamped
from sensor_msgs.msg import Imu
from std_srvs.srv import Trigger
imported = time.perf_counter() - t
rclpy.init()
node = rclpy.create_node('bare')
started = time.perf_counter() - t
node.destroy_node()
rclpy.shutdown()
print(json.dumps({'import_s': imported, 'start_s': started, 'torch': 'torch' in sys.modules,
                  'rss_mb': resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def probe(code: Path | None, model: str) -> dict:
    """One fresh process importing the node from ``code`` and starting it (None: the floor)."""
    env = dict(os.environ, PYTHONPATH=str(code or ''))
    out = subprocess.run([sys.executable, '-c', PROBE if code else BARE, model], env=env,
                         check=True,
                         capture_output=True, text=True, cwd='/').stdout
    return json.loads(out.splitlines()[-1])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--model', default='euroc')
    parser.add_argument('--runs', type=int, default=5)
    parser.add_argument('--other', type=Path, help='another checkout to compare with')
    args = parser.parse_args()
    codes = {'this checkout': Path(__file__).resolve().parents[1], 'rclpy + msgs': None}
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
    med = {k: {m: np.median([r[m] for r in runs[k]]) for m in ('start_s', 'rss_mb')}
           for k in ('this checkout', 'rclpy + msgs')}
    node, bare = med['this checkout'], med['rclpy + msgs']
    print(f'node / floor: import + start {node["start_s"] / bare["start_s"]:.2f}x, '
          f'max RSS {node["rss_mb"] / bare["rss_mb"]:.2f}x')


if __name__ == '__main__':
    main()
