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
    over = envelope.beyond(fed, bounds, FIELD, RATE)
    out = blend_batch(output, fed, RATE, blend, over)
    classical = fed[:, :3] - rest_bias.tracked_bias(fed[:, :3], fed[:, 3:], RATE, TRACKING)
    first = int(np.argmax(envelope.sustained(fed, round(RATE)) > 5.0))
    assert 400 < first < 500 and over[first:].all() and not over[:first].any()
    np.testing.assert_array_equal(out[first:], classical[first:])
    np.testing.assert_allclose(out[:first], (classical + WEIGHT * (output - classical))[:first],
                               rtol=0, atol=1e-15)
    blender = Blender(blend, RATE)
    per_sample = np.array([blender.apply(o, f, b) for o, f, b in zip(output, fed, over)])
    np.testing.assert_array_equal(per_sample, out)
    assert blender.classical_only == len(out) - first


def test_without_a_guard_every_sample_is_blended():
    fed, output = _stream()
    blend = Blend(WEIGHT, TRACKING)
    out = blend_batch(output, fed, RATE, blend)
    blender = Blender(blend, RATE)
    np.testing.assert_array_equal(np.array([blender.apply(o, f) for o, f in zip(output, fed)]),
                                  out)
    assert blender.classical_only == 0
    classical = fed[:, :3] - rest_bias.tracked_bias(fed[:, :3], fed[:, 3:], RATE, TRACKING)
    assert not np.isclose(out, classical).all(axis=1).any()


def test_blended_the_outputs_tracker_holds_beyond_the_bound_per_sample_and_over_arrays():
    """What the network's tracker would learn there (motion it never saw) is not kept."""
    from denoise_imu_ros.pipeline.stages import (BiasTrackingStage, EnvelopeApply, EnvelopeCheck,
                                                 Flow, Pipeline)
    fed, output = _stream()
    output[400:] += 0.05  # the network off by a bias where it accelerates beyond training
    bounds = InputEnvelope(10.0, 50.0, (0.0, 0.0, 0.0), sustained_accel_m_s2=5.0)

    def stages(blended=True):
        guard = envelope.Guard(bounds, FIELD, RATE, hold_beyond=blended)
        return Pipeline([BiasTrackingStage(TRACKING, RATE), EnvelopeCheck(guard, RATE),
                         EnvelopeApply(guard)])
    batch = stages().run(Flow(fed, out=output))
    over = envelope.beyond(fed, bounds, FIELD, RATE)
    first = int(np.argmax(over))
    assert 400 < first < 500
    np.testing.assert_array_equal(batch.bias[first:], np.repeat(batch.bias[first - 1:first],
                                                                len(fed) - first, axis=0))
    # unblended, the output there is the network's own: its tracker follows it
    free = rest_bias.tracked_bias(output, fed[:, 3:], RATE, TRACKING)
    np.testing.assert_array_equal(stages(blended=False).run(Flow(fed, out=output)).bias, free)
    assert np.abs(free[-1] - batch.bias[-1]).max() > 1e-3
    online = stages()
    per_sample = []
    for f, o in zip(fed, output):
        flow = Flow(f.copy(), out=o.copy())
        for stage in online.stages:
            stage.step(flow)
        per_sample.append(flow.bias)
    np.testing.assert_array_equal(np.array(per_sample), batch.bias)
