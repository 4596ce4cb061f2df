# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The node fixture of the runtime tests (rclpy, never torch)."""

import pytest
from ros_harness import Harness


@pytest.fixture()
def harness(model_file):
    """Yield a running node and client; torn down after the test."""
    made = []

    def make(**params):
        made.append(Harness(model_file, **params))
        return made[-1]
    yield make
    for h in made:
        h.close()
