# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Integration and AOE/ROE: against a plain loop, evo, and hand-made errors."""

from denoise_imu_ros.core.metrics import attitude_errors, integrate
from denoise_imu_ros.data.asl import read_asl
import numpy as np
import pytest
from scipy.spatial.transform import Rotation


def test_prefix_scan_integration_equals_the_step_by_step_loop():
    rng = np.random.default_rng(0)
    gyro, dt = rng.normal(size=(999, 3)), rng.uniform(0.004, 0.006, 999)
    q0 = Rotation.random(random_state=1)
    scan = integrate(q0.as_quat(), gyro, dt)
    r = q0
    for k in range(999):
        r = r * Rotation.from_rotvec(gyro[k] * dt[k])  # sample k drives stamp k -> k + 1
        if k % 97 == 0 or k == 998:
            assert (scan[k + 1].inv() * r).magnitude() < 1e-12
    assert (scan[0].inv() * q0).magnitude() == 0


def test_aoe_matches_evo_ape_rotation_error_on_a_real_raw_gyro_trajectory(euroc):
    from denoise_imu_ros.data.timebase import crop, onto_imu_stamps
    from evo.core import metrics
    from evo.core.trajectory import PoseTrajectory3D
    seq = onto_imu_stamps(crop(read_asl(euroc / 'V1_03_difficult'), 0.0, 40.0))  # 7633 poses
    est = integrate(seq.gt_quat[0], seq.imu[:-1, :3], seq.dt)
    ours = attitude_errors(est, Rotation.from_quat(seq.gt_quat), seq.gt_pos, seq.gt_valid)

    def traj(quat_xyzw):
        return PoseTrajectory3D(positions_xyz=seq.gt_pos,
                                orientations_quat_wxyz=quat_xyzw[:, [3, 0, 1, 2]],
                                timestamps=seq.stamp_ns * 1e-9)
    ape = metrics.APE(metrics.PoseRelation.rotation_angle_deg)
    ape.process_data((traj(seq.gt_quat), traj(est.as_quat())))
    assert ours.aoe == pytest.approx(ape.get_statistic(metrics.StatisticsType.rmse), rel=1e-6)
    assert ours.aoe > 50  # raw EuRoC gyro drifts by tens of degrees (71 in these 40 s)


def test_yaw_and_tilt_split_the_error_and_roe_ignores_a_constant_world_offset():
    n = 2000
    t = np.linspace(0, 20, n)
    gt = Rotation.from_rotvec(np.stack([0.3 * np.sin(t), 0.2 * np.cos(t), 0.5 * t], 1))
    pos = np.stack([t, np.zeros(n), np.zeros(n)], 1)  # 1 m/s along x: 20 m in all
    valid = np.ones(n, bool)
    world_yaw = Rotation.from_euler('z', 10, degrees=True) * gt
    err = attitude_errors(world_yaw, gt, pos, valid, distances=(7.0,))
    assert err.aoe == pytest.approx(10) and err.aoe_yaw == pytest.approx(10)
    assert err.tilt < 1e-6  # a heading error leaves the vertical where it is
    assert err.roe_median()[7.0] < 1e-9  # relative rotations are untouched
    tilt = Rotation.from_euler('x', 5, degrees=True) * gt
    err = attitude_errors(tilt, gt, pos, valid, distances=(35.0,))
    assert err.aoe == pytest.approx(5) and err.aoe_yaw < 1e-9
    assert err.tilt == pytest.approx(5)
    assert np.isnan(err.roe_median()[35.0])  # never travelled 35 m
    # yaw and tilt at once: the vertical 5 deg off; the 40 deg in the holes counts for nothing
    odd = np.arange(n) % 2 == 1
    both = Rotation.from_euler('ZX', np.where(odd[:, None], [30, 5], [0, 40]), degrees=True)
    err = attitude_errors(both * gt, gt, pos, odd, distances=())
    assert err.tilt == pytest.approx(5) and err.aoe > 30


