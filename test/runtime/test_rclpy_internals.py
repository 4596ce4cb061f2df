# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""rclpy's undocumented parts the node relies on still behave so in the installed rclpy."""

from denoise_imu_ros.runtime.rclpy_internals import (given_parameters, integer_given_for_double,
                                                     RCLError, RCLInvalidROSArgsError,
                                                     take_waiting)
from helpers import DOMAIN, imu_msg
import pytest
import rclpy
from rclpy.exceptions import ParameterException
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.utilities import remove_ros_args
from sensor_msgs.msg import Imu


@pytest.fixture
def context():
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx, domain_id=DOMAIN)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def test_rcl_errors_are_the_exceptions_rclpy_raises(tmp_path):
    assert issubclass(RCLInvalidROSArgsError, Exception) and issubclass(RCLError, Exception)
    broken = tmp_path / 'p.yaml'
    broken.write_text('/**:\n  ros__parameters: [unclosed\n')
    with pytest.raises(RCLInvalidROSArgsError):
        remove_ros_args(['--ros-args', '--params-file', str(broken)])
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx, domain_id=DOMAIN)
    rclpy.shutdown(context=ctx)
    with pytest.raises(RCLError):  # shut down twice: what a racing signal leads to
        ctx.shutdown()


def test_take_waiting_returns_the_queued_messages_in_order_then_none(context):
    node = rclpy.create_node('taker', context=context)
    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
    sub = node.create_subscription(Imu, 'imu/data_raw', lambda msg: None, qos)
    pub = node.create_publisher(Imu, 'imu/data_raw', qos)
    sent = [imu_msg(k * 5_000_000, [0.0, 0.0, 0.01 * k], [0.0, 0.0, 9.81]) for k in range(5)]
    for msg in sent:
        pub.publish(msg)
    taken, tries = [], 0
    while len(taken) < len(sent) and tries < 2000:
        msg = take_waiting(sub, Imu)
        tries += msg is None
        if msg is not None:
            taken.append(msg)
    assert [m.angular_velocity.z for m in taken] == [m.angular_velocity.z for m in sent]
    assert take_waiting(sub, Imu) is None
    node.destroy_node()


def test_an_integer_given_for_a_float_parameter_is_named(context):
    node = rclpy.create_node('params', context=context, parameter_overrides=[
        Parameter('max_gap_factor', value=5), Parameter('fixed_frame', value=3.5)])
    with pytest.raises(ParameterException) as err:
        node.declare_parameter('max_gap_factor', 3.0)
    assert integer_given_for_double(err.value) == ('max_gap_factor', '5')
    with pytest.raises(ParameterException) as other:  # another mismatch: nothing to advise
        node.declare_parameter('fixed_frame', 'world')
    assert integer_given_for_double(other.value) is None
    node.destroy_node()


def test_the_values_given_at_start_up_are_read_declared_or_not(context):
    node = rclpy.create_node('given', context=context, parameter_overrides=[
        Parameter('modle', value='euroc'), Parameter('rate_tolerance', value=0.1)])
    node.declare_parameter('rate_tolerance', 0.05)
    assert {k: v.value for k, v in given_parameters(node).items()} == {
        'modle': 'euroc', 'rate_tolerance': 0.1}
    node.destroy_node()
