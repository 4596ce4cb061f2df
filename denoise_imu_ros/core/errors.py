# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
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


class DataWarning(UserWarning):
    """Something in the input was left out or is doubtful; the work goes on (said once)."""


class DataNote(DataWarning):
    """How an input was read where nothing was left out (nanoseconds, a header): a note."""