def test_ground_truth_holes_are_skipped():
    n = 1000
    gt = Rotation.identity(n)
    est = Rotation.concatenate([Rotation.identity(500),
                                Rotation.from_euler('z', np.full((500, 1), 90.0), degrees=True)])
    valid = np.arange(n) < 500
    err = attitude_errors(est, gt, np.zeros((n, 3)), valid, distances=())
    assert err.aoe == 0 and np.isnan(err.error_deg[600])


def test_integration_starts_at_the_first_trusted_pose_not_one_across_a_hole():
    """A tail that starts inside a mocap hole starts from no interpolated pose."""
    from denoise_imu_ros.core.metrics import integrate_from_trusted, sequence_errors
    from denoise_imu_ros.core.records import Sequence
    n = 400
    t = np.arange(n) * 5_000_000
    gyro = np.tile([0.0, 0.0, 0.2], (n, 1))
    truth = Rotation.from_rotvec(np.outer(0.2 * t * 1e-9, [0.0, 0.0, 1.0]))
    quat = truth.as_quat()
    quat[:50] = Rotation.from_euler('x', 10, degrees=True).as_quat()  # interpolated, wrong
    valid = np.arange(n) >= 50
    seq = Sequence('s', t, np.hstack([gyro, np.tile([0.0, 0.0, 9.81], (n, 1))]), quat,
                   np.zeros((n, 3)), valid)
    est, err = sequence_errors(seq, gyro, distances=())
    assert err.aoe < 1e-9  # the true gyro, integrated from the first trusted pose
    np.testing.assert_allclose(est[50:].as_quat(), quat[50:], atol=1e-12)
    whole = integrate_from_trusted(quat, np.ones(n, bool), gyro, np.diff(t) * 1e-9)
    np.testing.assert_allclose(whole.as_quat()[0], quat[0])  # all trusted: from the first


def test_a_constant_bias_is_recovered_from_increments_between_sparse_poses():
    from denoise_imu_ros.core.metrics import fit_constant_bias, increment_residuals, increments
    rng = np.random.default_rng(5)
    n = 6001
    dt = np.full(n - 1, 0.005)
    rate = np.cumsum(rng.normal(scale=0.05, size=(n, 3)), axis=0)  # a body that turns
    truth = integrate(Rotation.random(random_state=2).as_quat(), rate[:-1], dt).as_quat()
    pose_at = np.zeros(n, bool)
    stamps = np.cumsum(rng.integers(40, 201, n // 40))
    pose_at[stamps[stamps < n]] = True  # keyframes, 40-200 samples apart
    valid = np.ones(n, bool)
    valid[3000:3100] = False  # a hole: no increment spans it
    bias = np.array([0.01, -0.02, 0.005])
    starts, ends = increments(valid, 128, pose_at)
    assert pose_at[starts].all() and pose_at[ends].all()
    assert ((ends - starts >= 128) & (ends - starts <= 256)).all()
    # a pose whose next one at least 128 samples on is further than 256: none from it
    stretched = [a for a in np.flatnonzero(pose_at) if (
        (later := stamps[(stamps >= a + 128) & (stamps < n)]).size and later[0] - a > 256)]
    assert stretched and not set(stretched) & set(starts)
    assert not ((starts < 3100) & (ends >= 3000)).any()
    # the fit is to first order in the bias: as close as from the blocks of a full grid
    fitted = fit_constant_bias(truth, valid, rate + bias, dt, 128, pose_at=pose_at)
    grid = fit_constant_bias(truth, valid, rate + bias, dt, 128)
    assert np.abs(fitted - bias).max() < 2e-4 and np.abs(grid - bias).max() < 2e-4
    res, duration = increment_residuals(truth, valid, rate, dt, 128, pose_at=pose_at)
    assert np.abs(res).max() < 1e-9 and np.allclose(duration, (ends - starts) * 0.005)
    # without pose_at, the non-overlapping blocks
    blocks = increments(valid, 128)
    assert (blocks[1] - blocks[0] == 128).all() and (blocks[0] % 128 == 0).all()
