# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Pre-integrated increments: exact on a trajectory made by the same steps, NEES chi-square."""

from denoise_imu_ros.core.rotation import exp, multiply
from denoise_imu_ros.evaluation.preintegration import (
    errors, GRAVITY, preintegrate, reference, velocity_from_positions, window_starts)
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

RATE = 200.0


def _trajectory(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Return a tumbling, accelerating body and its perfect IMU: the steps a VIO assumes."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    dt = np.full(n - 1, 1 / RATE)
    gyro = np.stack([0.8 * np.sin(0.7 * t), 0.5 * np.cos(1.3 * t), 0.3 + 0.2 * np.sin(t)], 1)
    gyro += 0.02 * rng.standard_normal((n, 3))
    quat = np.empty((n, 4))
    r = tuple(Rotation.from_euler('xyz', [0.3, -0.2, 1.0]).as_quat())
    for k in range(n):
        quat[k], r = r, multiply(r, exp(*(gyro[k] / RATE)))
    acc_world = np.stack([np.sin(0.5 * t), np.cos(0.9 * t), 0.3 * np.sin(2 * t)], 1)
    vel, pos = np.zeros((n, 3)), np.zeros((n, 3))
    vel[0] = (0.2, -0.1, 0.0)
    for k in range(n - 1):  # each step's world acceleration held over it
        pos[k + 1] = pos[k] + vel[k] * dt[k] + 0.5 * acc_world[k] * dt[k] ** 2
        vel[k + 1] = vel[k] + acc_world[k] * dt[k]
    specific = acc_world - np.array([0.0, 0.0, -GRAVITY])
    accel = Rotation.from_quat(quat).inv().apply(specific)
    return {'t': t, 'dt': dt, 'gyro': gyro, 'accel': accel, 'quat': quat,
            'pos': pos, 'vel': vel}


def test_the_perfect_imu_of_the_same_steps_gives_the_ground_truths_increments():
    tr = _trajectory(2000)
    starts = window_starts(np.ones(2000, bool), 200, stride=37)
    est = preintegrate(tr['gyro'], tr['accel'], tr['t'], starts, 200)
    ref = reference(tr['quat'], tr['pos'], tr['vel'], tr['t'], starts, 200)
    err = errors(est, ref)
    assert len(starts) > 40
    assert err['rotation_deg'].max() < 1e-9
    assert err['velocity_m_s'].max() < 1e-9 and err['position_m'].max() < 1e-9
    # and gravity, its sign and the frame each increment is in all matter
    wrong = reference(tr['quat'], tr['pos'], tr['vel'], tr['t'], starts, 200, gravity=9.7)
    assert errors(est, wrong)['velocity_m_s'].min() > 0.1


def test_the_propagated_covariance_makes_the_nees_chi_square():
    n, length = 30_000, 50
    tr = _trajectory(n, seed=1)
    rng = np.random.default_rng(2)
    gyro_std = np.array([0.01, 0.02, 0.005])
    accel_std = np.array([0.05, 0.08, 0.03])
    gyro = tr['gyro'] + gyro_std * rng.standard_normal((n, 3))
    accel = tr['accel'] + accel_std * rng.standard_normal((n, 3))
    starts = window_starts(np.ones(n, bool), length)
    est = preintegrate(gyro, accel, tr['t'], starts, length,
                       np.broadcast_to(gyro_std ** 2, (n, 3)),
                       np.broadcast_to(accel_std ** 2, (n, 3)))
    err = errors(est, reference(tr['quat'], tr['pos'], tr['vel'], tr['t'], starts, length))
    for name in ('rotation', 'velocity', 'position'):
        nees = err[f'nees_{name}']
        assert 2.6 < nees.mean() < 3.4, name             # 599 windows: 3 +- 0.1 (1 sigma)
        assert 0.69 < (nees < 4).mean() < 0.79, name      # 73.9 % inside 2 sigma
    # a covariance four times too small is told apart
    small = preintegrate(gyro, accel, tr['t'], starts, length,
                         np.broadcast_to(gyro_std ** 2 / 4, (n, 3)),
                         np.broadcast_to(accel_std ** 2 / 4, (n, 3)))
    truth = reference(tr['quat'], tr['pos'], tr['vel'], tr['t'], starts, length)
    assert errors(small, truth)['nees_velocity'].mean() > 10


def test_windows_leave_out_untrusted_ground_truth():
    valid = np.ones(100, bool)
    valid[35] = False
    starts = window_starts(valid, 10)
    assert list(starts) == [0, 10, 20, 40, 50, 60, 70, 80]  # 30's window ends at 40: has 35
    assert list(window_starts(np.ones(21, bool), 10)) == [0, 10]  # 10's last pose is 20
    assert len(window_starts(np.ones(10, bool), 10)) == 0


def test_velocity_of_positions_is_exact_on_a_quadratic():
    t = np.arange(400) / RATE
    pos = np.stack([1 + 2 * t - 0.5 * t ** 2, 3 * t ** 2, -t], 1)
    vel = velocity_from_positions(pos, t)
    np.testing.assert_allclose(vel, np.stack([2 - t, 6 * t, -np.ones_like(t)], 1), atol=1e-9)


@pytest.mark.parametrize('length', [1, 7])
def test_short_windows_match_one_step_by_hand(length):
    tr = _trajectory(50)
    est = preintegrate(tr['gyro'], tr['accel'], tr['t'], np.array([3]), length)
    rot, vel, pos = np.eye(3), np.zeros(3), np.zeros(3)
    for k in range(3, 3 + length):
        a = rot @ tr['accel'][k]
        pos, vel = pos + vel * tr['dt'][k] + 0.5 * a * tr['dt'][k] ** 2, vel + a * tr['dt'][k]
        rot = rot @ Rotation.from_rotvec(tr['gyro'][k] * tr['dt'][k]).as_matrix()
    np.testing.assert_allclose(est.rotation[0], rot, atol=1e-12)
    np.testing.assert_allclose(est.velocity[0], vel, atol=1e-12)
    np.testing.assert_allclose(est.position[0], pos, atol=1e-12)


def test_gtsam_pre_integrates_the_same_increments_and_covariance():
    gtsam = pytest.importorskip('gtsam')  # the VIO back-ends' library, in requirements.txt
    tr = _trajectory(600, seed=3)
    starts, length = np.array([0, 150, 399]), 200  # the last ends one stamp before 600
    gyro_var, accel_var = np.full((600, 3), 1e-4), np.full((600, 3), 4e-3)
    ours = preintegrate(tr['gyro'], tr['accel'], tr['t'], starts, length, gyro_var, accel_var)
    params = gtsam.PreintegrationParams.MakeSharedU(GRAVITY)
    params.setGyroscopeCovariance(np.eye(3) * 1e-4 / RATE)  # densities: variance x period
    params.setAccelerometerCovariance(np.eye(3) * 4e-3 / RATE)
    params.setIntegrationCovariance(np.zeros((3, 3)))
    order = [0, 1, 2, 6, 7, 8, 3, 4, 5]  # GTSAM's rotation, position, velocity
    for w, s in enumerate(starts):
        pim = gtsam.PreintegratedImuMeasurements(params, gtsam.imuBias.ConstantBias())
        for k in range(s, s + length):
            pim.integrateMeasurement(tr['accel'][k], tr['gyro'][k], tr['dt'][k])
        np.testing.assert_allclose(ours.rotation[w], pim.deltaRij().matrix(), atol=1e-4)
        np.testing.assert_allclose(ours.velocity[w], pim.deltaVij(), atol=1e-4)
        np.testing.assert_allclose(ours.position[w], pim.deltaPij(), atol=1e-4)
        # GTSAM's rotation coordinates are dR = Exp(theta); ours perturb dR on the right,
        # dR Exp(phi), and phi = J_r(theta) theta to first order
        jac = np.eye(9)
        jac[:3, :3] = gtsam.Rot3.ExpmapDerivative(gtsam.Rot3.Logmap(pim.deltaRij()))
        theirs = jac @ pim.preintMeasCov()[np.ix_(order, order)] @ jac.T
        np.testing.assert_allclose(np.diag(ours.covariance[w]), np.diag(theirs), rtol=1e-3)
        assert np.abs(ours.covariance[w] - theirs).max() < 1e-3 * np.abs(theirs).max()
