# Copyright 2026 denoise_imu_ros authors
# Licensed under the Apache License, Version 2.0
"""The ROS-free online pipeline: equals offline integration, handles bad stamps."""

from conftest import SAMPLE, untrained_model
from denoise_imu_ros.dataset import load_sequence
from denoise_imu_ros.evaluate import correct_gyro
from denoise_imu_ros.metrics import integrate
from denoise_imu_ros.online import gravity_attitude, OnlineDenoiser, Output
from denoise_imu_ros.streaming import StreamingCorrector
import numpy as np
import pytest
from scipy.spatial.transform import Rotation


@pytest.fixture(scope='module')
def seq():
    """Load the bundled real EuRoC sample with ground truth."""
    return load_sequence(SAMPLE)


@pytest.fixture()
def model():
    """Build an untrained eval-mode network."""
    return untrained_model()


def _run(denoiser, stamps, imu):
    return [denoiser.process(int(t), row[:3], row[3:]) for t, row in zip(stamps, imu)]


def test_online_attitude_equals_offline_integration_of_the_batch_output(seq, model):
    n = 3000
    outs = _run(OnlineDenoiser(StreamingCorrector.from_module(model), 200.0), seq.stamp_ns[:n],
                seq.imu[:n])
    gyro = correct_gyro(model, seq.imu[:n])
    np.testing.assert_allclose(np.array([o.gyro for o in outs]), gyro, atol=1e-6)
    start = gravity_attitude(seq.imu[0, 3:])
    offline = integrate(start.as_quat(), gyro[:-1], seq.dt[:n - 1])
    online = Rotation.from_quat(np.array([o.attitude for o in outs]))
    assert np.max((offline.inv() * online).magnitude()) < 1e-6
    assert outs[0].event == 'start' and all(o.event is None for o in outs[1:])


def test_gravity_attitude_levels_the_accelerometer():
    tilt = Rotation.from_euler('ZYX', [0.0, 0.2, -0.4])
    accel = tilt.inv().apply([0.0, 0.0, 9.81])
    assert (gravity_attitude(accel).inv() * tilt).magnitude() < 1e-12


def test_bad_stamps_and_values_are_dropped_and_counted(seq, model):
    den = OnlineDenoiser(StreamingCorrector.from_module(model), 200.0)
    t, imu = seq.stamp_ns, seq.imu
    assert isinstance(den.process(int(t[0]), imu[0, :3], imu[0, 3:]), Output)
    bad_gyro = np.array([np.nan, 0.0, 0.0])
    assert den.process(int(t[1]), bad_gyro, imu[1, 3:]) == 'non_finite'
    assert den.process(int(t[1]), imu[1, :3], np.array([0.0, np.inf, 0.0])) == 'non_finite'
    assert den.process(0, imu[1, :3], imu[1, 3:]) == 'zero_stamp'
    assert den.process(int(t[0]), imu[1, :3], imu[1, 3:]) == 'duplicate_stamp'
    assert den.process(int(t[0]) - 1000, imu[1, :3], imu[1, 3:]) == 'out_of_order'
    assert isinstance(den.process(int(t[1]), imu[1, :3], imu[1, 3:]), Output)
    assert den.counts == {'non_finite': 2, 'zero_stamp': 1, 'duplicate_stamp': 1,
                          'out_of_order': 1, 'accepted': 2, 'gap_resets': 0,
                          'time_jump_resets': 0}


def test_gap_restarts_the_network_and_holds_the_attitude(seq, model):
    den = OnlineDenoiser(StreamingCorrector.from_module(model), 200.0, max_gap_factor=3.0)
    first = _run(den, seq.stamp_ns[:600], seq.imu[:600])
    after = _run(den, seq.stamp_ns[1000:1600], seq.imu[1000:1600])  # 2 s gap
    assert after[0].event == 'gap' and den.counts['gap_resets'] == 1
    np.testing.assert_array_equal(after[0].attitude, first[-1].attitude)
    # the network restarted exactly as at start-up on the new segment
    np.testing.assert_allclose(np.array([o.gyro for o in after]),
                               correct_gyro(model, seq.imu[1000:1600]), atol=1e-6)


def test_backward_time_jump_resets_everything(seq, model):
    den = OnlineDenoiser(StreamingCorrector.from_module(model), 200.0, time_jump_s=1.0)
    _run(den, seq.stamp_ns[:800], seq.imu[:800])
    again = _run(den, seq.stamp_ns[:300], seq.imu[:300])  # a bag played again
    assert again[0].event == 'time_jump' and den.counts['time_jump_resets'] == 1
    fresh = _run(OnlineDenoiser(StreamingCorrector.from_module(model), 200.0), seq.stamp_ns[:300],
                 seq.imu[:300])
    np.testing.assert_allclose(again[-1].attitude, fresh[-1].attitude, atol=1e-12)


def test_reset_attitude_reinitialises_from_gravity_at_the_next_sample(seq, model):
    den = OnlineDenoiser(StreamingCorrector.from_module(model), 200.0)
    _run(den, seq.stamp_ns[:500], seq.imu[:500])
    den.reset_attitude()
    out = den.process(int(seq.stamp_ns[500]), seq.imu[500, :3], seq.imu[500, 3:])
    np.testing.assert_allclose(out.attitude, gravity_attitude(seq.imu[500, 3:]).as_quat())
