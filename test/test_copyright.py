# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""ament_copyright, where installed (a real ROS install; not on PyPI)."""

import pytest


@pytest.mark.copyright
@pytest.mark.linter
def test_copyright():
    main = pytest.importorskip('ament_copyright.main').main
    rc = main(argv=['.', 'test'])
    assert rc == 0, 'Found errors'
