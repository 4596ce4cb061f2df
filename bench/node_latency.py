# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
gyro_denoiser over DDS loopback: added latency, CPU use, drops, highest sustained rate.

Real EuRoC IMU samples are published on imu/data_raw at a fixed rate; imu/corrected is
received in this process. Their stamps step by the model's period whatever the rate they
are sent at: the node checks the stamps' rate against its model's and withholds every
output at a rate not its own, so a rate above the model's measures what a faster IMU
would cost the node doing all its work (a model trained at that rate does the same).
Latency = receive time - publish time (same clock). The node runs as its own process; a
pass-through relay (same QoS, no processing) is measured in the same run as the
transport floor, so the node's figures read as "floor + cost".
With several --models (e.g. a single network and an ensemble file), each runs as the node
in turn, in the same run. The sweep rates are tried with the first model only.
Run: .venv/bin/python bench/node_latency.py [--rates 200 1000] [--seconds 10]
         [--sweep 2000 3000 4000] [--models euroc ensemble.safetensors]
Needs ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST (set below if missing).
"""

import argparse
import os
from pathlib import Path
import sys
import time

os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
os.environ.setdefault('FASTDDS_BUILTIN_TRANSPORTS', 'UDPv4')
os.environ.setdefault('ROS_DOMAIN_ID', '57')

from denoise_imu_ros.core.modelfile import read_model_file  # noqa: E402
from denoise_imu_ros.core.msgs import stamp_ns  # noqa: E402
from denoise_imu_ros.data.load import load_imu  # noqa: E402
import numpy as np  # noqa: E402
import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from ros_link import start, wait_until_flowing  # noqa: E402
from sensor_msgs.msg import Imu  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'euroc' / 'V1_01_easy'
RELAY = """
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu
rclpy.init()
node = rclpy.create_node('relay')
pub = node.create_publisher(Imu, 'imu/corrected', QoSProfile(
    depth=100, reliability=ReliabilityPolicy.RELIABLE))
node.create_subscription(Imu, 'imu/data_raw', pub.publish, QoSProfile(
    depth=200, reliability=ReliabilityPolicy.BEST_EFFORT))
try:
    rclpy.spin(node)
except Exception:
    pass
"""


def cpu_seconds(pid):
    """User + system CPU time of a process, from /proc."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def run(kind, rates, seconds, imu, model='euroc'):
    """Start the node (or the relay); measure every rate; stop it."""
    cmd = ([sys.executable, '-m', 'denoise_imu_ros.runtime.node', '--ros-args',
            '-p', f'model:={model}', '--log-level', 'error'] if kind == 'node'
           else [sys.executable, '-c', RELAY])
    step_ns = int(round(1e9 / (read_model_file(model).meta.sample_rate_hz if kind == 'node'
                               else 200.0)))  # the stamps' step: the model's period
    proc = start(cmd)
    rclpy.init()
    bench = rclpy.create_node('latency_bench')
    sent, got = {}, {}
    pub = bench.create_publisher(Imu, 'imu/data_raw', QoSProfile(
        depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    sub = bench.create_subscription(
        Imu, 'imu/corrected',
        lambda m: got.setdefault(stamp_ns(m.header), time.perf_counter()),
        QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE))
    ex = SingleThreadedExecutor()
    ex.add_node(bench)
    stamp = wait_until_flowing(ex, pub, sub, got, 10**18, proc)
    results = []
    for rate in rates:
        sent.clear()
        got.clear()
        n = int(rate * seconds)
        period = 1.0 / rate
        # a fresh recording for the node: a jump forward restarts its history
        stamp += 10**10
        cpu0, t0 = cpu_seconds(proc.pid), time.perf_counter()
        for k in range(n):
            due = t0 + k * period
            while (now := time.perf_counter()) < due:
                ex.spin_once(timeout_sec=0) if due - now > 2e-4 else None
            msg = Imu()
            stamp += step_ns
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 10**9)
            row = imu[k % len(imu)]
            (msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z) = row[:3]
            (msg.linear_acceleration.x, msg.linear_acceleration.y,
             msg.linear_acceleration.z) = row[3:]
            sent[stamp] = time.perf_counter()
            pub.publish(msg)
        deadline = time.perf_counter() + 2.0
        while len(got) < n and time.perf_counter() < deadline:
            ex.spin_once(timeout_sec=0.01)
        wall = time.perf_counter() - t0
        cpu = (cpu_seconds(proc.pid) - cpu0) / wall
        lat = np.array([got[s] - sent[s] for s in sent if s in got]) * 1e3
        lost = [k for k, s in enumerate(sent) if s not in got]
        if lost:
            print(f'{kind} at {rate:g} Hz: lost messages number {lost[:10]} of {n}')
        results.append((kind, rate, n, n - len(lat), np.percentile(lat, 50) if len(lat) else
                        np.nan, np.percentile(lat, 99) if len(lat) else np.nan, cpu))
    ex.shutdown()
    bench.destroy_node()
    rclpy.try_shutdown()
    proc.terminate()
    proc.wait(timeout=10)
    return results


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--rates', type=float, nargs='+', default=[200.0, 1000.0])
    parser.add_argument('--sweep', type=float, nargs='*', default=[2000.0, 3000.0, 4000.0])
    parser.add_argument('--seconds', type=float, default=10.0)
    parser.add_argument('--models', nargs='+', default=['euroc'])
    args = parser.parse_args()
    imu = load_imu(DATA).imu
    rows = [('relay', *r[1:]) for r in run('relay', args.rates, args.seconds, imu)]
    for i, model in enumerate(args.models):
        rates = args.rates + (args.sweep if i == 0 else [])
        rows += [(Path(model).stem, *r[1:]) for r in run('node', rates, args.seconds, imu, model)]
    print(f'{"":18s} {"rate Hz":>8s} {"sent":>7s} {"lost":>5s} {"p50 ms":>7s} {"p99 ms":>7s} '
          f'{"CPU":>5s}')
    for kind, rate, n, lost, p50, p99, cpu in rows:
        print(f'{kind:18s} {rate:8.0f} {n:7d} {lost:5d} {p50:7.2f} {p99:7.2f} {cpu:5.0%}')
    first = Path(args.models[0]).stem
    ok = [r[1] for r in rows if r[0] == first and r[3] == 0]
    print(f'highest input rate the node sustained without a drop: {max(ok, default=0):.0f} Hz')


if __name__ == '__main__':
    main()
