# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Recordings in and out: ASL folders and bags, the IMU time base, pose alignment, check-data.

Builds on :mod:`denoise_imu_ros.core` (with rosbags for bags); never torch or rclpy.
``load`` reads any recording (``load_recording``, ``load_sequence``, ``load_imu``);
``asl`` and ``bags`` the two formats; ``timebase`` puts ground truth onto the IMU stamps;
``pose_alignment`` estimates and applies a clock offset and frame rotation; ``check`` is
check-data. Import the module you need: this package imports none of them.
"""

__all__ = ['asl', 'bags', 'check', 'load', 'pose_alignment', 'timebase']
