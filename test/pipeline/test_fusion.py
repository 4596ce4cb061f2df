# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The gravity-aided orientation: VQF online equals offline, the time convention, settings."""

from denoise_imu_ros.core.modelfile import read_model_file
from denoise_imu_ros.core.schema import parse_meta
from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.pipeline.fusion import (fuse, FusionSettings, GravityFilter,
                                             orientation_covariance, step_periods,
                                             VQF_OWN_DEFAULTS)
from denoise_imu_ros.pipeline.online import OnlineDenoiser
from helpers import SAMPLE
import numpy as np
import pytest
from scipy.spatial.transform import Rotation


@pytest.fixture(scope='module')
def imu():
    return load_imu(SAMPLE).imu[:3000]


@pytest.mark.parametrize('settings', [FusionSettings(), FusionSettings(10.0, True),
                                      FusionSettings(5.0, False, (-0.01, 0.12, 0.06)),
                                      FusionSettings(5.0, False, (-0.01, 0.12, 0.06), True)])
def test_online_equals_offline_bit_for_bit(imu, settings):
    online = GravityFilter(200.0, settings)
    buffer = np.empty(6)  # the caller refills one array, as a streaming engine may
    raw = imu[:, :3] + [0.01, -0.02, 0.005]  # a corrected gyro is not the raw one

    def update(row: np.ndarray, raw_gyro: np.ndarray) -> np.ndarray:
        buffer[:] = row
        return online.update(buffer[:3], buffer[3:], raw=raw_gyro)
    one_by_one = np.array([update(row, g) for row, g in zip(imu, raw)])
    assert np.array_equal(one_by_one, fuse(imu[:, :3], imu[:, 3:], 200.0, settings, raw=raw))
    online.reset()
    assert np.array_equal(online.update(imu[0, :3], imu[0, 3:], raw=raw[0]), one_by_one[0])


def test_the_classical_tilt_is_vqf_defaults_on_the_raw_imu_the_heading_the_filters(imu):
    """Never a worse tilt than what a user runs with no model, where chosen; our heading."""
    corrected = imu[:, :3] - [0.004, -0.003, 0.006]
    own = FusionSettings(5.0, False, (-0.01, 0.12, 0.06))
    split = Rotation.from_quat(fuse(corrected, imu[:, 3:], 200.0,
                                    FusionSettings(5.0, False, (-0.01, 0.12, 0.06), True),
                                    raw=imu[:, :3]))
    classical = Rotation.from_quat(fuse(imu[:, :3], imu[:, 3:], 200.0, VQF_OWN_DEFAULTS))
    heading = Rotation.from_quat(fuse(corrected, imu[:, 3:], 200.0, own))
    up = [0.0, 0.0, 1.0]
    np.testing.assert_allclose(split.inv().apply(up), classical.inv().apply(up), atol=1e-12)
    assert np.abs(heading.inv().apply(up) - classical.inv().apply(up)).max() > 1e-4
    np.testing.assert_allclose(split.as_euler('ZYX')[:, 0], heading.as_euler('ZYX')[:, 0],
                               atol=1e-12)
    with pytest.raises(ValueError, match='the classical tilt needs the raw gyro'):
        fuse(corrected, imu[:, 3:], 200.0, FusionSettings(classical_tilt=True))


@pytest.mark.parametrize('accel', [(0.0, 0.0, 9.81), (9.2, 0.1, -3.3), (-2.0, 6.0, 7.0),
                                   (0.5, -0.3, -9.7)])
def test_the_fused_orientation_starts_where_the_attitude_does(accel):
    """imu/data and imu/attitude in one earth frame: VQF's own heading turned to yaw 0."""
    from denoise_imu_ros.core.rotation import from_gravity
    first = GravityFilter(200.0).update(np.zeros(3), np.array(accel))
    expected = np.array(from_gravity(*accel))
    assert min(np.abs(first - expected).max(), np.abs(first + expected).max()) < 1e-9
    gyro, acc = np.zeros((50, 3)), np.tile(accel, (50, 1))
    batch = fuse(gyro, acc, 200.0)
    assert np.array_equal(batch[0], first)
    np.testing.assert_allclose(np.linalg.norm(batch, axis=1), 1.0, atol=1e-12)


def test_the_step_to_stamp_k_includes_sample_k():
    """Each interval at its two samples' mean: the yaw at stamp k includes sample k's rate."""
    rate = np.random.default_rng(0).uniform(-1.0, 1.0, 1000)
    gyro = np.stack([np.zeros(1000), np.zeros(1000), rate], axis=1)
    accel = np.tile([0.0, 0.0, 9.81], (1000, 1))
    quat = fuse(gyro, accel, 200.0, FusionSettings(tau_acc_s=1.0))
    yaw = Rotation.from_quat(quat).as_rotvec()[:, 2]
    expected = np.concatenate([[0.0], np.cumsum(0.5 * (rate[:-1] + rate[1:]) * 0.005)])
    np.testing.assert_allclose(np.unwrap(yaw), expected, atol=1e-9)


def test_a_lost_message_keeps_its_rotation_in_the_yaw():
    """VQF steps by one period; the real interval scales the gyro, online and offline."""
    stamps = 5_000_000 * np.array([k for k in range(2000) if k % 5 != 4])  # every 5th lost
    gyro = np.tile([0.0, 0.0, 0.5], (len(stamps), 1))
    accel = np.tile([0.0, 0.0, 9.81], (len(stamps), 1))
    periods = step_periods(stamps, 200.0)
    assert periods[0] == 0.0 and set(np.round(periods[1:], 9)) == {1.0, 2.0}
    online = GravityFilter(200.0, FusionSettings(tau_acc_s=1.0))
    one_by_one = np.array([online.update(g, a, p) for g, a, p in zip(gyro, accel, periods)])
    quat = fuse(gyro, accel, 200.0, FusionSettings(tau_acc_s=1.0), periods)
    assert np.array_equal(one_by_one, quat)
    yaw = np.unwrap(Rotation.from_quat(quat).as_rotvec()[:, 2])
    np.testing.assert_allclose(yaw[-1], 0.5 * stamps[-1] * 1e-9, atol=1e-9)
    # across a gap (the network restarts) no gyro step, as the online pipeline passes it
    assert step_periods(np.array([0, 5_000_000, 30_000_000]), 200.0).tolist() == [0, 1, 0]


