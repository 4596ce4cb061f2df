# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What one rclpy publish of a sensor_msgs/Imu costs, with and without a reader.

The node's cost per sample is mostly its publishes (bench/fusion_cost.py): this times
the publish alone, at an IMU's pace (1 kHz), in one run: a message to a topic with a
reader in another process, the same message pre-serialised (``serialize_message``,
timed apart) to a second such topic, and the message to a topic nobody reads; with the
QoS of ``--reliability`` on both sides.
Run: .venv/bin/python bench/publish_cost.py [--reliability reliable|best_effort]
"""

import argparse
import sys
import time

from denoise_imu_ros.core import msgs
import numpy as np
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from ros_link import start_reader, wait_until
from sensor_msgs.msg import Imu


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument('--reliability', choices=('reliable', 'best_effort'),
                        default='reliable')
    parser.add_argument('--messages', type=int, default=12000)
    args = parser.parse_args()
    policy = args.reliability.upper()
    rclpy.init()
    node = rclpy.create_node('publish_cost')
    qos = QoSProfile(depth=100, reliability=getattr(ReliabilityPolicy, policy))
    read, read_bytes, unread = (node.create_publisher(Imu, t, qos)
                                for t in ('read', 'read_bytes', 'unread'))
    sink = start_reader([(Imu, 'read'), (Imu, 'read_bytes')], policy)
    deadline = time.monotonic() + 20
    while (read.get_subscription_count() == 0 or read_bytes.get_subscription_count() == 0):
        if time.monotonic() > deadline or sink.poll() is not None:
            sink.terminate()
            sys.exit('publish_cost: the reader process did not subscribe')
        time.sleep(0.1)
    time.sleep(1.0)  # discovery settled
    types = msgs.rclpy_types()
    msg = msgs.imu(types, msgs.header(types, 10**9, 'imu0'), [0.1, 0.2, 0.3], [0.1, 9.8, 0.2])
    times = {'message, read': [], 'serialise': [], 'bytes, read': [], 'message, unread': []}
    due = time.perf_counter()
    for k in range(args.messages):
        due += 1e-3
        wait_until(due)
        t0 = time.perf_counter()
        if k % 3 == 0:
            read.publish(msg)
            times['message, read'].append(time.perf_counter() - t0)
        elif k % 3 == 1:
            raw = serialize_message(msg)
            t1 = time.perf_counter()
            read_bytes.publish(raw)
            times['serialise'].append(t1 - t0)
            times['bytes, read'].append(time.perf_counter() - t1)
        else:
            unread.publish(msg)
            times['message, unread'].append(time.perf_counter() - t0)
    for what, t in times.items():
        t = np.array(t) * 1e6
        print(f'{args.reliability:11s} {what:16s}: median {np.median(t):6.1f} us, '
              f'p99 {np.percentile(t, 99):6.1f} us ({len(t)})')
    sink.terminate()
    sink.wait()
    node.destroy_node()
    rclpy.shutdown()


if __name__ == '__main__':
    main()
