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
The robot path, never torch: the streaming engine, the online pipeline and what runs it.

``streaming`` (its step compiled from ``_step.c`` where built) and ``online`` are numpy
only, ``fusion`` adds VQF; ``process_bag`` adds rosbags; ``node`` and
``player`` add rclpy. Import the module you need: this package imports none of them, so
that process-bag never loads rclpy.
"""

__all__ = ['fusion', 'node', 'online', 'player', 'process_bag', 'streaming']
