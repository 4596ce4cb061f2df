# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""A ROS harness for the node tests: the node under test and a client in one context."""

import time

from denoise_imu_ros.pipeline.online import DROP_CAUSES
from denoise_imu_ros.runtime.node import GyroDenoiser
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import QuaternionStamped
from helpers import DOMAIN
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu


class Harness:
    """A context with the node under test and a client node that talks to it."""

    def __init__(self, model_file, **params):
        self.ctx = rclpy.context.Context()
        rclpy.init(context=self.ctx, domain_id=DOMAIN)
        overrides = [Parameter('model', value=str(model_file))]
        overrides += [Parameter(k, value=v) for k, v in params.items()]
        self.node = GyroDenoiser(context=self.ctx, parameter_overrides=overrides)
        self.client = rclpy.create_node('client', context=self.ctx)
        self.pub = self.client.create_publisher(
            Imu, 'imu/data_raw', QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
        self.corrected, self.fused, self.attitude, self.diagnostics = [], [], [], []
        reliable = QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE)
        self.client.create_subscription(Imu, 'imu/corrected', self.corrected.append, reliable)
        self.client.create_subscription(Imu, 'imu/data', self.fused.append, reliable)
        self.client.create_subscription(QuaternionStamped, 'imu/attitude',
                                        self.attitude.append, reliable)
        self.client.create_subscription(DiagnosticArray, '/diagnostics',
                                        self.diagnostics.append, 10)
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)
        self.executor.add_node(self.client)
        self.spin_until(lambda: self.pub.get_subscription_count() > 0)

    def spin_until(self, done, timeout=10.0):
        deadline = time.monotonic() + timeout
        while not done() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)
        assert done(), 'timed out'

    def processed(self):
        counts = self.node._denoiser.counts
        return counts['accepted'] + sum(counts[c] for c in DROP_CAUSES)

    def send(self, msgs):
        """Publish in bursts well inside the input queue; wait until all are handled."""
        start = self.processed()
        for k in range(0, len(msgs), 50):
            for msg in msgs[k:k + 50]:
                self.pub.publish(msg)
            self.spin_until(lambda: self.processed() - start >= min(k + 50, len(msgs)))
        self.spin_until(lambda: len(self.corrected) >= self.node._denoiser.counts['accepted']
                        - self.node.corrected_withheld)
        self.spin_until(lambda: len(self.attitude) >= self.node._denoiser.counts['accepted']
                        - self.node.attitude_withheld)
        if self.node._pub_fused is not None:
            self.spin_until(lambda: len(self.fused) >= self.node._denoiser.counts['accepted']
                            - self.node.fused_withheld)

    def close(self):
        """Stop the node and its client (a node stopped mid-test is not stopped again)."""
        if not self.ctx.ok():
            return
        self.executor.shutdown()
        self.node.destroy_node()
        self.client.destroy_node()
        rclpy.shutdown(context=self.ctx)
