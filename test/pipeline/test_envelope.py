# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The input envelope: measured, stored, and the fallback beyond it."""

from denoise_imu_ros.core.errors import ModelFileError
from denoise_imu_ros.core.limits import GRAVITY_M_S2
from denoise_imu_ros.core.schema import InputEnvelope, parse_meta
from denoise_imu_ros.pipeline.envelope import (beyond, combine, Guard, guard_batch, measure,
                                               resolve, Sustained, sustained, sustained_bound,
                                               too_fast, untrusted)
import numpy as np
import pytest

FIELD = 5


def _imu(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.normal(0, 0.5, (n, 3)),
                            rng.normal(0, 0.3, (n, 3)) + [0.0, 0.0, GRAVITY_M_S2]])


def test_the_envelope_is_the_largest_gyro_norm_and_accelerometer_offset_trained_on():
    a, b = _imu(100), _imu(50, 1)
    b[7, :3] = [3.0, 4.0, 0.0]                      # |gyro| 5 rad/s
    b[9, 3:] = [0.0, 0.0, GRAVITY_M_S2 - 6.5]      # 6.5 m/s^2 below gravity
    assert measure([a, b]) == InputEnvelope(5.0, 6.5)
    # the fallback: the mean correction over every sample
    corrections = [np.full((100, 3), 0.01), np.full((50, 3), 0.04)]
    np.testing.assert_allclose(measure([a, b], corrections).fallback_rad_s, [0.02] * 3)


def test_the_sustained_excursion_is_the_causal_mean_over_the_last_window_of_samples():
    imu = _imu(60, 2)
    dev = np.abs(np.linalg.norm(imu[:, 3:], axis=1) - GRAVITY_M_S2)
    expected = [dev[max(0, n - 9):n + 1].mean() for n in range(60)]
    np.testing.assert_allclose(sustained(imu, 10), expected, rtol=1e-12)
    # the bound: the largest over recordings, over one second of samples
    b = _imu(30, 3)
    b[5:25, 3:] = [0.0, 0.0, GRAVITY_M_S2 + 4.0]  # 20 samples 4 m/s^2 off gravity
    assert sustained_bound([imu, b], 20.0) == pytest.approx(4.0)
    assert sustained_bound([imu], 20.0) == pytest.approx(sustained(imu, 20).max())
    assert combine([InputEnvelope(1.0, 2.0, sustained_accel_m_s2=0.5),
                    InputEnvelope(1.0, 2.0, sustained_accel_m_s2=0.7)]).sustained_accel_m_s2 == 0.7
    assert combine([InputEnvelope(1.0, 2.0, sustained_accel_m_s2=0.5),
                    InputEnvelope(1.0, 2.0)]).sustained_accel_m_s2 is None


def test_the_fallback_replaces_the_correction_for_a_receptive_field_after_a_sample_outside():
    fed = _imu(40)
    fed[:, :3] = 0.1
    fed[10, :3] = [0.0, 9.0, 0.0]  # outside
    output = fed[:, :3] + np.arange(40)[:, None] * 1e-3  # a correction that keeps changing
    bounds = InputEnvelope(1.0, 5.0, (0.01, -0.02, 0.03))
    guarded = guard_batch(output, fed, bounds, FIELD)
    inside = [n for n in range(40) if not 10 <= n < 10 + FIELD]
    assert np.array_equal(guarded[inside], output[inside])
    # samples 10-14 see sample 10 in their receptive field: input plus the fallback
    np.testing.assert_array_equal(guarded[10:15], fed[10:15, :3] + [0.01, -0.02, 0.03])
    assert guard_batch(output, fed, None, FIELD) is output


def test_untrusted_the_output_falls_back_to_what_the_tracker_gives():
    """Beyond the envelope: the input less the tracked bias, held through fast motion."""
    from denoise_imu_ros.core.schema import BiasTracking
    from denoise_imu_ros.pipeline.stages import finish
    from denoise_imu_ros.pipeline.rest_bias import tracked_bias
    rng = np.random.default_rng(5)
    n, rate = 8000, 200.0
    fed = np.column_stack([rng.normal(0, 0.3, (n, 3)) + [0.01, -0.008, 0.004],
                           rng.normal(0, 0.05, (n, 3)) + [0.0, 0.0, GRAVITY_M_S2]])
    fed[6000:6200, :3] *= 20.0  # fast motion the model never saw
    output = fed[:, :3] + 0.002 * np.sin(np.arange(n) / 50.0)[:, None]
    bounds, settings = InputEnvelope(4.0, 5.0), BiasTracking(0.05, 30.0, 0.05)
    hold = too_fast(fed, bounds, FIELD)
    bias = tracked_bias(output, fed[:, 3:], rate, settings, hold)
    assert np.abs(bias[5999]).max() > 1e-3  # it has learnt a bias by then
    np.testing.assert_array_equal(bias[hold], np.tile(bias[5999], (int(hold.sum()), 1)))
    done = finish(output, fed, rate, settings, bounds, FIELD)
    bad = untrusted(fed, bounds, FIELD)
    np.testing.assert_array_equal(done[bad], fed[bad, :3] - bias[bad])
    np.testing.assert_array_equal(done[~bad], (output - bias)[~bad])


