# Copyright 2026 denoise_imu_ros authors
# Licensed under the Apache License, Version 2.0
"""Shared fixtures: the real data (skipped cleanly when absent), models, a ROS harness."""

import os
from pathlib import Path
import time

from builtin_interfaces.msg import Time
from denoise_imu_ros.model import GyroNet, ModelConfig
from denoise_imu_ros.modelfile import save_model
from denoise_imu_ros.node import GyroDenoiser
from denoise_imu_ros.online import DROP_CAUSES
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import QuaternionStamped
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu
import torch

DATA = Path(__file__).resolve().parents[1].parent / 'shared' / 'data'
SAMPLE = Path(__file__).resolve().parents[1] / 'denoise_imu_ros' / 'sample' / 'euroc_V1_03_90s'


def untrained_model(**config) -> GyroNet:
    """Build a seeded, untrained eval-mode network with EuRoC-like input normalisation."""
    torch.manual_seed(0)
    model = GyroNet(ModelConfig(**config))
    model.set_normalization(torch.tensor([0.0, 0.0, 0.0, 9.0, 0.0, -3.0]),
                            torch.tensor([0.3, 0.3, 0.3, 1.0, 1.0, 1.0]))
    return model.eval()


@pytest.fixture()
def model_file(tmp_path) -> Path:
    """Write an untrained but complete 200 Hz model file with residual std figures."""
    path = tmp_path / 'model.safetensors'
    save_model(path, untrained_model(), {
        'dataset': 'test', 'sample_rate_hz': 200.0,
        'validation': {'gyro_residual_std': [0.01, 0.02, 0.03]}})
    return path


@pytest.fixture(scope='session')
def data_dir() -> Path:
    """Return ../shared/data, or skip the test."""
    if not (DATA / 'euroc').is_dir():
        pytest.skip(f'real data not found at {DATA}')
    return DATA


@pytest.fixture(scope='session')
def euroc(data_dir: Path) -> Path:
    """Return the folder of the EuRoC ASL sequences."""
    return data_dir / 'euroc'


DOMAIN = 10 + os.getpid() % 90  # this run's own DDS domain


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
        self.corrected, self.attitude, self.diagnostics = [], [], []
        reliable = QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE)
        self.client.create_subscription(Imu, 'imu/corrected', self.corrected.append, reliable)
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
        self.spin_until(lambda: len(self.corrected) >= self.node._denoiser.counts['accepted'])
        self.spin_until(lambda: len(self.attitude) >= self.node._denoiser.counts['accepted']
                        - self.node.attitude_withheld)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.client.destroy_node()
        rclpy.shutdown(context=self.ctx)


@pytest.fixture()
def harness(model_file):
    """Yield a running node and client; torn down after the test."""
    made = []

    def make(**params):
        made.append(Harness(model_file, **params))
        return made[-1]
    yield make
    for h in made:
        h.close()


def imu_msg(stamp_ns, gyro, accel, frame='imu4'):
    """Build a sensor_msgs/Imu as a driver would."""
    msg = Imu()
    msg.header.stamp = Time(sec=int(stamp_ns // 10**9), nanosec=int(stamp_ns % 10**9))
    msg.header.frame_id = frame
    (msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z) = map(float, gyro)
    (msg.linear_acceleration.x, msg.linear_acceleration.y,
     msg.linear_acceleration.z) = map(float, accel)
    msg.linear_acceleration_covariance[0] = 0.04
    return msg
