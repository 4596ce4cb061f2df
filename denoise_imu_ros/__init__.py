# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Learned gyro correction for open-loop attitude (Brossard et al., RA-L 2020) on ROS 2.

Five rooms, one dependency direction (held by import-linter contracts in setup.cfg):
``core`` <- ``data`` <- ``runtime`` (the robot path, never torch) and ``learn`` (torch)
<- ``evaluation``; ``cli`` and ``demo`` sit on top. Runtime and learn never import each
other.
"""

__version__ = '0.5.0'

__all__ = ['__version__']
