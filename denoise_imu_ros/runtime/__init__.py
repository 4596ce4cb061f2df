# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The robot path, never torch: the streaming engine, the online pipeline and what runs it.

``streaming`` (its step compiled from ``_step.c`` where built) and ``online`` are numpy
only, ``fusion`` adds VQF; ``process_bag`` adds rosbags; ``node`` and
``player`` add rclpy. Import the module you need: this package imports none of them, so
that process-bag never loads rclpy.
"""

__all__ = ['advice', 'fusion', 'node', 'online', 'outputs', 'player', 'process_bag',
           'rclpy_internals', 'streaming']
