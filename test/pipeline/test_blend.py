# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The classical mix: T + W (N - T), T alone where the acceleration stays off gravity too long."""

import math

from denoise_imu_ros.core.limits import GRAVITY_M_S2
from denoise_imu_ros.core.schema import BiasTracking, Blend, InputEnvelope
from denoise_imu_ros.pipeline import envelope, rest_bias
from denoise_imu_ros.pipeline.blend import blend_batch, Blender
import numpy as np

RATE, FIELD, WEIGHT = 200.0, 8, 0.4
TRACKING = BiasTracking(math.radians(0.05), 30.0, math.radians(0.05))


def _stream(n=600, seed=3):
    rng = np.random.default_rng(seed)
    fed = np.zeros((n, 6))
    fed[:, :3] = rng.normal(0.0, 0.3, (n, 3)) + 0.002
    fed[:, 3:] = rng.normal(0.0, 0.2, (n, 3)) + [0.0, 0.0, GRAVITY_M_S2]
    fed[400:, 3:] *= 3.0  # hard acceleration to the end: beyond the bound within a second
    output = fed[:, :3] + rng.normal(0.0, 0.01, (n, 3)) - 0.002
    return fed, output


def test_the_classical_alone_where_the_bound_is_passed_the_blend_elsewhere():
    fed, output = _stream()
    bounds = InputEnvelope(10.0, 50.0, (0.0, 0.0, 0.0), sustained_accel_m_s2=5.0)
    blend = Blend(WEIGHT, TRACKING)
    out = blend_batch(output, fed, RATE, blend, bounds, FIELD)
    classical = fed[:, :3] - rest_bias.tracked_bias(fed[:, :3], fed[:, 3:], RATE, TRACKING)
    beyond = int(np.argmax(envelope.sustained(fed, round(RATE)) > 5.0))
    assert 400 < beyond < 500
    np.testing.assert_array_equal(out[beyond:], classical[beyond:])
    np.testing.assert_allclose(out[:beyond], (classical + WEIGHT * (output - classical))[:beyond],
                               rtol=0, atol=1e-15)
    blender = Blender(blend, RATE, bounds, FIELD)
    per_sample = np.array([blender.apply(o, f) for o, f in zip(output, fed)])
    np.testing.assert_array_equal(per_sample, out)
    assert blender.classical_only == len(out) - beyond


def test_without_a_guard_every_sample_is_blended():
    fed, output = _stream()
    blend = Blend(WEIGHT, TRACKING)
    out = blend_batch(output, fed, RATE, blend, None, FIELD)
    blender = Blender(blend, RATE, None, FIELD)
    np.testing.assert_array_equal(np.array([blender.apply(o, f) for o, f in zip(output, fed)]),
                                  out)
    assert blender.classical_only == 0
    classical = fed[:, :3] - rest_bias.tracked_bias(fed[:, :3], fed[:, 3:], RATE, TRACKING)
    assert not np.isclose(out, classical).all(axis=1).any()