def test_gravity_pulls_the_tilt_back_and_yaw_starts_at_zero():
    tilt = Rotation.from_euler('ZYX', [0.0, 0.2, -0.4])
    accel = np.tile(tilt.inv().apply([0.0, 0.0, 9.81]), (2000, 1))
    gyro = np.tile([0.0, 0.02, 0.0], (2000, 1))  # a bias the filter must not integrate away
    quat = fuse(gyro, accel, 200.0, FusionSettings(tau_acc_s=1.0))
    up = tilt.inv().apply([0.0, 0.0, 1.0])  # the vertical seen from the body

    def tilt_error_deg(q: np.ndarray) -> float:
        return float(np.degrees(np.arccos(np.clip(Rotation.from_quat(q).inv().apply(
            [0.0, 0.0, 1.0]) @ up, -1.0, 1.0))))
    assert tilt_error_deg(quat[0]) < 1e-6  # the first accelerometer sets the tilt
    # after 10 s the tilt error is the bias over the time constant, not a growing drift
    assert tilt_error_deg(quat[-1]) < np.degrees(0.02 * 1.0) * 1.5
    assert abs(tilt_error_deg(quat[-1]) - tilt_error_deg(quat[-400])) < 0.01


def test_the_accelerometer_bias_is_removed_before_the_filter_sees_it():
    """A bias b tilts the vertical by about |b| / g; removing it gives the true tilt back."""
    tilt = Rotation.from_euler('ZYX', [0.0, 0.2, -0.4])
    up = tilt.inv().apply([0.0, 0.0, 1.0])
    bias = np.array([0.0, 0.15, -0.05])
    accel = np.tile(9.81 * up + bias, (1000, 1))
    gyro = np.zeros((1000, 3))

    def tilt_error_deg(settings: FusionSettings) -> float:
        seen = Rotation.from_quat(fuse(gyro, accel, 200.0, settings)[-1]).inv().apply(
            [0.0, 0.0, 1.0])
        return float(np.degrees(np.arccos(np.clip(seen @ up, -1.0, 1.0))))
    assert tilt_error_deg(FusionSettings(1.0)) == pytest.approx(
        np.degrees(np.linalg.norm(np.cross(up, bias)) / 9.81), rel=0.05)
    assert tilt_error_deg(FusionSettings(1.0, False, tuple(bias))) < 1e-6
    np.testing.assert_array_equal(fuse(gyro, accel, 200.0, FusionSettings(1.0, False, tuple(
        bias))), fuse(gyro, accel - bias, 200.0, FusionSettings(1.0)))


def test_the_online_pipeline_fuses_its_own_corrected_gyro(model_file, imu):
    mf = read_model_file(model_file)
    den = OnlineDenoiser.from_model_file(mf, FusionSettings(2.0, False))
    stamps = 1_000_000_000 + 5_000_000 * np.arange(len(imu))
    stamps[500:] += 5_000_000  # a message lost: its interval is two periods
    outs = [den.process(int(t), row[:3], row[3:]) for t, row in zip(stamps, imu)]
    gyro = np.array([o.gyro for o in outs])
    assert np.array_equal(np.array([o.orientation for o in outs]), fuse(
        gyro, imu[:, 3:], 200.0, FusionSettings(2.0, False), step_periods(stamps, 200.0)))
    # a backward jump resets the filter: the sample after it starts from its accelerometer
    back = den.process(int(stamps[0]), imu[0, :3], imu[0, 3:])
    assert np.array_equal(back.orientation, fuse(gyro[:1], imu[:1, 3:], 200.0)[0])
    assert OnlineDenoiser.from_model_file(mf).process(1, imu[0, :3], imu[0, 3:]).orientation \
        is None


def test_covariance_comes_from_the_model_file_or_the_node_or_a_default():
    meta = parse_meta({'fusion': {'orientation_std_rad': [0.01, 0.02, 0.03]}}, 'm')
    assert orientation_covariance(meta)[::4] == pytest.approx([1e-4, 4e-4, 9e-4])
    assert orientation_covariance(meta, 0.1)[::4] == pytest.approx([0.01] * 3)
    assert orientation_covariance(parse_meta({}, 'm'))[::4] == pytest.approx([0.0025] * 3)


def test_a_classical_tilt_is_refused_without_the_raw_gyro_and_on_other_filters(imu):
    from denoise_imu_ros.evaluation.filters import Filter
    from denoise_imu_ros.pipeline.stages import Flow, Orientation
    orientation = Orientation(200.0, FusionSettings(classical_tilt=True))
    with pytest.raises(ValueError, match='the classical tilt needs the raw gyro'):
        orientation.run(Flow(imu, out=imu[:, :3]))  # the model's input is not the raw gyro
    flow = Flow.recording(imu)
    flow.out = imu[:, :3]
    orientation.run(flow)  # a recording's flow carries its raw gyro
    assert np.isfinite(flow.orientation).all()
    with pytest.raises(ValueError, match='the classical tilt is a VQF setting'):
        Filter('madgwick', gain=0.1, classical_tilt=True)
