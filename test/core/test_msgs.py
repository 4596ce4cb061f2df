# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The message builders: a refilled message is the message built afresh."""

from denoise_imu_ros.core import msgs
from denoise_imu_ros.data.bags import BAG_TYPES
import numpy as np
import pytest


def _numbers(m) -> list[float]:
    o, w, a, s = m.orientation, m.angular_velocity, m.linear_acceleration, m.header.stamp
    return [s.sec, s.nanosec, w.x, w.y, w.z, *m.angular_velocity_covariance, a.x, a.y, a.z,
            *m.linear_acceleration_covariance, o.x, o.y, o.z, o.w, *m.orientation_covariance]


@pytest.mark.parametrize('types', [msgs.rclpy_types(), BAG_TYPES], ids=['rclpy', 'bag'])
def test_refilling_the_outgoing_messages_equals_building_them(types):
    rng = np.random.default_rng(0)
    raws = [msgs.imu(types, msgs.header(types, 10**9 + k * 5_000_000, 'imu0'),
                     rng.normal(size=3), rng.normal(size=3), accel_cov=rng.uniform(size=9))
            for k in range(3)]
    gyro_cov, fused_cov = np.full(9, 0.1), np.full(9, 0.2)
    reused = attitude = None
    for k, raw in enumerate(raws):
        gyro, quat = rng.normal(size=3), np.array([0.1, -0.2, 0.3, 0.9])
        embed = quat if k == 1 else None  # the orientation comes and goes
        fresh = msgs.corrected_imu(types, raw, gyro, gyro_cov, embed, fused_cov)
        reused = msgs.corrected_imu(types, raw, gyro, gyro_cov, embed, fused_cov, into=reused)
        assert _numbers(reused) == _numbers(fresh) and reused.header.frame_id == 'imu0'
        msgs.reorient(reused, quat, fused_cov)  # imu/data, published from the same message
        fresh_att = msgs.attitude(types, raw, 'odom', quat)
        attitude = msgs.attitude(types, raw, 'odom', quat, into=attitude)

        def fields(m) -> list:
            q = m.quaternion
            return [m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id,
                    q.x, q.y, q.z, q.w]
        assert fields(attitude) == fields(fresh_att) and fresh_att.header.frame_id == 'odom'
