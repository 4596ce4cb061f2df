# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Strict JSON: a figure that does not exist is null, never NaN or Infinity."""

import json
import math

from denoise_imu_ros.core.jsonio import dumps
import numpy as np


def test_non_finite_figures_are_null_and_numpy_values_plain():
    report = {'aoe_deg': np.float32(1.5), 'nees': [np.nan, math.inf, -np.inf],
              'count': np.int64(3), 'bias': np.array([[0.25, np.nan]]), 'label': 'euroc'}
    text = dumps(report)
    assert json.loads(text) == {'aoe_deg': 1.5, 'nees': [None, None, None], 'count': 3,
                                'bias': [[0.25, None]], 'label': 'euroc'}
    assert 'NaN' not in text and 'Infinity' not in text
