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
The physical range of an IMU sample: one limit for the node and every offline reader.

Values beyond it are not motion but corruption (a bit flip, a wrong unit, an
uninitialised field): the float32 network would overflow on them (~3e38) or turn them
into an attitude ruined for good. The limits sit well above every MEMS IMU's range
(gyros saturate at 2,000-4,000 deg/s, accelerometers at 16-200 g).
"""

from __future__ import annotations

import numpy as np

MAX_GYRO_RAD_S = 100.0    # ~5,700 deg/s
MAX_ACCEL_M_S2 = 2000.0   # ~200 g


def in_range(gyro: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """Whether each sample (last axis xyz) is finite and within the physical range."""
    with np.errstate(invalid='ignore'):
        return ((np.abs(gyro) <= MAX_GYRO_RAD_S).all(-1)
                & (np.abs(accel) <= MAX_ACCEL_M_S2).all(-1))


def describe() -> str:
    """Describe the limits, for error messages."""
    return f'|gyro| <= {MAX_GYRO_RAD_S:g} rad/s, |accel| <= {MAX_ACCEL_M_S2:g} m/s^2'
