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