def _online(guard: Guard, output: np.ndarray, fed: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the guarded outputs and the per-sample too-fast and beyond flags."""
    rows, fast, over = [], [], []
    for o, f in zip(output, fed):
        guard.check(f)
        fast.append(guard.too_fast)
        over.append(guard.beyond)
        rows.append(guard.apply(o, f))
    return np.array(rows), np.array(fast), np.array(over)


def test_per_sample_equals_the_arrays_bit_for_bit_and_restarts_on_reset():
    fed = _imu(2000, 2)
    fed[300:320, 3:] *= 3.0     # a shock on the accelerometer
    fed[1000:1400, :3] *= 6.0   # fast rotation
    fed[1600:1800, 3:] *= 1.5   # a second of sustained acceleration
    output = fed[:, :3] + np.random.default_rng(3).normal(0, 0.01, (2000, 3))
    bounds = InputEnvelope(2.5, 8.0, sustained_accel_m_s2=3.0)
    batch = guard_batch(output, fed, bounds, 51)
    guard = Guard(bounds, 51, 200.0)
    online, fast, over = _online(guard, output, fed)
    assert np.array_equal(online, batch)
    assert np.array_equal(fast, too_fast(fed, bounds, 51))
    assert np.array_equal(over, beyond(fed, bounds, 51, 200.0))
    assert 0 < guard.guarded == int((batch != output).any(axis=1).sum()) < 2000
    assert over[1760:1900].all() and not over[:1600].any()  # not the shock: a mean over 1 s
    guard.reset()
    again, _, over_again = _online(guard, output[1000:], fed[1000:])
    assert np.array_equal(again, guard_batch(output[1000:], fed[1000:], bounds, 51))
    assert np.array_equal(over_again, beyond(fed[1000:], bounds, 51, 200.0))


def test_beyond_needs_a_sustained_bound_and_the_sustained_mean_streams():
    fed = _imu(600, 5)
    fed[200:, 3:] *= 2.0
    assert not beyond(fed, InputEnvelope(2.5, 50.0), FIELD, 100.0).any()
    assert Guard(InputEnvelope(2.5, 50.0), FIELD, 100.0).hold is False
    mean = Sustained(100)
    np.testing.assert_array_equal([mean.update(a) for a in fed[:, 3:]], sustained(fed, 100))


def test_too_fast_is_the_gyro_alone_over_the_receptive_field():
    fed = _imu(400, 4)
    fed[:, :3] = 0.1
    fed[100:103, 3:] = [0.0, 0.0, 40.0]   # a tap: outside, not too fast
    fed[200, :3] = [0.0, 0.0, 3.0]        # one fast sample
    bounds = InputEnvelope(1.0, 5.0)
    fast = too_fast(fed, bounds, FIELD)
    assert np.flatnonzero(fast).tolist() == list(range(200, 200 + FIELD))
    assert untrusted(fed, bounds, FIELD)[100:103 + FIELD - 1].all()


def test_the_model_file_entry_is_checked():
    stored = InputEnvelope(5.0, 2.0, (0.01, 0.0, -0.08))
    assert parse_meta({'input_envelope': stored.as_dict()}, 'm').input_envelope == stored
    assert parse_meta({'input_envelope': {'gyro_rad_s': 5.0, 'accel_offset_m_s2': 2.0}},
                      'm').input_envelope == InputEnvelope(5.0, 2.0)
    assert parse_meta({}, 'm').input_envelope is None
    for bad in ({'gyro_rad_s': -1.0, 'accel_offset_m_s2': 2.0}, {'gyro_rad_s': 5.0}, [5, 2],
                {'gyro_rad_s': 5.0, 'accel_offset_m_s2': 2.0, 'fallback_rad_s': [0, 0, 3]}):
        with pytest.raises(ModelFileError, match='m: inconsistent'):
            parse_meta({'input_envelope': bad}, 'm')


def test_an_ensemble_takes_the_widest_bounds_and_the_mean_fallback():
    a = InputEnvelope(5.0, 2.0, (0.01, 0.0, 0.0))
    b = InputEnvelope(4.0, 3.0, (0.03, 0.02, 0.0))
    both = combine([a, b])
    assert (both.gyro_rad_s, both.accel_offset_m_s2) == (5.0, 3.0)
    np.testing.assert_allclose(both.fallback_rad_s, [0.02, 0.01, 0.0])
    assert combine([a, None]) is None


def test_the_guard_follows_the_model_file_or_is_turned_off():
    bounds = {'gyro_rad_s': 1.0, 'accel_offset_m_s2': 2.0}
    meta = parse_meta({'input_envelope': bounds}, 'm')
    assert resolve(meta, 'model') == meta.input_envelope is not None
    assert resolve(meta, 'off') is None
    assert resolve(parse_meta({}, 'm'), 'model') is None  # a file without one
    with pytest.raises(ValueError, match="envelope guard 'on': one of model, off"):
        resolve(meta, 'on')
