# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Message conversion in one place: the node, process-bag, the player and bag writing.

The same functions build rclpy messages (the node, the player) and rosbags typestore
messages (bags), given the message classes (:func:`rclpy_types`, :func:`bag_types`):
every field is passed explicitly, which both kinds of constructor accept. So the node
and process-bag cannot drift apart in what they publish.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

NO_ORIENTATION = np.array([-1.0] + [0.0] * 8)  # REP-145: orientation not provided
NO_ORIENTATION.flags.writeable = False
UNKNOWN_COVARIANCE = np.zeros(9)  # REP-145: covariance unknown
IDENTITY = (0.0, 0.0, 0.0, 1.0)
UNKNOWN_COVARIANCE.flags.writeable = False


class MsgTypes(NamedTuple):
    """The message classes the builders use."""

    Header: Any
    Time: Any
    Imu: Any
    Vector3: Any
    Quaternion: Any
    QuaternionStamped: Any


def rclpy_types() -> MsgTypes:
    """Message classes of rclpy (imported here: bag tools need no ROS install)."""
    from builtin_interfaces.msg import Time
    from geometry_msgs.msg import Quaternion, QuaternionStamped, Vector3
    from sensor_msgs.msg import Imu
    from std_msgs.msg import Header
    return MsgTypes(Header, Time, Imu, Vector3, Quaternion, QuaternionStamped)


def bag_types(typestore: Any) -> MsgTypes:
    """Message classes of a rosbags typestore."""
    t = typestore.types
    return MsgTypes(t['std_msgs/msg/Header'], t['builtin_interfaces/msg/Time'],
                    t['sensor_msgs/msg/Imu'], t['geometry_msgs/msg/Vector3'],
                    t['geometry_msgs/msg/Quaternion'], t['geometry_msgs/msg/QuaternionStamped'])


def stamp_ns(header: Any) -> int:
    """Nanoseconds of a header stamp (rclpy or rosbags message)."""
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def imu_fields(msg: Any) -> tuple[int, np.ndarray, np.ndarray]:
    """Stamp (ns), gyro (3,) and accel (3,) of a sensor_msgs/Imu."""
    w, a = msg.angular_velocity, msg.linear_acceleration
    return stamp_ns(msg.header), np.array([w.x, w.y, w.z]), np.array([a.x, a.y, a.z])


def header(types: MsgTypes, stamp: int, frame_id: str) -> Any:
    """Build a header with a stamp in ns."""
    sec, nanosec = divmod(int(stamp), 1_000_000_000)
    return types.Header(stamp=types.Time(sec=sec, nanosec=nanosec), frame_id=frame_id)


def _vec(types: MsgTypes, v: Any) -> Any:
    return types.Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _quat(types: MsgTypes, q: Any) -> Any:
    return types.Quaternion(x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))


def imu(types: MsgTypes, head: Any, gyro: Any, accel: Any,
        orientation: Any = IDENTITY, orientation_cov: Any = NO_ORIENTATION,
        gyro_cov: Any = np.zeros(9), accel_cov: Any = np.zeros(9)) -> Any:
    """Build a sensor_msgs/Imu from arrays (orientation xyzw, covariances row-major)."""
    return types.Imu(header=head, orientation=_quat(types, orientation),
                     orientation_covariance=np.asarray(orientation_cov, np.float64),
                     angular_velocity=_vec(types, gyro),
                     angular_velocity_covariance=np.asarray(gyro_cov, np.float64),
                     linear_acceleration=_vec(types, accel),
                     linear_acceleration_covariance=np.asarray(accel_cov, np.float64))


def finite_covariance(cov: Any) -> np.ndarray:
    """Return a covariance as it is, or all zeros ('unknown', REP-145) if not finite."""
    cov = np.asarray(cov, np.float64)
    return cov if np.isfinite(cov).all() else UNKNOWN_COVARIANCE


def corrected_imu(types: MsgTypes, raw: Any, gyro: np.ndarray, gyro_cov: Any,
                  attitude: np.ndarray | None = None, orientation_cov: Any = None,
                  accel_cov: Any = None, into: Any = None,
                  accel: np.ndarray | None = None) -> Any:
    """
    Build the imu/corrected message of a raw one: its header, never re-stamped.

    The accelerometer is ``accel`` (None: the raw message's); its covariance passes
    through (``accel_cov`` when the caller has
    already checked it; a non-finite one becomes zeros, 'unknown', never NaN on the
    wire); the orientation is the attitude
    with ``orientation_cov`` when given, else absent (covariance[0] = -1, REP-145).
    ``into``, a message this built before, is overwritten instead of building one: a
    publish serialises at once, and building a message costs several times filling it.
    The header is the raw message's own object (as the stamp of :func:`attitude` with
    ``into``): neither is changed in place here, and must not be.
    """
    msg = imu(types, raw.header, gyro, (0.0, 0.0, 0.0)) if into is None else into
    msg.header = raw.header
    w, la = msg.angular_velocity, msg.linear_acceleration
    w.x, w.y, w.z = float(gyro[0]), float(gyro[1]), float(gyro[2])
    if accel is None:
        a = raw.linear_acceleration
        la.x, la.y, la.z = a.x, a.y, a.z
    else:
        la.x, la.y, la.z = float(accel[0]), float(accel[1]), float(accel[2])
    msg.angular_velocity_covariance = np.asarray(gyro_cov, np.float64)
    msg.linear_acceleration_covariance = finite_covariance(
        raw.linear_acceleration_covariance) if accel_cov is None else accel_cov
    if attitude is None:
        return reorient(msg, IDENTITY, NO_ORIENTATION)
    return reorient(msg, attitude, orientation_cov)


def reorient(msg: Any, quat: np.ndarray, orientation_cov: Any) -> Any:
    """
    Set an Imu's orientation and its covariance in place; return the message.

    The node publishes imu/corrected, then the same message with the fused orientation
    as imu/data (a publish serialises at once): one message built per sample, not two.
    """
    o = msg.orientation
    o.x, o.y, o.z, o.w = map(float, quat)
    msg.orientation_covariance = np.asarray(orientation_cov, np.float64)
    return msg


def attitude(types: MsgTypes, raw: Any, frame_id: str, quat: np.ndarray,
             into: Any = None) -> Any:
    """
    Build the imu/attitude message: the raw message's stamp, in the fixed frame.

    ``into``, a message this built before for the same frame, is overwritten instead.
    """
    if into is None:
        return types.QuaternionStamped(header=header(types, stamp_ns(raw.header), frame_id),
                                       quaternion=_quat(types, quat))
    into.header.stamp = raw.header.stamp
    q = into.quaternion
    q.x, q.y, q.z, q.w = map(float, quat)
    return into


def copy_imu(types: MsgTypes, src: Any) -> Any:
    """Copy every field of an Imu into an Imu of ``types`` (e.g. bag to rclpy)."""
    o, w, a = src.orientation, src.angular_velocity, src.linear_acceleration
    return imu(types, header(types, stamp_ns(src.header), src.header.frame_id),
               (w.x, w.y, w.z), (a.x, a.y, a.z), orientation=(o.x, o.y, o.z, o.w),
               orientation_cov=src.orientation_covariance,
               gyro_cov=src.angular_velocity_covariance,
               accel_cov=src.linear_acceleration_covariance)
