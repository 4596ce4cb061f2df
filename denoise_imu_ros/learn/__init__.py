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
Training, with torch: the network, its loss, the training loop, recipes.

``config`` and ``recipe`` are torch-free (``init-recipe`` needs no torch); ``model``,
``checkpoint``, ``so3``, ``loss``, ``parallel`` and ``train`` import it. Import the
module you need: this package imports none of them.
"""

__all__ = ['checkpoint', 'config', 'loss', 'model', 'parallel', 'recipe', 'so3', 'train']
