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
"""Exceptions of the package, one per area; the CLI turns them into exit codes."""


class DenoiseError(Exception):
    """Base class: anything the user can fix (a bad file, a bad option)."""


class DatasetError(DenoiseError):
    """An IMU/ground-truth recording (ASL folder or bag) cannot be used."""


class ModelFileError(DenoiseError):
    """A model file is missing, corrupt or of another version."""


class TrainingError(DenoiseError):
    """Training cannot go on (bad configuration, non-finite loss)."""


class OutputError(DenoiseError):
    """An output cannot be written (it exists, it is an input, the disk refuses it)."""


class OptionError(DenoiseError):
    """An option value is out of its range (a playback rate, a start sample)."""
