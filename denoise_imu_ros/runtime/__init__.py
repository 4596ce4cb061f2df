# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
What runs the pipeline on a robot or a bag, never torch: the node, process-bag, the player.

``settings`` (the node's parameters as one object), ``outputs`` (what a sample publishes),
``diagnostics`` (what ``/diagnostics`` says) and ``advice`` (start-up warnings) are pure
Python over the pipeline; ``process_bag`` adds rosbags; ``node`` and ``player`` add rclpy
(its undocumented parts in ``rclpy_internals``). Import the module you need: this package
imports none of them, so that process-bag never loads rclpy.
"""

__all__ = ['advice', 'diagnostics', 'node', 'outputs', 'player', 'process_bag',
           'rclpy_internals', 'settings']
