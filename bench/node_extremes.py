# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The live node under extreme input: real EuRoC IMU at 200 Hz over DDS, extremes injected.

Extreme or odd values are injected between the real samples (+-1.8e308, 5e38, 3.4e38,
1e20, NaN, inf, denormals, -0.0); the node runs as its own process.

Prints: real samples sent and answered, injected samples and how many the node accepted
(in-range ones such as denormals are valid input), non-finite values received (must be
0), and whether the node is still running at the end.
Run: .venv/bin/python bench/node_extremes.py [--seconds 30] [--every 10]
"""

import argparse
import os
from pathlib import Path
import sys
import time

os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
os.environ.setdefault('FASTDDS_BUILTIN_TRANSPORTS', 'UDPv4')
os.environ.setdefault('ROS_DOMAIN_ID', '58')

from denoise_imu_ros.core import msgs  # noqa: E402
from denoise_imu_ros.data.load import load_imu  # noqa: E402
import numpy as np  # noqa: E402
import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from ros_link import start, stop, wait_until_flowing  # noqa: E402
from sensor_msgs.msg import Imu  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'euroc' / 'V1_01_easy'
EXTREMES = [1.8e308, -1.8e308, 5e38, 3.4e38, -1e20, np.nan, np.inf, 5e-324, -0.0, 1e-310]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--seconds', type=float, default=30.0)
    parser.add_argument('--every', type=int, default=10, help='inject after every N-th sample')
    args = parser.parse_args()
    imu = load_imu(DATA).imu
    node = start([sys.executable, '-m', 'denoise_imu_ros.runtime.node', '--ros-args',
                  '-p', 'model:=euroc', '--log-level', 'error'])
    rclpy.init()
    bench = rclpy.create_node('extremes_bench')
    types = msgs.rclpy_types()
    got = {}

    def received(m):
        w = m.angular_velocity
        got[msgs.stamp_ns(m.header)] = (w.x, w.y, w.z)
    pub = bench.create_publisher(Imu, 'imu/data_raw', QoSProfile(
        depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    sub = bench.create_subscription(Imu, 'imu/corrected', received, QoSProfile(
        depth=10000, reliability=ReliabilityPolicy.RELIABLE))
    ex = SingleThreadedExecutor()
    ex.add_node(bench)
    stamp = wait_until_flowing(ex, pub, sub, got, 10**18, node) + 10**10  # a fresh start
    rng = np.random.default_rng(0)
    real, injected = [], []
    t0 = time.perf_counter()
    for k in range(int(200 * args.seconds)):
        due = t0 + k / 200.0
        while (now := time.perf_counter()) < due:
            ex.spin_once(timeout_sec=0) if due - now > 2e-4 else None
        stamp += 5_000_000
        row = imu[k % len(imu)]
        pub.publish(msgs.imu(types, msgs.header(types, stamp, 'imu0'), row[:3], row[3:]))
        real.append(stamp)
        if k % args.every == args.every - 1:  # an extreme sample 1 ms after this one
            bad = row.copy()
            bad[rng.choice(6, size=rng.integers(1, 4), replace=False)] = rng.choice(EXTREMES)
            pub.publish(msgs.imu(types, msgs.header(types, stamp + 1_000_000, 'imu0'),
                                 bad[:3], bad[3:]))
            injected.append(stamp + 1_000_000)
    deadline = time.perf_counter() + 3.0
    while time.perf_counter() < deadline:
        ex.spin_once(timeout_sec=0.01)
    alive = node.poll() is None
    values = np.array(list(got.values())) if got else np.zeros((0, 3))
    lost = [k for k, s in enumerate(real) if s not in got]
    print(f'real samples sent {len(real)}, answered {len(real) - len(lost)}'
          + (f' (unanswered: sample {", ".join(map(str, lost[:10]))})' if lost else ''))
    print(f'injected samples {len(injected)}, accepted (in range) '
          f'{sum(s in got for s in injected)}')
    print(f'non-finite values received: {int((~np.isfinite(values)).sum())}')
    print(f'node still running: {alive}')
    stop(ex, bench, node)


if __name__ == '__main__':
    main()
