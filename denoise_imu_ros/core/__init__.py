# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The core: what every other room builds on, with numpy, scipy and safetensors alone.

The network's geometry (``architecture``), model files (``modelfile``), recordings and
sequences (``records``), the metrics, the input limits, message builders (``msgs``),
atomic outputs, strict JSON, the errors of every area, and the quaternion products where
scipy costs more than the work (``rotation``). It imports no other room, and never torch
or rclpy. Import the module you need: this package imports none of them, so that the
node does not load the offline metrics (and scipy's rotations) it never uses.
"""

__all__ = ['architecture', 'atomic', 'errors', 'jsonio', 'limits', 'metrics', 'modelfile',
           'msgs', 'records', 'rotation']
