# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The parts of rclpy the node uses that are not its documented API, in one place.

Each is needed for something the public API does not give: rcl's own errors (a signal
shutting rclpy down mid-call, a malformed ``--params-file``), taking the messages already
queued behind one in the same callback (one executor wake per message cannot keep up at
1 kHz), the parameter a ``ParameterException`` names (ROS does not turn ``5`` into
``5.0``: the node says how to write it), and the values given at start-up (a misspelt
name is said, not silently ignored). test/runtime/test_rclpy_internals.py exercises
each against the installed rclpy, so a release that changes one fails there, not on a
robot.
"""

from __future__ import annotations

import re
from typing import Any

from rclpy.exceptions import ParameterException
from rclpy.impl.implementation_singleton import rclpy_implementation as _impl
from rclpy.node import Node
from rclpy.subscription import Subscription

__all__ = ['given_parameters', 'integer_given_for_double', 'RCLError',
           'RCLInvalidROSArgsError', 'take_waiting']

RCLError = _impl.RCLError  # any rcl failure surfaced by rclpy's C extension
RCLInvalidROSArgsError = _impl.RCLInvalidROSArgsError  # remove_ros_args on bad --ros-args

_INTEGER_FOR_DOUBLE = re.compile(r"parameter '([^']+)' to '(-?\d+)' of type 'INTEGER', "
                                 r"expecting type 'DOUBLE'")


def take_waiting(subscription: Subscription, msg_type: type) -> Any | None:
    """Return the next message already queued on ``subscription``, or None: rclpy's own take."""
    with subscription.handle:
        taken = subscription.handle.take_message(msg_type, False)
    return None if taken is None else taken[0]


def given_parameters(node: Node) -> dict[str, Any]:
    """Return the parameter values given at start-up, declared or not (rclpy's, private)."""
    return getattr(node, '_parameter_overrides', {})


def integer_given_for_double(err: ParameterException) -> tuple[str, str] | None:
    """Return (name, value) where ``err`` is an integer given for a float parameter."""
    found = _INTEGER_FOR_DOUBLE.search(' '.join(str(err).split()))
    return None if found is None else (found[1], found[2])
