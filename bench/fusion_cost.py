# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The node's per-message cost with the fused orientation (imu/data) on and off.

One process, two nodes built from the same model (``publish_fused`` true and false),
each fed the same real V1_01 IMU messages through its own subscription callback, with a
subscriber on every output topic in a process of its own, so that each publish
serialises and sends to a reader that takes it; the rounds alternate between the nodes.
Messages are handed over at ``--rate`` (an IMU's pace, so that the reader keeps up as it
would on a robot; 0: back to back). Prints the median and p99 callback time of each, the
median over rounds of their ratio, and how much of the difference is the imu/data
publish itself (rclpy's, timed around the call in the same callbacks). Also the CPU time
per message: the callback thread's, and that of the process's other threads (Fast DDS's;
with ``--publication-mode ASYNCHRONOUS`` a publish hands its send to one of them), so
that a cost moved off the callback is still counted.
Run: .venv/bin/python bench/fusion_cost.py [--model euroc] [--messages 3000] [--rounds 3]
[--rate 1000] [--publication-mode SYNCHRONOUS|ASYNCHRONOUS] [--pin]
"""

import argparse
import os
from pathlib import Path
import sys
import time

from denoise_imu_ros.core import msgs
from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.runtime.node import GyroDenoiser
from geometry_msgs.msg import QuaternionStamped
import numpy as np
import rclpy
from rclpy.parameter import Parameter
from ros_link import start_reader, wait_until
from sensor_msgs.msg import Imu

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'euroc' / 'V1_01_easy'


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('--model', default='euroc')
    parser.add_argument('--messages', type=int, default=3000)
    parser.add_argument('--rounds', type=int, default=3)
    parser.add_argument('--rate', type=float, default=1000.0, help='Hz; 0: back to back')
    parser.add_argument('--pin', action='store_true',
                        help='this process on the first CPU, the reader on the others: '
                             "the node's own cost, without the reader's work competing")
    parser.add_argument('--publication-mode', choices=('SYNCHRONOUS', 'ASYNCHRONOUS'),
                        help="rmw_fastrtps's RMW_FASTRTPS_PUBLICATION_MODE (default: the "
                             "environment's, else rmw_fastrtps's own)")
    args = parser.parse_args()
    if args.publication_mode:
        os.environ['RMW_FASTRTPS_PUBLICATION_MODE'] = args.publication_mode
    print(f'RMW_FASTRTPS_PUBLICATION_MODE: '
          f'{os.environ.get("RMW_FASTRTPS_PUBLICATION_MODE", "(unset: SYNCHRONOUS)")}')
    cpus = sorted(os.sched_getaffinity(0))
    if args.pin and len(cpus) < 2:
        sys.exit('fusion_cost: --pin needs two CPUs')
    if args.pin:  # every thread running already (numpy's BLAS pool), and those to come
        for tid in os.listdir('/proc/self/task'):
            os.sched_setaffinity(int(tid), cpus[:1])
    rec = load_imu(DATA)
    types = msgs.rclpy_types()
    messages = [msgs.imu(types, msgs.header(types, int(t), 'imu0'), r[:3], r[3:])
                for t, r in zip(rec.imu_stamp_ns[:args.messages], rec.imu[:args.messages])]
    rclpy.init()
    nodes = {on: GyroDenoiser(parameter_overrides=[Parameter('model', value=args.model),
                                                   Parameter('publish_fused', value=on)])
             for on in (True, False)}
    sink = start_reader([(Imu, 'imu/corrected'), (Imu, 'imu/data'),
                         (QuaternionStamped, 'imu/attitude')],
                        cpus=cpus[1:] if args.pin else None)
    deadline = time.monotonic() + 20

    def unread() -> list[str]:
        return [t for on, n in nodes.items() for t in ('imu/corrected', 'imu/attitude') + (
            ('imu/data',) if on else ()) if n.count_subscribers(t) == 0]
    while time.monotonic() < deadline and unread() and sink.poll() is None:
        time.sleep(0.1)
    if unread():
        sink.terminate()
        sys.exit(f'fusion_cost: no reader on {", ".join(sorted(set(unread())))}: '
                 'the publishes would cost nothing')
    publish_s: list[float] = []  # imu/data's publish call, inside the callbacks timed
    outputs = nodes[True]._outputs
    rclpy_publish = outputs.send_fused

    def timed_publish(msg: Imu) -> None:
        t = time.perf_counter()
        rclpy_publish(msg)
        publish_s.append(time.perf_counter() - t)
    outputs.send_fused = timed_publish
    times = {True: [], False: []}
    cpu = {True: [], False: []}  # per round: (callback thread, other threads) s/message
    ratios, ratios_less, cpu_ratios = [], [], []
    for _ in range(args.rounds):
        medians, medians_less = {}, {}
        for on, node in nodes.items():
            node._denoiser.engine.reset()
            node._denoiser._last_ns = None
            this, less, callback_cpu = [], [], 0.0
            due = time.perf_counter()
            process0, thread0 = time.process_time(), time.thread_time()
            for m in messages:
                if args.rate > 0:
                    due += 1.0 / args.rate
                    wait_until(due)
                first = len(publish_s)
                c0 = time.thread_time()
                t0 = time.perf_counter()
                node._on_imu(m)
                this.append(time.perf_counter() - t0)
                callback_cpu += time.thread_time() - c0
                less.append(this[-1] - sum(publish_s[first:]))
            time.sleep(0.05)  # a send handed to another thread ends within the round
            others = (time.process_time() - process0) - (time.thread_time() - thread0)
            cpu[on].append((callback_cpu / len(messages), others / len(messages)))
            times[on] += this
            medians[on] = np.median(this)
            medians_less[on] = np.median(less)  # off: nothing to take away
        ratios.append(medians[True] / medians[False])
        ratios_less.append(medians_less[True] / medians[False])
        cpu_ratios.append(sum(cpu[True][-1]) / sum(cpu[False][-1]))
    for on in (True, False):
        t = np.array(times[on]) * 1e6
        print(f'imu/data {"on " if on else "off"}: median {np.median(t):7.1f} us, '
              f'p99 {np.percentile(t, 99):7.1f} us per message ({len(t)} messages)')
    for on in (True, False):
        callback, others = np.mean(cpu[on], axis=0) * 1e6
        print(f'imu/data {"on " if on else "off"}: CPU {callback + others:7.1f} us per '
              f'message (callback thread {callback:.1f}, other threads {others:.1f})')
    print(f'ratio on/off: {np.median(ratios):.2f} (median over {len(ratios)} rounds; '
          f'each round: {", ".join(f"{r:.2f}" for r in ratios)})')
    print(f'of which the imu/data publish call: median {np.median(publish_s) * 1e6:.1f} us; '
          f'ratio on/off without it: {np.median(ratios_less):.2f}')
    print(f'CPU ratio on/off: {np.median(cpu_ratios):.2f} (median over rounds; each: '
          f'{", ".join(f"{r:.2f}" for r in cpu_ratios)})')
    sink.terminate()
    for node in nodes.values():
        node.destroy_node()
    rclpy.shutdown()


if __name__ == '__main__':
    main()
