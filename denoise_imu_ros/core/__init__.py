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

The network's geometry (``ModelConfig``), model files, recordings and sequences, the
metrics, the input limits, message builders, atomic outputs and the errors of every
area. It imports no other room, and never torch or rclpy.
"""

from .architecture import ModelConfig
from .atomic import atomic_output
from .errors import (DatasetError, DenoiseError, ModelFileError, OptionError, OutputError,
                     TrainingError)
from .metrics import attitude_errors, integrate, score, sequence_errors
from .modelfile import ModelFile, read_model_file, shipped_models, write_model_file
from .records import Recording, Sequence

__all__ = ['DatasetError', 'DenoiseError', 'ModelConfig', 'ModelFile', 'ModelFileError',
           'OptionError', 'OutputError', 'Recording', 'Sequence', 'TrainingError',
           'atomic_output', 'attitude_errors', 'integrate', 'read_model_file', 'score',
           'sequence_errors', 'shipped_models', 'write_model_file']
