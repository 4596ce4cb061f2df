# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""A model taught without its poses' heading: its correction about the vertical dropped."""

from denoise_imu_ros.core.limits import GRAVITY_M_S2
from denoise_imu_ros.core.schema import parse_meta, REST_ONLY, RestBiasSettings
from denoise_imu_ros.pipeline.stages import finish
from denoise_imu_ros.pipeline.vertical import drop_vertical, drops_vertical, up_in_body, Vertical
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from vqf import VQF

RATE = 200.0


def _recording(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Return a turning body's model input (n, 6) and a model output (n, 3) near it."""
    rng = np.random.default_rng(seed)
    gyro = np.cumsum(rng.normal(0, 0.02, (n, 3)), axis=0)
    att = Rotation.identity()
    accel = np.empty((n, 3))
    for k in range(n):  # gravity seen by the turning body, plus vibration
        accel[k] = att.inv().apply([0.0, 0.0, GRAVITY_M_S2]) + rng.normal(0, 0.05, 3)
        att = att * Rotation.from_rotvec(gyro[k] / RATE)
    fed = np.column_stack([gyro, accel])
    return fed, gyro + rng.normal(0, 0.01, (n, 3)) + [0.002, -0.001, 0.004]


def test_up_in_body_is_the_world_z_axis_seen_from_the_body():
    q = Rotation.random(50, random_state=1)
    x, y, z, w = q.as_quat().T
    np.testing.assert_allclose(np.column_stack(up_in_body(w, x, y, z)),
                               q.inv().apply([0.0, 0.0, 1.0]), atol=1e-12)


def test_per_sample_equals_the_arrays_bit_for_bit_and_restarts_on_reset():
    fed, output = _recording(1500)
    batch = drop_vertical(output, fed, RATE)
    vertical = Vertical(RATE)
    online = np.array([vertical.apply(o, f) for o, f in zip(output, fed)])
    assert np.array_equal(online, batch)
    vertical.reset()
    again = np.array([vertical.apply(o, f) for o, f in zip(output[700:], fed[700:])])
    assert np.array_equal(again, drop_vertical(output[700:], fed[700:], RATE))


def test_only_the_correction_about_the_vertical_is_dropped():
    """At rest, tilted: the vertical is the accelerometer's direction."""
    n = 2000
    up = Rotation.from_euler('xy', [0.4, -0.3]).inv().apply([0.0, 0.0, 1.0])
    fed = np.column_stack([np.zeros((n, 3)), np.tile(up * GRAVITY_M_S2, (n, 1))])
    about_up, across = 0.01 * up, 0.01 * np.cross(up, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(drop_vertical(np.tile(about_up, (n, 1)), fed, RATE), 0.0,
                               atol=1e-12)
    # a correction across the vertical tilts the filter it drives, within its time constant
    kept = drop_vertical(np.tile(across + about_up, (n, 1)), fed, RATE)
    assert np.abs(kept - across).max() < 0.05 * np.linalg.norm(across)


def test_it_is_causal_and_leaves_the_input_gyro_alone():
    fed, output = _recording(1000, 2)
    out = drop_vertical(output, fed, RATE)
    later = output.copy()
    later[600:] += 0.5
    np.testing.assert_array_equal(drop_vertical(later, fed, RATE)[:600], out[:600])
    np.testing.assert_allclose(drop_vertical(fed[:, :3], fed, RATE), fed[:, :3], atol=1e-15)
    assert np.abs(out - output).max() > 1e-3  # the correction had a vertical part


def test_sample_k_is_projected_on_the_vertical_of_the_outputs_before_it():
    fed, output = _recording(600, 4)
    out = drop_vertical(output, fed, RATE)
    moved = output.copy()
    delta = np.array([0.03, -0.02, 0.05])
    moved[400] += delta  # the vertical at 400 comes from the outputs up to 399
    shifted = np.vstack([np.zeros(3), output[:-1]])
    wxyz = VQF(1.0 / RATE, motionBiasEstEnabled=False, restBiasEstEnabled=False).updateBatch(
        shifted, np.ascontiguousarray(fed[:, 3:]))['quat6D'][400]
    up = Rotation.from_quat(np.roll(wxyz, -1)).inv().apply([0.0, 0.0, 1.0])
    expected = out[400] + delta - (delta @ up) * up
    np.testing.assert_allclose(drop_vertical(moved, fed, RATE)[400], expected, atol=1e-12)


def test_finish_drops_the_vertical_last_and_only_when_asked():
    fed, output = _recording(800, 3)
    kept = finish(output, fed, RATE, None, None, 1)
    np.testing.assert_array_equal(kept, output)
    np.testing.assert_array_equal(finish(output, fed, RATE, None, None, 1, True),
                                  drop_vertical(output, fed, RATE))


@pytest.mark.parametrize('weight, dropped', [(0.0, True), (0, True), (0.25, False),
                                             (1.0, False), (None, False), (False, False),
                                             ('0', False)])
def test_a_model_drops_it_where_its_recipe_left_the_heading_out(weight, dropped):
    config = {} if weight is None else {'heading_weight': weight}
    meta = parse_meta({'train_config': config, 'rest_bias': RestBiasSettings().to_dict()}, 'm')
    assert drops_vertical(meta) is dropped


def test_only_a_model_fed_the_gyro_less_its_turn_on_bias_drops_it():
    """Fed the raw gyro, the output would keep the whole turn-on bias about the vertical."""
    heading_0 = {'train_config': {'heading_weight': 0.0}}
    rest = {'rest_bias': RestBiasSettings().to_dict()}
    assert not drops_vertical(parse_meta(heading_0, 'm'))
    assert drops_vertical(parse_meta(heading_0, 'm'), 'on')
    assert not drops_vertical(parse_meta(dict(heading_0, **rest), 'm'), 'off')
    assert not drops_vertical(parse_meta(dict(heading_0, **rest, kind=REST_ONLY), 'm'))
