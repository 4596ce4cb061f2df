# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
gyro_denoiser left running: its memory, losses and /diagnostics over a long stream.

Real EuRoC IMU samples go to the node's imu/data_raw at a fixed rate for ``--minutes``, in
bursts of ``--burst`` (a driver's read), so this process stays light beside the node. Every
``--event-every`` seconds something a robot does happens, in turn: the host clock steps
back 2 s (stamps and all), or ``~/reset_attitude`` is called during motion. Printed each
minute: the node's resident memory, messages sent and received on imu/corrected and
imu/data, and the /diagnostics status just before the minute ended; after each event, the
first /diagnostics status that follows it, and the service's answer. At the end: memory's
growth after the first minute (what a leak would show), and every message missing.
Run: .venv/bin/python bench/node_soak.py [--minutes 60] [--rate 1000] [--model euroc]
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
from denoise_imu_ros.core.modelfile import read_model_file  # noqa: E402
from denoise_imu_ros.data.load import load_imu  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from ros_link import start, stop, wait_until_flowing  # noqa: E402
from sensor_msgs.msg import Imu  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'euroc' / 'V1_01_easy'
CLOCK_STEP_NS = 2 * 10**9
SHOWN = ('time_jump_resets', 'gap_resets', 'accepted', 'corrected_withheld',
         'attitude_withheld', 'fused_withheld', 'buffer_fill')


def rss_mib(pid: int) -> float:
    """Resident memory of a process, from /proc."""
    for line in Path(f'/proc/{pid}/status').read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) / 1024
    raise RuntimeError(f'no VmRSS for process {pid}')


def said(array: DiagnosticArray) -> str:
    """One line of a /diagnostics message: level, message and the values shown."""
    status = array.status[0]
    values = {kv.key: kv.value for kv in status.values}
    level = ('OK', 'WARN', 'ERROR', 'STALE')[status.level[0]]
    return f'{level} "{status.message}" ' + ' '.join(
        f'{k}={values[k]}' for k in SHOWN if k in values)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('--minutes', type=float, default=60.0)
    parser.add_argument('--rate', type=float, default=1000.0, help='messages per second')
    parser.add_argument('--burst', type=int, default=10, help='messages sent at once')
    parser.add_argument('--event-every', type=float, default=300.0, help='seconds')
    parser.add_argument('--model', default='euroc')
    args = parser.parse_args()
    imu, types = load_imu(DATA).imu, msgs.rclpy_types()
    step_ns = int(round(1e9 / read_model_file(args.model).meta.sample_rate_hz))
    proc = start([sys.executable, '-m', 'denoise_imu_ros.runtime.node', '--ros-args',
                  '-p', f'model:={args.model}', '--log-level', 'error'])
    rclpy.init()
    bench = rclpy.create_node('soak_bench')
    got: dict[int, None] = {}  # stamps answered on imu/corrected
    fused = [0]
    diag: list[tuple[float, str]] = []  # (when received, what it said)
    pub = bench.create_publisher(Imu, 'imu/data_raw', QoSProfile(
        depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    sub = bench.create_subscription(
        Imu, 'imu/corrected', lambda m: got.setdefault(msgs.stamp_ns(m.header), None),
        QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE))
    bench.create_subscription(Imu, 'imu/data', lambda m: fused.__setitem__(0, fused[0] + 1),
                              QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE))
    bench.create_subscription(DiagnosticArray, '/diagnostics',
                              lambda m: diag.append((time.perf_counter(), said(m))), 10)
    reset = bench.create_client(Trigger, 'gyro_denoiser/reset_attitude')
    ex = SingleThreadedExecutor()
    ex.add_node(bench)
    stamp = wait_until_flowing(ex, pub, sub, got, 10**18, proc)
    stamp += 10**10  # a fresh recording for the node
    ex.spin_once(timeout_sec=0.1)
    got.clear()  # what the start-up's samples brought back is not counted
    fused[0] = 0
    n = int(args.rate * args.minutes * 60)
    period = args.burst / args.rate
    sent: list[int] = []
    pending: list[tuple[str, float]] = []  # events whose first /diagnostics is awaited
    settle_s = 0.2  # a status received this long after an event was sent after it
    events, rows, minute = 0, [], 0
    t0 = time.perf_counter()
    first_rss = rss_mib(proc.pid)
    print(f'node at start: {first_rss:.1f} MiB resident')
    print(f'{"min":>4s} {"RSS MiB":>8s} {"sent":>8s} {"corrected":>9s} {"imu/data":>8s}  '
          '/diagnostics')
    for k in range(0, n, args.burst):
        due = t0 + (k // args.burst) * period
        ex.spin_once(timeout_sec=0)  # at least once a burst, however late
        while (left := due - time.perf_counter()) > 0:  # take what came back meanwhile
            ex.spin_once(timeout_sec=left)
        for j in range(k, min(k + args.burst, n)):
            stamp += step_ns
            row = imu[j % len(imu)]
            sent.append(stamp)
            pub.publish(msgs.imu(types, msgs.header(types, stamp, 'imu0'), row[:3], row[3:]))
        while pending and diag and diag[-1][0] - t0 > pending[0][1] + settle_s:
            what, at = pending.pop(0)
            print(f'     {what} at {at:.0f} s, then /diagnostics: {diag[-1][1]}')
        elapsed = time.perf_counter() - t0
        if elapsed >= (events + 1) * args.event_every:
            events += 1
            if events % 2:
                stamp -= CLOCK_STEP_NS + step_ns // 2  # off the stamps already sent
                pending.append(('clock stepped back 2 s', elapsed))
            else:
                if not reset.service_is_ready():
                    sys.exit('the node offers no ~/reset_attitude')
                answer = reset.call_async(Trigger.Request())
                answer.add_done_callback(lambda done: print(
                    f'     ~/reset_attitude answered: success {done.result().success}'))
                pending.append(('~/reset_attitude', elapsed))
        if elapsed >= (minute + 1) * 60:
            minute += 1
            rss = rss_mib(proc.pid)
            rows.append(rss)
            print(f'{minute:4d} {rss:8.1f} {len(sent):8d} {len(got):9d} {fused[0]:8d}  '
                  f'{diag[-1][1] if diag else ""}', flush=True)
    deadline = time.perf_counter() + 3.0
    while len(got) < len(sent) and time.perf_counter() < deadline:
        ex.spin_once(timeout_sec=0.01)
    rows.append(rss_mib(proc.pid))  # at the end
    missing = [s for s in sent if s not in got]
    print(f'sent {len(sent)}, answered on imu/corrected {len(sent) - len(missing)}, '
          f'imu/data messages {fused[0]}; missing on imu/corrected: {len(missing)}')
    if len(rows) > 1:
        hours = (time.perf_counter() - t0 - 60) / 3600
        print(f'resident memory after minute 1: {rows[0]:.1f} MiB, at the end {rows[-1]:.1f} '
              f'MiB ({(rows[-1] - rows[0]) / hours:+.1f} MiB per hour), '
              f'range {min(rows):.1f}-{max(rows):.1f}')
    stop(ex, bench, proc)


if __name__ == '__main__':
    main()
