# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Shared by the node benches: their child processes, and samples flowing through them."""

import ctypes
import os
import signal
import subprocess
import sys
import time

import rclpy
from rclpy.executors import Executor
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.subscription import Subscription
from sensor_msgs.msg import Imu


def _die_with_parent() -> None:
    """In the child, before it runs: SIGTERM when the bench dies, however it dies."""
    ctypes.CDLL(None).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG (Linux)


def start(cmd: list[str], cpus: list[int] | None = None) -> subprocess.Popen:
    """
    Start a process the bench talks to (node, relay, reader) that dies with the bench.

    A bench stopped by a signal or a timeout would otherwise leave it running, on the
    same ROS domain: it answers the next bench's samples and takes its CPU. ``cpus``:
    the only CPUs it and its threads run on.
    """
    def before_exec() -> None:
        _die_with_parent()
        if cpus:
            os.sched_setaffinity(0, cpus)
    return subprocess.Popen(cmd, preexec_fn=before_exec)


READER = """
import importlib, sys
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
rclpy.init()
reader = rclpy.create_node('reader')
qos = QoSProfile(depth=100, reliability=getattr(ReliabilityPolicy, sys.argv[1]))
for spec in sys.argv[2:]:
    module, name, topic = spec.split(':')
    msg_type = getattr(importlib.import_module(module), name)
    reader.create_subscription(msg_type, topic, lambda m: None, qos)
try:
    rclpy.spin(reader)
except (KeyboardInterrupt, Exception):  # stopped by the bench, in whatever state
    pass
"""


def start_reader(topics: list[tuple[type, str]], reliability: str = 'RELIABLE',
                 cpus: list[int] | None = None) -> subprocess.Popen:
    """
    Start a process that subscribes to every (message type, topic) and takes each message.

    A publish to a topic nobody reads costs less than one a reader takes: a bench of the
    node's publishes needs a reader on each, in a process of its own as on a robot.
    """
    specs = [f'{t.__module__}:{t.__name__}:{topic}' for t, topic in topics]
    return start([sys.executable, '-c', READER, reliability.upper(), *specs], cpus)


def stop(ex: Executor, bench: Node, proc: subprocess.Popen) -> None:
    """End a bench: its executor, its node and ROS in this process, then the process tested."""
    ex.shutdown()
    bench.destroy_node()
    rclpy.try_shutdown()
    proc.terminate()
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def wait_until(due: float) -> None:
    """Sleep most of the way to ``due`` (``time.perf_counter``), spin the last 0.2 ms."""
    time.sleep(max(0.0, due - time.perf_counter() - 2e-4))
    while time.perf_counter() < due:
        pass


def wait_until_flowing(ex: Executor, pub: Publisher, sub: Subscription, got: dict,
                       stamp_ns: int, proc: subprocess.Popen | None = None) -> int:
    """
    Publish still samples until one comes back; return the last stamp used.

    Matched (both ways) is not yet flowing: what is published in the first tens of
    milliseconds after matching can be lost on the way in or out, which a bench would
    count as the node's losses (6 to 33 of the first messages, before this). With
    ``proc`` (the process under test), its early exit ends the bench.
    """
    while pub.get_subscription_count() == 0 or sub.get_publisher_count() == 0:
        if proc is not None and proc.poll() is not None:
            sys.exit(f'the process under test exited with status {proc.returncode}')
        ex.spin_once(timeout_sec=0.1)
    while not got:
        stamp_ns += 10_000_000
        msg = Imu()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 10**9)
        msg.linear_acceleration.z = 9.81
        pub.publish(msg)
        ex.spin_once(timeout_sec=0.01)
    got.clear()
    return stamp_ns
