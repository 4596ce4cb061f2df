# Copyright 2026 denoise_imu_ros authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Learned gyro correction for open-loop attitude (Brossard et al., RA-L 2020) on ROS 2.

Five rooms, one dependency direction (held by import-linter contracts in setup.cfg):
``core`` <- ``data`` <- ``runtime`` (the robot path, never torch) and ``learn`` (torch)
<- ``evaluation``; ``cli`` and ``demo`` sit on top. Runtime and learn never import each
other.
"""

__version__ = '0.1.0'

__all__ = ['__version__']
