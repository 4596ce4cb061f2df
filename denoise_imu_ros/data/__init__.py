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
Recordings in and out: ASL folders and bags, the IMU time base, pose alignment, check-data.

Builds on :mod:`denoise_imu_ros.core` (with rosbags for bags); never torch or rclpy.
``load`` reads any recording (``load_recording``, ``load_sequence``, ``load_imu``);
``asl`` and ``bags`` the two formats; ``timebase`` puts ground truth onto the IMU stamps;
``pose_alignment`` estimates and applies a clock offset and frame rotation; ``check`` is
check-data. Import the module you need: this package imports none of them.
"""

__all__ = ['asl', 'bags', 'check', 'load', 'pose_alignment', 'timebase']
