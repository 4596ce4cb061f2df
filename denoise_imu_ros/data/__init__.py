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
"""

from .bags import read_bag, write_bag
from .check import check
from .load import is_bag, load_imu, load_recording, load_sequence
from .pose_alignment import apply_pose_alignment, estimate_pose_alignment
from .timebase import crop, onto_imu_stamps, overlap

__all__ = ['apply_pose_alignment', 'check', 'crop', 'estimate_pose_alignment', 'is_bag',
           'load_imu', 'load_recording', 'load_sequence', 'onto_imu_stamps', 'overlap',
           'read_bag', 'write_bag']
